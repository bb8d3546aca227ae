//! Running a scene end to end: the time loop, output, analyses, checks and `summary.json`.

use crate::progress::Progress;
use crate::simulation::{Balancer, Simulation};
use crate::time_loop::{drive, Due, Flow, LoopPlan, Stepper};
use analysis::{self, Results};
use decomposition::{Comm, SingleProcess};
use io::atomic::ensure_writable_dir;
use io::checkpoint;
use io::hdf5_out::Layout;
use io::OutputError;
use lbm::fields::{Fields, Totals};
use lbm::Real;
use scene::{SceneError, ValidScene};
use std::path::{Path, PathBuf};

mod output;
mod overrides;
mod summary;
use output::Output;
pub use overrides::{Length, Overrides};
use summary::summarise;
pub use summary::Summary;

pub use crate::driver::{stage_stats, StageStats, Status};
pub use crate::error::RunError;
pub use scene::{Backend, GpuStorage, Kernel, Precision};

/// Options from the command line that complement the scene (its changes to the scene's
/// `[run]` are [`Overrides`], applied to the scene before the run).
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Output folder.
    pub out_dir: PathBuf,
    /// The scene's own length when [`Overrides::apply`] replaced it: a run shorter than
    /// that reports its checks without judging them. `None`: the scene's length is its own.
    pub scene_length: Option<Length>,
    /// Show progress (bar on a terminal, log lines otherwise).
    pub progress: bool,
    /// Continue from this checkpoint instead of the initial condition.
    pub restart: Option<PathBuf>,
    /// Start even beyond the step and memory limits ([`crate::budget`]).
    pub force: bool,
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
    check_quantities(scene)?;
    if comm.is_root() {
        ensure_writable_dir(&opts.out_dir)?;
    }
    comm.barrier();
    let precision = scene.scene.run.precision;
    match precision {
        Precision::F32 => run_typed::<f32>(scene, opts, precision, comm),
        Precision::F64 => run_typed::<f64>(scene, opts, precision, comm),
    }
}

/// Every check names a quantity the scene's probes and analyses produce.
pub fn check_quantities(scene: &ValidScene) -> Result<(), SceneError> {
    let names = analysis::result_names(scene);
    match scene
        .scene
        .checks
        .iter()
        .find(|c| !names.contains(&c.quantity))
    {
        None => Ok(()),
        Some(c) => Err(SceneError::Invalid {
            path: scene.path.clone(),
            line: None,
            key: "quantity".into(),
            message: format!(
                "check on unknown quantity `{}`; this scene produces: {}",
                c.quantity,
                names.join(", ")
            ),
        }),
    }
}

/// Number of steps a fluid run will take: the scene's `[run] steps`, else its `end_time_s`
/// (s) in whole steps (at least 1).
pub fn step_count(scene: &ValidScene) -> u64 {
    let run = &scene.scene.run;
    fluid_steps(
        scene,
        Length {
            steps: run.steps,
            end_time_s: run.end_time_s,
        },
    )
}

/// The fluid steps of `length`: its steps, else its end time in whole steps (at least 1).
fn fluid_steps(scene: &ValidScene, length: Length) -> u64 {
    let in_steps = |t: f64| (t / scene.units.dt_s).round().max(1.0) as u64;
    length
        .steps
        .unwrap_or_else(|| in_steps(length.end_time_s.unwrap_or(0.0)))
}

/// A fluid (or coupled) simulation as the driver's time loop steps it, with its output.
struct FluidStepper<'a, T: Real + hdf5::H5Type> {
    scene: &'a ValidScene,
    sim: Simulation<T>,
    out: Output,
    /// The step the run stops after.
    last_step: u64,
    /// The last step's fields, kept from its snapshot for the summary's totals (holding
    /// the fields between snapshots would cost three values per cell for the whole run).
    final_fields: Option<Fields>,
    /// The fields `observe` computed for the snapshot that follows in the same step (their
    /// speeds checked first).
    snapshot_fields: Option<Fields>,
    /// What a checkpoint carries besides the populations.
    totals_initial: Totals,
    momentum_initial: Option<[[f64; 2]; 2]>,
    grains_initial: Vec<[f64; 3]>,
    /// `check`'s memory estimate for the run, all ranks (bytes).
    memory_estimate: f64,
    /// The load balance of a run on several ranks (only coupled runs move their slabs).
    balance: Option<Balancer>,
}

