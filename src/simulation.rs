//! A simulation: the state of the physics a scene asked for, and `step()` as an ordered
//! list of named, timed stages. A fluid-only scene holds only a lattice (this rank's slab).

use crate::driver::Lap;
use crate::error::RunError;
use analysis::flows::{taylor_green_pressure, taylor_green_velocity};
use coupling::{CouplingError, LbmDem};
use decomposition::{Comm, Side, SlabHalo, SlabPartition};
use io::probes::Series;
use lbm::curved::CurvedWalls;
use lbm::fields::{Fields, Totals};
use lbm::gpu::{GpuContext, GpuFluid};
use lbm::lattice::StepError;
use lbm::{FluidBackend, Lattice, Real};
use scene::{
    build_lattice, Backend, BuiltGeometry, GpuStorage, Initial, Kernel, Units, ValidScene,
};
use std::sync::Arc;

mod probes;
mod rebalance;
use probes::{check_grain_probes, probe_targets, ProbeTarget};
pub use rebalance::Balancer;

/// A curved-wall cell that went bad on any rank (`bad` on this one: its plan index and
/// density), as the fluid's error naming it, the same on every rank; the step is `step`
/// (counted from 1). Collective (one agreement per call on more than one rank).
fn curved_failure(
    w: &CurvedWalls,
    comm: &dyn Comm,
    step: u64,
    bad: Option<(usize, f64)>,
) -> Result<(), StepError> {
    let any = match comm.size() {
        1 => bad.is_some(),
        _ => comm.any(bad.is_some()),
    };
    if !any {
        return Ok(());
    }
    let mine = bad.map_or(Vec::new(), |(n, rho)| {
        let (x, y) = w.cell_of(n);
        vec![x as f64, y as f64, rho]
    });
    let all = comm.all_gather_f64(&mine);
    Err(StepError {
        step,
        x: all[0] as usize,
        y: all[1] as usize,
        density: all[2],
    })
}

/// Whether the CPU lattice runs in place: asked for, or `auto` (it measured faster in f32
/// and f64 alike, with grains or without; the same bits either way).
pub fn in_place(kernel: Kernel, _grains: bool) -> bool {
    match kernel {
        Kernel::InPlace | Kernel::Auto => true,
        Kernel::TwoArray => false,
    }
}

/// Names of the stages of one step, in execution order.
pub const STAGES: [&str; 6] = [
    "collide-stream",
    "halo-wait",
    "coupling",
    "dem",
    "boundaries",
    "probes",
];
/// Index of each stage in [`STAGES`].
pub mod stage {
    /// Fused stream–collide (halo exchange overlapped, wait excluded).
    pub const COLLIDE_STREAM: usize = 0;
    /// Exposed waiting for halos.
    pub const HALO_WAIT: usize = 1;
    /// Fluid–grain exchange at the grains' surfaces, and the re-mapping after they move.
    pub const COUPLING: usize = 2;
    /// DEM sub-steps of a coupled run.
    pub const DEM: usize = 3;
    /// Halo refill of local faces, inlet ramps.
    pub const BOUNDARIES: usize = 4;
    /// Probe sampling and reduction.
    pub const PROBES: usize = 5;
}

/// Accumulated wall time per stage.
#[derive(Debug, Clone, Default)]
pub struct StageTimes {
    /// Seconds per entry of [`STAGES`].
    pub seconds: [f64; STAGES.len()],
    /// Of them, the seconds spent in communication.
    pub waits: [f64; STAGES.len()],
    /// Seconds of the steps spent in communication (collectives and waiting for messages,
    /// inside the stages): what the load balance takes away to find each rank's own work.
    pub waited: f64,
}

impl StageTimes {
    /// Run `f` and add its duration to stage `i`.
    pub fn time<R>(&mut self, i: usize, f: impl FnOnce() -> R) -> R {
        let lap = Lap::start();
        let r = f();
        self.add(i, lap);
        r
    }

    /// Add the time since `lap` started, and its communication, to stage `i`.
    pub fn add(&mut self, i: usize, lap: Lap) {
        let (seconds, waited) = lap.elapsed();
        self.seconds[i] += seconds;
        self.waits[i] += waited;
    }
}

