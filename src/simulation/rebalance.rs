//! Load balance of a coupled run on several ranks: the slab boundaries follow the measured
//! work as the grains move.
//!
//! Every `[coupling] rebalance_every_steps` the ranks share how long each spent on its own
//! work since the last check (its steps' time less the time it waited in communication),
//! split into fluid (the sweep and the boundaries, per fluid cell) and grains (coupling and
//! DEM, per owned grain). When the busiest rank is more than `rebalance_tolerance` above
//! the mean, those measured costs give every lattice column a cost (its fluid cells times
//! the cost of a cell, plus the grains centred in it times the cost of a grain), and the
//! columns are split again, no slab narrower than a grain's reach. The state then moves to
//! the new slabs as a checkpoint restart on them would read it, in memory: the populations
//! column by column to their new owners, the grains gathered and spread again, the grain
//! count checked. A rebalanced run gives the same bits as one rank (`tests/mpi_coupled.rs`).

use super::{stage, Simulation};
use crate::error::RunError;
use decomposition::{move_columns, Comm, SlabPartition};
use lbm::d2q9::Q;
use lbm::lattice::{FaceCondition, FLUID};
use lbm::{Collision, Lattice, LatticeSetup, Real};
use scene::ValidScene;

/// Steps measured before the first check of a run.
const FIRST_CHECK_STEPS: u64 = 10;

/// When and how a coupled run on several ranks rebalances, and what it measured.
#[derive(Debug)]
pub struct Balancer {
    every: u64,
    /// The first check: a few steps into the run, since the starting slabs split the fluid
    /// cells alone.
    first: u64,
    tolerance: f64,
    /// Stage seconds and communication at the start of the measurement.
    seconds_then: [f64; super::STAGES.len()],
    waited_then: f64,
    /// Times the slabs moved.
    pub rebalances: u64,
    /// The busiest rank's work over the mean at the last check (1: balanced).
    pub last_imbalance: f64,
}

impl Balancer {
    /// The balancer of `scene` on `ranks` ranks, from step `start` (a restart's); `None` on
    /// one rank. Only a coupled scene with `rebalance_every_steps > 0` moves its slabs; the
    /// others are measured for the summary's `load_imbalance`.
    pub fn new(scene: &ValidScene, ranks: usize, start: u64) -> Option<Self> {
        let c = scene.scene.coupling.as_ref();
        let every = match (c, &scene.scene.grains) {
            (Some(c), Some(_)) => c.rebalance_every_steps(),
            _ => 0,
        };
        (ranks > 1).then(|| Self {
            every,
            first: start + FIRST_CHECK_STEPS.min(every),
            tolerance: c.map_or(scene::coupling::DEFAULT_REBALANCE_TOLERANCE, |c| {
                c.rebalance_tolerance()
            }),
            seconds_then: [0.0; super::STAGES.len()],
            waited_then: 0.0,
            rebalances: 0,
            last_imbalance: 1.0,
        })
    }

    /// Whether the check is due after `step`: 10 steps in, then at its cadence. A move
    /// after an odd step is as exact as after an even one: the import keeps the in-place
    /// kernel's layout (`Lattice::import_interior`).
    pub fn due(&self, step: u64) -> bool {
        self.every > 0 && (step == self.first || step.is_multiple_of(self.every))
    }

    /// New slabs for `sim` when the measured work since the last check is out of balance
    /// and the cost model finds a split whose busiest rank has less work; `None` otherwise.
    /// Every rank decides the same from the same gathered numbers. Collective.
    pub fn plan<T: Real>(&mut self, sim: &Simulation<T>, comm: &dyn Comm) -> Option<SlabPartition> {
        let grains = sim.grains.as_ref()?;
        let ranks = self.measure(sim, comm);
        let busy: Vec<f64> = ranks.iter().map(|r| r[0]).collect();
        let mean = busy.iter().sum::<f64>() / busy.len() as f64;
        let max = busy.iter().cloned().fold(0.0, f64::max);
        self.last_imbalance = if mean > 0.0 { max / mean } else { 1.0 };
        if !(max > (1.0 + self.tolerance) * mean) {
            return None;
        }
        let (per_cell, per_grain) = costs_of(&ranks);
        let columns = sim.partition.columns();
        let mut here = grains.grains_per_column(columns);
        comm.sum_f64(&mut here);
        // A column of solid still costs a little (its halo and boundary work).
        let floor = per_cell.max(f64::MIN_POSITIVE);
        let costs: Vec<f64> = (0..columns)
            .map(|x| (sim.column_fluid[x] * per_cell + here[x] * per_grain).max(floor))
            .collect();
        let busiest = |p: &SlabPartition| {
            (0..p.ranks())
                .map(|r| {
                    let s = p.slab(r);
                    costs[s.x_begin..s.x_end].iter().sum::<f64>()
                })
                .fold(0.0, f64::max)
        };
        let min_width = grains.min_slab_columns();
        let new = SlabPartition::weighted_min_width(&costs, comm.size(), min_width).ok()?;
        // A move costs several steps: worth it only for a clear gain (any gain when the
        // scene tolerates no imbalance).
        let gain = (0.5 * self.tolerance).min(0.05);
        let better = busiest(&new) < (1.0 - gain) * busiest(&sim.partition);
        (new != sim.partition && better).then_some(new)
    }

