//! The fluid side of the coupling: after each stream–collide sweep, the cells next to
//! grains (bounce-back schemes) or inside them (partially saturated method) are recomputed
//! from the previous buffer with the grains' surfaces applied, and the momentum they hand
//! to each grain is summed in a fixed order. Between steps, cells that a moving grain
//! covers or uncovers are handed over with their momentum.
//!
//! Momentum is counted on the shifted populations (h = f − w). The rest state's part
//! (ρ₀ c_s² on the surface) integrates to zero over a closed surface, and leaving it out is
//! what makes fluid + grain momentum conserved to round-off (tested).

use super::map::{cover, shares, GrainView, Share, SlabFrame, NONE};
use super::{Refill, Scheme};
use crate::lbm::collision::{equilibrium, Moments};
use crate::lbm::d2q9::{CX, CY, OPP, Q, W};
use crate::lbm::{Lattice, Real};
use rayon::prelude::*;
use thiserror::Error;

/// A coupled step that cannot go on.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CouplingError {
    /// A cell next to or inside a grain went NaN or non-positive.
    #[error("unstable at step {step}: cell ({x}, {y}) next to grain {grain} has density {density} (NaN or ≤ 0); lower the grains' speed in lattice units (smaller time step), raise τ, or refine the lattice")]
    Unstable {
        /// Fluid step.
        step: u64,
        /// Global cell x.
        x: usize,
        /// Cell y.
        y: usize,
        /// Grain id.
        grain: u64,
        /// The offending density.
        density: f64,
    },
    /// A grain left the fluid domain (through an open or periodic face).
    #[error("at step {step}: grain {grain} left the fluid domain at {position:?} m; grains cannot cross open or periodic faces yet: close the domain with walls or keep the grains away from them")]
    Left {
        /// Fluid step.
        step: u64,
        /// Grain id.
        grain: u64,
        /// Its centre (m).
        position: [f64; 2],
    },
}

/// Most grains that can act on one cell in one step (links of a boundary cell, or grains
/// overlapping a cell).
pub(super) const MAX_PER_CELL: usize = 8;

/// The shares (indices into the share list) of one cell, in grain order.
#[derive(Debug, Clone, Copy)]
pub(super) struct ShareRun {
    pub(super) cell: u32,
    pub(super) shares: [u32; MAX_PER_CELL],
    pub(super) n: u8,
}

/// One recomputed cell: its new populations (shifted), density, and the momentum it hands
/// to each grain (fx, fy, torque; lattice units).
#[derive(Debug, Clone, Copy)]
pub(super) struct CellUpdate {
    pub(super) cell: u32,
    pub(super) h: [f64; Q],
    pub(super) rho: f64,
    pub(super) n: u8,
    pub(super) links: [(u32, [f64; 3]); MAX_PER_CELL],
}

impl CellUpdate {
    pub(super) fn new(cell: u32) -> Self {
        Self {
            cell,
            h: [0.0; Q],
            rho: 1.0,
            n: 0,
            links: [(0, [0.0; 3]); MAX_PER_CELL],
        }
    }

    /// Add grain g's share; shares of one grain are merged.
    pub(super) fn push(&mut self, g: u32, p: [f64; 3]) {
        let n = self.n as usize;
        if let Some(l) = self.links[..n].iter_mut().find(|l| l.0 == g) {
            l.1[0] += p[0];
            l.1[1] += p[1];
            l.1[2] += p[2];
        } else if n < MAX_PER_CELL {
            self.links[n] = (g, p);
            self.n += 1;
        } else {
            // More than eight grains on one cell cannot happen for disks at least three
            // cells across; keep the momentum with the last one rather than lose it.
            let l = &mut self.links[MAX_PER_CELL - 1].1;
            l[0] += p[0];
            l[1] += p[1];
            l[2] += p[2];
        }
    }
}

/// Per-grain hydrodynamic force and torque of one step, lattice units (momentum per step;
/// torque about the grain's centre, per step).
pub type GrainForce = [f64; 3];

