//! One MPM body system and its time step, written as the ordered, timed stages of the
//! chosen update scheme (USF, USL or MUSL).

use super::grid::{Boundaries, GridSpec, NodeFields};
use super::material::Material;
use super::mohr_coulomb::Prepared;
use super::order::{sort_points, OrderScratch, REORDER_EVERY};
use super::points::Points;
use super::shape::ShapeKind;
use super::sweeps::{grid_to_points, update_nodes, update_stress, velocities, Interp, NodeUpdate};
use super::transfer::{particles_to_strips, strips_to_nodes, Columns, P2g, Strip};
use std::time::Instant;
use thiserror::Error;

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
pub const MPM_STAGES: [&str; 5] = ["sort", "p2g", "grid", "stress", "g2p"];

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
    /// Fraction of PIC in the velocity update (0 = pure FLIP).
    pub pic: f64,
    /// Materials, indexed by the points' `material`.
    pub materials: Vec<Material>,
}

/// The CFL limit h / c (s), c = max dilatational wave speed of the materials.
pub fn critical_dt(materials: &[Material], h: f64) -> f64 {
    let c = materials.iter().map(|m| m.wave_speed()).fold(0.0, f64::max);
    h / c
}

/// Why a step could not be completed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MpmError {
    /// A point reached the edge of the grid through an open side.
    #[error("step {step}: material point {id} left the grid at ({x:.6}, {y:.6}) m; enlarge the domain or close that side")]
    LeftDomain {
        /// Step number.
        step: u64,
        /// Point id.
        id: u64,
        /// Position x (m).
        x: f64,
        /// Position y (m).
        y: f64,
    },
    /// A point's position became non-finite.
    #[error("step {step}: the run went unstable: material point {id} has a non-finite position; reduce the time step (courant) or check the material")]
    Unstable {
        /// Step number.
        step: u64,
        /// Point id.
        id: u64,
    },
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
    columns: Columns,
    strips: Vec<Strip>,
    scratch: OrderScratch,
    pos_next: Vec<[f64; 2]>,
    prepared: Vec<Prepared>,
    min_mass: f64,
    /// Simulated time (s).
    pub time: f64,
    /// Steps done.
    pub steps: u64,
    /// Seconds spent per stage (see [`MPM_STAGES`]).
    pub seconds: [f64; 5],
    /// Points that yielded in the last stress update.
    pub yielded: usize,
}

impl MpmSystem {
    /// A system of `points` on the grid of `setup`. The points are sorted on the first step.
    pub fn new(setup: MpmSetup, points: Points) -> Self {
        let min_point = points.mass.iter().cloned().fold(f64::INFINITY, f64::min);
        let min_mass = if min_point.is_finite() {
            1e-9 * min_point
        } else {
            0.0
        };
        MpmSystem {
            prepared: setup.materials.iter().map(|m| m.prepare()).collect(),
            nodes: NodeFields::new(&setup.spec),
            strips: vec![Strip::default(); setup.spec.nx],
            setup,
            points,
            columns: Columns::default(),
            scratch: OrderScratch::default(),
            pos_next: Vec::new(),
            min_mass,
            time: 0.0,
            steps: 0,
            seconds: [0.0; 5],
            yielded: 0,
        }
    }

    fn all_node_cols(&self) -> std::ops::Range<i64> {
        -1..self.setup.spec.nx as i64 + 2
    }

    fn p2g(&mut self, what: P2g) {
        let s = &self.setup;
        particles_to_strips(
            &self.points,
            &self.columns,
            &s.spec,
            s.shape,
            what,
            &mut self.strips,
        );
        let cols = self.all_node_cols();
        strips_to_nodes(&self.strips, &s.spec, what, cols, &mut self.nodes);
    }

    fn node_update(&self) -> NodeUpdate {
        NodeUpdate {
            gravity: self.setup.gravity,
            dt: self.setup.dt,
            damping: self.setup.damping,
            min_mass: self.min_mass,
        }
    }