    /// Each rank's `[own work (s), fluid cells, grains]` since the measurement started, on
    /// every rank. Collective.
    fn measure<T: Real>(&self, sim: &Simulation<T>, comm: &dyn Comm) -> Vec<[f64; 3]> {
        let (now, waited) = (sim.times.seconds, sim.times.waited);
        let d = |i: usize| now[i] - self.seconds_then[i];
        let stepping: f64 = [
            stage::COLLIDE_STREAM,
            stage::HALO_WAIT,
            stage::COUPLING,
            stage::DEM,
            stage::BOUNDARIES,
        ]
        .into_iter()
        .map(d)
        .sum();
        let own = (stepping - (waited - self.waited_then)).max(0.0);
        let cells = sim.fluid.lattice().fluid_cells() as f64;
        let owned = sim.grains.as_ref().map_or(0, |g| g.system().owned()) as f64;
        let all = comm.all_gather_f64(&[own, cells, owned]);
        all.chunks_exact(3).map(|v| [v[0], v[1], v[2]]).collect()
    }

    /// The busiest rank's own work over the mean since the last check (or the slabs last
    /// moved), for the summary; 1 when nothing was measured. Collective.
    pub fn final_imbalance<T: Real>(&mut self, sim: &Simulation<T>, comm: &dyn Comm) -> f64 {
        let ranks = self.measure(sim, comm);
        let mean = ranks.iter().map(|r| r[0]).sum::<f64>() / ranks.len() as f64;
        let max = ranks.iter().map(|r| r[0]).fold(0.0, f64::max);
        if mean > 0.0 {
            self.last_imbalance = max / mean;
        }
        self.last_imbalance
    }

    /// Start the next measurement from `sim`'s clocks now (after a check, and after the
    /// state moved: the move's own time is not a step's).
    pub fn restart_window<T: Real>(&mut self, sim: &Simulation<T>) {
        self.seconds_then = sim.times.seconds;
        self.waited_then = sim.times.waited;
    }
}

/// The cost of a fluid cell and of a grain (s per window) from each rank's
/// `[own work, fluid cells, grains]`: the least-squares fit of work = a · cells + b · grains
/// over the ranks, which puts what grains add to the sweep (their partially saturated or
/// link cells) on the grains. Where the ranks cannot tell the two apart (as many grains per
/// cell everywhere) or the fit is not positive: a cell costs what it costs on the rank where
/// cells are cheapest, and the grains the rest.
fn costs_of(ranks: &[[f64; 3]]) -> (f64, f64) {
    let s = |f: &dyn Fn(&[f64; 3]) -> f64| ranks.iter().map(f).sum::<f64>();
    let (ff, fg, gg) = (
        s(&|r| r[1] * r[1]),
        s(&|r| r[1] * r[2]),
        s(&|r| r[2] * r[2]),
    );
    let (fw, gw) = (s(&|r| r[1] * r[0]), s(&|r| r[2] * r[0]));
    let det = ff * gg - fg * fg;
    if det > 1e-9 * ff * gg {
        let (a, b) = ((fw * gg - gw * fg) / det, (gw * ff - fw * fg) / det);
        if a > 0.0 && b >= 0.0 {
            return (a, b);
        }
    }
    let per_cell = ranks
        .iter()
        .filter(|r| r[1] > 0.0)
        .map(|r| r[0] / r[1])
        .fold(f64::INFINITY, f64::min);
    let per_cell = if per_cell.is_finite() { per_cell } else { 0.0 };
    let (work, cells, grains) = (s(&|r| r[0]), s(&|r| r[1]), s(&|r| r[2]));
    let rest = (work - per_cell * cells).max(0.0);
    let per_grain = if grains > 0.0 { rest / grains } else { 0.0 };
    (per_cell, per_grain)
}

