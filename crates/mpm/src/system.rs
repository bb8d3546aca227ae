//! One MPM body system and its time step, written as the ordered, timed stages of the
//! chosen update scheme (USF, USL or MUSL).

use super::balance::{balanced_columns, column_counts, REBALANCE_EVERY};
pub use super::error::MpmError;
use super::grid::{Boundaries, GridSpec, NodeFields, SideWalls};
use super::material::Material;
use super::mohr_coulomb::Prepared;
use super::order::{sort_points, OrderScratch, REORDER_EVERY};
use super::points::Points;
use super::shape::ShapeKind;
use super::sweeps::{
    average_volumetric, grid_to_points, update_nodes, update_stress, velocities,
    velocity_gradients, Interp, NodeUpdate, VelocityUpdate,
};
use super::transfer::{particles_to_strips, strips_to_nodes, Columns, P2g, Strip};
use decomposition::Comm;
use std::time::Instant;

/// When the stress is updated relative to the grid momentum update.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scheme {
    /// Update stress first, with the velocities mapped at the start of the step.
    Usf,
    /// Update stress last, with the updated grid velocities.
    Usl,
    /// Modified USL (Sulsky et al. 1995): stress from velocities remapped from the
    /// updated points.
    Musl,
}

/// Names of the timed stages, in the order their seconds are kept.
pub const MPM_STAGES: [&str; 6] = ["sort", "p2g", "grid", "stress", "g2p", "migrate"];

/// Everything the solver needs besides the points.
#[derive(Debug, Clone, PartialEq)]
pub struct MpmSetup {
    /// Background grid.
    pub spec: GridSpec,
    /// Shape functions.
    pub shape: ShapeKind,
    /// Update scheme.
    pub scheme: Scheme,
    /// Grid boundary conditions.
    pub boundaries: Boundaries,
    /// Gravity (m/s²).
    pub gravity: [f64; 2],
    /// Time step (s); at most the CFL limit (see [`critical_dt`]).
    pub dt: f64,
    /// Cundall local damping α (0 = off).
    pub damping: f64,
    /// Point velocity update: FLIP blended with PIC, or APIC.
    pub velocity_update: VelocityUpdate,
    /// Replace each point's volumetric strain rate by its cell's mean (see
    /// [`super::sweeps::average_volumetric`]).
    pub volumetric_averaging: bool,
    /// Materials, indexed by the points' `material`.
    pub materials: Vec<Material>,
    /// Friction of the side walls of a quasi-two-dimensional channel; `None` for a plane
    /// strain body without walls.
    pub side_walls: Option<SideWalls>,
}

impl MpmSetup {
    /// A plain setup of one material: USF, Δt = ½ of the CFL limit, no damping, pure FLIP,
    /// no volumetric averaging, no side walls. Override fields with struct update syntax.
    pub fn plain(
        spec: GridSpec,
        shape: ShapeKind,
        boundaries: Boundaries,
        gravity: [f64; 2],
        material: Material,
    ) -> Self {
        MpmSetup {
            spec,
            shape,
            scheme: Scheme::Usf,
            boundaries,
            gravity,
            dt: 0.5 * critical_dt(&[material], spec.h),
            damping: 0.0,
            velocity_update: VelocityUpdate::Flip { pic: 0.0 },
            volumetric_averaging: false,
            materials: vec![material],
            side_walls: None,
        }
    }

    /// The side walls' 2 μ_w / W (1/m); 0 without side walls.
    pub fn wall_coefficient(&self) -> f64 {
        self.side_walls.map_or(0.0, |w| w.coefficient())
    }

    /// Whether side walls brake the flow (present with a positive coefficient): the P2G
    /// passes then collect the wall force and the node update applies it.
    pub fn side_walls_act(&self) -> bool {
        self.wall_coefficient() > 0.0
    }
}

/// The CFL limit h / c (s), c the largest wave speed of a stress-carrying point (see
/// [`Material::max_wave_speed`]; the initial one without separation, checked every step).
pub fn critical_dt(materials: &[Material], h: f64) -> f64 {
    let c = materials
        .iter()
        .map(|m| {
            if m.separation_volume_ratio.is_finite() {
                m.max_wave_speed()
            } else {
                m.wave_speed()
            }
        })
        .fold(0.0, f64::max);
    h / c
}

