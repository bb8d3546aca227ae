//! Running an MPM scene: fill the bodies (or restore a checkpoint), then the time loop of
//! the solver's timed stages (sort, P2G with the strip exchange, grid, stress, G2P,
//! migration) plus output, and at the end the analyses, checks and `summary.json`.

use crate::driver::{Lap, RunHeader, StageClock};
use crate::progress::Progress;
use crate::run::{Length, RunError, RunOptions, Status};
use crate::time_loop::{drive, particle_last_step, Due, Flow, LoopEnd, LoopPlan, Stepper};
use analysis::checks::evaluate;
use analysis::collapse::{
    collapse_results, thick_front, thick_front_results, PileShape, QUANTITIES, THICK_QUANTITIES,
};
use analysis::Results;
use decomposition::Comm;
use io::atomic::{ensure_writable_dir, write_atomic};
use io::mpm_checkpoint::{self, MpmRunState};
use io::mpm_out::{write_mpm_png, MpmWriter};
use mpm::{MpmError, MpmSystem, Points, Totals, MPM_STAGES};
use scene::{GrainAnalysis, MpmScene, PictureField, ValidMpmScene};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Everything an MPM run's `summary.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct MpmSummary {
    /// The keys every summary starts with (see [`RunHeader`]).
    #[serde(flatten)]
    pub run: RunHeader,
    /// The scene as parsed.
    pub scene: MpmScene,
    /// Cell-column boundaries of the ranks' slabs at the end.
    pub slab_columns: Vec<usize>,
    /// Material points.
    pub points: u64,
    /// Grid cells (nx, ny) and cell size (m).
    pub cells: [usize; 2],
    /// See `cells`.
    pub cell_size_m: f64,
    /// Time step (s) and the CFL limit it satisfies.
    pub time_step_s: f64,
    /// See `time_step_s`.
    pub critical_time_step_s: f64,
    /// Point updates per second over the loop (all ranks).
    pub point_steps_per_s: f64,
    /// Points handed to another rank.
    pub migrated: u64,
    /// Slab rebalances.
    pub rebalances: u64,
    /// Seconds waiting for strips and migrations, slowest rank.
    pub comm_wait_s: f64,
    /// Total mass at the start and the end (kg/m): must agree.
    pub mass_kg_m: [f64; 2],
    /// Kinetic energy at the end (J/m).
    pub kinetic_energy_j_m: f64,
    /// Momentum at the end (kg/s per metre).
    pub momentum: [f64; 2],
    /// Points that yielded in the last step.
    pub yielding_points: u64,
    /// Snapshots written.
    pub snapshots: usize,
}

/// The stepper's own stage (the solver times [`MPM_STAGES`]; the driver output and
/// checkpoints).
const OBSERVE: [&str; 1] = ["observe"];

/// Per background-cell column of the points on every rank (collective): the farthest point
/// edge, the highest point edge and the highest point centre (m; −∞ when empty).
pub fn deposit_columns(points: &Points, h: f64, nx: usize, comm: &dyn Comm) -> Vec<[f64; 3]> {
    let mut cols = vec![f64::NEG_INFINITY; 3 * nx];
    for i in 0..points.len() {
        let [x, y] = points.pos[i];
        let c = ((x / h).floor().max(0.0) as usize).min(nx - 1);
        let half = points.half0[i];
        cols[3 * c] = cols[3 * c].max(x + half);
        cols[3 * c + 1] = cols[3 * c + 1].max(y + half);
        cols[3 * c + 2] = cols[3 * c + 2].max(y);
    }
    let all = comm.all_gather_f64(&cols);
    let mut merged = vec![[f64::NEG_INFINITY; 3]; nx];
    for r in all.chunks_exact(3 * nx) {
        for (m, v) in merged.iter_mut().zip(r.chunks_exact(3)) {
            for k in 0..3 {
                m[k] = m[k].max(v[k]);
            }
        }
    }
    merged
}

/// The deposit of a column collapse from its [`deposit_columns`] (cells `h` wide): length
/// from the wall to the front and height above the floor (m). The front is the farthest
/// point edge of the cell columns occupied without a gap from the wall, so points flung
/// ahead of the mass do not count.
pub fn deposit_shape(cols: &[[f64; 3]], wall_x: f64, floor_y: f64, h: f64) -> PileShape {
    let first = wall_column(cols.len(), wall_x, h);
    let (mut reach, mut height) = (wall_x, floor_y);
    for c in &cols[first..] {
        if c[0] == f64::NEG_INFINITY {
            break;
        }
        reach = reach.max(c[0]);
        height = height.max(c[1]);
    }
    PileShape {
        length_m: reach - wall_x,
        height_m: height - floor_y,
    }
}

