//! Running a grains-only scene: prepare the sample (pack, settle, trim, or load), then the
//! driver's time loop over a [`GrainStepper`] — walls (removals), DEM step (with migration
//! and ghost exchange inside), observations — and the analyses, checks and `summary.json`.

use crate::driver::{Lap, RunHeader, StageClock};
use crate::progress::Progress;
use crate::run::{Length, RunError, RunOptions};
use crate::time_loop::{drive, particle_last_step, Due, Flow, LoopEnd, LoopPlan, Stepper};
use analysis::checks::evaluate;
use analysis::collapse::{collapse_results, pile_shape, QUANTITIES};
use analysis::Results;
use decomposition::Comm;
use dem::walls::apply_walls;
use dem::{Grains, SlabDem};
use io::atomic::{ensure_writable_dir, write_atomic};
use io::grains_checkpoint::{self, GrainRunState};
use io::grains_out::GrainWriter;
use io::grains_picture::write_grains_png;
use scene::{GrainAnalysis, GrainScene, ValidGrainScene};
use serde::Serialize;
use std::path::{Path, PathBuf};

pub(crate) mod sample;

pub use sample::gather_grains;
use sample::{bounds_for, global_state, prepare, start};

/// The grain solver's own stages, in the order of a step (the driver adds output and
/// checkpoint).
pub const GRAIN_STAGES: [&str; 3] = ["walls", "dem", "observe"];

/// Everything a grains run's `summary.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct GrainSummary {
    /// The keys every summary starts with (see [`RunHeader`]).
    #[serde(flatten)]
    pub run: RunHeader,
    /// The scene as parsed.
    pub scene: GrainScene,
    /// x-boundaries of the ranks' slabs at the end (m).
    pub slab_bounds_m: Vec<f64>,
    /// Grains in the run.
    pub grains: usize,
    /// Time step (s) and the λ it satisfies.
    pub time_step_s: f64,
    /// See `time_step_s`.
    pub lambda: f64,
    /// Steps spent settling the sample (0 when it was not settled).
    pub settle_steps: u64,
    /// Grain-steps per second over the loop (all ranks).
    pub grain_steps_per_s: f64,
    /// Grains handed to another rank, all ranks together.
    pub migrated: u64,
    /// Times the slab boundaries moved to rebalance the grain counts.
    pub rebalances: u64,
    /// Seconds waiting for ghost and migration messages, slowest rank.
    pub comm_wait_s: f64,
    /// Contacts at the end.
    pub contacts: usize,
    /// Verlet-list rebuilds.
    pub list_rebuilds: u64,
    /// Kinetic energy at the end (J/m).
    pub kinetic_energy_j_m: f64,
    /// Total momentum at the end (kg m/s per m).
    pub momentum: [f64; 2],
    /// Snapshots written.
    pub snapshots: usize,
}

/// A distributed grain system as the driver's time loop steps it, with its output.
pub struct GrainStepper<'a> {
    scene: &'a ValidGrainScene,
    out_dir: PathBuf,
    /// The grains on this rank.
    pub d: SlabDem,
    writer: GrainWriter,
    /// The pictures' size and the top of their speed scale (m/s), fixed for the run.
    picture: io::figure::PictureStyle,
    /// Wall and floor of a column-collapse analysis.
    collapse_at: Option<(f64, f64)>,
    /// (t, deposit length, kinetic energy) every [`FRONT_EVERY_STEPS`] steps of a collapse
    /// that did not restart (s, m, J/m).
    fronts: Vec<(f64, f64, f64)>,
    start_step: u64,
    settle_steps: u64,
    /// (x, y, r) of every grain at the start, by id.
    initial: Grains,
    /// `check`'s memory estimate for the run, all ranks (bytes).
    memory_estimate: f64,
    /// When the last wall goes (s).
    last_removal: f64,
    grains: usize,
    /// This rank's seconds per [`GRAIN_STAGES`].
    pub clock: StageClock,
}

