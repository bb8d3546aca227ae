//! Running a scene end to end: the time loop, output, analyses, checks and `summary.json`.

use crate::progress::Progress;
use crate::simulation::{stage, Simulation, STAGES};
use analysis::checks::evaluate;
use analysis::{self, Results};
use decomposition::{Comm, SingleProcess};
use io::atomic::{ensure_writable_dir, write_atomic};
use io::checkpoint;
use io::hdf5_out::Layout;
use io::OutputError;
use lbm::fields::Totals;
use lbm::Real;
use scene::{SceneError, Units, ValidScene};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

mod output;
use output::Output;

pub use crate::driver::{stage_stats, StageStats, Status};
use crate::driver::{RunHeader, Signals};
pub use crate::error::RunError;
pub use scene::{Backend, GpuStorage, Kernel, Precision};

/// Options from the command line that override or complement the scene.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Output folder.
    pub out_dir: PathBuf,
    /// Precision override.
    pub precision: Option<Precision>,
    /// Backend override (the scene's `[run] backend` otherwise).
    pub backend: Option<Backend>,
    /// GPU population storage override (the scene's `[run] gpu_storage` otherwise).
    pub gpu_storage: Option<GpuStorage>,
    /// CPU kernel override (the scene's `[run] kernel` otherwise).
    pub kernel: Option<Kernel>,
    /// Length override: run to this step.
    pub steps: Option<u64>,
    /// Length override: run to this simulated time (s).
    pub end_time_s: Option<f64>,
    /// Show progress (bar on a terminal, log lines otherwise).
    pub progress: bool,
    /// Continue from this checkpoint instead of the initial condition.
    pub restart: Option<PathBuf>,
}

/// Everything `summary.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// The keys every summary starts with (see [`RunHeader`]).
    #[serde(flatten)]
    pub run: RunHeader,
    /// The scene as parsed (defaults filled in).
    pub scene: scene::Scene,
    /// Precision used.
    pub precision: Precision,
    /// Backend used.
    pub backend: Backend,
    /// GPU population storage used.
    pub gpu_storage: GpuStorage,
    /// The device that ran the fluid solver (rank 0's).
    pub device: String,
    /// Columns `[x_begin, x_end)` of each rank.
    pub partition: Vec<[usize; 2]>,
    /// Halo bytes sent per step, all ranks together.
    pub halo_bytes_per_step: u64,
    /// Derived lattice parameters.
    pub units: Units,
    /// Lattice size.
    pub cells: [usize; 2],
    /// Fluid cells.
    pub fluid_cells: usize,
    /// Distribution storage (bytes).
    pub memory_bytes: usize,
    /// Million lattice-cell updates per second over the whole loop (all cells).
    pub mlups: f64,
    /// MLUPS of the collide–stream stage alone.
    pub kernel_mlups: f64,
    /// Coupled runs: the "coupling" stage's seconds per pass (`coupling::PASSES`), the
    /// slowest rank's. Absent without grains.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub coupling_pass_seconds: BTreeMap<&'static str, f64>,
    /// Coupled runs: `coupling::COUNTS` summed over ranks (remaps of the cover map done in
    /// place and afresh, grains decided and skipped in them, boundary lists kept and
    /// rescanned). Absent without grains.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub coupling_counts: BTreeMap<&'static str, u64>,
    /// HDF5 snapshot data written (bytes, all ranks) and the slowest rank's seconds in
    /// the HDF5 write calls: their ratio is the parallel write bandwidth.
    pub snapshot_bytes: u64,
    /// See `snapshot_bytes`.
    pub snapshot_write_s: f64,
    /// Totals at the start and the end (lattice units).
    pub totals_initial: Totals,
    /// See `totals_initial`.
    pub totals_final: Totals,
    /// Last sample of each probe (SI).
    pub probes: BTreeMap<String, BTreeMap<String, f64>>,
}

/// Validate, run and summarise a scene on one process. See [`run_on`].
pub fn run(scene: &ValidScene, opts: &RunOptions) -> Result<Summary, RunError> {
    run_on(scene, opts, &SingleProcess)
}