/// The deposit's front where it is at least `min_height` thick (m from the wall): see
/// [`thick_front`], on the highest point centres above the floor.
pub fn deposit_thick_front(
    cols: &[[f64; 3]],
    wall_x: f64,
    floor_y: f64,
    h: f64,
    min_height: f64,
) -> f64 {
    let tops: Vec<f64> = cols.iter().map(|c| c[2] - floor_y).collect();
    thick_front(
        &tops,
        h,
        wall_column(cols.len(), wall_x, h),
        wall_x,
        min_height,
    )
}

/// The cell column holding the wall x = `wall_x` (m) among `nx` columns `h` wide.
fn wall_column(nx: usize, wall_x: f64, h: f64) -> usize {
    ((wall_x / h).floor().max(0.0) as usize).min(nx - 1)
}

/// The message of the rank that failed (collective): every rank stops together, but only
/// the one holding the offending point can name it.
fn first_error(e: &MpmError, comm: &dyn Comm) -> String {
    let own = match e {
        MpmError::Elsewhere { .. } => String::new(),
        other => other.to_string(),
    };
    let all = comm.all_gather_bytes(format!("{own}\0").as_bytes());
    all.split(|&b| b == 0)
        .map(|m| String::from_utf8_lossy(m).into_owned())
        .find(|m| !m.is_empty())
        .unwrap_or_else(|| e.to_string())
}

/// An MPM system as the driver's time loop steps it, with its output.
pub struct MpmStepper<'a> {
    scene: &'a ValidMpmScene,
    out_dir: PathBuf,
    /// The points and grid on this rank.
    pub sys: MpmSystem,
    writer: MpmWriter,
    /// Top of the pictures' colour scale (m/s or plastic strain).
    vmax: f64,
    /// The column's length and height at the start (m), for a collapse analysis.
    initial_shape: [f64; 2],
    /// Simulated time after which the run may stop early (s): 10 % of the run.
    settle_after_s: f64,
    /// This rank's seconds in [`OBSERVE`].
    clock: StageClock,
    /// `check`'s memory estimate for the run, all ranks (bytes).
    memory_estimate: f64,
}

impl Stepper for MpmStepper<'_> {
    fn steps_done(&self) -> u64 {
        self.sys.steps
    }

    fn time_s(&self) -> f64 {
        self.sys.time
    }

    fn advance(&mut self, comm: &dyn Comm) -> Flow {
        match self.sys.step(comm) {
            Ok(()) => Flow::Go,
            Err(e) => Flow::Unstable(first_error(&e, comm)),
        }
    }

    fn observe(&mut self, comm: &dyn Comm, due: Due) -> Result<Flow, RunError> {
        if !due.step.is_multiple_of(100) && !due.last {
            return Ok(Flow::Go);
        }
        let t = Lap::start();
        let tot = self.sys.totals(comm)?;
        let stop = self.scene.scene.run.stop_below_specific_kinetic_energy_j_kg;
        let flow = if !tot.kinetic_energy.is_finite() {
            Flow::Unstable(format!(
                "step {}: the kinetic energy is not finite; reduce the Courant number",
                due.step
            ))
        } else if stop > 0.0
            && self.sys.time > self.settle_after_s
            && tot.kinetic_energy / tot.mass < stop
        {
            Flow::Settled
        } else {
            Flow::Go
        };
        self.clock.add("observe", t);
        Ok(flow)
    }

    fn snapshot(&mut self, comm: &dyn Comm) -> Result<(), RunError> {
        self.writer.write(&self.sys, comm)?;
        let out = &self.scene.scene.output;
        if out.pictures() {
            let name = format!("mpm_step_{:08}.png", self.sys.steps);
            let path = self.out_dir.join("pictures").join(name);
            let style = io::figure::PictureStyle {
                size_px: out.picture_size_px(),
                limit: self.vmax,
            };
            let field = out.picture_field();
            write_mpm_png(&path, &self.sys, field, style, self.sys.time, comm)?;
        }
        Ok(())
    }

    fn checkpoint(&mut self, comm: &dyn Comm, path: &Path, next: f64) -> Result<(), RunError> {
        let mut migrated = [self.sys.migrated as f64];
        comm.sum_f64(&mut migrated);
        let state = MpmRunState {
            step: self.sys.steps,
            time_s: self.sys.time,
            next_output_s: next,
            migrated: migrated[0] as u64,
            initial_shape_m: self.initial_shape,
        };
        mpm_checkpoint::write(path, comm, &self.sys, &state)?;
        Ok(())
    }
}