impl<T: Real + hdf5::H5Type> Stepper for FluidStepper<'_, T> {
    fn steps_done(&self) -> u64 {
        self.sim.fluid.lattice().steps_done()
    }

    fn time_s(&self) -> f64 {
        self.scene.units.time_si(self.steps_done())
    }

    fn advance(&mut self, comm: &dyn Comm) -> Flow {
        match self.sim.step(comm) {
            Ok(()) => Flow::Go,
            Err(e) => Flow::Unstable(e.to_string()),
        }
    }

    fn observe(&mut self, comm: &dyn Comm, due: Due) -> Result<Flow, RunError> {
        let every = self.scene.scene.output.probe_every_steps();
        let probe = due.step.is_multiple_of(every) && self.sim.has_probes();
        if probe || due.snapshot || due.checkpoint {
            // A device backend checks for instabilities every few steps; nothing is
            // recorded or written from a bad state.
            if let Err(e) = self.sim.check(comm) {
                return Ok(Flow::Unstable(e.to_string()));
            }
        }
        if probe {
            self.sim.record_probes(comm);
        }
        if due.snapshot || due.checkpoint {
            // The fields (read after the probes, as the snapshot reads them), their speeds
            // checked: a run can go wrong with every density positive (a flow accelerated
            // past the lattice's speed of sound), and no snapshot or checkpoint keeps such a
            // state as if it were good.
            let f = self.sim.fields(comm);
            let x0 = self.sim.fluid.lattice().x_offset();
            if let Some(e) = supersonic_cell(&f, x0, due.step, comm) {
                return Ok(Flow::Unstable(e));
            }
            if due.snapshot {
                self.snapshot_fields = Some(f);
            }
        }
        Ok(Flow::Go)
    }

    fn snapshot(&mut self, comm: &dyn Comm) -> Result<(), RunError> {
        let step = self.steps_done();
        let f = match self.snapshot_fields.take() {
            Some(f) => f,
            None => self.sim.fields(comm),
        };
        self.out
            .snapshot(step, &self.scene.units, &mut self.sim, comm, &f)?;
        if step == self.last_step {
            self.final_fields = Some(f);
        }
        Ok(())
    }

    fn checkpoint(&mut self, comm: &dyn Comm, path: &Path, _next: f64) -> Result<(), RunError> {
        let pops = self.sim.fluid.export_interior();
        let sim = &self.sim;
        let lattice = sim.fluid.lattice();
        let steps = lattice.steps_done();
        let state = checkpoint::RunState {
            step: steps,
            time_s: self.scene.units.time_si(steps),
            precision: T::NAME.into(),
            totals_initial: self.totals_initial.to_array(),
            series: sim.series.clone(),
        };
        let lat = checkpoint::LatticeState {
            global: [sim.partition.columns(), lattice.ny()],
            slab: (lattice.x_offset(), lattice.nx()),
            populations: &pops,
        };
        match &sim.grains {
            None => checkpoint::write(path, comm, &lat, &state)?,
            Some(c) => {
                let grains = io::coupled_checkpoint::CoupledState {
                    dem: &c.dem,
                    per_grain: c.per_grain_state(),
                    momentum_initial: self.momentum_initial,
                    initial: &self.grains_initial,
                };
                io::coupled_checkpoint::write(path, comm, &lat, &state, &grains)?
            }
        }
        Ok(())
    }

    fn rebalance(&mut self, comm: &dyn Comm, due: Due) -> Result<(), RunError> {
        let Some(b) = &mut self.balance else {
            return Ok(());
        };
        if !b.due(due.step) {
            return Ok(());
        }
        if let Some(p) = b.plan(&self.sim, comm) {
            b.rebalances += 1;
            self.sim.repartition(self.scene, p, comm)?;
            let lat = self.sim.fluid.lattice();
            self.out.set_block(lat.x_offset(), lat.nx());
        }
        b.restart_window(&self.sim);
        Ok(())
    }
}

