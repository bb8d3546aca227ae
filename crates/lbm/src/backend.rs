//! The fluid solver behind one coarse trait, so that the device that runs it (rayon on
//! the CPU, wgpu on a GPU) is chosen at run time. Precision stays a type parameter.

use super::d2q9::Q;
use super::fields::Fields;
use super::lattice::{Lattice, StepError};
use super::moving::{MovingCells, PlanKind, Refill};
use super::real::Real;
use decomposition::Comm;

/// One rank's fluid solver. The [`Lattice`] it exposes always holds the geometry, the
/// step count and the counters; its populations are current only on the CPU backend
/// (a device backend copies them to the host when asked, e.g. by `export_interior`).
pub trait FluidBackend<T: Real> {
    /// Short description of the device ("cpu", "gpu: NVIDIA H100 (Vulkan)").
    fn device(&self) -> String;
    /// Geometry, step count and halo counters of this rank's slab.
    fn lattice(&self) -> &Lattice<T>;
    /// Fused stream–collide with bounce-back and Zou–He links and the halo exchange.
    /// Collective. A device backend may report an instability a few steps late (at its
    /// next check), always with the step and cell where it first appeared.
    fn stream_collide(&mut self, comm: &dyn Comm) -> Result<(), StepError>;
    /// Refill local halos (periodic, free-slip, outflow).
    fn update_boundaries(&mut self);
    /// [`FluidBackend::stream_collide`] with the cells of moving surfaces (see
    /// [`super::moving`]) recomputed after the sweep; one momentum per link or share in
    /// `moving`, or their sums per body and column (see [`FluidBackend::sums_per_body`]).
    /// Returns the plan index and density of the first such cell (on this rank)
    /// that went bad. Collective.
    fn stream_collide_moving(
        &mut self,
        comm: &dyn Comm,
        moving: &mut MovingCells<'_>,
    ) -> Result<Option<(usize, f64)>, StepError>;
    /// Whether [`FluidBackend::stream_collide_moving`] sums the momenta of a plan of `kind`
    /// per body and column itself when the plan's [`super::moving::BodyColumns`] ask for it
    /// (a device backend: then only those sums come back to the host), or some of them (the
    /// CPU's in-place sweep, for partially saturated cells on a slab with no exchanged face:
    /// the bodies inside one block of its rows, summed from momenta still in cache; see
    /// [`super::moving::BodyColumns::body_slot`]).
    fn sums_per_body(&self, _kind: PlanKind) -> bool {
        false
    }
    /// Make every halo cell of the current state hold its neighbour's whole cell: the local
    /// faces refilled (periodic, free-slip, outflow) and all nine populations of the
    /// neighbours' edge columns across rank faces. Collective.
    fn refresh_halos_full(&mut self, comm: &dyn Comm);
    /// Set cells to the equilibrium at ρ = 1 and their velocity.
    fn set_rest(&mut self, cells: &[u32], velocity: &[[f64; 2]]);
    /// Σ h_i c_i of each cell of the current state.
    fn momentum_of_cells(&mut self, cells: &[u32], out: &mut Vec<[f64; 2]>);
    /// The nine own values (post-collision, shifted: f_i − w_i) of each of `cells` (padded
    /// interior cells) in the current state.
    fn whole_cells(&mut self, cells: &[u32]) -> Vec<[f64; Q]>;
    /// Rebuild cells a surface has uncovered; the momentum of each new cell.
    fn apply_refills(&mut self, refills: &[Refill], momentum: &mut Vec<[f64; 2]>);
    /// Scale every Zou–He velocity face from the next step on (start-up ramps).
    fn set_inlet_scale(&mut self, factor: f64);
    /// Make sure no instability has happened so far (before output that must be good).
    /// Collective.
    fn check(&mut self, comm: &dyn Comm) -> Result<(), StepError>;
    /// Momentum-exchange force on every solid during the last step (lattice units); the
    /// same reduction order on any rank count. Collective.
    fn forces(&mut self, comm: &dyn Comm) -> Vec<[f64; 2]>;
    /// Fill the exchanged halos of the current state (before sampling cells next to a
    /// rank face). Collective.
    fn refresh_halos(&mut self, comm: &dyn Comm);
    /// Density and velocity of local fluid cells (x, y), lattice units. Cells next to a
    /// rank face read the exchanged halo: call [`FluidBackend::refresh_halos`] first.
    fn sample(&mut self, cells: &[(usize, usize)]) -> Vec<(f64, [f64; 2])>;
    /// All local fields at the current step (exchanged halos refreshed first). Collective.
    fn fields(&mut self, comm: &dyn Comm) -> Fields;
    /// Interior populations `[9][ny][nx]` (checkpoints).
    fn export_interior(&mut self) -> Vec<T>;
    /// Replace the state with `data` after `step` steps (restart, rebalance), in the layout
    /// a run that had gone on would hold. Collective.
    fn import_interior(&mut self, data: &[T], step: u64, comm: &dyn Comm);
}

