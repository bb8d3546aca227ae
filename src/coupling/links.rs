//! Bounce-back schemes: the fluid cells next to a grain (its *boundary*), the plan of their
//! links to it, and the loads they hand to each grain.

use super::exchange::{neighbour, Coupler, Unstable};
use super::gather::{gather2, gather_chunked, group_by_row};
use super::map::{nearest_image, GrainView, NONE};
use super::Scheme;
use crate::lbm::d2q9::{CX, CY, Q, W};
use crate::lbm::moving::MovingLink;
use crate::lbm::{Lattice, Real};

impl Coupler {
    /// The covered and boundary cell lists from `owner` (for the grains `views` it was
    /// built from). Covered: `touched` restricted to interior cells. Boundary: grain by grain
    /// (id order), each image's cells in row order, the interior fluid cells no grain covers
    /// that neighbour a cell of that grain; a cell next to several grains is listed with the
    /// first. Both orders are the restriction of a partition-independent order.
    pub(super) fn rebuild_lists<T: Real>(&mut self, lat: &Lattice<T>, views: &[GrainView]) {
        self.covered.clear();
        self.boundary.clear();
        self.boundary_mask.clear();
        if self.scheme == Scheme::Psm {
            return;
        }
        let f = self.frame;
        let interior = |k: usize| {
            let (x, y) = f.local(k);
            x >= 0 && y >= 0 && x < f.nx as i64 && y < f.ny as i64
        };
        self.covered.extend(
            self.touched
                .iter()
                .copied()
                .filter(|&k| interior(k as usize)),
        );
        let owner = &self.owner;
        let fluid = |k: usize| lat.is_fluid_at(k);
        gather_chunked(views.len(), &mut self.chunks, |g, out| {
            boundary_of(&f, owner, &fluid, views, g, |k, mask| {
                out.push((k as u32, mask))
            });
        });
        for &(k, mask) in self.chunks.iter().flatten() {
            if !self.mark[k as usize] {
                self.mark[k as usize] = true;
                self.boundary.push(k);
                self.boundary_mask.push(mask);
            }
        }
        for &k in &self.boundary {
            self.mark[k as usize] = false;
        }
    }

    /// Plan the boundary cells' links (half-way or interpolated bounce-back with the grain's
    /// surface velocity), grouped by row for the sweep.
    pub(super) fn plan_links<T: Real>(&mut self, lat: &Lattice<T>, views: &[GrainView]) {
        let f = self.frame;
        let interpolated = self.scheme == Scheme::Interpolated;
        let (owner, boundary, masks) = (&self.owner, &self.boundary, &self.boundary_mask);
        group_by_row(
            boundary.len(),
            f.ny,
            |c| f.local(boundary[c] as usize).1 as usize,
            &mut self.links.rows,
            &mut self.order,
        );
        let order = &self.order;
        // One pass per cell to count its links, one to write them (in parallel, in order).
        gather2(
            order.len(),
            &mut self.links.start,
            &mut self.links.links,
            &mut self.link_grain,
            |c| masks[order[c] as usize].count_ones() as usize,
            |c, out, own| {
                let k = boundary[order[c] as usize] as usize;
                let mask = masks[order[c] as usize];
                let centre = f.centre(k);
                let dirs = (1..Q).filter(|&i| mask & (1 << (i - 1)) != 0);
                for (at, i) in dirs.enumerate() {
                    let g = owner[neighbour(&f, k, i, -1)];
                    let grain = &views[g as usize];
                    let (cx, cy) = (CX[i] as f64, CY[i] as f64);
                    let (mid, image) = link_midpoint(&f, centre, i, grain);
                    let ub = GrainView {
                        centre: image,
                        ..*grain
                    }
                    .surface_velocity(mid);
                    let q = if interpolated {
                        let q =
                            super::geometry::link_fraction(centre, [-cx, -cy], image, grain.radius);
                        let ff = neighbour(&f, k, i, 1);
                        // Interpolation below ½ needs a plain fluid cell upstream.
                        if q < 0.5 && !(lat.is_fluid_at(ff) && owner[ff] == NONE) {
                            0.5
                        } else {
                            q
                        }
                    } else {
                        0.5
                    };
                    out[at] = MovingLink {
                        dir: i as u8,
                        q,
                        // Ladd 1994 moving-wall term 2 w_i ρ_w (c_i·u_b)/c_s², ρ_w = 1
                        // (seed eq. 5.45).
                        wall: 6.0 * W[i] * (cx * ub[0] + cy * ub[1]),
                    };
                    own[at] = g;
                }
            },
        );
        self.links.cells.clear();
        self.links
            .cells
            .extend(order.iter().map(|&o| boundary[o as usize]));
    }