/// The first fluid cell (lowest global row, then column) over all ranks whose speed is not
/// below the lattice's speed of sound 1/√3 (or is NaN), as the error that stops the run;
/// `fields` are this rank's, its first column global column `x0`. Collective.
fn supersonic_cell(fields: &Fields, x0: usize, step: u64, comm: &dyn Comm) -> Option<String> {
    let limit = lbm::units::SOUND_SPEED;
    let mine: Vec<f64> = (0..fields.rho.len())
        .filter(|&k| fields.fluid[k])
        .map(|k| (k, fields.ux[k].hypot(fields.uy[k])))
        .find(|&(_, speed)| !(speed < limit))
        .map(|(k, speed)| {
            let (x, y) = (k % fields.nx + x0, k / fields.nx);
            vec![y as f64, x as f64, speed]
        })
        .unwrap_or_default();
    if !comm.any(!mine.is_empty()) {
        return None;
    }
    let all = comm.all_gather_f64(&mine);
    let first = all
        .chunks(3)
        .min_by(|a, b| (a[0], a[1]).partial_cmp(&(b[0], b[1])).expect("finite"))?;
    Some(format!(
        "unstable at step {step}: cell ({}, {}) moves at {:.3} lattice units, at or past the \
         lattice's speed of sound 1/√3 ≈ 0.577 (densities can stay positive); reduce the \
         velocity or body force, raise τ or refine the lattice",
        first[1] as usize, first[0] as usize, first[2]
    ))
}

/// The fluid and the grains' momenta (an analysis asks for the momentum balance; it reads
/// every fluid cell). Collective.
fn momenta<T: Real>(
    sim: &mut Simulation<T>,
    scene: &ValidScene,
    comm: &dyn Comm,
) -> Option<[[f64; 2]; 2]> {
    let wanted = scene
        .scene
        .analyses
        .iter()
        .any(|a| matches!(a, scene::Analysis::MomentumBalance));
    let Simulation { grains, fluid, .. } = sim;
    grains.as_ref().filter(|_| wanted).map(|c| {
        let (f, g) = c.momentum(fluid.as_mut(), comm);
        [f, g]
    })
}

/// The backend, GPU storage and kernel of the scene's run.
fn devices(scene: &ValidScene) -> Result<(Backend, GpuStorage, Kernel), RunError> {
    let run = &scene.scene.run;
    let (backend, storage, precision) = (run.backend, run.gpu_storage, run.precision);
    if storage == GpuStorage::F16 && (backend != Backend::Gpu || precision != Precision::F32) {
        return Err(scene
            .invalid(
                "gpu_storage",
                "FP16 storage needs the GPU backend with f32 arithmetic: add `--backend gpu \
             --precision f32` (or set `backend` and `precision` in [run]), or drop `gpu_storage`"
                    .into(),
            )
            .into());
    }
    Ok((backend, storage, run.kernel))
}

/// Build the simulation of `scene`, from its initial condition or from `opts.restart`,
/// with what its checkpoints carry: the initial totals, momenta and grain positions.
#[allow(clippy::type_complexity)]
fn set_up<T: Real + hdf5::H5Type>(
    scene: &ValidScene,
    opts: &RunOptions,
    devices: (Backend, GpuStorage, Kernel),
    comm: &dyn Comm,
) -> Result<(Simulation<T>, Totals, Option<[[f64; 2]; 2]>, Vec<[f64; 3]>), RunError> {
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
    let (backend, storage, kernel) = devices;
    let mut sim = Simulation::<T>::new(scene, comm, backend, storage, kernel, restored_grains)?;
    let momentum_initial = match momentum_restored {
        Some(m) => Some(m),
        None => momenta(&mut sim, scene, comm),
    };
    // Where the grains were at step 0, for analyses (and checkpoints, which carry it on).
    let grains_initial: Vec<[f64; 3]> = match (initial_restored, &sim.grains) {
        (Some(g), _) => g,
        (None, Some(c)) => c.positions(comm),
        (None, None) => Vec::new(),
    };
    let Some(path) = &opts.restart else {
        let initial = sim.fields(comm);
        let totals = sim.totals(comm, &initial);
        return Ok((sim, totals, momentum_initial, grains_initial));
    };
    let (nx, ny) = (sim.partition.columns(), sim.fluid.lattice().ny());
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
            message: "holds grains, but this scene has none; restart the coupled scene that \
                      wrote it"
                .into(),
        }
        .into());
    }
    sim.restore(comm, &r.populations, r.run.step, r.run.series);
    let totals = Totals::from_array(r.run.totals_initial);
    Ok((sim, totals, momentum_initial, grains_initial))
}