impl Stepper for GrainStepper<'_> {
    fn steps_done(&self) -> u64 {
        self.d.system.steps
    }

    fn time_s(&self) -> f64 {
        self.d.system.time
    }

    fn advance(&mut self, comm: &dyn Comm) -> Flow {
        let t = Lap::start();
        let sys = &mut self.d.system;
        for (w, spec) in self.scene.scene.grains.walls.iter().enumerate() {
            if spec.remove_at_s.is_some_and(|r| sys.time >= r) && !sys.walls[w].removed {
                sys.remove_wall(w);
            }
        }
        self.clock.add("walls", t);
        let t = Lap::start();
        self.d.step(comm);
        self.clock.add("dem", t);
        Flow::Go
    }

    fn observe(&mut self, comm: &dyn Comm, due: Due) -> Result<Flow, RunError> {
        let t = Lap::start();
        let flow = self.health(comm, due);
        self.clock.add("observe", t);
        Ok(flow)
    }

    fn snapshot(&mut self, comm: &dyn Comm) -> Result<(), RunError> {
        self.writer.write(&self.d.system, comm)?;
        if self.scene.scene.output.pictures() {
            let name = format!("grains_step_{:08}.png", self.d.system.steps);
            write_grains_png(
                &self.out_dir.join("pictures").join(name),
                &self.d.system,
                ([0.0, 0.0], self.scene.scene.domain.size()),
                self.picture,
                self.d.system.time,
                comm,
            )?;
        }
        Ok(())
    }

    fn checkpoint(&mut self, comm: &dyn Comm, path: &Path, next: f64) -> Result<(), RunError> {
        let g = &self.initial;
        let state = GrainRunState {
            step: self.d.system.steps,
            time_s: self.d.system.time,
            next_output_s: next,
            settle_steps: self.settle_steps,
            migrated: self.d.migrated,
            initial: (0..g.len())
                .flat_map(|i| [g.x[i], g.y[i], g.r[i]])
                .collect(),
        };
        grains_checkpoint::write(path, comm, &self.d, &state)?;
        Ok(())
    }
}

/// How often a grains run with a collapse analysis records its front (steps; a multiple of
/// the 100 of the health check).
const FRONT_EVERY_STEPS: u64 = 200;

impl GrainStepper<'_> {
    /// Every 100 steps and at the last, a finite kinetic energy and the scene's early stop
    /// once the grains are at rest; every [`FRONT_EVERY_STEPS`] steps of a column collapse
    /// (a multiple of 100), the deposit's front and that energy for `front.csv` and the
    /// front's timing.
    fn health(&mut self, comm: &dyn Comm, due: Due) -> Flow {
        let step = due.step;
        if !step.is_multiple_of(100) && !due.last {
            return Flow::Go;
        }
        let (ke, _, _) = global_state(&self.d, comm);
        if let (Some((wx, fy)), true) = (
            self.collapse_at,
            step.is_multiple_of(FRONT_EVERY_STEPS) && self.start_step == 0,
        ) {
            let g = gather_grains(&self.d.system, comm);
            let length = pile_shape(&g.x, &g.y, &g.r, wx, fy).length_m;
            self.fronts.push((self.d.system.time, length, ke));
        }
        if !ke.is_finite() {
            return Flow::Unstable(format!(
                "the grains' kinetic energy is not finite at step {step} (t = {:.6e} s): \
                 the time step is too large for these contacts; lower lambda",
                self.d.system.time
            ));
        }
        let stop = self.scene.scene.run.stop_below_kinetic_energy_j_m;
        if stop > 0.0 && self.d.system.time > self.last_removal && ke / (self.grains as f64) < stop
        {
            return Flow::Settled;
        }
        Flow::Go
    }
}

/// A warning when grains ended with their centres outside the domain `size` (m): nothing
/// but the scene's walls bounds a grains scene, so a grain that rolls off a bed's end falls
/// for ever, and its energy keeps the run from settling. Collective.
fn escaped_grains(d: &SlabDem, size: [f64; 2], comm: &dyn Comm) -> Option<String> {
    let (g, n) = (&d.system.grains, d.system.owned());
    // A grain with a non-finite position is the instability check's to report.
    let outside = |i: &usize| {
        let (x, y) = (g.x[*i], g.y[*i]);
        x.is_finite()
            && y.is_finite()
            && (!(0.0..=size[0]).contains(&x) || !(0.0..=size[1]).contains(&y))
    };
    let escaped: Vec<usize> = (0..n).filter(outside).collect();
    let mut count = [escaped.len() as f64];
    comm.sum_f64(&mut count);
    let mine = escaped
        .iter()
        .map(|&i| g.y[i])
        .fold(f64::INFINITY, f64::min);
    let lowest = -comm.max_f64(-mine);
    (count[0] > 0.0).then(|| {
        format!(
            "{} grain(s) ended outside the domain [0, {}] × [0, {}] m (the lowest of them at \
             y = {lowest:.4} m): nothing but walls holds grains in; add [[grains.walls]] where \
             they left",
            count[0], size[0], size[1]
        )
    })
}

