//! Bounce-back schemes: the fluid cells next to a grain (its *boundary*), the plan of their
//! links to it, and the loads they hand to each grain.

use super::boundary_lists::Entry;
use super::exchange::{neighbour, Coupler, Unstable};
use super::gather::gather2;
use super::map::{nearest_image, GrainView};
use super::Scheme;
use crate::lbm::d2q9::{CX, CY, Q, W};
use crate::lbm::moving::MovingLink;
use crate::lbm::{Lattice, Real};

impl Coupler {
    /// The boundary cell list from `owner` (for the grains `views` it was built from),
    /// grouped by row: the interior fluid cells no grain covers that neighbour a covered
    /// cell, each listed with the first grain among its neighbours' owners
    /// (`boundary_lists::boundary_of`); within a row, grain by grain (id order), each
    /// grain's cells in scan order. Each grain's cells are rescanned only where the last
    /// remap could have changed them (see `boundary_lists.rs`).
    pub(super) fn rebuild_lists<T: Real>(&mut self, lat: &Lattice<T>, views: &[GrainView]) {
        if self.scheme == Scheme::Psm {
            return;
        }
        let f = self.frame;
        let fluid = |k: usize| lat.is_fluid_at(k);
        self.lists.rebuild(&f, &self.owner, &fluid, views);
        // A stable counting sort by row: the plan then reads the list in order. Every slot
        // of the list is written below, so only its length is set first.
        let rows = &mut self.boundary_rows;
        rows.clear();
        rows.resize(f.ny + 1, 0);
        for (_, e) in self.lists.entries() {
            rows[e.row as usize + 1] += 1;
        }
        for y in 0..f.ny {
            rows[y + 1] += rows[y];
        }
        let n = rows[f.ny] as usize;
        self.boundary.resize(n, Entry::default());
        self.boundary_grain.resize(n, 0);
        self.row_next.clear();
        self.row_next.extend_from_slice(&rows[..f.ny]);
        for (g, e) in self.lists.entries() {
            let slot = &mut self.row_next[e.row as usize];
            self.boundary[*slot as usize] = *e;
            self.boundary_grain[*slot as usize] = g;
            *slot += 1;
        }
    }

    /// Plan the boundary cells' links (half-way or interpolated bounce-back with the grain's
    /// surface velocity), in the list's order (grouped by row for the sweep). The map is
    /// read only for links to a grain other than the one a cell is listed with: the lists
    /// hold the rest.
    pub(super) fn plan_links(&mut self, views: &[GrainView]) {
        let f = self.frame;
        let interpolated = self.scheme == Scheme::Interpolated;
        let (owner, boundary) = (&self.owner, &self.boundary);
        let listed = &self.boundary_grain;
        self.links.rows.clone_from(&self.boundary_rows);
        // One pass per cell to count its links, one to write them (in parallel, in order).
        gather2(
            boundary.len(),
            &mut self.links.start,
            &mut self.links.links,
            &mut self.link_grain,
            |b| boundary[b].links.count_ones() as usize,
            |b, out, own| {
                let e = boundary[b];
                let k = e.cell as usize;
                let centre = f.centre_in_row(k, e.row as usize);
                let dirs = (1..Q).filter(|&i| e.links & (1 << (i - 1)) != 0);
                for (at, i) in dirs.enumerate() {
                    let bit = 1u8 << (i - 1);
                    let g = if e.foreign & bit != 0 {
                        owner[neighbour(&f, k, i, -1)]
                    } else {
                        listed[b]
                    };
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
                        // Interpolation below ½ needs a plain fluid cell upstream. Both
                        // tests are combined without a branch: which way `q < 0.5` goes
                        // is unpredictable, and it waits on a square root.
                        let half = (q < 0.5) & (e.plain & bit == 0);
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
        self.links.cells.extend(boundary.iter().map(|e| e.cell));
    }

    /// Add each link's momentum (as the sweep reported it) to its grain's column sums, in
    /// plan order (in parallel over bands of columns): the grain receives −(f*_ī + f_i) c_i (seed eq. 5.47) at the link's
    /// midpoint (torque, eq. 5.48). Maps the first bad plan cell to (cell, grain, density).
    pub(super) fn collect_links(
        &mut self,
        views: &[GrainView],
        bad: Option<(usize, f64)>,
    ) -> Option<Unstable> {
        let f = self.frame;
        let (plan, grains, momentum) = (&self.links, &self.link_grain, &self.link_momentum);
        let rows = &plan.rows;
        let columns = f.x0..f.x0 + f.nx;
        self.sums
            .fill_by_columns(columns.start, columns.end, |band, sums| {
                for y in 0..rows.len().saturating_sub(1) {
                    for c in rows[y] as usize..rows[y + 1] as usize {
                        let k = plan.cells[c] as usize;
                        let col = (f.x_in_row(k, y) + f.x0 as i64) as usize;
                        if !band.contains(&col) {
                            continue;
                        }
                        let centre = f.centre_in_row(k, y);
                        for l in plan.start[c] as usize..plan.start[c + 1] as usize {
                            let (i, m) = (plan.links[l].dir as usize, momentum[l]);
                            let g = grains[l] as usize;
                            let (cx, cy) = (CX[i] as f64, CY[i] as f64);
                            let (mid, image) = link_midpoint(&f, centre, i, &views[g]);
                            let arm = [mid[0] - image[0], mid[1] - image[1]];
                            let (px, py) = (-m * cx, -m * cy);
                            let load = [px, py, arm[0] * py - arm[1] * px];
                            sums.add(g, views[g].centre[0], image[0], col, load);
                        }
                    }
                }
            });
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