fn run_typed<T: Real + hdf5::H5Type>(
    scene: &ValidScene,
    opts: &RunOptions,
    precision: Precision,
    comm: &dyn Comm,
) -> Result<Summary, RunError> {
    let n = step_count(scene);
    let devices = devices(scene)?;
    let one_buffer = devices.0 == Backend::Cpu
        && crate::simulation::in_place(devices.2, scene.scene.grains.is_some());
    let bytes = std::mem::size_of::<T>() as f64;
    let cost = crate::budget::fluid_cost(scene, n, bytes, one_buffer, comm.size());
    crate::budget::admit(cost, comm, opts.force)?;
    let (sim, totals_initial, momentum_initial, grains_initial) =
        set_up::<T>(scene, opts, devices, comm)?;
    let lattice = sim.fluid.lattice();
    let (nx, ny) = (sim.partition.columns(), lattice.ny());
    let start_step = lattice.steps_done();
    let layout = Layout {
        nx,
        ny,
        x0: lattice.x_offset(),
        width: lattice.nx(),
        dx: scene.units.dx_m,
    };
    let resume = opts.restart.as_ref().map(|_| start_step);
    let out = Output::new(&opts.out_dir, scene, layout, comm, resume)?;
    let mut stepper = FluidStepper {
        scene,
        sim,
        out,
        last_step: n,
        final_fields: None,
        snapshot_fields: None,
        totals_initial,
        momentum_initial,
        grains_initial,
        memory_estimate: cost.memory_bytes,
        balance: Balancer::new(scene, comm.size(), start_step),
    };
    if start_step == 0 {
        stepper.sim.record_probes(comm);
    }
    let mut progress = Progress::new(
        n,
        (nx * ny) as f64,
        scene.units.dt_s,
        opts.progress && comm.is_root(),
    );
    let output = &scene.scene.output;
    let next = resume.map(|s| crate::time_loop::next_output_after(scene.units.time_si(s), output));
    let own = opts.scene_length.map_or(n, |l| fluid_steps(scene, l));
    let plan = LoopPlan::new(n, output, &opts.out_dir, next).scene_length(own);
    let end = drive(&mut stepper, &plan, &mut progress, comm)?;
    stepper.out.finish(comm);
    summarise(
        scene,
        stepper,
        end,
        (precision, devices),
        comm,
        &opts.out_dir,
    )
}

/// Results of the analyses (rank 0 runs them on the gathered lattice and shares them), or
/// the run's mass and top speed when the scene asks for none. Collective.
fn analyse<T: Real + hdf5::H5Type>(
    st: &mut FluidStepper<T>,
    fields: Fields,
    totals_final: Totals,
    comm: &dyn Comm,
) -> Result<(Results, Vec<analysis::AnalysisError>), RunError> {
    let scene = st.scene;
    let momentum_final = momenta(&mut st.sim, scene, comm);
    let sim = &st.sim;
    let grain_radius = match &sim.grains {
        Some(c) => c.radii(comm),
        None => Vec::new(),
    };
    let grains_final = sim.grains.as_ref().map(|c| c.positions(comm));
    let (mut results, skipped) = if !scene.scene.analyses.is_empty() {
        // Only rank 0 holds the whole lattice (and only when an analysis reads it).
        let global = analysis::needs_fields(scene)
            .then(|| sim.gather_fields_at_root(comm, fields))
            .flatten();
        let local = comm.is_root().then(|| {
            // A panic here would leave the other ranks waiting for the results: make it an
            // error that they receive too.
            let inputs = analysis::Inputs {
                scene,
                fields: global.as_ref(),
                steps: sim.fluid.lattice().steps_done(),
                series: &sim.series,
                totals: (st.totals_initial, totals_final),
                momentum: st.momentum_initial.zip(momentum_final),
                grain_radius: grain_radius.clone(),
                grains: grains_final.map(|f| (st.grains_initial.clone(), f)),
            };
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                Ok(analysis::run_all(&inputs))
            }))
            .unwrap_or_else(|_| Err(analysis::panicked()))
        });
        let outcome = analysis::share_from_root(comm, local)?;
        (outcome.results, outcome.skipped)
    } else {
        let mut r = Results::new();
        r.insert("run.mass".into(), totals_final.mass);
        r.insert(
            "run.mass_drift_per_1e4_steps".into(),
            analysis::mass_drift_per_1e4_steps(
                st.totals_initial.mass,
                totals_final.mass,
                sim.fluid.lattice().steps_done(),
            ),
        );
        r.insert(
            "run.max_speed_m_s".into(),
            scene.units.velocity_to_si(totals_final.max_speed),
        );
        (r, Vec::new())
    };
    if let Some(c) = &sim.grains {
        results.insert("coupling.substeps".into(), c.substeps() as f64);
        results.insert("coupling.grains".into(), grain_radius.len() as f64);
    }
    Ok((results, skipped))
}