/// Run a grains scene on every rank of `comm` (collective). Writes `grains.h5` +
/// `grains.xdmf`, `pictures/grains_*.png` and (rank 0) `summary.json` into `opts.out_dir`.
pub fn run_grains(
    scene: &ValidGrainScene,
    opts: &RunOptions,
    comm: &dyn Comm,
) -> Result<GrainSummary, RunError> {
    let s = &scene.scene;
    if comm.is_root() {
        ensure_writable_dir(&opts.out_dir)?;
        ensure_writable_dir(&opts.out_dir.join("pictures"))?;
    }
    comm.barrier();
    let (d, settle_steps, initial, resume) = set_up(scene, opts, comm)?;
    let grains = d.global_count(comm);
    let writer = GrainWriter::open(&opts.out_dir, comm, resume.as_ref().map(|r| r.step), false)?;
    if comm.is_root() {
        let pics = opts.out_dir.join("pictures");
        io::figure::remove_stale(&pics, resume.as_ref().map(|r| r.step))
            .map_err(|source| io::OutputError::Io { path: pics, source })?;
    }
    // Speed scale of the pictures unless the scene sets it: free fall over the sample
    // height, the same for every frame.
    let height = initial.y.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - initial.y.iter().cloned().fold(f64::INFINITY, f64::min);
    let g_abs = s.grains.gravity_m_s2[0].hypot(s.grains.gravity_m_s2[1]);
    let frame_speed = (2.0 * g_abs * height.max(1e-9)).sqrt();
    let dt = d.system.dt;
    let length = Length {
        steps: s.run.steps,
        end_time_s: s.run.end_time_s,
    };
    let last_step = particle_last_step(length, dt);
    // The packing before its settling trim holds more grains than the run: the scene's
    // estimate, as `check` gives it, bounds the peak.
    let held = scene.estimated_grains().unwrap_or(grains as f64);
    let cost =
        crate::budget::grain_cost(held, last_step.saturating_sub(d.system.steps), comm.size());
    crate::budget::admit(cost, comm, opts.force)?;
    let mut progress = Progress::new(
        last_step,
        grains as f64,
        dt,
        opts.progress && comm.is_root(),
    )
    .with_unit("M grain-steps/s");
    let plan = LoopPlan::new(
        last_step,
        &s.output,
        &opts.out_dir,
        resume.as_ref().map(|r| r.next_output_s),
    )
    .scene_length(particle_last_step(opts.scene_length.unwrap_or(length), dt));
    let collapse_at = s
        .analyses
        .iter()
        .map(|a| match a {
            GrainAnalysis::ColumnCollapse {
                wall_x_m,
                floor_y_m,
                ..
            } => (*wall_x_m, *floor_y_m),
        })
        .next();
    let mut stepper = GrainStepper {
        scene,
        out_dir: opts.out_dir.clone(),
        start_step: d.system.steps,
        d,
        writer,
        picture: io::figure::PictureStyle {
            size_px: s.output.picture_size_px(),
            limit: s
                .output
                .picture_limits()
                .speed_m_s
                .unwrap_or(io::figure::round_up(frame_speed)),
        },
        collapse_at,
        fronts: Vec::new(),
        settle_steps,
        initial,
        last_removal: s
            .grains
            .walls
            .iter()
            .filter_map(|w| w.remove_at_s)
            .fold(0.0, f64::max),
        grains,
        memory_estimate: cost.memory_bytes,
        clock: StageClock::new(&GRAIN_STAGES),
    };
    let end = drive(&mut stepper, &plan, &mut progress, comm)?;
    if comm.is_root() && s.output.pictures() {
        io::figure::write_movies(&opts.out_dir.join("pictures"), &["grains_step_"]);
    }
    summarise(scene, stepper, end, g_abs, comm, &opts.out_dir)
}

/// The distributed system at the start: a prepared sample, or a checkpoint's grains. Also
/// the settling steps, the grains at the start (x, y, r by id) and a restart's state.
fn set_up(
    scene: &ValidGrainScene,
    opts: &RunOptions,
    comm: &dyn Comm,
) -> Result<(SlabDem, u64, Grains, Option<GrainRunState>), RunError> {
    let s = &scene.scene;
    let Some(p) = &opts.restart else {
        let (grains, settle_steps) = prepare(scene, comm)?;
        let allow = s.grains.allow_overlap || settle_steps > 0;
        let d = start(scene, grains, allow, comm)?;
        let initial = gather_grains(&d.system, comm);
        return Ok((d, settle_steps, initial, None));
    };
    let r = grains_checkpoint::read(p, comm, s.grains.walls.len())?;
    let bounds = bounds_for(scene, &r.grains, comm);
    let mut setup = scene.dem_setup(&r.grains);
    apply_walls(&mut setup.walls, &r.walls);
    let clock = (r.run.time_s, r.run.step);
    let mut d = SlabDem::restore(r.grains, r.history, &bounds, setup, clock, comm)?;
    d.system.global_damping = s.grains.global_damping_1_s;
    if comm.is_root() {
        d.migrated = r.run.migrated;
    }
    let mut initial = Grains::default();
    for p in r.run.initial.chunks_exact(3) {
        initial.push([p[0], p[1]], p[2], s.grains.density_kg_m3, false);
    }
    Ok((d, r.run.settle_steps, initial, Some(r.run)))
}

