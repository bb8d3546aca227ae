//! Bounce-back schemes: the fluid cells next to a grain (its *boundary*), the plan of their
//! links to it, and the loads they hand to each grain.

use super::exchange::{neighbour, Coupler, Unstable};
use super::gather::{gather2, group_by_row};
use super::map::{nearest_image, GrainView, NONE};
use super::Scheme;
use crate::lbm::d2q9::{CX, CY, Q, W};
use crate::lbm::moving::MovingLink;
use crate::lbm::{Lattice, Real};

impl Coupler {
    /// The boundary cell list from `owner` (for the grains `views` it was built from):
    /// grain by grain (id order), each image's cells in row order, the interior fluid cells
    /// no grain covers that neighbour a cell of that grain; a cell next to several grains is
    /// listed with the first (`boundary_lists::boundary_of`). The order is the restriction
    /// of a partition-independent order. Each grain's cells are rescanned only where the
    /// last remap could have changed them (see `boundary_lists.rs`).
    pub(super) fn rebuild_lists<T: Real>(&mut self, lat: &Lattice<T>, views: &[GrainView]) {
        self.boundary.clear();
        self.boundary_mask.clear();
        self.boundary_row.clear();
        if self.scheme == Scheme::Psm {
            return;
        }
        let f = self.frame;
        let owner = &self.owner;
        let fluid = |k: usize| lat.is_fluid_at(k);
        let boundary = &mut self.boundary;
        let (masks, rows) = (&mut self.boundary_mask, &mut self.boundary_row);
        self.lists
            .rebuild(&f, owner, &fluid, views, |(k, mask, y)| {
                boundary.push(k);
                masks.push(mask);
                rows.push(y);
            });
    }

    /// Plan the boundary cells' links (half-way or interpolated bounce-back with the grain's
    /// surface velocity), grouped by row for the sweep.
    pub(super) fn plan_links<T: Real>(&mut self, lat: &Lattice<T>, views: &[GrainView]) {
        let f = self.frame;
        let interpolated = self.scheme == Scheme::Interpolated;
        let (owner, boundary, masks) = (&self.owner, &self.boundary, &self.boundary_mask);
        let rows = &self.boundary_row;
        group_by_row(
            boundary.len(),
            f.ny,
            |c| rows[c] as usize,
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
                let b = order[c] as usize;
                let k = boundary[b] as usize;
                let mask = masks[b];
                let centre = f.centre_in_row(k, rows[b] as usize);
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
                        // Interpolation below ½ needs a plain fluid cell upstream. Both
                        // tests are evaluated and combined without a branch: which way
                        // `q < 0.5` goes is unpredictable, and it waits on a square root.
                        let upstream = lat.is_fluid_at(ff) & (owner[ff] == NONE);
                        let half = (q < 0.5) & !upstream;
                        [q, 0.5][half as usize]
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
        let rows = &self.links.rows;
        for y in 0..rows.len().saturating_sub(1) {
            for c in rows[y] as usize..rows[y + 1] as usize {
                let k = self.links.cells[c] as usize;
                let col = (f.x_in_row(k, y) + f.x0 as i64) as usize;
                let centre = f.centre_in_row(k, y);
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