impl<T: Real> FluidBackend<T> for Lattice<T> {
    fn device(&self) -> String {
        format!("cpu ({} rayon threads)", rayon::current_num_threads())
    }
    fn lattice(&self) -> &Lattice<T> {
        self
    }
    fn stream_collide(&mut self, comm: &dyn Comm) -> Result<(), StepError> {
        Lattice::stream_collide(self, comm)
    }
    fn stream_collide_moving(
        &mut self,
        comm: &dyn Comm,
        moving: &mut MovingCells<'_>,
    ) -> Result<Option<(usize, f64)>, StepError> {
        Lattice::stream_collide_moving(self, comm, moving)
    }
    fn sums_per_body(&self, kind: PlanKind) -> bool {
        kind == PlanKind::Partial && self.in_place() && !self.exchanges_x()
    }
    fn refresh_halos_full(&mut self, comm: &dyn Comm) {
        Lattice::update_boundaries(self);
        self.refresh_exchange_full(comm);
    }
    fn set_rest(&mut self, cells: &[u32], velocity: &[[f64; 2]]) {
        Lattice::set_rest(self, cells, velocity)
    }
    fn momentum_of_cells(&mut self, cells: &[u32], out: &mut Vec<[f64; 2]>) {
        Lattice::momentum_of_cells(self, cells, out)
    }
    fn whole_cells(&mut self, cells: &[u32]) -> Vec<[f64; Q]> {
        cells.iter().map(|&k| self.whole_cell(k as usize)).collect()
    }

    fn apply_refills(&mut self, refills: &[Refill], momentum: &mut Vec<[f64; 2]>) {
        Lattice::apply_refills(self, refills, momentum)
    }
    fn update_boundaries(&mut self) {
        Lattice::update_boundaries(self)
    }
    fn set_inlet_scale(&mut self, factor: f64) {
        Lattice::set_inlet_scale(self, factor)
    }
    fn check(&mut self, _comm: &dyn Comm) -> Result<(), StepError> {
        // The CPU sweep checks every step.
        Ok(())
    }
    fn forces(&mut self, comm: &dyn Comm) -> Vec<[f64; 2]> {
        Lattice::forces(self, comm)
    }
    fn refresh_halos(&mut self, comm: &dyn Comm) {
        self.refresh_exchange(comm);
    }
    fn sample(&mut self, cells: &[(usize, usize)]) -> Vec<(f64, [f64; 2])> {
        cells
            .iter()
            .map(|&(x, y)| Lattice::sample(self, x, y))
            .collect()
    }
    fn fields(&mut self, comm: &dyn Comm) -> Fields {
        self.refresh_exchange(comm);
        Lattice::fields(self)
    }
    fn export_interior(&mut self) -> Vec<T> {
        Lattice::export_interior(self)
    }
    fn import_interior(&mut self, data: &[T], step: u64, comm: &dyn Comm) {
        Lattice::import_interior(self, data, step, comm)
    }
}