/// Validate, run and summarise a scene on every rank of `comm` (collective). Writes into
/// `opts.out_dir`: every rank writes its block of `fields.h5` and of checkpoints; rank 0
/// writes `summary.json`, the XDMF, probe CSVs and pictures. An instability is not an
/// `Err`: the summary says `unstable` and the output so far is kept.
pub fn run_on(scene: &ValidScene, opts: &RunOptions, comm: &dyn Comm) -> Result<Summary, RunError> {
    let names = analysis::result_names(scene);
    for c in &scene.scene.checks {
        if !names.contains(&c.quantity) {
            return Err(SceneError::Invalid {
                path: scene.path.clone(),
                line: None,
                key: "quantity".into(),
                message: format!(
                    "check on unknown quantity `{}`; this scene produces: {}",
                    c.quantity,
                    names.join(", ")
                ),
            }
            .into());
        }
    }
    if comm.is_root() {
        ensure_writable_dir(&opts.out_dir)?;
    }
    comm.barrier();
    let precision = opts.precision.unwrap_or(scene.scene.run.precision);
    match precision {
        Precision::F32 => run_typed::<f32>(scene, opts, precision, comm),
        Precision::F64 => run_typed::<f64>(scene, opts, precision, comm),
    }
}

/// Number of steps a run will take.
/// Number of steps a fluid run will take: `steps`, else `end_time_s` (s) in whole steps,
/// else the scene's own `steps` or `end_time_s`.
pub fn step_count(scene: &ValidScene, steps: Option<u64>, end_time_s: Option<f64>) -> u64 {
    let in_steps = |t: f64| (t / scene.units.dt_s).round().max(1.0) as u64;
    steps
        .or(end_time_s.map(in_steps))
        .or(scene.scene.run.steps)
        .unwrap_or_else(|| in_steps(scene.scene.run.end_time_s.unwrap_or(0.0)))
}