/// Points, grid and scratch of one rank.
#[derive(Debug)]
pub struct MpmSystem {
    /// Setup.
    pub setup: MpmSetup,
    /// The points, in canonical order after each step's sort.
    pub points: Points,
    /// Node fields of the last step.
    pub nodes: NodeFields,
    pub(super) columns: Columns,
    pub(super) strips: Vec<Strip>,
    scratch: OrderScratch,
    pos_next: Vec<[f64; 2]>,
    grads: Vec<[f64; 4]>,
    prepared: Vec<Prepared>,
    min_mass: f64,
    /// Simulated time (s).
    pub time: f64,
    /// Steps done.
    pub steps: u64,
    /// Seconds spent per stage (see [`MPM_STAGES`]).
    pub seconds: [f64; 6],
    /// Points that yielded in the last stress update (this rank).
    pub yielded: usize,
    /// The stress-carrying point with the largest wave speed in the last stress update:
    /// (c² J in m²/s², index).
    fastest: (f64, usize),
    /// Cell-column boundaries of the ranks' slabs (length ranks + 1).
    pub(super) bounds: Vec<usize>,
    /// This rank.
    pub(super) rank: usize,
    /// Points handed to another rank by this rank.
    pub migrated: u64,
    /// Times the slab boundaries moved to balance the point counts.
    pub rebalances: u64,
    /// Seconds spent waiting for strip and migration messages.
    pub comm_seconds: f64,
}

impl MpmSystem {
    /// The share of this rank of a system of `points` (every rank passes the same, full
    /// set) on the grid of `setup` (collective). The slabs are whole cell columns that
    /// balance the point counts; the points are sorted on the first step.
    pub fn new(setup: MpmSetup, points: Points, comm: &dyn Comm) -> Result<Self, MpmError> {
        let min_point = points.mass.iter().cloned().fold(f64::INFINITY, f64::min);
        let min_point = -comm.max_f64(-min_point);
        let min_mass = if min_point.is_finite() {
            1e-9 * min_point
        } else {
            0.0
        };
        let spec = setup.spec;
        let bounds = balanced_columns(&column_counts(&points, &spec)?, comm.size(), spec.nx)?;
        let mut sys = MpmSystem {
            prepared: setup.materials.iter().map(|m| m.prepare()).collect(),
            nodes: NodeFields::new(&spec),
            strips: vec![Strip::default(); spec.nx],
            setup,
            points,
            columns: Columns::default(),
            scratch: OrderScratch::default(),
            pos_next: Vec::new(),
            grads: Vec::new(),
            min_mass,
            time: 0.0,
            steps: 0,
            seconds: [0.0; 6],
            yielded: 0,
            fastest: (0.0, 0),
            bounds,
            rank: comm.rank(),
            migrated: 0,
            rebalances: 0,
            comm_seconds: 0.0,
        };
        sys.keep_own();
        Ok(sys)
    }

    /// The cell columns this rank owns.
    pub fn own_columns(&self) -> std::ops::Range<usize> {
        self.bounds[self.rank]..self.bounds[self.rank + 1]
    }

    /// Node columns this rank computes: the support of its cell columns.
    fn node_cols(&self) -> std::ops::Range<i64> {
        let c = self.own_columns();
        c.start as i64 - 1..c.end as i64 + 2
    }

    fn p2g(&mut self, what: P2g, comm: &dyn Comm) {
        let own = self.own_columns();
        let s = &self.setup;
        particles_to_strips(
            &self.points,
            &self.columns,
            (&s.spec, s.shape, s.wall_coefficient()),
            (what, s.velocity_update == VelocityUpdate::Apic),
            &mut self.strips[own.clone()],
            own.start,
        );
        self.exchange_strips(comm);
        let cols = self.node_cols();
        let spec = self.setup.spec;
        let walls = self.setup.side_walls_act();
        strips_to_nodes(&self.strips, &spec, (what, walls), cols, &mut self.nodes);
    }

    fn node_update(&self) -> NodeUpdate {
        NodeUpdate {
            gravity: self.setup.gravity,
            dt: self.setup.dt,
            damping: self.setup.damping,
            min_mass: self.min_mass,
            side_walls: self.setup.side_walls_act(),
        }
    }

    /// Recompute the points' cells and the canonical order. A point outside the grid on
    /// any rank is an error on every rank (collective).
    pub(super) fn sort(&mut self, comm: &dyn Comm, reorder: bool) -> Result<(), MpmError> {
        let spec = self.setup.spec;
        let (points, columns) = (&mut self.points, &mut self.columns);
        let res = sort_points(points, &spec, columns, &mut self.scratch, reorder);
        let failed = comm.any(res.is_err());
        let step = self.steps;
        match res {
            Err(o) if o.pos[0].is_finite() && o.pos[1].is_finite() => Err(MpmError::LeftDomain {
                step,
                id: o.id,
                x: o.pos[0],
                y: o.pos[1],
            }),
            Err(o) => Err(MpmError::Unstable { step, id: o.id }),
            Ok(()) if failed => Err(MpmError::Elsewhere { step }),
            Ok(()) => Ok(()),
        }
    }