/// The coupling state of one slab.
pub struct Coupler {
    pub(super) scheme: Scheme,
    pub(super) refill: Refill,
    pub(super) frame: SlabFrame,
    /// Covering grain per padded cell (bounce-back schemes).
    pub(super) owner: Vec<u32>,
    /// The map being built for the next step (kept for its allocation).
    pub(super) next_owner: Vec<u32>,
    /// Cells (padded, halo included) set in `owner` and in `next_owner`.
    pub(super) touched: Vec<u32>,
    pub(super) next_touched: Vec<u32>,
    /// Interior exterior-fluid cells with at least one covered neighbour, increasing index.
    pub(super) boundary: Vec<u32>,
    /// Interior covered cells, increasing index.
    pub(super) covered: Vec<u32>,
    /// Solid fractions (partially saturated method).
    pub(super) shares: Vec<Share>,
    /// Cells refilled by the last remap (kept for its allocation).
    pub(super) refills: Vec<(u32, [f64; Q])>,
    /// Recomputed cells of the last exchange (kept for their allocation).
    pub(super) updates: Vec<CellUpdate>,
    /// Rest populations of the covered cells (kept for their allocation).
    pub(super) rest: Vec<[f64; Q]>,
    /// The shares of each cell (partially saturated method): indices into `shares`.
    pub(super) runs: Vec<ShareRun>,
    /// Per padded cell: its run in `runs`, or NONE (PSM), or whether it is listed in
    /// `boundary` (bounce-back schemes).
    pub(super) run_of: Vec<u32>,
    pub(super) mark: Vec<bool>,
    /// Force of the last exchange per grain.
    pub(super) force: Vec<GrainForce>,
    /// Momentum handed over by covering and uncovering since the last exchange.
    pub(super) handover: Vec<GrainForce>,
}

impl Coupler {
    /// A coupler for `grains` grains on the slab `frame`. Place the grains with
    /// [`Coupler::start`].
    pub fn new(scheme: Scheme, refill: Refill, frame: SlabFrame, grains: usize) -> Self {
        let cells = frame.stride * (frame.ny + 2);
        Self {
            refills: Vec::new(),
            scheme,
            refill,
            frame,
            owner: vec![NONE; cells],
            next_owner: vec![NONE; cells],
            touched: Vec::new(),
            next_touched: Vec::new(),
            updates: Vec::new(),
            rest: Vec::new(),
            runs: Vec::new(),
            run_of: vec![NONE; cells],
            mark: vec![false; cells],
            boundary: Vec::new(),
            covered: Vec::new(),
            shares: Vec::new(),
            force: vec![[0.0; 3]; grains],
            handover: vec![[0.0; 3]; grains],
        }
    }

    /// The interface scheme.
    pub fn scheme(&self) -> Scheme {
        self.scheme
    }

    /// Place the grains on the lattice before the first step: build the maps and, for the
    /// bounce-back schemes, fill the covered cells with equilibrium at the grain velocity.
    pub fn start<T: Real>(&mut self, lat: &mut Lattice<T>, grains: &[GrainView]) {
        self.map(lat, grains);
        self.owner.clone_from(&self.next_owner);
        self.touched.clone_from(&self.next_touched);
        self.rebuild_lists(lat);
        if self.scheme != Scheme::Psm {
            let plane = lat.plane();
            let (owner, covered, frame) = (&self.owner, &self.covered, self.frame);
            let buf = lat.current_buffer_mut();
            for &k in covered {
                let g = &grains[owner[k as usize] as usize];
                let eq = rest_at::<T>(rigid_velocity(&frame, g, frame.centre(k as usize)));
                for i in 0..Q {
                    buf[i * plane + k as usize] = eq[i];
                }
            }
        }
    }

