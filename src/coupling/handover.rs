//! Between fluid steps: the grains have moved, so the cells they cover change hands. A cell a
//! grain newly covers gives its fluid momentum to the grain (Aidun, Lu & Ding 1998); a cell it
//! uncovers is refilled and its momentum is taken from the grain. Also the fluid half of the
//! momentum balance.

use super::exchange::{moments_of, momentum, neighbour, rigid_velocity, Coupler};
use super::map::{GrainView, NONE};
use super::{Refill, Scheme};
use crate::lbm::collision::{equilibrium, Moments};
use crate::lbm::d2q9::{CX, CY, Q};
use crate::lbm::{Lattice, Real};

impl Coupler {
    /// Stage "coupling", after the grains moved: map them again. A fluid cell that a grain
    /// now covers hands its momentum to the grain; a cell a grain uncovers is refilled
    /// (equilibrium at the surface velocity with its fluid neighbours' mean density, plus
    /// their non-equilibrium part with [`Refill::Extrapolation`]) and its momentum is taken
    /// from the grain. Both are added to the next step's force. Call before
    /// [`Lattice::update_boundaries`].
    pub fn remap<T: Real>(&mut self, lat: &mut Lattice<T>, grains: &[GrainView]) {
        for h in &mut self.handover {
            *h = [0.0; 3];
        }
        self.map(lat, grains);
        if self.scheme == Scheme::Psm {
            return;
        }
        let f = self.frame;
        let plane = lat.plane();
        let mut refills = std::mem::take(&mut self.refills);
        refills.clear();
        {
            let buf = lat.current_buffer();
            // Only cells covered before (uncovered now) or after (covered now) can change
            // hands: a cell in both lists changes in at most one of them. The lists' order is
            // fixed, so is every sum.
            let interior = |k: &u32| {
                let (x, y) = f.local(*k as usize);
                x >= 0 && y >= 0 && x < f.nx as i64 && y < f.ny as i64
            };
            let (covered, touched) = (
                std::mem::take(&mut self.covered),
                std::mem::take(&mut self.next_touched),
            );
            let changed = covered
                .iter()
                .chain(touched.iter().filter(|k| interior(k)))
                .copied();
            for k in changed {
                let k = k as usize;
                {
                    let (old, new) = (self.owner[k], self.next_owner[k]);
                    if old == new {
                        continue;
                    }
                    let p = f.centre(k);
                    if old == NONE {
                        // Covered: the grain takes the cell's momentum (Aidun, Lu & Ding 1998).
                        let j = momentum(buf, plane, k);
                        self.hand(new, grains, p, j, 1.0);
                    } else if new == NONE {
                        let g = &grains[old as usize];
                        let h = self.refill_cell(buf, plane, k, g, p, |m| lat.is_fluid_at(m));
                        let j = momentum(&h, 1, 0);
                        self.hand(old, grains, p, j, -1.0);
                        refills.push((k as u32, h.map(|v| v.to_f64())));
                    }
                }
            }
            self.covered = covered;
            self.next_touched = touched;
        }
        let buf = lat.current_buffer_mut();
        for (k, h) in &refills {
            for i in 0..Q {
                buf[i * plane + *k as usize] = T::from_f64(h[i]);
            }
        }
        self.refills = refills;
        std::mem::swap(&mut self.owner, &mut self.next_owner);
        std::mem::swap(&mut self.touched, &mut self.next_touched);
        self.rebuild_lists(lat);
    }

    /// Add `sign · j` (momentum at point p) to grain g's handover.
    fn hand(&mut self, g: u32, grains: &[GrainView], p: [f64; 2], j: [f64; 2], sign: f64) {
        let c = super::map::nearest_image(&self.frame, &grains[g as usize], p);
        let r = [p[0] - c[0], p[1] - c[1]];
        let h = &mut self.handover[g as usize];
        h[0] += sign * j[0];
        h[1] += sign * j[1];
        h[2] += sign * (r[0] * j[1] - r[1] * j[0]);
    }

    /// Populations for a cell that grain `g` has just uncovered.
    fn refill_cell<T: Real>(
        &self,
        buf: &[T],
        plane: usize,
        k: usize,
        g: &GrainView,
        p: [f64; 2],
        fluid: impl Fn(usize) -> bool,
    ) -> [T; Q] {
        let f = self.frame;
        let u = rigid_velocity(&f, g, p);
        let mut rho_sum = 0.0;
        let mut n = 0;
        let c = super::map::nearest_image(&f, g, p);
        let normal = [p[0] - c[0], p[1] - c[1]];
        let mut along: Option<(f64, usize)> = None;
        let (x, y) = f.local(k);
        for i in 1..Q {
            let (xm, ym) = (x + CX[i] as i64, y + CY[i] as i64);
            let m = neighbour(&f, k, i, 1);
            let interior = xm >= 0 && ym >= 0 && xm < f.nx as i64 && ym < f.ny as i64;
            if !interior || !fluid(m) || !self.is_exterior_fluid(m) {
                continue;
            }
            rho_sum += 1.0 + (0..Q).map(|j| buf[j * plane + m].to_f64()).sum::<f64>();
            n += 1;
            let dot = (CX[i] as f64 * normal[0] + CY[i] as f64 * normal[1])
                / ((CX[i] * CX[i] + CY[i] * CY[i]) as f64).sqrt();
            if along.is_none_or(|(d, _)| dot > d) {
                along = Some((dot, m));
            }
        }
        let rho = if n > 0 { rho_sum / n as f64 } else { 1.0 };
        let eq = equilibrium(&Moments {
            drho: rho - 1.0,
            rho,
            ux: u[0],
            uy: u[1],
        });
        let mut h = eq;
        if let (Refill::Extrapolation, Some((_, m))) = (self.refill, along) {
            // Caiazzo 2005: f = f^eq(ρ̄, u_s) + f^neq of the fluid neighbour along the normal.
            let hm: [f64; Q] = std::array::from_fn(|j| buf[j * plane + m].to_f64());
            let eq_m = equilibrium(&moments_of(&hm));
            for j in 0..Q {
                h[j] += hm[j] - eq_m[j];
            }
        }
        h.map(T::from_f64)
    }

    /// Whether padded cell `k` is fluid that no grain covers (under the map being built).
    fn is_exterior_fluid(&self, k: usize) -> bool {
        self.next_owner[k] == NONE && self.owner[k] == NONE
    }

    /// Momentum of the fluid in the interior cells no grain covers (lattice units), summed
    /// row by row: the fluid half of the momentum balance.
    pub fn fluid_momentum<T: Real>(&self, lat: &Lattice<T>) -> [f64; 2] {
        let f = self.frame;
        let buf = lat.current_buffer();
        let plane = lat.plane();
        let mut total = [0.0; 2];
        for y in 0..f.ny as i64 {
            for x in 0..f.nx as i64 {
                let k = f.padded(x, y);
                if !lat.is_fluid_at(k) || (self.scheme != Scheme::Psm && self.owner[k] != NONE) {
                    continue;
                }
                let j = momentum(buf, plane, k);
                total[0] += j[0];
                total[1] += j[1];
            }
        }
        total
    }
}