/// The wall and floor of the scene's column-collapse analysis, and its thick-front height.
fn collapse_of(s: &MpmScene) -> (Option<(f64, f64)>, Option<f64>) {
    match s.analyses.first() {
        Some(GrainAnalysis::ColumnCollapse {
            wall_x_m,
            floor_y_m,
            front_min_height_m,
        }) => (Some((*wall_x_m, *floor_y_m)), *front_min_height_m),
        None => (None, None),
    }
}

/// Run an MPM scene on every rank of `comm` (collective). Writes `mpm.h5` + `mpm.xdmf`,
/// `pictures/mpm_*.png` and (rank 0) `summary.json` into `opts.out_dir`.
pub fn run_mpm(
    scene: &ValidMpmScene,
    opts: &RunOptions,
    comm: &dyn Comm,
) -> Result<MpmSummary, RunError> {
    let s = &scene.scene;
    if comm.is_root() {
        ensure_writable_dir(&opts.out_dir)?;
        ensure_writable_dir(&opts.out_dir.join("pictures"))?;
    }
    comm.barrier();
    let restored = match &opts.restart {
        Some(p) => Some(mpm_checkpoint::read(p, comm)?),
        None => None,
    };
    if comm.is_root() {
        let pics = opts.out_dir.join("pictures");
        let after = restored.as_ref().map(|r| r.run.step);
        io::figure::remove_stale(&pics, after)
            .map_err(|source| io::OutputError::Io { path: pics, source })?;
    }
    let spec = scene.setup.spec;
    let (points, resume) = match restored {
        Some(r) => (r.points, Some(r.run)),
        None => (scene.points.clone(), None),
    };
    let length = Length {
        steps: s.run.steps,
        end_time_s: s.run.end_time_s,
    };
    let last_step = particle_last_step(length, scene.setup.dt);
    let done = resume.map_or(0, |r| r.step);
    let cost = crate::budget::mpm_cost(scene, last_step.saturating_sub(done), comm.size());
    crate::budget::admit(cost, comm, opts.force)?;
    let mut sys = MpmSystem::new(scene.setup.clone(), points, comm)?;
    let initial_shape = match (&resume, collapse_of(s).0) {
        (Some(r), _) => r.initial_shape_m,
        (None, Some((wx, fy))) => {
            let cols = deposit_columns(&sys.points, spec.h, spec.nx, comm);
            let d = deposit_shape(&cols, wx, fy, spec.h);
            [d.length_m, d.height_m]
        }
        (None, None) => [f64::NAN; 2],
    };
    if let Some(r) = &resume {
        sys.time = r.time_s;
        sys.steps = r.step;
        if comm.is_root() {
            sys.migrated = r.migrated;
        }
    }
    let start_totals = sys.totals(comm)?;
    let writer = MpmWriter::open(&opts.out_dir, &sys, comm, resume.map(|r| r.step))?;
    // Colour scale unless the scene sets it: the free-fall speed over the bodies' height
    // (rounded up), or plastic strain 0–1.
    let g_abs = s.mpm.gravity_m_s2[0].hypot(s.mpm.gravity_m_s2[1]);
    let ys = scene.points.pos.iter().map(|p| p[1]);
    let body_height =
        ys.clone().fold(f64::NEG_INFINITY, f64::max) - ys.fold(f64::INFINITY, f64::min);
    let height = if body_height > 0.0 {
        body_height
    } else {
        spec.height()
    };
    let limits = s.output.picture_limits();
    let vmax = match s.output.picture_field() {
        PictureField::PlasticStrain => limits.plastic_strain.unwrap_or(1.0),
        _ => limits.speed_m_s.unwrap_or(io::figure::round_up(
            (2.0 * g_abs * height).sqrt().max(1e-9),
        )),
    };
    let dt = sys.setup.dt;
    let mut progress = Progress::new(
        last_step,
        start_totals.points as f64,
        dt,
        opts.progress && comm.is_root(),
    )
    .with_unit("M point-steps/s");
    let plan = LoopPlan::new(
        last_step,
        &s.output,
        &opts.out_dir,
        resume.map(|r| r.next_output_s),
    )
    .scene_length(particle_last_step(opts.scene_length.unwrap_or(length), dt));
    let mut stepper = MpmStepper {
        scene,
        out_dir: opts.out_dir.clone(),
        sys,
        writer,
        vmax,
        initial_shape,
        settle_after_s: 0.1 * scene.end_time_s(),
        clock: StageClock::new(&OBSERVE),
        memory_estimate: cost.memory_bytes,
    };
    let end = drive(&mut stepper, &plan, &mut progress, comm)?;
    if comm.is_root() && s.output.pictures() {
        io::figure::write_movies(&opts.out_dir.join("pictures"), &["mpm_step_"]);
    }
    summarise(scene, stepper, end, start_totals, comm, &opts.out_dir)
}