    /// Force and torque on each grain from the last exchange plus any covering and
    /// uncovering since, lattice units.
    pub fn forces(&self) -> impl Iterator<Item = GrainForce> + '_ {
        self.force
            .iter()
            .zip(&self.handover)
            .map(|(f, h)| [f[0] + h[0], f[1] + h[1], f[2] + h[2]])
    }

    /// Cells covered by a grain now (bounce-back schemes), for output masks: padded indices.
    pub fn covered_cells(&self) -> &[u32] {
        &self.covered
    }

    /// Solid fraction of every interior cell (padded index → Σ ε, capped at 1).
    pub fn solid_fraction(&self, out: &mut [f64]) {
        out.fill(0.0);
        match self.scheme {
            Scheme::Psm => {
                for s in &self.shares {
                    let e = &mut out[s.cell as usize];
                    *e = (*e + s.fraction).min(1.0);
                }
            }
            _ => {
                for &k in &self.covered {
                    out[k as usize] = 1.0;
                }
            }
        }
    }

    /// Build the next map (owners or shares) for the grains at their current positions.
    pub(super) fn map<T: Real>(&mut self, lat: &Lattice<T>, grains: &[GrainView]) {
        let fluid = |k: usize| lat.is_fluid_at(k);
        match self.scheme {
            Scheme::Psm => shares(&self.frame, grains, fluid, &mut self.shares),
            _ => cover(
                &self.frame,
                grains,
                fluid,
                &mut self.next_owner,
                &mut self.next_touched,
            ),
        }
    }

    /// Covered and boundary cell lists from `owner`.
    pub(super) fn rebuild_lists<T: Real>(&mut self, lat: &Lattice<T>) {
        for &k in &self.boundary {
            self.mark[k as usize] = false;
        }
        self.covered.clear();
        self.boundary.clear();
        if self.scheme == Scheme::Psm {
            return;
        }
        let f = self.frame;
        let interior = |k: usize| {
            let (x, y) = f.local(k);
            x >= 0 && y >= 0 && x < f.nx as i64 && y < f.ny as i64
        };
        // Every boundary cell neighbours a covered cell (halo ones included); each is listed
        // once, in the order the covered cells were set (fixed).
        for &k in &self.touched {
            let k = k as usize;
            if interior(k) {
                self.covered.push(k as u32);
            }
            for i in 1..Q {
                let n = neighbour(&f, k, i, 1);
                if interior(n) && self.owner[n] == NONE && lat.is_fluid_at(n) && !self.mark[n] {
                    self.mark[n] = true;
                    self.boundary.push(n as u32);
                }
            }
        }
    }

    /// Stage "coupling", fluid side: recompute the cells at the grains' surfaces in the
    /// buffer the sweep just wrote, and record the momentum each grain receives. Call after
    /// [`Lattice::stream_collide`] and before [`Lattice::update_boundaries`].
    pub fn exchange<T: Real>(
        &mut self,
        lat: &mut Lattice<T>,
        grains: &[GrainView],
        ids: &[u64],
    ) -> Result<(), CouplingError> {
        for f in &mut self.force {
            *f = [0.0; 3];
        }
        match self.scheme {
            Scheme::Psm => self.exchange_psm(lat, grains, ids),
            _ => self.exchange_links(lat, grains, ids),
        }
    }

    fn exchange_links<T: Real>(
        &mut self,
        lat: &mut Lattice<T>,
        grains: &[GrainView],
        ids: &[u64],
    ) -> Result<(), CouplingError> {
        let f = self.frame;
        let plane = lat.plane();
        let interpolated = self.scheme == Scheme::Interpolated;
        let step = lat.steps_done();
        // Recompute each boundary cell from the previous buffer (read only, in parallel),
        // then write them and sum the grains' forces in cell order (fixed, so the sums do
        // not depend on the thread count).
        let mut updates = std::mem::take(&mut self.updates);
        {
            let (lat, owner) = (&*lat, &self.owner);
            let prev = lat.previous_buffer();
            self.boundary
                .par_iter()
                .with_min_len(64)
                .map(|&kb| {
                    let k = kb as usize;
                    let (x, y) = f.local(k);
                    let mut h = lat.gather_previous(x as usize, y as usize);
                    let centre = f.centre(k);
                    let mut u = CellUpdate::new(kb);
                    for i in 1..Q {
                        let n = neighbour(&f, k, i, -1);
                        let g = owner[n];
                        if g == NONE {
                            continue;
                        }
                        let grain = &grains[g as usize];
                        let (cx, cy) = (CX[i] as f64, CY[i] as f64);
                        let mid = [centre[0] - 0.5 * cx, centre[1] - 0.5 * cy];
                        let c = super::map::nearest_image(&f, grain, mid);
                        let ub = GrainView {
                            centre: c,
                            ..*grain
                        }
                        .surface_velocity(mid);
                        // Ladd 1994 moving-wall term 2 w_i ρ_w (c_i·u_b)/c_s², ρ_w = 1 (seed eq. 5.45).
                        let ladd = 6.0 * W[i] * (cx * ub[0] + cy * ub[1]);
                        let out_i = prev[OPP[i] * plane + k].to_f64();
                        let hi = if interpolated {
                            let q =
                                super::geometry::link_fraction(centre, [-cx, -cy], c, grain.radius);
                            let ff = neighbour(&f, k, i, 1);
                            if q < 0.5 && lat.is_fluid_at(ff) && owner[ff] == NONE {
                                // Bouzidi, Firdaouss & Lallemand 2001, eq. 5 (q < ½), moving wall.
                                2.0 * q * out_i
                                    + (1.0 - 2.0 * q) * prev[OPP[i] * plane + ff].to_f64()
                                    + ladd
                            } else if q >= 0.5 {
                                // Bouzidi et al. 2001, eq. 5 (q ≥ ½).
                                let same = prev[i * plane + k].to_f64();
                                (out_i + (2.0 * q - 1.0) * same + ladd) / (2.0 * q)
                            } else {
                                out_i + ladd
                            }
                        } else {
                            out_i + ladd
                        };
                        h[i] = T::from_f64(hi);
                        // The grain receives −(f*_ī + f_i) c_i (seed eq. 5.47), torque about
                        // its centre at the link's midpoint (eq. 5.48).
                        let m = out_i + h[i].to_f64();
                        let (px, py) = (-m * cx, -m * cy);
                        let r = [mid[0] - c[0], mid[1] - c[1]];
                        u.push(g, [px, py, r[0] * py - r[1] * px]);
                    }
                    let m = lat.collide_one(&mut h);
                    u.rho = m.rho.to_f64();
                    u.h = h.map(|v| v.to_f64());
                    u
                })
                .collect_into_vec(&mut updates);
        }
        let bad = self.apply(lat, &updates);
        self.updates = updates;
        // The fluid under a grain rests at its velocity (read by nothing but the refill).
        let owner = &self.owner;
        let mut rest = std::mem::take(&mut self.rest);
        self.covered
            .par_iter()
            .with_min_len(256)
            .map(|&k| {
                let g = &grains[owner[k as usize] as usize];
                rest_at::<f64>(rigid_velocity(&f, g, f.centre(k as usize)))
            })
            .collect_into_vec(&mut rest);
        let buf = lat.current_buffer_mut();
        for (&k, eq) in self.covered.iter().zip(&rest) {
            for i in 0..Q {
                buf[i * plane + k as usize] = T::from_f64(eq[i]);
            }
        }
        self.rest = rest;
        if let Some((k, density)) = bad {
            return Err(self.unstable(step, k, density, grains, ids));
        }
        Ok(())
    }

    /// Write recomputed cells and add their momentum to the grains, in list order. Returns
    /// the first cell whose density is NaN or non-positive.
    pub(super) fn apply<T: Real>(
        &mut self,
        lat: &mut Lattice<T>,
        updates: &[CellUpdate],
    ) -> Option<(usize, f64)> {
        let plane = lat.plane();
        let buf = lat.current_buffer_mut();
        let mut bad = None;
        for u in updates {
            let k = u.cell as usize;
            for i in 0..Q {
                buf[i * plane + k] = T::from_f64(u.h[i]);
            }
            for &(g, p) in &u.links[..u.n as usize] {
                let acc = &mut self.force[g as usize];
                acc[0] += p[0];
                acc[1] += p[1];
                acc[2] += p[2];
            }
            if !(u.rho > 0.0) && bad.is_none() {
                bad = Some((k, u.rho));
            }
        }
        bad
    }

    pub(super) fn unstable(
        &self,
        step: u64,
        k: usize,
        density: f64,
        grains: &[GrainView],
        ids: &[u64],
    ) -> CouplingError {
        let p = self.frame.centre(k);
        let nearest = (0..grains.len())
            .min_by(|&a, &b| {
                let d = |g: usize| {
                    let c = super::map::nearest_image(&self.frame, &grains[g], p);
                    (c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2)
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap_or(0);
        let (x, y) = self.frame.local(k);
        CouplingError::Unstable {
            step,
            x: (x + self.frame.x0 as i64) as usize,
            y: y as usize,
            grain: ids.get(nearest).copied().unwrap_or(0),
            density,
        }
    }
}

/// Velocity of grain `g`'s rigid motion at point `p`, about its image nearest to `p`.
#[inline]
pub(super) fn rigid_velocity(f: &SlabFrame, g: &GrainView, p: [f64; 2]) -> [f64; 2] {
    let c = super::map::nearest_image(f, g, p);
    GrainView { centre: c, ..*g }.surface_velocity(p)
}

/// Padded index of the neighbour of `k` at `sign · c_i`.
#[inline]
pub(super) fn neighbour(f: &SlabFrame, k: usize, i: usize, sign: i64) -> usize {
    (k as i64 + sign * (CX[i] as i64 + CY[i] as i64 * f.stride as i64)) as usize
}

/// Σ h_i c_i of padded cell `k`.
pub(super) fn momentum<T: Real>(buf: &[T], plane: usize, k: usize) -> [f64; 2] {
    let mut j = [0.0; 2];
    for i in 1..Q {
        let h = buf[i * plane + k].to_f64();
        j[0] += h * CX[i] as f64;
        j[1] += h * CY[i] as f64;
    }
    j
}

/// Density and velocity of shifted populations (no force correction).
pub(super) fn moments_of(h: &[f64; Q]) -> Moments<f64> {
    let drho: f64 = h.iter().sum();
    let j = momentum(h, 1, 0);
    let rho = 1.0 + drho;
    Moments {
        drho,
        rho,
        ux: j[0] / rho,
        uy: j[1] / rho,
    }
}

/// Shifted equilibrium at ρ = 1 and velocity u.
pub(super) fn rest_at<T: Real>(u: [f64; 2]) -> [T; Q] {
    equilibrium(&Moments {
        drho: 0.0,
        rho: 1.0,
        ux: u[0],
        uy: u[1],
    })
    .map(T::from_f64)
}
