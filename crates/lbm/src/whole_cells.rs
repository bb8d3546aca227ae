//! Whole cells of the current state between steps, in either layout (two arrays, or in place
//! after a local or a push step): what moving surfaces read and write when they cover or
//! uncover cells (`coupling/handover.rs`). Every access goes through [`Access::own`], so the
//! same logical values are read and written whatever the layout, and a coupled run gives the
//! same bits with either kernel.
//!
//! In place, a halo cell's nine values are not all stored (each step keeps only the ones a
//! cell pulls): they are evaluated by the two-array kernel's halo rules from the interior
//! (periodic, free-slip, outflow), and across rank faces taken from the neighbours' edge
//! columns exchanged by [`Lattice::refresh_exchange_full`].

use super::aligned::Disjoint;
use super::d2q9::Q;
use super::lattice::{Face, FaceCondition, Lattice};
use super::moving::{equilibrium_at, momentum_of, refill_cell, Refill};
use super::real::Real;
use decomposition::{pack_words, unpack_words, Comm, Side};
use rayon::prelude::*;

impl<T: Real> Lattice<T> {
    /// Density of padded interior cell `k` in the current state.
    pub(crate) fn density_at(&self, k: usize) -> f64 {
        let (buf, acc) = (&self.buf[self.cur], self.access());
        1.0 + (0..Q).map(|i| buf[acc.own(i, k)].to_f64()).sum::<f64>()
    }

    /// Set each of `cells` (padded interior cells, each at most once) in the current state
    /// to the equilibrium at ρ = 1 and the matching velocity (the fluid at rest inside a
    /// solid).
    pub fn set_rest(&mut self, cells: &[u32], velocity: &[[f64; 2]]) {
        let acc = self.access();
        let buf = Disjoint(self.buf[self.cur].as_mut_ptr());
        cells
            .par_iter()
            .zip(velocity.par_iter())
            .with_min_len(1024)
            .for_each(|(&k, &u)| {
                let eq = equilibrium_at(0.0, u);
                for (i, v) in eq.iter().enumerate() {
                    // SAFETY: each cell is listed once, and each (direction, cell) has its
                    // own slot in every layout.
                    unsafe { buf.write(acc.own(i, k as usize), T::from_f64(*v)) };
                }
            });
    }

    /// Σ h_i c_i of each of `cells` (padded interior cells) in the current state.
    pub fn momentum_of_cells(&self, cells: &[u32], out: &mut Vec<[f64; 2]>) {
        let (buf, acc) = (&self.buf[self.cur], self.access());
        out.clear();
        out.extend(cells.iter().map(|&k| {
            let h: [f64; Q] = std::array::from_fn(|i| buf[acc.own(i, k as usize)].to_f64());
            momentum_of(&h)
        }));
    }

    /// Rebuild each cell of `refills` as [`refill_cell`] says, reading whole neighbour cells
    /// (halo ones too: call [`Lattice::update_boundaries`] and
    /// [`Lattice::refresh_exchange_full`] first). `momentum[r]` receives Σ h_i c_i of the
    /// new cell. Precondition: no refilled cell is a listed neighbour of another.
    pub fn apply_refills(&mut self, refills: &[Refill], momentum: &mut Vec<[f64; 2]>) {
        let (stride, acc) = (self.stride, self.access());
        momentum.clear();
        for r in refills {
            let h = refill_cell(r, stride, |m| self.whole_cell(m));
            let mut stored = [0.0; Q];
            for i in 0..Q {
                let v = T::from_f64(h[i]);
                self.buf[self.cur][acc.own(i, r.cell as usize)] = v;
                stored[i] = v.to_f64();
            }
            momentum.push(momentum_of(&stored));
        }
    }

    /// All nine post-collision values of padded cell `m` (halo cells included) in the
    /// current state.
    pub(crate) fn whole_cell(&self, m: usize) -> [f64; Q] {
        if !self.in_place() {
            // Two arrays: the halo cells hold whole cells after the refreshes.
            let buf = &self.buf[self.cur];
            return std::array::from_fn(|j| buf[j * self.plane + m].to_f64());
        }
        let (x, y) = ((m % self.stride) as i64 - 1, (m / self.stride) as i64 - 1);
        std::array::from_fn(|j| self.own_anywhere(x, y, j).to_f64())
    }

    /// In place: cell (x, y)'s post-collision value in direction `s` (local, −1 ≤ x ≤ nx,
    /// −1 ≤ y ≤ ny) as the two-array kernel's halo would hold it: the y faces' rules first,
    /// then the x faces' (as `fill_halo` composes them at the corners), rank faces from the
    /// last full exchange; zero for wall and open halos, which are never read as fluid.
    fn own_anywhere(&self, x: i64, y: i64, s: usize) -> T {
        let outside_x = x < 0 || x >= self.nx as i64;
        let x_face = if x < 0 { Face::West } else { Face::East };
        if outside_x && self.faces[x_face as usize] == FaceCondition::Exchange {
            let side = (x >= 0) as usize;
            let rows = self.ny + 2;
            return self.full_halo[side]
                .get(s * rows + (y + 1) as usize)
                .copied()
                .unwrap_or_default();
        }
        // The drain's resolution of the face rules (which never reaches an exchanged face
        // from inside the slab).
        match self.halo_index(x, y, s) {
            super::inplace::NONE => T::default(),
            at => self.buf[0][at],
        }
    }

    /// In place: [`Lattice::refresh_exchange_full`], into `full_halo` (the halo cells' slots
    /// hold other values in this layout). Collective when the slab has neighbours.
    pub(crate) fn refresh_exchange_full_in_place(&mut self, comm: &dyn Comm) {
        let (nx, rows) = (self.nx as i64, self.ny + 2);
        self.halo.set_message_bytes(Q * rows * T::BYTES);
        for (side, x) in [(Side::Left, 0), (Side::Right, nx - 1)] {
            if self.halo.peer(side).is_none() {
                continue;
            }
            // The edge column's padded rows as the two-array kernel sends them (its y
            // halos filled by the y faces' rules).
            let values: Vec<T> = (0..Q)
                .flat_map(|i| (-1..=self.ny as i64).map(move |y| (i, y)))
                .map(|(i, y)| self.own_anywhere(x, y, i))
                .collect();
            pack_words(self.halo.send_mut(side), values);
        }
        let mut halo = std::mem::take(&mut self.halo);
        self.halo_wait_s += halo.exchange(comm, &mut || {});
        self.halo = halo;
        for (n, side) in [Side::Left, Side::Right].into_iter().enumerate() {
            self.full_halo[n].clear();
            if self.halo.peer(side).is_none() {
                continue;
            }
            let data = self.halo.recv(side);
            self.full_halo[n].extend(unpack_words::<T>(data).take(Q * rows));
        }
        self.halo
            .set_message_bytes(super::lattice::HALO_DIRS * rows * T::BYTES);
    }
}