/// A one-cell lattice that holds the place of a slab while its state moves.
fn one_cell_lattice<T: Real>() -> Lattice<T> {
    Lattice::new(LatticeSetup {
        nx: 1,
        ny: 1,
        cells: vec![FLUID],
        faces: [
            FaceCondition::Periodic,
            FaceCondition::Periodic,
            FaceCondition::Periodic,
            FaceCondition::Periodic,
        ],
        solids: Vec::new(),
        collision: Collision::Bgk,
        tau0: 1.0,
        smagorinsky: None,
        force: [0.0; 2],
    })
}

impl<T: Real> Simulation<T> {
    /// Move this run to the slabs of `partition`: the populations go column by column to
    /// their new owners, the grains are gathered and spread again (their count checked),
    /// and the lattice, the coupling and the probes are built on the new slabs as a restart
    /// builds them. The stage times and the coupling's counters carry on. Collective.
    pub fn repartition(
        &mut self,
        scene: &ValidScene,
        partition: SlabPartition,
        comm: &dyn Comm,
    ) -> Result<(), RunError> {
        let step = self.fluid.lattice().steps_done();
        let rows = Q * self.fluid.lattice().ny();
        let (state, counters) = match &self.grains {
            Some(g) => {
                let state = g.gather_state(comm).map_err(|id| {
                    RunError::Internal(format!(
                        "the load balance after step {step} found grain {id} on two ranks: a \
                         bug; the output so far is kept, and a restart from the last \
                         checkpoint with `[coupling] rebalance_every_steps = 0` avoids it"
                    ))
                })?;
                (Some(state), Some(g.counters()))
            }
            None => (None, None),
        };
        let before = state.as_ref().map_or(0, |s| s.grains.len());
        // The old slab goes before the columns move, and the moved block is the only copy
        // left when the new slab is allocated.
        let old = self.fluid.export_interior();
        self.grains = None;
        self.curved = None;
        self.fluid = Box::new(one_cell_lattice::<T>());
        let populations = move_columns(comm, &self.partition, &partition, rows, &old);
        drop(old);
        let series = std::mem::take(&mut self.series);
        let mut next = Self::on_slabs(scene, comm, self.devices, state, Some(partition))?;
        next.restore(comm, &populations, step, series);
        next.times = std::mem::take(&mut self.times);
        if let (Some(g), Some(c)) = (&mut next.grains, counters) {
            g.continue_counters(c);
            let after = g.dem.global_count(comm);
            if after != before {
                return Err(lost_grains(before as u64, after as u64, step));
            }
        }
        *self = next;
        Ok(())
    }
}

/// The error of a rebalance that lost or duplicated grains.
fn lost_grains(before: u64, after: u64, step: u64) -> RunError {
    RunError::Internal(format!(
        "the load balance after step {step} changed the grain count from {before} to {after}: \
         a bug; the output so far is kept, and a restart from the last checkpoint with \
         `[coupling] rebalance_every_steps = 0` avoids it"
    ))
}

#[cfg(test)]
mod tests {
    use super::costs_of;

    #[test]
    fn the_fit_puts_the_grains_work_on_the_grains() {
        // A cell costs 1, a grain 3: rank 0 holds 100 cells and 50 grains, rank 1 300 cells.
        let (a, b) = costs_of(&[[250.0, 100.0, 50.0], [300.0, 300.0, 0.0]]);
        assert!(
            (a - 1.0).abs() < 1e-12 && (b - 3.0).abs() < 1e-12,
            "{a} {b}"
        );
        // Three ranks, the same costs, fitted exactly.
        let (a, b) = costs_of(&[
            [250.0, 100.0, 50.0],
            [300.0, 300.0, 0.0],
            [230.0, 200.0, 10.0],
        ]);
        assert!(
            (a - 1.0).abs() < 1e-12 && (b - 3.0).abs() < 1e-12,
            "{a} {b}"
        );
        // As many grains per cell on every rank: a cell costs what the cheaper rank's do
        // (1.5), the grains the rest.
        let (a, b) = costs_of(&[[150.0, 100.0, 10.0], [400.0, 200.0, 20.0]]);
        assert!(
            (a - 1.5).abs() < 1e-12 && (b - 100.0 / 30.0).abs() < 1e-12,
            "{a} {b}"
        );
        // A fit that makes grains cost less than nothing falls back too.
        let (a, b) = costs_of(&[[100.0, 100.0, 50.0], [400.0, 300.0, 0.0]]);
        assert!(a > 0.0 && b >= 0.0, "{a} {b}");
    }
}
