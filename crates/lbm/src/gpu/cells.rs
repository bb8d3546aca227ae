//! Whole cells between host and device for the moving surfaces (`moving.rs`): rest fills,
//! refills, cell momenta and full halos go through small gather and scatter kernels, so
//! their arithmetic is the CPU backend's, to the bit.

use super::fluid::moving::Kernel;
use super::fluid::GpuFluid;
use crate::d2q9::Q;
use crate::moving::{equilibrium_at, momentum_of, refill_cell, refill_sources, Refill};
use crate::Real;
use decomposition::Comm;
use std::collections::HashMap;

impl<T: Real> GpuFluid<T> {
    /// The 9 populations of each of `cells` (padded) in the current state.
    pub(crate) fn gather(&mut self, cells: &[u32]) -> Vec<T> {
        if cells.is_empty() {
            return Vec::new();
        }
        let cur = self.host_mut().cur;
        let mut idx = vec![cells.len() as u32, 0];
        idx.extend_from_slice(cells);
        let zeros = vec![T::default(); Q * cells.len()];
        self.run_moving(&[(Kernel::Gather, cells.len())], cur, &idx, &zeros, 0);
        self.moving_reals(0, Q * cells.len())
    }

    /// Write the 9 populations of each of `cells` (padded) into the current state.
    pub(crate) fn scatter(&mut self, cells: &[u32], values: &[T]) {
        if cells.is_empty() {
            return;
        }
        let dst_is_cur = self.host_mut().cur ^ 1;
        let mut idx = vec![cells.len() as u32, 0];
        idx.extend_from_slice(cells);
        self.run_moving(
            &[(Kernel::Scatter, cells.len())],
            dst_is_cur,
            &idx,
            values,
            0,
        );
    }

    /// Rest fill (see [`crate::Lattice::set_rest`]): the same values, made on the host.
    pub(crate) fn rest(&mut self, cells: &[u32], velocity: &[[f64; 2]]) {
        let values: Vec<T> = velocity
            .iter()
            .flat_map(|&u| equilibrium_at(0.0, u).map(T::from_f64))
            .collect();
        self.scatter(cells, &values);
    }

    /// Cell momenta (see [`crate::Lattice::momentum_of_cells`]).
    pub(crate) fn cell_momenta(&mut self, cells: &[u32], out: &mut Vec<[f64; 2]>) {
        let v = self.gather(cells);
        out.clear();
        out.extend(v.chunks_exact(Q).map(|c| {
            let h: [f64; Q] = std::array::from_fn(|i| c[i].to_f64());
            momentum_of(&h)
        }));
    }

    /// Refills (see [`crate::Lattice::apply_refills`]): the neighbours come from the
    /// device, the values are made on the host with the CPU's arithmetic.
    pub(crate) fn refills(&mut self, refills: &[Refill], momentum: &mut Vec<[f64; 2]>) {
        momentum.clear();
        if refills.is_empty() {
            return;
        }
        let stride = self.host_mut().stride;
        let mut sources: Vec<u32> = refills
            .iter()
            .flat_map(|r| refill_sources(r, stride))
            .map(|k| k as u32)
            .collect();
        sources.sort_unstable();
        sources.dedup();
        let v = self.gather(&sources);
        let at: HashMap<usize, usize> = sources
            .iter()
            .enumerate()
            .map(|(j, &k)| (k as usize, j))
            .collect();
        let mut values = Vec::with_capacity(Q * refills.len());
        for r in refills {
            let h = refill_cell(r, stride, |m| {
                let j = at[&m];
                std::array::from_fn(|i| v[Q * j + i].to_f64())
            });
            let stored = h.map(T::from_f64);
            values.extend_from_slice(&stored);
            momentum.push(momentum_of(&stored.map(|x| x.to_f64())));
        }
        let cells: Vec<u32> = refills.iter().map(|r| r.cell).collect();
        self.scatter(&cells, &values);
    }

    /// Whole neighbour cells in the halos (see
    /// [`crate::FluidBackend::refresh_halos_full`]): the device's halo fills, then the
    /// edge columns travel through the host's halo exchange.
    pub(crate) fn halos_full(&mut self, comm: &dyn Comm) {
        crate::FluidBackend::update_boundaries(self);
        self.flush();
        let host = self.host_mut();
        let sides = host.exchanged_faces();
        if sides == [false, false] {
            return;
        }
        let (nx, ny, stride, plane, cur) = (host.nx, host.ny, host.stride, host.plane, host.cur);
        // Padded columns of the exchanged sides: (edge, halo).
        let columns: Vec<(usize, usize)> = [(1, 0), (nx, nx + 1)]
            .into_iter()
            .zip(sides)
            .filter_map(|(c, on)| on.then_some(c))
            .collect();
        let cells = |pick: fn(&(usize, usize)) -> usize| -> Vec<u32> {
            columns
                .iter()
                .flat_map(|c| (0..ny + 2).map(move |yp| (yp * stride + pick(c)) as u32))
                .collect()
        };
        let edges = cells(|c| c.0);
        let v = self.gather(&edges);
        let host = self.host_mut();
        for (j, &k) in edges.iter().enumerate() {
            for i in 0..Q {
                host.buf[cur][i * plane + k as usize] = v[Q * j + i];
            }
        }
        host.refresh_exchange_full(comm);
        let halos = cells(|c| c.1);
        let host = self.host_mut();
        let values: Vec<T> = halos
            .iter()
            .flat_map(|&k| (0..Q).map(move |i| (i, k)))
            .map(|(i, k)| host.buf[cur][i * plane + k as usize])
            .collect();
        self.scatter(&halos, &values);
    }
}