    /// Add each link's momentum (as the sweep reported it) to its grain's column sums, in
    /// plan order: the grain receives −(f*_ī + f_i) c_i (seed eq. 5.47) at the link's
    /// midpoint (torque, eq. 5.48). Maps the first bad plan cell to (cell, grain, density).
    pub(super) fn collect_links(
        &mut self,
        views: &[GrainView],
        bad: Option<(usize, f64)>,
    ) -> Option<Unstable> {
        let f = self.frame;
        for (c, &k) in self.links.cells.iter().enumerate() {
            let col = self.column(k as usize);
            let centre = f.centre(k as usize);
            for l in self.links.start[c] as usize..self.links.start[c + 1] as usize {
                let (i, m) = (self.links.links[l].dir as usize, self.link_momentum[l]);
                let g = self.link_grain[l] as usize;
                let (cx, cy) = (CX[i] as f64, CY[i] as f64);
                let (mid, image) = link_midpoint(&f, centre, i, &views[g]);
                let arm = [mid[0] - image[0], mid[1] - image[1]];
                let (px, py) = (-m * cx, -m * cy);
                let load = [px, py, arm[0] * py - arm[1] * px];
                self.sums.add(g, views[g].centre[0], image[0], col, load);
            }
        }
        bad.map(|(c, rho)| {
            let l = self.links.start[c] as usize;
            (self.links.cells[c] as usize, self.link_grain[l], rho)
        })
    }
}

/// The midpoint of the link from the cell centred at `centre` along −c_i (where the
/// half-way wall sits) and the image of `grain` nearest to it: the plan and the load
/// collection both use this, so a link's velocity and its torque arm agree to the bit.
#[inline]
fn link_midpoint(
    f: &super::map::SlabFrame,
    centre: [f64; 2],
    i: usize,
    grain: &GrainView,
) -> ([f64; 2], [f64; 2]) {
    let mid = [
        centre[0] - 0.5 * CX[i] as f64,
        centre[1] - 0.5 * CY[i] as f64,
    ];
    (mid, nearest_image(f, grain, mid))
}

/// Visit the boundary cells of grain `g` (see [`Coupler::rebuild_lists`]) in order, each
/// with its link mask: bit i − 1 set where the neighbour at x − c_i is covered (by any
/// grain).
fn boundary_of(
    f: &super::map::SlabFrame,
    owner: &[u32],
    fluid: &impl Fn(usize) -> bool,
    views: &[GrainView],
    g: usize,
    mut visit: impl FnMut(usize, u8),
) {
    let grain = &views[g];
    for c in f.images(grain) {
        f.for_box(c, grain.radius + 1.0, |k, x, y| {
            let interior = x >= 0 && y >= 0 && x < f.nx as i64 && y < f.ny as i64;
            if interior
                && owner[k] == NONE
                && fluid(k)
                && (1..Q).any(|i| owner[neighbour(f, k, i, -1)] == g as u32)
            {
                let covered = |i: usize| owner[neighbour(f, k, i, -1)] != NONE;
                let mask = (1..Q).fold(0u8, |m, i| m | ((covered(i) as u8) << (i - 1)));
                visit(k, mask);
            }
        });
    }
}