/// The column-collapse results of the deposit (gathered) against the initial column.
fn collapse_analysis(st: &GrainStepper, end: &LoopEnd, g_abs: f64, comm: &dyn Comm) -> Results {
    let mut results = Results::new();
    let fin = gather_grains(&st.d.system, comm);
    let initial = &st.initial;
    for a in &st.scene.scene.analyses {
        let GrainAnalysis::ColumnCollapse {
            wall_x_m,
            floor_y_m,
            ..
        } = a;
        let before = pile_shape(&initial.x, &initial.y, &initial.r, *wall_x_m, *floor_y_m);
        let after = pile_shape(&fin.x, &fin.y, &fin.r, *wall_x_m, *floor_y_m);
        // The time the motion stopped; NaN when it did not stop before the run's end (the
        // end is not a stop time).
        let flow_time = end.settled_s.map_or(f64::NAN, |t| t - st.last_removal);
        let values = collapse_results(before, after, g_abs, flow_time);
        for (k, v) in QUANTITIES.iter().zip(values) {
            results.insert(format!("collapse.{k}"), v);
        }
        // When the front passed 10 % and 95 % of its run-out, in τ_c, and its mean speed
        // between (not after a restart: the series before it is gone).
        let times: Vec<f64> = st.fronts.iter().map(|f| f.0 - st.last_removal).collect();
        let fronts: Vec<f64> = st.fronts.iter().map(|f| f.1).collect();
        let [t10, t95, speed] =
            analysis::collapse::front_timing(&times, &fronts, before.length_m, after.length_m);
        let tau_c = (before.height_m / g_abs).sqrt();
        results.insert("collapse.front_t95".into(), t95 / tau_c);
        results.insert("collapse.front_t10".into(), t10 / tau_c);
        results.insert("collapse.front_speed_m_s".into(), speed);
    }
    results
}

/// Analyses, checks and `summary.json` (rank 0) of a finished loop (collective).
fn summarise(
    scene: &ValidGrainScene,
    st: GrainStepper,
    end: LoopEnd,
    g_abs: f64,
    comm: &dyn Comm,
    out_dir: &Path,
) -> Result<GrainSummary, RunError> {
    let s = &scene.scene;
    let results = collapse_analysis(&st, &end, g_abs, comm);
    let checks = evaluate(&s.checks, &results);
    let d = &st.d;
    let (ke, momentum, _) = global_state(d, comm);
    let mut counts = [
        d.migrated as f64,
        d.system.contacts() as f64,
        d.comm_seconds,
    ];
    let comm_wait = comm.max_f64(d.comm_seconds);
    comm.sum_f64(&mut counts);
    let mut warnings = scene.warnings.clone();
    warnings.extend(escaped_grains(d, s.domain.size(), comm));
    let mut header = RunHeader::new(
        "grains",
        scene.path.clone(),
        s.title.clone(),
        warnings,
        comm,
    );
    header.status = end.status;
    header.error = end.error.clone();
    header.restarted_from_step = end.start_step;
    header.steps = d.system.steps;
    header.simulated_time_s = d.system.time;
    header.settled_at_s = end.settled_s;
    header.wall_time_s = end.wall_s;
    header.set_traffic(end.traffic, comm);
    header.set_stages(&[&st.clock, &end.clock], comm);
    header.checkpoints = end.checkpoints.clone();
    header.results = results;
    header.judge(checks, &[], end.shortened);
    header.set_memory(st.memory_estimate, comm);
    let steps = (d.system.steps - end.start_step) as f64;
    let summary = GrainSummary {
        run: header,
        scene: s.clone(),
        slab_bounds_m: d.bounds().to_vec(),
        grains: st.grains,
        time_step_s: d.system.dt,
        lambda: scene.lambda(),
        settle_steps: st.settle_steps,
        grain_steps_per_s: st.grains as f64 * steps / end.wall_s.max(1e-12),
        migrated: counts[0] as u64,
        rebalances: d.rebalances,
        comm_wait_s: comm_wait,
        contacts: counts[1] as usize,
        list_rebuilds: d.system.list_rebuilds(),
        kinetic_energy_j_m: ke,
        momentum,
        snapshots: st.writer.snapshots(),
    };
    if comm.is_root() {
        if !st.fronts.is_empty() {
            let mut csv = String::from("time_s,front_m,kinetic_energy_j_m\n");
            for (t, x, ke) in &st.fronts {
                csv.push_str(&format!("{t:.9e},{x:.9e},{ke:.9e}\n"));
            }
            write_atomic(&out_dir.join("front.csv"), csv.as_bytes())?;
        }
        let json = crate::summary_units::summary_json(&summary);
        write_atomic(&out_dir.join("summary.json"), &json)?;
    }
    Ok(summary)
}
