//! The coupled grains of a fluid scene on one rank's slab: the distributed DEM, the coupler,
//! the ghost grains, and the unit conversions between them (the DEM works in SI, the coupler
//! in lattice units).
//!
//! A grain belongs to the rank whose fluid slab holds its centre (the DEM's slabs are the
//! fluid's). Forces on a grain are summed per lattice column wherever its cells are, and
//! its owner adds the columns in order, so a coupled run gives the same bits on any number
//! of ranks (tested with mpirun).

use super::exchange::{Coupler, CouplingError, Unstable};
use super::ghosts::GrainHalo;
use super::map::{GrainView, SlabFrame};
use super::sums::Load;
use super::{Refill, Scheme};
use decomposition::{Comm, SlabPartition};
use dem::walls::{apply_walls, WallStates};
use dem::{DemError, DemSetup, DemSystem, Grains, SlabDem};
use lbm::lattice::FaceCondition;
use lbm::moving::MovingCells;
use lbm::units::Units;
use lbm::{FluidBackend, Real};
use thiserror::Error;

mod handoff;
mod reduce;
mod report;
mod repulsion;
mod setup;
mod views;

pub use handoff::CouplingCounters;
use reduce::Which;
pub use setup::{check_grains, fluid_walls, MIN_CELLS_PER_DIAMETER};
use setup::{grain_reach, slab_bounds_m, slab_error, slab_frame};

/// Where a grain in view comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Source {
    /// This rank owns it (index among the owned grains).
    Owned(u32),
    /// A ghost from the neighbour on this side.
    Ghost(u8),
}

/// Values carried with each owned grain through the DEM's migration: the previous step's
/// hydrodynamic force and torque (for the two-step average), then the one held in the last
/// advance (both SI).
const CARRY: usize = 6;

/// What a restart gives the coupled grains instead of preparing the sample.
pub struct RestoredCoupling {
    /// Every grain, sorted by id, with the forces of its last evaluation.
    pub grains: Grains,
    /// Pair and wall contact history.
    pub history: dem::system::HistoryMap,
    /// Wall ends and removal flags.
    pub walls: WallStates,
    /// DEM time (s) and steps.
    pub clock: (f64, u64),
    /// Per grain, by id: external force held (SI), the previous hydrodynamic force (SI)
    /// and the pending hand-over (lattice units).
    pub per_grain: Vec<(u64, [f64; 9])>,
}

/// Grains coupled to this rank's slab of the fluid.
pub struct LbmDem {
    /// The grains and their contacts (SI units, N and m per metre of depth), distributed
    /// over the fluid's slabs.
    pub dem: SlabDem,
    coupler: Coupler,
    halo: GrainHalo,
    substeps: u32,
    units: Units,
    /// Domain size (m).
    domain: [f64; 2],
    /// Grains in view (owned, then ghosts, merged in increasing id), lattice units.
    views: Vec<GrainView>,
    ids: Vec<u64>,
    source: Vec<Source>,
    /// Masses of the grains in view (kg/m), for the repulsion.
    mass: Vec<f64>,
    /// Per owned grain: its view.
    view_of: Vec<u32>,
    /// Owned grains then ghosts, as [`LbmDem::refresh_views`] gathers them, by increasing id.
    id_order: Vec<u32>,
    /// Per owned grain: the last exchange's load and the last remap's hand-over (lattice).
    load: Vec<Load>,
    handover: Vec<Load>,
    /// Hold the average of the last two steps' forces.
    average: bool,
    /// Repulsion (range m, strength in submerged weights), if on.
    repulsion: Option<(f64, f64)>,
    /// |g| (1 − ρ/ρ_s): submerged weight per unit mass (m/s²).
    reduced_gravity: f64,
    /// Walls to remove at a time (index, time s).
    removals: Vec<(usize, f64)>,
    /// r_h / r: the radius the fluid sees over the contact radius.
    hydro_ratio: f64,
    /// Fluid steps taken (for messages).
    step: u64,
    /// Scratch for partial sums.
    partials: Vec<(u32, Load)>,
    /// How far a grain reaches into its neighbours' cells (m): the narrowest slab.
    reach_m: f64,
    /// Counters of the couplings this one replaced (a rebalance).
    earlier: CouplingCounters,
}