fn run_typed<T: Real + hdf5::H5Type>(
    scene: &ValidScene,
    opts: &RunOptions,
    precision: Precision,
    comm: &dyn Comm,
) -> Result<Summary, RunError> {
    let run = &scene.scene.run;
    let n = step_count(scene, opts.steps, opts.end_time_s);
    let backend = opts.backend.unwrap_or(run.backend);
    let storage = opts.gpu_storage.unwrap_or(run.gpu_storage);
    if storage == GpuStorage::F16 && (backend != Backend::Gpu || precision != Precision::F32) {
        return Err(SceneError::Invalid {
            path: scene.path.clone(),
            line: None,
            key: "gpu_storage".into(),
            message: "FP16 storage needs the GPU backend with f32 arithmetic: add `--backend gpu --precision f32` (or set `backend` and `precision` in [run]), or drop `gpu_storage`".into(),
        }
        .into());
    }
    // A coupled restart reads the grains before the simulation is built (they are not
    // prepared again); the fluid follows below as for any run.
    let (restored_grains, momentum_restored, initial_restored) =
        match (&opts.restart, &scene.scene.grains) {
            (Some(path), Some(_)) => {
                let walls = crate::coupled::wall_count(scene)?;
                let r = io::coupled_checkpoint::read(path, comm, walls)?;
                (Some(r.grains), r.momentum_initial, Some(r.initial))
            }
            _ => (None, None, None),
        };
    let kernel = opts.kernel.unwrap_or(run.kernel);
    let mut sim = Simulation::<T>::new(scene, comm, backend, storage, kernel, restored_grains)?;
    // The momentum balance reads every fluid cell: only when an analysis asks for it.
    let wants_momentum = scene
        .scene
        .analyses
        .iter()
        .any(|a| matches!(a, scene::Analysis::MomentumBalance));
    let momentum = |sim: &mut Simulation<T>| {
        let Simulation { grains, fluid, .. } = sim;
        grains.as_ref().filter(|_| wants_momentum).map(|c| {
            let (f, g) = c.momentum(fluid.as_mut(), comm);
            [f, g]
        })
    };
    let momentum_initial = match momentum_restored {
        Some(m) => Some(m),
        None => momentum(&mut sim),
    };
    // Where the grains were at step 0, for analyses (and checkpoints, which carry it on).
    let grains_initial: Vec<[f64; 3]> = match (initial_restored, &sim.grains) {
        (Some(g), _) => g,
        (None, Some(c)) => c.positions(comm),
        (None, None) => Vec::new(),
    };
    let (nx, ny) = (sim.partition.columns(), sim.fluid.lattice().ny());
    let checkpoint_path = opts.out_dir.join("checkpoint.h5");
    let mut totals_initial = None;
    if let Some(path) = &opts.restart {
        let r = checkpoint::read::<T>(
            path,
            comm,
            T::NAME,
            [nx, ny],
            (sim.fluid.lattice().x_offset(), sim.fluid.lattice().nx()),
            &sim.series,
        )?;
        if r.grains && sim.grains.is_none() {
            return Err(OutputError::Checkpoint {
                path: path.clone(),
                message: "holds grains, but this scene has none; restart the coupled scene \
                          that wrote it"
                    .into(),
            }
            .into());
        }
        sim.restore(&r.populations, r.run.step, r.run.series);
        totals_initial = Some(Totals::from_array(r.run.totals_initial));
    }
    let start_step = sim.fluid.lattice().steps_done();
    let layout = Layout {
        nx,
        ny,
        x0: sim.fluid.lattice().x_offset(),
        width: sim.fluid.lattice().nx(),
        dx: scene.units.dx_m,
    };
    let resume = opts.restart.as_ref().map(|_| start_step);
    let mut out = Output::new(&opts.out_dir, scene, layout, comm, resume)?;
    // Fields are computed once per output step and shared by snapshot, totals and analyses.
    let initial = sim.fields(comm);
    let totals_initial = match totals_initial {
        Some(t) => t,
        None => sim.totals(comm, &initial),
    };
    if start_step == 0 {
        if run.output_every > 0 {
            out.snapshot(0, &scene.units, &mut sim, comm, &initial)?;
        }
        sim.record_probes(comm);
    }
    // The fields of the last snapshot are kept only when they are the final step's (the
    // summary's totals reuse them): holding them between snapshots would cost three f64
    // values per cell for the whole run.
    let mut latest_step = start_step;
    let mut final_fields = (n <= start_step).then_some(initial);
    let mut progress = Progress::new(
        n,
        (nx * ny) as f64,
        scene.units.dt_s,
        opts.progress && comm.is_root(),
    );
    let signals = Signals::install();
    let mut checkpoints = Vec::new();
    let mut last_checkpoint = Instant::now();
    let start = Instant::now();
    let mut error = None;
    let mut interrupted = false;
    let write_checkpoint = |sim: &mut Simulation<T>, checkpoints: &mut Vec<PathBuf>| {
        let t = Instant::now();
        let pops = sim.fluid.export_interior();
        let steps = sim.fluid.lattice().steps_done();
        let state = checkpoint::RunState {
            step: steps,
            time_s: scene.units.time_si(steps),
            precision: T::NAME.into(),
            totals_initial: totals_initial.to_array(),
            series: sim.series.clone(),
        };
        let lat = checkpoint::LatticeState {
            global: [nx, ny],
            slab: (sim.fluid.lattice().x_offset(), sim.fluid.lattice().nx()),
            populations: &pops,
        };
        let r = match &sim.grains {
            None => checkpoint::write(&checkpoint_path, comm, &lat, &state),
            Some(c) => {
                let grains = io::coupled_checkpoint::CoupledState {
                    dem: &c.dem,
                    per_grain: c.per_grain_state(),
                    momentum_initial,
                    initial: &grains_initial,
                };
                io::coupled_checkpoint::write(&checkpoint_path, comm, &lat, &state, &grains)
            }
        };
        sim.times.seconds[stage::CHECKPOINT] += t.elapsed().as_secs_f64();
        checkpoints.push(checkpoint_path.clone());
        r
    };
    for step in start_step + 1..=n {
        if let Err(e) = sim.step(comm) {
            error = Some(e.to_string());
            break;
        }
        let probe = step % run.probe_every == 0 && sim.has_probes();
        let output = (run.output_every > 0 && step % run.output_every == 0) || step == n;
        if probe || output {
            // A device backend checks for instabilities every few steps; nothing is
            // recorded from a bad state.
            if let Err(e) = sim.check(comm) {
                error = Some(e.to_string());
                break;
            }
        }
        if probe {
            sim.record_probes(comm);
        }
        if output {
            let t = Instant::now();
            let f = sim.fields(comm);
            out.snapshot(step, &scene.units, &mut sim, comm, &f)?;
            latest_step = step;
            if step == n {
                final_fields = Some(f);
            }
            sim.times.seconds[stage::OUTPUT] += t.elapsed().as_secs_f64();
        }
        // Signals and the wall-clock cadence are agreed on by all ranks after every step,
        // so all checkpoint (and stop) together.
        let wall_due = run.checkpoint_minutes > 0.0
            && last_checkpoint.elapsed().as_secs_f64() >= 60.0 * run.checkpoint_minutes;
        let agreed = signals.agree(comm, wall_due);
        let due = (run.checkpoint_every > 0 && step % run.checkpoint_every == 0)
            || agreed.checkpoint
            || (step == n && run.checkpoint_at_end);
        if due {
            if let Err(e) = sim.check(comm) {
                error = Some(e.to_string());
                break;
            }
            write_checkpoint(&mut sim, &mut checkpoints)?;
            last_checkpoint = Instant::now();
        }
        progress.update(step);
        if agreed.stop {
            interrupted = true;
            break;
        }
    }
    let wall = start.elapsed().as_secs_f64();
    progress.finish();
    let steps = sim.fluid.lattice().steps_done();
    // `final_fields` is only ever the state the loop ended in.
    let fields = final_fields.unwrap_or_else(|| sim.fields(comm));
    if (error.is_some() || interrupted) && latest_step != steps {
        // Keep the state the run stopped in for diagnosis, unless that step's snapshot is
        // written already (a step that fails leaves the step count where it was: the
        // snapshot is then the last good state). Earlier snapshots stay untouched.
        out.snapshot(steps, &scene.units, &mut sim, comm, &fields)?;
    }
    let totals_final = sim.totals(comm, &fields);
    let momentum_final = momentum(&mut sim);
    let grain_radius = match &sim.grains {
        Some(c) => c.radii(comm),
        None => Vec::new(),
    };
    let grains_final = sim.grains.as_ref().map(|c| c.positions(comm));
    let results = if error.is_none() && !interrupted && !scene.scene.analyses.is_empty() {
        // Only rank 0 holds the whole lattice (and only when an analysis reads it); it runs
        // the analyses and every rank receives its results.
        let global = analysis::needs_fields(scene)
            .then(|| sim.gather_fields_at_root(comm, fields))
            .flatten();
        let local = comm.is_root().then(|| {
            // A panic here would leave the other ranks waiting for the results: make it an
            // error that they receive too.
            let inputs = analysis::Inputs {
                scene,
                fields: global.as_ref(),
                steps,
                series: &sim.series,
                totals: (totals_initial, totals_final),
                momentum: momentum_initial.zip(momentum_final),
                grain_radius: grain_radius.clone(),
                grains: grains_final.map(|f| (grains_initial.clone(), f)),
            };
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| analysis::run_all(&inputs)))
                .unwrap_or_else(|_| Err(analysis::panicked()))
        });
        analysis::share_from_root(comm, local)?
    } else if error.is_none() && !interrupted {
        let mut r = Results::new();
        r.insert("run.mass".into(), totals_final.mass);
        r.insert(
            "run.max_speed_m_s".into(),
            scene.units.velocity_to_si(totals_final.max_speed),
        );
        r
    } else {
        Results::new()
    };
    let mut results = results;
    if let Some(c) = &sim.grains {
        results.insert("coupling.substeps".into(), c.substeps() as f64);
        results.insert("coupling.grains".into(), grain_radius.len() as f64);
    }
    let checks = evaluate(&scene.scene.checks, &results);
    let status = match (&error, interrupted, checks.iter().all(|c| c.passed)) {
        (Some(_), _, _) => Status::Unstable,
        (None, true, _) => Status::Interrupted,
        (None, false, true) => Status::Ok,
        (None, false, false) => Status::ChecksFailed,
    };
    let updates = (nx * ny) as f64 * (steps - start_step) as f64;
    let probes = sim
        .series
        .iter()
        .filter(|s| !s.is_empty())
        .map(|s| {
            let last = s.len() - 1;
            let row = s
                .columns
                .iter()
                .enumerate()
                .map(|(c, name)| (name.to_string(), s.values[last * s.columns.len() + c]))
                .collect();
            (s.name.clone(), row)
        })
        .collect();
    let per_rank = comm.all_gather_f64(&sim.times.seconds);
    let k = STAGES.len();
    let stages: BTreeMap<&'static str, StageStats> = STAGES
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let v: Vec<f64> = (0..comm.size()).map(|r| per_rank[r * k + i]).collect();
            let sum = v.iter().sum::<f64>();
            let stats = StageStats {
                sum_s: sum,
                max_s: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                min_s: v.iter().copied().fold(f64::INFINITY, f64::min),
                mean_s: sum / v.len() as f64,
            };
            (*name, stats)
        })
        .collect();
    // Every rank of a coupled run holds grains (maybe none in view), so this is collective.
    let coupling_pass_seconds = match &sim.grains {
        Some(g) => stage_stats(&coupling::PASSES, &g.pass_seconds(), comm).1,
        None => BTreeMap::new(),
    };
    let coupling_counts = match &sim.grains {
        Some(g) => {
            let mut v: Vec<f64> = g.counts().iter().map(|&c| c as f64).collect();
            comm.sum_f64(&mut v);
            coupling::COUNTS
                .iter()
                .zip(v)
                .map(|(n, c)| (*n, c as u64))
                .collect()
        }
        None => BTreeMap::new(),
    };
    let wall = comm.max_f64(wall);
    let mut halo_bytes = [sim.fluid.lattice().halo_bytes_per_step() as f64];
    comm.sum_f64(&mut halo_bytes);
    let solver = if sim.grains.is_some() {
        "coupled"
    } else {
        "fluid"
    };
    let mut header = RunHeader::new(
        solver,
        scene.path.clone(),
        scene.scene.title.clone(),
        scene.warnings.clone(),
        comm,
    );
    header.status = status;
    header.error = error;
    header.restarted_from_step = start_step;
    header.steps = steps;
    header.simulated_time_s = scene.units.time_si(steps);
    header.wall_time_s = wall;
    header.stage_seconds = stages.iter().map(|(k, v)| (*k, v.max_s)).collect();
    let kernel_mlups = updates / stages[STAGES[stage::COLLIDE_STREAM]].max_s.max(1e-12) / 1e6;
    header.stages = stages;
    header.checkpoints = checkpoints;
    header.results = results;
    header.checks = checks;
    let summary = Summary {
        run: header,
        scene: scene.scene.clone(),
        precision,
        backend,
        gpu_storage: storage,
        device: sim.fluid.device(),
        partition: (0..comm.size())
            .map(|r| {
                let s = sim.partition.slab(r);
                [s.x_begin, s.x_end]
            })
            .collect(),
        halo_bytes_per_step: halo_bytes[0] as u64,
        units: scene.units,
        cells: [nx, ny],
        fluid_cells: sim.fluid_cells(comm),
        memory_bytes: sim.fluid.lattice().storage_bytes(),
        mlups: updates / wall.max(1e-12) / 1e6,
        kernel_mlups,
        coupling_pass_seconds,
        coupling_counts,
        snapshot_bytes: out.bytes,
        snapshot_write_s: comm.max_f64(out.write_s),
        totals_initial,
        totals_final,
        probes,
    };
    if comm.is_root() {
        for s in &sim.series {
            s.write_csv(&opts.out_dir)?;
        }
        let json = serde_json::to_vec_pretty(&summary).expect("summary serialises");
        write_atomic(&opts.out_dir.join("summary.json"), &json)?;
    }
    comm.barrier();
    Ok(summary)
}