    /// Advance one time step (collective). On error the points are those of the failed
    /// step's start.
    pub fn step(&mut self, comm: &dyn Comm) -> Result<(), MpmError> {
        let mut t = Instant::now();
        let mut lap = |seconds: &mut [f64; 6], stage: usize| {
            seconds[stage] += t.elapsed().as_secs_f64();
            t = Instant::now();
        };
        let spec = self.setup.spec;
        if self.steps > 0 && self.steps.is_multiple_of(REBALANCE_EVERY) {
            self.rebalance(comm);
        }
        self.sort(comm, self.steps.is_multiple_of(REORDER_EVERY))?;
        lap(&mut self.seconds, 0);
        let (dt, cols, u) = (self.setup.dt, self.node_cols(), self.node_update());
        let (b, min_mass) = (self.setup.boundaries, self.min_mass);
        match self.setup.scheme {
            Scheme::Usl => {
                self.p2g(P2g::All, comm);
                lap(&mut self.seconds, 1);
                velocities(&mut self.nodes, &spec, &b, min_mass, cols.clone());
                update_nodes(&mut self.nodes, &spec, &b, &u, cols);
                lap(&mut self.seconds, 2);
                self.stress_sweep();
                lap(&mut self.seconds, 3);
                self.g2p();
                lap(&mut self.seconds, 4);
            }
            Scheme::Usf => {
                self.p2g(P2g::MassMomentum, comm);
                lap(&mut self.seconds, 1);
                velocities(&mut self.nodes, &spec, &b, min_mass, cols.clone());
                lap(&mut self.seconds, 2);
                self.stress_sweep();
                lap(&mut self.seconds, 3);
                self.p2g(P2g::Force, comm);
                lap(&mut self.seconds, 1);
                update_nodes(&mut self.nodes, &spec, &b, &u, cols);
                lap(&mut self.seconds, 2);
                self.g2p();
                lap(&mut self.seconds, 4);
            }
            Scheme::Musl => {
                self.p2g(P2g::All, comm);
                lap(&mut self.seconds, 1);
                velocities(&mut self.nodes, &spec, &b, min_mass, cols.clone());
                update_nodes(&mut self.nodes, &spec, &b, &u, cols.clone());
                lap(&mut self.seconds, 2);
                self.g2p();
                lap(&mut self.seconds, 4);
                // Remap the updated point momenta (old positions) to the grid.
                self.p2g(P2g::MassMomentum, comm);
                lap(&mut self.seconds, 1);
                velocities(&mut self.nodes, &spec, &b, min_mass, cols);
                lap(&mut self.seconds, 2);
                self.stress_sweep();
                lap(&mut self.seconds, 3);
            }
        }
        self.check_courant(comm)?;
        std::mem::swap(&mut self.points.pos, &mut self.pos_next);
        self.time += dt;
        self.steps += 1;
        if comm.size() > 1 {
            self.migrate(comm);
        }
        lap(&mut self.seconds, 5);
        Ok(())
    }

    /// The Courant number of the fastest stress-carrying point must stay ≤ 1 (collective).
    fn check_courant(&self, comm: &dyn Comm) -> Result<(), MpmError> {
        let (c2j, i) = self.fastest;
        let courant = c2j.sqrt() * self.setup.dt / self.setup.spec.h;
        let worst = comm.max_f64(courant);
        if worst <= 1.0 {
            return Ok(());
        }
        if courant < worst {
            return Err(MpmError::Elsewhere { step: self.steps });
        }
        let p = &self.points;
        let m = &self.setup.materials[p.material[i] as usize];
        Err(MpmError::CflExceeded {
            step: self.steps,
            id: p.id[i],
            x: p.pos[i][0],
            y: p.pos[i][1],
            ratio: c2j / (m.wave_speed() * m.wave_speed()),
            courant,
        })
    }

    /// Stress update from the constrained nodal velocity `v_new` (the mapped one for USF
    /// and MUSL's remap, the updated one for USL).
    fn stress_sweep(&mut self) {
        let it = Interp {
            spec: &self.setup.spec,
            kind: self.setup.shape,
            columns: &self.columns,
        };
        velocity_gradients(&self.points, &it, &self.nodes.v_new, &mut self.grads);
        if self.setup.volumetric_averaging {
            average_volumetric(&self.points, &self.columns, &mut self.grads);
        }
        let (yielded, fastest) = update_stress(
            &mut self.points,
            &self.grads,
            &self.setup.materials,
            &self.prepared,
            self.setup.dt,
        );
        self.yielded = yielded;
        self.fastest = fastest;
    }

    fn g2p(&mut self) {
        let it = Interp {
            spec: &self.setup.spec,
            kind: self.setup.shape,
            columns: &self.columns,
        };
        grid_to_points(
            &mut self.points,
            &it,
            &self.nodes,
            &self.setup.boundaries,
            self.setup.dt,
            self.setup.velocity_update,
            &mut self.pos_next,
        );
    }
}
