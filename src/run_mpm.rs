//! Running an MPM scene: fill the bodies (or restore a checkpoint), then the time loop of
//! the solver's timed stages (sort, P2G with the strip exchange, grid, stress, G2P,
//! migration) plus output, and at the end the analyses, checks and `summary.json`.

use crate::driver::{RunHeader, Signals};
use crate::progress::Progress;
use crate::run::{stage_stats, RunError, RunOptions, Status};
use analysis::checks::evaluate;
use analysis::collapse::{
    collapse_results, thick_front, thick_front_results, PileShape, QUANTITIES, THICK_QUANTITIES,
};
use analysis::Results;
use decomposition::Comm;
use io::atomic::{ensure_writable_dir, write_atomic};
use io::mpm_checkpoint::{self, MpmRunState};
use io::mpm_out::{write_mpm_png, MpmWriter};
use mpm::{MpmError, MpmSystem, Points, MPM_STAGES};
use scene::{GrainAnalysis, MpmScene, PictureField, ValidMpmScene};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

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

/// Names of the stages in `summary.json`: the solver's, then output.
const STAGES: [&str; 7] = ["sort", "p2g", "grid", "stress", "g2p", "migrate", "output"];

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
    let spec = scene.setup.spec;
    let (collapse, thick_min_height) = match s.analyses.first() {
        Some(GrainAnalysis::ColumnCollapse {
            wall_x_m,
            floor_y_m,
            front_min_height_m,
        }) => (Some((*wall_x_m, *floor_y_m)), *front_min_height_m),
        None => (None, None),
    };
    let (points, resume) = match restored {
        Some(r) => (r.points, Some(r.run)),
        None => (scene.points.clone(), None),
    };
    let mut sys = MpmSystem::new(scene.setup.clone(), points, comm)?;
    let initial_shape = match (&resume, collapse) {
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
    let mut writer = MpmWriter::open(&opts.out_dir, &sys, comm, resume.map(|r| r.step))?;
    let field = s.run.picture_field;
    // Colour scale: free-fall speed over the domain height, or plastic strain 0–1.
    let g_abs = s.mpm.gravity_m_s2[0].hypot(s.mpm.gravity_m_s2[1]);
    let vmax = match field {
        PictureField::Speed => (2.0 * g_abs * spec.height()).sqrt().max(1e-9),
        PictureField::PlasticStrain => 1.0,
    };
    let picture = |sys: &MpmSystem| -> Result<(), RunError> {
        if s.run.pictures {
            let name = format!("mpm_step_{:08}.png", sys.steps);
            write_mpm_png(
                &opts.out_dir.join("pictures").join(name),
                sys,
                field,
                vmax,
                comm,
            )?;
        }
        Ok(())
    };
    if resume.is_none() {
        writer.write(&sys, comm)?;
        picture(&sys)?;
    }
    let dt = sys.setup.dt;
    let end_time = opts.end_time_s.unwrap_or(s.run.end_time_s);
    let total_steps = opts.steps.unwrap_or((end_time / dt).ceil() as u64);
    let mut progress = Progress::new(
        total_steps,
        start_totals.points as f64,
        dt,
        opts.progress && comm.is_root(),
    )
    .with_unit("M point-steps/s");
    let mut next_output = resume.map_or(s.run.output_every_s, |r| r.next_output_s);
    let start_step = sys.steps;
    let (mut status, mut error, mut stop_time) = (Status::Ok, None, None);
    let signals = Signals::install();
    let checkpoint_path = opts.out_dir.join("checkpoint.h5");
    let mut checkpoints = Vec::new();
    let write_checkpoint = |sys: &MpmSystem, next_output: f64, list: &mut Vec<PathBuf>| {
        let mut migrated = [sys.migrated as f64];
        comm.sum_f64(&mut migrated);
        let state = MpmRunState {
            step: sys.steps,
            time_s: sys.time,
            next_output_s: next_output,
            migrated: migrated[0] as u64,
            initial_shape_m: initial_shape,
        };
        mpm_checkpoint::write(&checkpoint_path, comm, sys, &state)?;
        list.push(checkpoint_path.clone());
        Ok::<(), RunError>(())
    };
    let mut output_seconds = 0.0;
    let t0 = Instant::now();
    while sys.steps < total_steps {
        if let Err(e) = sys.step(comm) {
            status = Status::Unstable;
            error = Some(first_error(&e, comm));
            break;
        }
        let step = sys.steps;
        let t = Instant::now();
        if step % 100 == 0 || step == total_steps {
            let tot = sys.totals(comm)?;
            if !tot.kinetic_energy.is_finite() {
                status = Status::Unstable;
                error = Some(format!(
                    "step {step}: the kinetic energy is not finite; reduce the Courant number"
                ));
                break;
            }
            let quiet = s.run.stop_below_specific_kinetic_energy_j_kg > 0.0
                && sys.time > 0.1 * s.run.end_time_s
                && tot.kinetic_energy / tot.mass < s.run.stop_below_specific_kinetic_energy_j_kg;
            if quiet {
                stop_time = Some(sys.time);
                output_seconds += t.elapsed().as_secs_f64();
                break;
            }
        }
        if s.run.output_every_s > 0.0 && sys.time >= next_output {
            next_output += s.run.output_every_s;
            writer.write(&sys, comm)?;
            picture(&sys)?;
        }
        // Signals are agreed on by all ranks after every step, so all ranks checkpoint (and
        // stop) together.
        let agreed = signals.agree(comm, false);
        let every = s.run.checkpoint_every > 0 && step % s.run.checkpoint_every == 0;
        if agreed.checkpoint || every {
            write_checkpoint(&sys, next_output, &mut checkpoints)?;
        }
        output_seconds += t.elapsed().as_secs_f64();
        if agreed.stop {
            status = Status::Interrupted;
            break;
        }
        progress.update(step);
    }
    progress.finish();
    let wall = t0.elapsed().as_secs_f64();
    if status == Status::Ok && s.run.checkpoint_at_end {
        write_checkpoint(&sys, next_output, &mut checkpoints)?;
    }
    if status == Status::Ok {
        let t = Instant::now();
        writer.write(&sys, comm)?;
        picture(&sys)?;
        output_seconds += t.elapsed().as_secs_f64();
    }
    let mut results = Results::new();
    if let (Some((wx, fy)), Status::Ok) = (collapse, status) {
        let before = PileShape {
            length_m: initial_shape[0],
            height_m: initial_shape[1],
        };
        let cols = deposit_columns(&sys.points, spec.h, spec.nx, comm);
        let after = deposit_shape(&cols, wx, fy, spec.h);
        let values = collapse_results(before, after, g_abs, stop_time.unwrap_or(sys.time));
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
    }
    let checks = evaluate(&s.checks, &results);
    if status == Status::Ok && checks.iter().any(|c| !c.passed) {
        status = Status::ChecksFailed;
    }
    let mut local = sys.seconds.to_vec();
    local.push(output_seconds);
    let (stages, stage_seconds) = stage_stats(&STAGES, &local, comm);
    let end = if status == Status::Unstable {
        start_totals
    } else {
        sys.totals(comm)?
    };
    let mut counts = [sys.migrated as f64, sys.yielded as f64];
    comm.sum_f64(&mut counts);
    let comm_wait = comm.max_f64(sys.comm_seconds);
    debug_assert_eq!(MPM_STAGES.len() + 1, STAGES.len());
    let mut header = RunHeader::new(
        "mpm",
        scene.path.clone(),
        s.title.clone(),
        scene.warnings.clone(),
        comm,
    );
    header.status = status;
    header.error = error;
    header.restarted_from_step = start_step;
    header.steps = sys.steps;
    header.simulated_time_s = sys.time;
    header.wall_time_s = wall;
    header.stage_seconds = stage_seconds;
    header.stages = stages;
    header.checkpoints = checkpoints;
    header.results = results;
    header.checks = checks;
    let summary = MpmSummary {
        run: header,
        scene: s.clone(),
        slab_columns: sys.slab_columns().to_vec(),
        points: start_totals.points,
        cells: [spec.nx, spec.ny],
        cell_size_m: spec.h,
        time_step_s: dt,
        critical_time_step_s: scene.critical_dt,
        point_steps_per_s: start_totals.points as f64 * (sys.steps - start_step) as f64
            / wall.max(1e-12),
        migrated: counts[0] as u64,
        rebalances: sys.rebalances,
        comm_wait_s: comm_wait,
        mass_kg_m: [start_totals.mass, end.mass],
        kinetic_energy_j_m: end.kinetic_energy,
        momentum: end.momentum,
        yielding_points: counts[1] as u64,
        snapshots: writer.snapshots(),
    };
    if comm.is_root() {
        let json = serde_json::to_vec_pretty(&summary).expect("summary serialises");
        write_atomic(&opts.out_dir.join("summary.json"), &json)?;
    }
    Ok(summary)
}