/// Why a step could not be taken.
#[derive(Debug, thiserror::Error)]
pub enum StepFailure {
    /// The fluid went unstable.
    #[error(transparent)]
    Fluid(#[from] StepError),
    /// The coupling stopped (unstable cell at a grain, grain out of the domain).
    #[error(transparent)]
    Coupling(#[from] CouplingError),
}

/// The fluid state of this rank's slab plus the run's probes.
pub struct Simulation<T: Real> {
    /// This rank's slab of the lattice, on the device the run chose.
    pub fluid: Box<dyn FluidBackend<T>>,
    /// Derived units.
    pub units: Units,
    /// How the columns are split over ranks.
    pub partition: SlabPartition,
    /// Recorded probe series, in scene order (identical on every rank).
    pub series: Vec<Series>,
    targets: Vec<ProbeTarget>,
    /// Longest inlet ramp (s); 0 when none.
    ramp_s: f64,
    /// Stage timers.
    pub times: StageTimes,
    /// Exchange of the velocity columns next to rank faces (for vorticity).
    field_halo: SlabHalo,
    /// A point probe sits on a column next to a rank face, so sampling reads the halo.
    probe_on_rank_face: bool,
    /// Grains coupled to the fluid, when the scene has them.
    pub grains: Option<LbmDem>,
    /// Circular obstacles with curved walls (interpolated bounce-back), when the scene has
    /// them (scenes without grains only).
    curved: Option<CurvedWalls>,
    /// Fluid cells of each global column (the load-balance cost of the fluid).
    column_fluid: Vec<f64>,
    /// The backend, GPU storage and kernel the run chose (a rebalance builds on them).
    devices: (Backend, GpuStorage, Kernel),
}

/// Fluid cells of each global column.
fn fluid_per_column(built: &BuiltGeometry) -> Vec<f64> {
    let (gnx, ny) = (built.setup.nx, built.setup.ny);
    (0..gnx)
        .map(|x| {
            (0..ny)
                .filter(|&y| built.setup.cells[y * gnx + x] == 0)
                .count() as f64
        })
        .collect()
}

/// Columns split over the ranks of `comm` by fluid-cell count.
fn partition_by_fluid(
    scene: &ValidScene,
    column_fluid: &[f64],
    comm: &dyn Comm,
) -> Result<SlabPartition, RunError> {
    let costs: Vec<f64> = column_fluid.iter().map(|&n| n.max(1.0)).collect();
    SlabPartition::weighted(&costs, comm.size()).map_err(|e| {
        scene
            .invalid(
                "cells",
                format!("{e}; run on fewer ranks or use a wider lattice"),
            )
            .into()
    })
}

/// This rank's slab in the scene's initial condition, boundaries applied.
fn initial_lattice<T: Real>(
    scene: &ValidScene,
    built: &BuiltGeometry,
    partition: &SlabPartition,
    comm: &dyn Comm,
    one_buffer: bool,
) -> Lattice<T> {
    let units = scene.units;
    let (gnx, ny) = (built.setup.nx, built.setup.ny);
    let mut lattice = if one_buffer {
        Lattice::<T>::new_slab_one_buffer(&built.setup, partition, comm.rank())
    } else {
        Lattice::<T>::new_slab(&built.setup, partition, comm.rank())
    };
    let (x0, nx) = (lattice.x_offset(), lattice.nx());
    match scene.scene.fluid.initial {
        Initial::Rest => {}
        Initial::Uniform { velocity_m_s } => {
            let u = [
                units.velocity_to_lattice(velocity_m_s[0]),
                units.velocity_to_lattice(velocity_m_s[1]),
            ];
            for y in 0..ny {
                for x in 0..nx {
                    lattice.set_equilibrium(x, y, 1.0, u);
                }
            }
        }
        Initial::TaylorGreen { amplitude_m_s } => {
            let u0 = units.velocity_to_lattice(amplitude_m_s);
            for y in 0..ny {
                for x in 0..nx {
                    let (px, py) = ((x0 + x) as f64 + 0.5, y as f64 + 0.5);
                    let u = taylor_green_velocity(gnx, ny, u0, units.nu_lattice, 0.0, px, py);
                    // ρ = 1 + p/c_s² (lattice units).
                    let rho = 1.0 + 3.0 * taylor_green_pressure(gnx, ny, u0, px, py);
                    lattice.set_equilibrium(x, y, rho, u);
                }
            }
        }
    }
    lattice.update_boundaries();
    lattice
}

/// The longest inlet ramp of the scene's faces (s); 0 when none.
fn inlet_ramp_s(scene: &ValidScene) -> f64 {
    let b = &scene.scene.boundaries;
    [&b.west, &b.east, &b.south, &b.north]
        .iter()
        .map(|f| match f {
            scene::BoundarySpec::Velocity { ramp_time_s, .. } => *ramp_time_s,
            _ => 0.0,
        })
        .fold(0.0, f64::max)
}

impl<T: Real> Simulation<T> {
    /// Allocate this rank's slab, rasterise obstacles, apply the initial condition, place
    /// probes, and move the slab to `backend`'s device. Columns are split over the ranks
    /// of `comm` by fluid-cell count.
    pub fn new(
        scene: &ValidScene,
        comm: &dyn Comm,
        backend: Backend,
        storage: GpuStorage,
        kernel: Kernel,
        restored: Option<coupling::RestoredCoupling>,
    ) -> Result<Self, RunError> {
        Self::on_slabs(scene, comm, (backend, storage, kernel), restored, None)
    }

    /// [`Simulation::new`] on the slabs of `partition` (by fluid-cell count when `None`).
    fn on_slabs(
        scene: &ValidScene,
        comm: &dyn Comm,
        devices: (Backend, GpuStorage, Kernel),
        restored: Option<coupling::RestoredCoupling>,
        partition: Option<SlabPartition>,
    ) -> Result<Self, RunError> {
        let (backend, storage, kernel) = devices;
        let built = build_lattice(scene)?;
        let units = scene.units;
        let invalid = |key: &str, message: String| scene.invalid(key, message);
        let (targets, series) = probe_targets(scene, &built)?;
        let ny = built.setup.ny;
        let column_fluid = fluid_per_column(&built);
        let partition = match partition {
            Some(p) => p,
            None => partition_by_fluid(scene, &column_fluid, comm)?,
        };
        // A lattice that goes in place below never needs the two-array kernel's second buffer.
        let goes_in_place =
            backend == Backend::Cpu && in_place(kernel, scene.scene.grains.is_some());
        let mut lattice = initial_lattice::<T>(scene, &built, &partition, comm, goes_in_place);
        if goes_in_place {
            lattice.make_in_place();
        } else if kernel == Kernel::InPlace {
            return Err(invalid(
                "kernel",
                "the in-place kernel runs on the CPU backend: use kernel = \"two-array\" or \
                 \"auto\" with the GPU backend"
                    .into(),
            )
            .into());
        }
        let mut fluid: Box<dyn FluidBackend<T>> = match backend {
            Backend::Cpu => Box::new(lattice),
            Backend::Gpu => Box::new(GpuFluid::new(
                lattice,
                Arc::new(GpuContext::open()?),
                storage,
            )?),
        };
        let grains = if scene.scene.grains.is_some() {
            let c = crate::coupled::lbm_dem(
                scene,
                fluid.as_mut(),
                &built.setup.faces,
                &partition,
                comm,
                restored,
            )?;
            check_grain_probes(scene, &targets, &c, comm)?;
            fluid.update_boundaries();
            Some(c)
        } else {
            None
        };
        let mut field_halo = SlabHalo::new(&partition, comm.rank(), false);
        field_halo.set_message_bytes(ny * 9);
        let edges: Vec<usize> = (0..comm.size())
            .flat_map(|r| {
                let s = partition.slab(r);
                [s.x_begin, s.x_end - 1]
            })
            .collect();
        let probe_on_rank_face = comm.size() > 1
            && targets.iter().any(|t| match t {
                ProbeTarget::Point(c) => c.iter().any(|(x, _, _)| edges.contains(x)),
                _ => false,
            });
        let ramp_s = inlet_ramp_s(scene);
        let curved = (!built.curved.is_empty() && grains.is_none())
            .then(|| CurvedWalls::new(fluid.lattice(), &built.curved));
        let mut sim = Self {
            column_fluid,
            devices,
            curved,
            probe_on_rank_face,
            fluid,
            units,
            partition,
            series,
            targets,
            ramp_s,
            times: StageTimes::default(),
            field_halo,
            grains,
        };
        sim.apply_ramp();
        Ok(sim)
    }

    /// Continue from a checkpoint: populations, step and probe series. Collective.
    pub fn restore(&mut self, comm: &dyn Comm, populations: &[T], step: u64, series: Vec<Series>) {
        self.fluid.import_interior(populations, step, comm);
        self.series = series;
        self.apply_ramp();
    }

    /// Inlet factor sin²(π t / 2T) for t < T, for the step about to be taken.
    fn apply_ramp(&mut self) {
        if self.ramp_s > 0.0 {
            let t = self.units.time_si(self.fluid.lattice().steps_done() + 1);
            let r = if t >= self.ramp_s {
                1.0
            } else {
                (0.5 * std::f64::consts::PI * t / self.ramp_s).sin().powi(2)
            };
            self.fluid.set_inlet_scale(r);
        }
    }

    /// The fluid stages of one step: collide–stream (with bounce-back and Zou–He links,
    /// the halo exchange overlapped with the inner cells), then the local halo boundaries.
    /// Probes and output are driven by the caller. Collective.
    pub fn step(&mut self, comm: &dyn Comm) -> Result<(), StepFailure> {
        let before = decomposition::Traffic::now();
        let r = self.stages(comm);
        self.times.waited += decomposition::Traffic::now().since(before).wait_seconds();
        r
    }

    /// The stages of [`Simulation::step`].
    fn stages(&mut self, comm: &dyn Comm) -> Result<(), StepFailure> {
        let lat = &mut self.fluid;
        if let Some(c) = &mut self.grains {
            self.times.time(stage::COUPLING, || c.plan(lat.as_ref()));
        }
        let wait0 = lat.lattice().halo_wait_seconds();
        let lap = Lap::start();
        let r = match (&mut self.grains, &mut self.curved) {
            (Some(c), _) => lat.stream_collide_moving(comm, &mut c.moving()),
            (None, Some(w)) => lat.stream_collide_moving(comm, &mut w.moving()),
            (None, None) => lat.stream_collide(comm).map(|_| None),
        };
        let waited = lat.lattice().halo_wait_seconds() - wait0;
        let (seconds, communication) = lap.elapsed();
        self.times.seconds[stage::COLLIDE_STREAM] += seconds - waited;
        self.times.seconds[stage::HALO_WAIT] += waited;
        // The halo wait is communication (none on one process, whose halo is a local
        // copy); the sweep's own (a collective on an unstable cell) is the rest.
        let halo = waited.min(communication);
        self.times.waits[stage::COLLIDE_STREAM] += communication - halo;
        self.times.waits[stage::HALO_WAIT] += halo;
        let bad = r?;
        if let Some(w) = &self.curved {
            let step = lat.lattice().steps_done();
            curved_failure(w, comm, step, bad)?;
        }
        if let Some(c) = &mut self.grains {
            let fluid = lat.as_mut();
            let step = fluid.lattice().steps_done();
            self.times
                .time(stage::COUPLING, || c.exchange(step, bad, comm))?;
            self.times.time(stage::DEM, || c.advance(comm))?;
            self.times.time(stage::COUPLING, || c.remap(fluid, comm));
        }
        self.times
            .time(stage::BOUNDARIES, || lat.update_boundaries());
        self.apply_ramp();
        Ok(())
    }

    /// Whether the scene has probes to record.
    pub fn has_probes(&self) -> bool {
        !self.targets.is_empty()
    }

    /// Make sure the state is good before it is recorded (a device backend checks for
    /// instabilities only every few steps). Collective.
    pub fn check(&mut self, comm: &dyn Comm) -> Result<(), StepError> {
        self.fluid.check(comm)
    }

    /// This slab's fields at the current step (exchanged halos refreshed first; the fluid
    /// under bounce-back grains at rest at their velocity). Collective.
    pub fn fields(&mut self, comm: &dyn Comm) -> Fields {
        self.show_grains();
        let mut f = self.fluid.fields(comm);
        for (x, y, rho, u) in self.link_cell_moments(None) {
            let k = y * f.nx + x;
            (f.rho[k], f.ux[k], f.uy[k]) = (rho, u[0], u[1]);
        }
        if let Some(c) = &self.grains {
            // Under a bounce-back grain: the fluid at rest at the grain's velocity, as
            // `show_grains` set it. A plain read there would pull values across rank faces
            // that the neighbour's rest fill does not reach in the pushed layout.
            let stride = self.fluid.lattice().stride();
            let (cells, velocity) = c.coupler().rest_cells();
            for (&k, u) in cells.iter().zip(velocity) {
                let (x, y) = (k as usize % stride - 1, k as usize / stride - 1);
                let at = y * f.nx + x;
                (f.rho[at], f.ux[at], f.uy[at]) = (1.0, u[0], u[1]);
            }
        }
        if let Some(w) = &self.curved {
            // Inside a curved wall: solid, as [`Fields`] shows solids.
            let stride = self.fluid.lattice().stride();
            for &k in w.interior() {
                let (x, y) = (k as usize % stride - 1, k as usize / stride - 1);
                let at = y * f.nx + x;
                (f.rho[at], f.ux[at], f.uy[at], f.fluid[at]) = (1.0, 0.0, 0.0, false);
            }
        }
        f
    }

    /// Before fields or probes are read: the fluid under bounce-back grains at rest at
    /// their velocity, local halos refilled, so that cells next to a grain read it the
    /// same way on any rank count (the sweep's values under grains are never used).
    fn show_grains(&mut self) {
        if let Some(c) = &mut self.grains {
            c.fill_rest(self.fluid.as_mut());
            self.fluid.update_boundaries();
        }
    }

    /// Totals over the whole lattice from this slab's `f`; same bits on any rank count.
    /// Collective.
    pub fn totals(&self, comm: &dyn Comm, f: &Fields) -> Totals {
        let sums = comm.all_gather_f64(&f.column_sums());
        Totals::from_column_sums(&sums, comm.max_f64(f.max_speed()))
    }

    /// Vorticity of this slab's `f`, using the neighbours' edge columns. Collective.
    pub fn vorticity(&mut self, comm: &dyn Comm, f: &Fields) -> Vec<f64> {
        let (nx, ny) = (f.nx, f.ny);
        for (side, x) in [(Side::Left, 0), (Side::Right, nx - 1)] {
            let out = self.field_halo.send_mut(side);
            for y in 0..ny {
                out[9 * y..9 * y + 8].copy_from_slice(&f.uy[y * nx + x].to_le_bytes());
                out[9 * y + 8] = f.fluid[y * nx + x] as u8;
            }
        }
        self.field_halo.exchange(comm, &mut || {});
        let column = |side| {
            self.field_halo.peer(side).map(|_| {
                let data = self.field_halo.recv(side);
                let uy: Vec<f64> = (0..ny)
                    .map(|y| f64::from_le_bytes(data[9 * y..9 * y + 8].try_into().unwrap()))
                    .collect();
                let fluid: Vec<bool> = (0..ny).map(|y| data[9 * y + 8] != 0).collect();
                (uy, fluid)
            })
        };
        let (w, e) = (column(Side::Left), column(Side::Right));
        f.vorticity_with(
            w.as_ref().map(|(u, b)| (u.as_slice(), b.as_slice())),
            e.as_ref().map(|(u, b)| (u.as_slice(), b.as_slice())),
        )
    }

    /// The whole lattice's fields from every slab's `f`, on the root (rank 0) only (`None`
    /// elsewhere), so that no other rank holds the whole lattice: for the pictures and the
    /// analyses, which only the root computes. On one rank, `f` itself. A field left empty
    /// on every rank (one the caller does not need) stays empty. Collective.
    pub fn gather_fields_at_root(&self, comm: &dyn Comm, f: Fields) -> Option<Fields> {
        if comm.size() == 1 {
            return Some(f);
        }
        let g = self.assemble(comm, &f);
        comm.is_root().then_some(g)
    }

    /// The whole lattice's fields from the slabs' `f`, each field's values gathered in
    /// rank order on the root (empty fields on the other ranks).
    fn assemble(&self, comm: &dyn Comm, f: &Fields) -> Fields {
        let gather = |local: &[f64]| comm.gather_f64(local);
        let (gnx, ny) = (self.partition.columns(), f.ny);
        let place = |all: &[f64]| -> Vec<f64> {
            if all.is_empty() {
                return Vec::new();
            }
            let mut out = vec![0.0; gnx * ny];
            let mut at = 0;
            for r in 0..comm.size() {
                let s = self.partition.slab(r);
                for y in 0..ny {
                    out[y * gnx + s.x_begin..y * gnx + s.x_end]
                        .copy_from_slice(&all[at..at + s.width()]);
                    at += s.width();
                }
            }
            out
        };
        let fluid_local: Vec<f64> = f.fluid.iter().map(|&b| b as u8 as f64).collect();
        Fields {
            nx: gnx,
            ny,
            rho: place(&gather(&f.rho)),
            ux: place(&gather(&f.ux)),
            uy: place(&gather(&f.uy)),
            fluid: place(&gather(&fluid_local))
                .into_iter()
                .map(|v| v != 0.0)
                .collect(),
        }
    }

    /// Fluid cells of the whole lattice. Collective.
    pub fn fluid_cells(&self, comm: &dyn Comm) -> usize {
        let mut n = [self.fluid.lattice().fluid_cells() as f64];
        comm.sum_f64(&mut n);
        n[0] as usize
    }
}
