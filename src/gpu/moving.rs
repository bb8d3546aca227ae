//! Moving surfaces (`lbm::moving`) on the device backend.

use super::fluid::GpuFluid;
use crate::lbm::moving::{MovingCells, Refill};
use crate::lbm::Real;

impl<T: Real> GpuFluid<T> {
    /// Recompute the cells of `moving` after a sweep (see
    /// [`crate::lbm::Lattice::apply_moving`]).
    pub(crate) fn moving_cells(&mut self, moving: &mut MovingCells<'_>) -> Option<(usize, f64)> {
        if matches!(moving, MovingCells::None) {
            return None;
        }
        self.pull_both();
        let bad = self.host_mut().apply_moving(moving);
        self.push_current();
        bad
    }

    /// Whole neighbour cells in the halos (see
    /// [`crate::lbm::FluidBackend::refresh_halos_full`]).
    pub(crate) fn halos_full(&mut self, comm: &dyn decomposition::Comm) {
        let cur = self.host_mut().cur;
        self.pull(cur);
        let host = self.host_mut();
        host.update_boundaries();
        host.refresh_exchange_full(comm);
        self.push_current();
    }

    /// Rest fill (see [`crate::lbm::Lattice::set_rest`]).
    pub(crate) fn rest(&mut self, cells: &[u32], velocity: &[[f64; 2]]) {
        self.pull_both();
        self.host_mut().set_rest(cells, velocity);
        self.push_current();
    }

    /// Cell momenta (see [`crate::lbm::Lattice::momentum_of_cells`]).
    pub(crate) fn cell_momenta(&mut self, cells: &[u32], out: &mut Vec<[f64; 2]>) {
        self.pull_both();
        self.host_mut().momentum_of_cells(cells, out);
    }

    /// Refills (see [`crate::lbm::Lattice::apply_refills`]).
    pub(crate) fn refills(&mut self, refills: &[Refill], momentum: &mut Vec<[f64; 2]>) {
        self.pull_both();
        self.host_mut().apply_refills(refills, momentum);
        self.push_current();
    }
}