/// What the coupled grains are, in plain numbers: everything [`LbmDem::new`] takes besides
/// the grains and the fluid. The driver builds it from a scene.
#[derive(Debug, Clone)]
pub struct LbmDemSetup {
    /// Interface scheme.
    pub scheme: Scheme,
    /// How a cell a grain uncovers is refilled (bounce-back schemes).
    pub refill: Refill,
    /// SI ↔ lattice units of the fluid.
    pub units: Units,
    /// Domain size (m), the fluid's.
    pub domain_m: [f64; 2],
    /// The DEM: the scene's own walls (a wall along each wall face of the fluid is added
    /// to them), contact model, gravity reduced by buoyancy (m/s²), λ, and the sub-step
    /// Δt/n_s (s).
    pub dem: DemSetup,
    /// Friction of the walls added along the fluid's wall faces.
    pub face_wall_friction: f64,
    /// DEM sub-steps n_s per fluid step.
    pub substeps: u32,
    /// Whether the grains may start overlapping (a settled sample presses into itself).
    pub allow_overlap: bool,
    /// Global damping of the grains' motion (1/s).
    pub global_damping_1_s: f64,
    /// Hold the average of the last two steps' forces.
    pub average_forces: bool,
    /// Short-range repulsion (range m, strength in submerged weights), if on.
    pub repulsion: Option<(f64, f64)>,
    /// r_h / r in (0, 1]: the radius the fluid sees, as a fraction of the contact radius.
    pub hydrodynamic_radius_ratio: f64,
    /// Walls to remove at a time (index among the scene's walls, time s).
    pub removals: Vec<(usize, f64)>,
}

/// Why the coupled grains could not be set up.
#[derive(Debug, Error)]
pub enum SetupError {
    /// A value of the scene does not work: the key it belongs to and what to do.
    #[error("{key}: {message}")]
    Invalid {
        /// The scene key.
        key: &'static str,
        /// What is wrong and the fix.
        message: String,
    },
    /// The DEM refused the grains.
    #[error(transparent)]
    Dem(#[from] DemError),
}

impl LbmDem {
    /// Add a DEM wall on every wall face of the fluid (`faces`: the whole lattice's) to
    /// the walls of `setup`, spread `grains` (every grain, sorted by id: the prepared sample
    /// or, with `restored`, the checkpoint's) over the slabs of `partition`, and place them
    /// on this rank's `fluid`. Errors name the key: a slab too narrow for the grains.
    /// Collective.
    pub fn new<T: Real>(
        setup: LbmDemSetup,
        grains: Grains,
        restored: Option<RestoredCoupling>,
        fluid: &mut dyn FluidBackend<T>,
        faces: &[FaceCondition; 4],
        partition: &SlabPartition,
        comm: &dyn Comm,
    ) -> Result<Self, SetupError> {
        let LbmDemSetup {
            scheme,
            refill,
            units,
            domain_m: domain,
            dem: mut dem_setup,
            face_wall_friction,
            substeps,
            allow_overlap,
            global_damping_1_s,
            average_forces,
            repulsion,
            removals,
            hydrodynamic_radius_ratio,
        } = setup;
        let along_faces = fluid_walls(faces, domain, face_wall_friction, &dem_setup.walls);
        dem_setup.walls.extend(along_faces);
        let gravity = dem_setup.gravity;
        let bounds = slab_bounds_m(partition, units.dx_m, comm);
        let rmax = grains.r.iter().cloned().fold(0.0, f64::max);
        let fresh = restored.is_none();
        let (mut dem, per_grain) = match restored {
            None => {
                let d = SlabDem::new(grains, &bounds, dem_setup, allow_overlap, comm);
                (d.map_err(slab_error)?, Vec::new())
            }
            Some(r) => {
                apply_walls(&mut dem_setup.walls, &r.walls);
                let d = SlabDem::restore(grains, r.history, &bounds, dem_setup, r.clock, comm);
                (d.map_err(slab_error)?, r.per_grain)
            }
        };
        dem.system.global_damping = global_damping_1_s;
        // Grain indices must stay fixed between migrations: the held forces follow them.
        dem.system.spatial_sort = false;
        dem.rebalance_every = 0;
        dem.system.enable_carry(CARRY);
        let range = repulsion.map_or(0.0, |r| r.0);
        let margin = grain_reach(rmax, range, units.dx_m, partition, comm)?;
        let lat = fluid.lattice();
        let frame = slab_frame(lat, faces);
        let periodic_x = frame.periodic_x;
        let halo = GrainHalo::new(partition, comm.rank(), units.dx_m, periodic_x, margin);
        let owned = dem.system.owned();
        let mut me = Self {
            dem,
            coupler: Coupler::new(scheme, refill, frame),
            halo,
            substeps,
            units,
            domain,
            views: Vec::new(),
            ids: Vec::new(),
            source: Vec::new(),
            mass: Vec::new(),
            view_of: Vec::new(),
            id_order: Vec::new(),
            load: vec![[0.0; 3]; owned],
            handover: vec![[0.0; 3]; owned],
            average: average_forces,
            repulsion,
            reduced_gravity: gravity[0].hypot(gravity[1]),
            removals,
            hydro_ratio: hydrodynamic_radius_ratio,
            step: lat.steps_done(),
            partials: Vec::new(),
            reach_m: 2.0 * rmax + margin,
            earlier: CouplingCounters::default(),
        };
        if !fresh {
            me.restore_per_grain(&per_grain);
        }
        me.refresh_views(comm);
        me.coupler.start(fluid, &me.views, &me.ids, fresh);
        Ok(me)
    }