    /// Advance one time step. On error the state is that of the failed step's start,
    /// except for the points' order.
    pub fn step(&mut self) -> Result<(), MpmError> {
        let mut t = Instant::now();
        let mut lap = |seconds: &mut [f64; 5], stage: usize| {
            seconds[stage] += t.elapsed().as_secs_f64();
            t = Instant::now();
        };
        let spec = self.setup.spec;
        let reorder = self.steps % REORDER_EVERY == 0;
        let (points, columns) = (&mut self.points, &mut self.columns);
        match sort_points(points, &spec, columns, &mut self.scratch, reorder) {
            Ok(()) => {}
            Err(o) if o.pos[0].is_finite() && o.pos[1].is_finite() => {
                return Err(MpmError::LeftDomain {
                    step: self.steps,
                    id: o.id,
                    x: o.pos[0],
                    y: o.pos[1],
                })
            }
            Err(o) => {
                return Err(MpmError::Unstable {
                    step: self.steps,
                    id: o.id,
                })
            }
        }
        lap(&mut self.seconds, 0);
        let (dt, cols, u) = (self.setup.dt, self.all_node_cols(), self.node_update());
        let b = self.setup.boundaries;
        match self.setup.scheme {
            Scheme::Usl => {
                self.p2g(P2g::All);
                lap(&mut self.seconds, 1);
                velocities(
                    &mut self.nodes,
                    &spec,
                    &b,
                    self.min_mass,
                    cols.clone(),
                    false,
                );
                update_nodes(&mut self.nodes, &spec, &b, &u, cols);
                lap(&mut self.seconds, 2);
                self.stress_sweep(false);
                lap(&mut self.seconds, 3);
                self.g2p();
                lap(&mut self.seconds, 4);
            }
            Scheme::Usf => {
                self.p2g(P2g::MassMomentum);
                lap(&mut self.seconds, 1);
                velocities(
                    &mut self.nodes,
                    &spec,
                    &b,
                    self.min_mass,
                    cols.clone(),
                    false,
                );
                lap(&mut self.seconds, 2);
                self.stress_sweep(true);
                lap(&mut self.seconds, 3);
                self.p2g(P2g::Force);
                lap(&mut self.seconds, 1);
                update_nodes(&mut self.nodes, &spec, &b, &u, cols);
                lap(&mut self.seconds, 2);
                self.g2p();
                lap(&mut self.seconds, 4);
            }
            Scheme::Musl => {
                self.p2g(P2g::All);
                lap(&mut self.seconds, 1);
                velocities(
                    &mut self.nodes,
                    &spec,
                    &b,
                    self.min_mass,
                    cols.clone(),
                    false,
                );
                update_nodes(&mut self.nodes, &spec, &b, &u, cols.clone());
                lap(&mut self.seconds, 2);
                self.g2p();
                lap(&mut self.seconds, 4);
                // Remap the updated point momenta (old positions) to the grid.
                self.p2g(P2g::MassMomentum);
                lap(&mut self.seconds, 1);
                velocities(&mut self.nodes, &spec, &b, self.min_mass, cols, true);
                lap(&mut self.seconds, 2);
                self.stress_sweep(false);
                lap(&mut self.seconds, 3);
            }
        }
        std::mem::swap(&mut self.points.pos, &mut self.pos_next);
        self.time += dt;
        self.steps += 1;
        Ok(())
    }

    fn stress_sweep(&mut self, old: bool) {
        let it = Interp {
            spec: &self.setup.spec,
            kind: self.setup.shape,
            columns: &self.columns,
        };
        let v = if old {
            &self.nodes.v_old
        } else {
            &self.nodes.v_new
        };
        self.yielded = update_stress(
            &mut self.points,
            &it,
            v,
            &self.setup.materials,
            &self.prepared,
            self.setup.dt,
        );
    }

    fn g2p(&mut self) {
        let it = Interp {
            spec: &self.setup.spec,
            kind: self.setup.shape,
            columns: &self.columns,
        };
        let (dt, pic) = (self.setup.dt, self.setup.pic);
        grid_to_points(
            &mut self.points,
            &it,
            &self.nodes,
            dt,
            pic,
            &mut self.pos_next,
        );
    }

    /// Kinetic energy per metre of depth (J/m), summed in point order.
    pub fn kinetic_energy(&self) -> f64 {
        let p = &self.points;
        (0..p.len())
            .map(|i| 0.5 * p.mass[i] * (p.vel[i][0].powi(2) + p.vel[i][1].powi(2)))
            .sum()
    }

    /// Momentum per metre of depth (kg/s), summed in point order.
    pub fn momentum(&self) -> [f64; 2] {
        let p = &self.points;
        (0..p.len()).fold([0.0; 2], |a, i| {
            [
                a[0] + p.mass[i] * p.vel[i][0],
                a[1] + p.mass[i] * p.vel[i][1],
            ]
        })
    }
}