/// The column-collapse results of the deposit against the initial column.
fn collapse_analysis(st: &MpmStepper, end: &LoopEnd, comm: &dyn Comm) -> Results {
    let mut results = Results::new();
    let s = &st.scene.scene;
    let (Some((wx, fy)), thick_min_height) = collapse_of(s) else {
        return results;
    };
    let spec = st.scene.setup.spec;
    let g_abs = s.mpm.gravity_m_s2[0].hypot(s.mpm.gravity_m_s2[1]);
    let before = PileShape {
        length_m: st.initial_shape[0],
        height_m: st.initial_shape[1],
    };
    let cols = deposit_columns(&st.sys.points, spec.h, spec.nx, comm);
    let after = deposit_shape(&cols, wx, fy, spec.h);
    let values = collapse_results(before, after, g_abs, end.settled_s.unwrap_or(st.sys.time));
    for (k, v) in QUANTITIES.iter().zip(values) {
        results.insert(format!("collapse.{k}"), v);
    }
    if let Some(min_height) = thick_min_height {
        let front = deposit_thick_front(&cols, wx, fy, spec.h, min_height);
        for (k, v) in THICK_QUANTITIES
            .iter()
            .zip(thick_front_results(before, front))
        {
            results.insert(format!("collapse.{k}"), v);
        }
    }
    results
}

/// Analyses, checks and `summary.json` (rank 0) of a finished loop (collective).
fn summarise(
    scene: &ValidMpmScene,
    mut st: MpmStepper,
    end: LoopEnd,
    start_totals: Totals,
    comm: &dyn Comm,
    out_dir: &Path,
) -> Result<MpmSummary, RunError> {
    let s = &scene.scene;
    let status = end.status;
    let results = if status == Status::Ok {
        collapse_analysis(&st, &end, comm)
    } else {
        Results::new()
    };
    let checks = evaluate(&s.checks, &results);
    let end_totals = if status == Status::Unstable {
        start_totals
    } else {
        st.sys.totals(comm)?
    };
    let sys = &st.sys;
    let mut counts = [sys.migrated as f64, sys.yielded as f64];
    comm.sum_f64(&mut counts);
    let comm_wait = comm.max_f64(sys.comm_seconds);
    let mut header = RunHeader::new(
        "mpm",
        scene.path.clone(),
        s.title.clone(),
        scene.warnings.clone(),
        comm,
    );
    header.status = status;
    header.error = end.error.clone();
    header.restarted_from_step = end.start_step;
    header.steps = sys.steps;
    header.simulated_time_s = sys.time;
    header.settled_at_s = end.settled_s;
    header.wall_time_s = end.wall_s;
    let solver = StageClock::with_seconds(&MPM_STAGES, &sys.seconds);
    header.set_traffic(end.traffic, comm);
    header.set_stages(&[&solver, &st.clock, &end.clock], comm);
    header.checkpoints = end.checkpoints.clone();
    header.results = results;
    header.judge(checks, &[], end.shortened);
    header.set_memory(st.memory_estimate, comm);
    let spec = scene.setup.spec;
    let steps = (sys.steps - end.start_step) as f64;
    let summary = MpmSummary {
        run: header,
        scene: s.clone(),
        slab_columns: sys.slab_columns().to_vec(),
        points: start_totals.points,
        cells: [spec.nx, spec.ny],
        cell_size_m: spec.h,
        time_step_s: sys.setup.dt,
        critical_time_step_s: scene.critical_dt,
        point_steps_per_s: start_totals.points as f64 * steps / end.wall_s.max(1e-12),
        migrated: counts[0] as u64,
        rebalances: sys.rebalances,
        comm_wait_s: comm_wait,
        mass_kg_m: [start_totals.mass, end_totals.mass],
        kinetic_energy_j_m: end_totals.kinetic_energy,
        momentum: end_totals.momentum,
        yielding_points: counts[1] as u64,
        snapshots: st.writer.snapshots(),
    };
    if comm.is_root() {
        let json = crate::summary_units::summary_json(&summary);
        write_atomic(&out_dir.join("summary.json"), &json)?;
    }
    Ok(summary)
}