    /// Put each owned grain's checkpointed state (by id) back in place.
    fn restore_per_grain(&mut self, rows: &[(u64, [f64; 9])]) {
        let sys = &mut self.dem.system;
        let mut external = Vec::with_capacity(sys.owned());
        for i in 0..sys.owned() {
            let id = sys.grains.id[i];
            let p = rows
                .binary_search_by_key(&id, |r| r.0)
                .map(|k| rows[k].1)
                .unwrap_or([0.0; 9]);
            external.push([p[0], p[1], p[2]]);
            sys.carry_mut(i)[..3].copy_from_slice(&p[3..6]);
            self.handover[i] = [p[6], p[7], p[8]];
        }
        sys.restore_external(external);
    }

    /// DEM sub-steps per fluid step.
    pub fn substeps(&self) -> u32 {
        self.substeps
    }

    /// Seconds this rank spent in each pass of the "coupling" stage ([`super::PASSES`]).
    pub fn pass_seconds(&self) -> [f64; 6] {
        let now = self.coupler.pass_seconds();
        std::array::from_fn(|k| self.earlier.passes[k] + now[k])
    }

    /// This rank's counts of [`super::COUNTS`] (see [`Coupler::counts`]).
    pub fn counts(&self) -> [u64; 6] {
        let now = self.coupler.counts();
        std::array::from_fn(|k| self.earlier.counts[k] + now[k])
    }

    /// The coupler (maps, loads).
    pub fn coupler(&self) -> &Coupler {
        &self.coupler
    }

    /// The DEM system of this rank (owned grains first).
    pub fn system(&self) -> &DemSystem {
        &self.dem.system
    }

    /// Hydrodynamic force and torque on owned grain `i` held during the last advance
    /// (N/m, N·m/m).
    pub fn hydrodynamic(&self, i: usize) -> [f64; 3] {
        let c = self.dem.system.carry(i);
        [c[3], c[4], c[5]]
    }

    /// Grains in view (owned and ghosts, increasing id), lattice units.
    pub fn views(&self) -> &[GrainView] {
        &self.views
    }

    /// Stage "coupling" before the sweep: plan the cells at the grains' surfaces (see
    /// [`Coupler::plan`]).
    pub fn plan<T: Real>(&mut self, fluid: &dyn FluidBackend<T>) {
        let kind = self.coupler.plan_kind();
        self.coupler
            .plan(fluid.lattice(), &self.views, fluid.sums_per_body(kind));
    }

    /// The planned cells, for the fluid's sweep.
    pub fn moving(&mut self) -> MovingCells<'_> {
        self.coupler.moving()
    }

    /// Stage "coupling" after the sweep: every grain's load is summed on its owner. `bad`
    /// is what the sweep reported. Errors (on every rank) when a recomputed cell went bad.
    /// Collective.
    pub fn exchange(
        &mut self,
        step: u64,
        bad: Option<(usize, f64)>,
        comm: &dyn Comm,
    ) -> Result<(), CouplingError> {
        self.step = step;
        let bad = self.coupler.collect(&self.views, bad);
        self.agree(comm, bad)?;
        let t = std::time::Instant::now();
        self.load = self.reduce(Which::Exchange, comm);
        self.coupler
            .add_pass(super::pass::REDUCE, t.elapsed().as_secs_f64());
        Ok(())
    }

    /// Show the grains in the fluid's fields: the fluid under them at rest at their velocity
    /// (bounce-back schemes; see [`Coupler::fill_rest`]).
    pub fn fill_rest<T: Real>(&mut self, fluid: &mut dyn FluidBackend<T>) {
        self.coupler.fill_rest(fluid, &self.views);
    }

    /// The first bad cell over all ranks, known to every rank. Collective.
    fn agree(&self, comm: &dyn Comm, bad: Option<Unstable>) -> Result<(), CouplingError> {
        if !comm.any(bad.is_some()) {
            return Ok(());
        }
        let mine = match bad {
            Some((k, g, density)) => {
                let f = self.frame();
                let (x, y) = f.local(k);
                vec![
                    (x + f.x0 as i64) as f64,
                    y as f64,
                    f64::from_bits(self.ids[g as usize]),
                    density,
                ]
            }
            None => Vec::new(),
        };
        let all = comm.all_gather_f64(&mine);
        Err(CouplingError::Unstable {
            step: self.step,
            x: all[0] as usize,
            y: all[1] as usize,
            grain: all[2].to_bits(),
            density: all[3],
        })
    }

    fn frame(&self) -> SlabFrame {
        self.coupler.frame()
    }

    /// Stage "dem": hold the hydrodynamic force (and the repulsion) and take the DEM
    /// sub-steps of one fluid step, then exchange the ghosts. Errors (on every rank) when a
    /// grain leaves the fluid domain. Collective.
    pub fn advance(&mut self, comm: &dyn Comm) -> Result<(), CouplingError> {
        let u = self.units;
        let owned = self.dem.system.owned();
        let mut held = Vec::with_capacity(owned);
        for i in 0..owned {
            let (a, b) = (self.load[i], self.handover[i]);
            // Lattice momentum per step → N/m; the torque's arm is in cells (× Δx).
            let h = [
                u.force_to_si(a[0] + b[0]),
                u.force_to_si(a[1] + b[1]),
                u.force_to_si(a[2] + b[2]) * u.dx_m,
            ];
            let carry = self.dem.system.carry_mut(i);
            if self.average {
                // Ladd 1994 (part I, §4): the force of two successive steps, averaged, damps
                // the step-to-step oscillation that makes explicit bounce-back coupling
                // unstable for light grains (their rotation first).
                held.push([
                    0.5 * (h[0] + carry[0]),
                    0.5 * (h[1] + carry[1]),
                    0.5 * (h[2] + carry[2]),
                ]);
                carry[..3].copy_from_slice(&h);
            } else {
                held.push(h);
            }
            carry[3..].copy_from_slice(&h);
        }
        if let Some((range, strength)) = self.repulsion {
            self.add_repulsion(range, strength, &mut held);
        }
        self.dem.system.set_external(&held);
        let t_end = self.dem.system.time + u.dt_s;
        for (w, t) in &self.removals {
            if *t <= t_end && !self.dem.system.walls[*w].removed {
                self.dem.system.remove_wall(*w);
            }
        }
        for _ in 0..self.substeps {
            self.dem.step(comm);
        }
        let g = &self.dem.system.grains;
        let outside: Vec<f64> = (0..self.dem.system.owned())
            .filter(|&i| {
                let (x, y) = (g.x[i], g.y[i]);
                !(x >= 0.0 && y >= 0.0 && x <= self.domain[0] && y <= self.domain[1])
            })
            .flat_map(|i| [f64::from_bits(g.id[i]), g.x[i], g.y[i]])
            .collect();
        if comm.any(!outside.is_empty()) {
            let all = comm.all_gather_f64(&outside);
            return Err(CouplingError::Left {
                step: self.step,
                grain: all[0].to_bits(),
                position: [all[1], all[2]],
            });
        }
        self.check_speeds(comm)?;
        // The owned set may have changed (migration); the loads are recomputed before use.
        let owned = self.dem.system.owned();
        self.load.resize(owned, [0.0; 3]);
        self.handover.resize(owned, [0.0; 3]);
        self.refresh_views(comm);
        Ok(())
    }

    /// Errors (on every rank) when a grain moves faster than the lattice's speed of sound
    /// c_s = 1/√3 cells per step, the lowest id first. Collective.
    fn check_speeds(&self, comm: &dyn Comm) -> Result<(), CouplingError> {
        let limit = self.units.velocity_to_si(lbm::units::SOUND_SPEED);
        let g = &self.dem.system.grains;
        let mine: Vec<f64> = (0..self.dem.system.owned())
            .filter(|&i| !(g.vx[i].hypot(g.vy[i]) <= limit))
            .min_by_key(|&i| g.id[i])
            .map(|i| vec![f64::from_bits(g.id[i]), g.vx[i].hypot(g.vy[i])])
            .unwrap_or_default();
        if !comm.any(!mine.is_empty()) {
            return Ok(());
        }
        let all = comm.all_gather_f64(&mine);
        let (grain, speed) = all
            .chunks(2)
            .map(|c| (c[0].to_bits(), c[1]))
            .min_by_key(|c| c.0)
            .unwrap_or((0, f64::NAN));
        Err(CouplingError::TooFast {
            step: self.step,
            grain,
            speed_lattice: self.units.velocity_to_lattice(speed),
            speed_m_s: speed,
        })
    }

    /// Stage "coupling" after the grains moved: see [`Coupler::remap`]; the hand-over is
    /// summed on the owners. Collective.
    pub fn remap<T: Real>(&mut self, fluid: &mut dyn FluidBackend<T>, comm: &dyn Comm) {
        self.coupler.remap(fluid, &self.views, &self.ids, comm);
        if self.coupler.hands_over() {
            let t = std::time::Instant::now();
            self.handover = self.reduce(Which::Handover, comm);
            self.coupler
                .add_pass(super::pass::REDUCE, t.elapsed().as_secs_f64());
        }
    }
}
