//! Bounce-back schemes: the fluid cells next to a grain (its *boundary*), the plan of their
//! links to it, and the loads they hand to each grain.

use super::boundary_lists::Entry;
use super::exchange::{neighbour, Coupler, Unstable};
use super::gather::gather2;
use super::map::{nearest_image_at, GrainView};
use super::Scheme;
use crate::lbm::d2q9::{CX, CY, Q};
use crate::lbm::moving::{MovingLink, RigidMotion};
use crate::lbm::{Lattice, Real};

impl Coupler {
    /// The boundary cell list from `owner` (for the grains `views` it was built from),
    /// grouped by row: the interior fluid cells no grain covers that neighbour a covered
    /// cell, each listed with the first grain among its neighbours' owners
    /// (`boundary_lists::boundary_of`); within a row, grain by grain (id order), each
    /// grain's cells in scan order. Each grain's cells are rescanned only where the last
    /// remap could have changed them (see `boundary_lists.rs`).
    pub(super) fn rebuild_lists<T: Real>(&mut self, lat: &Lattice<T>, views: &[GrainView]) {
        self.group_lists(&|k: usize| lat.is_fluid_at(k), views);
    }

    /// [`Coupler::rebuild_lists`] with `fluid(k)` telling whether padded cell k is fluid.
    fn group_lists(&mut self, fluid: &(impl Fn(usize) -> bool + Sync), views: &[GrainView]) {
        if self.scheme == Scheme::Psm {
            return;
        }
        let f = self.frame;
        self.lists.rebuild(&f, &self.owner, fluid, views);
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

    /// Plan the boundary cells' links (half-way or interpolated bounce-back), in the list's
    /// order (grouped by row for the sweep): each link names its direction and its grain's
    /// rigid motion (one per grain view, or per image of it in a periodic frame), from
    /// which the sweep computes the moving-wall term. The map is read only for links to a
    /// grain other than the one a cell is listed with: the lists hold the rest.
    pub(super) fn plan_links(&mut self, views: &[GrainView]) {
        let f = self.frame;
        self.plan_bodies(views);
        self.links.rows.clone_from(&self.boundary_rows);
        self.links.x0 = f.x0 as i64;
        let mut links = std::mem::take(&mut self.links.links);
        let mut starts = std::mem::take(&mut self.links.start);
        if self.scheme == Scheme::Interpolated {
            let mut q = std::mem::take(&mut self.links.fractions);
            self.fill_links(views, &mut starts, &mut links, &mut q, Some(|q| q));
            self.links.fractions = q;
        } else {
            self.links.fractions.clear();
            let mut none: Vec<()> = Vec::new();
            self.fill_links(views, &mut starts, &mut links, &mut none, None);
        }
        self.links.links = links;
        self.links.start = starts;
        self.links.cells.clear();
        self.links
            .cells
            .extend(self.boundary.iter().map(|e| e.cell));
    }

    /// The plan's rigid bodies for `views`: view g's motion about each image that reaches
    /// the slab (only its centre in a frame with no periodic axis), the first at
    /// `body_start[g]`, in the order of `frame.images` (see `nearest_image_at`).
    fn plan_bodies(&mut self, views: &[GrainView]) {
        let f = self.frame;
        let (bodies, start, grain) = (
            &mut self.links.bodies,
            &mut self.body_start,
            &mut self.body_grain,
        );
        bodies.clear();
        start.clear();
        grain.clear();
        let periodic = f.periodic_x || f.periodic_y;
        for (g, v) in views.iter().enumerate() {
            start.push(bodies.len() as u32);
            let motion = |centre| RigidMotion {
                velocity: v.velocity,
                omega: v.omega,
                centre,
            };
            let before = bodies.len();
            if periodic {
                bodies.extend(f.images(v).map(motion));
            }
            if bodies.len() == before {
                bodies.push(motion(v.centre));
            }
            grain.resize(bodies.len(), g as u32);
        }
    }

    /// Fill the plan's link starts and links (and, with `fraction` (interpolated
    /// bounce-back), each link's q into `q`), one parallel pass per boundary cell.
    fn fill_links<B: Send + Copy + Default>(
        &self,
        views: &[GrainView],
        starts: &mut Vec<u32>,
        links: &mut Vec<MovingLink>,
        q: &mut Vec<B>,
        fraction: Option<fn(f64) -> B>,
    ) {
        let f = self.frame;
        let (owner, boundary) = (&self.owner, &self.boundary);
        let (listed, body_start) = (&self.boundary_grain, &self.body_start);
        // One pass per cell to count its links, one to write them (in parallel, in order).
        gather2(
            boundary.len(),
            starts,
            links,
            q,
            |b| boundary[b].links.count_ones() as usize,
            |b, out, qs| {
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
                    let (image, centre_of) = link_image(&f, centre, i, grain);
                    out[at] = MovingLink::new(i, body_start[g as usize] + image as u32);
                    if let Some(fraction) = fraction {
                        let (cx, cy) = (CX[i] as f64, CY[i] as f64);
                        let q = super::geometry::link_fraction(
                            centre,
                            [-cx, -cy],
                            centre_of,
                            grain.radius,
                        );
                        // Interpolation below ½ needs a plain fluid cell upstream. Both
                        // tests are combined without a branch: which way `q < 0.5` goes
                        // is unpredictable, and it waits on a square root.
                        let half = (q < 0.5) & (e.plain & bit == 0);
                        qs[at] = fraction([q, 0.5][half as usize]);
                    }
                }
            },
        );
    }

    /// Add each link's momentum (as the sweep reported it) to its grain's column sums, in
    /// plan order (in parallel over bands of columns): the grain receives −(f*_ī + f_i) c_i
    /// (seed eq. 5.47) at the link's midpoint (torque about the body's centre, eq. 5.48).
    /// Maps the first bad plan cell to (cell, grain, density).
    pub(super) fn collect_links(
        &mut self,
        views: &[GrainView],
        bad: Option<(usize, f64)>,
    ) -> Option<Unstable> {
        let f = self.frame;
        let (plan, grains, momentum) = (&self.links, &self.body_grain, &self.link_momentum);
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
                            let (link, m) = (plan.links[l], momentum[l]);
                            let (i, b) = (link.dir(), link.body());
                            let (g, image) = (grains[b] as usize, plan.bodies[b].centre);
                            let (cx, cy) = (CX[i] as f64, CY[i] as f64);
                            let mid = [centre[0] - 0.5 * cx, centre[1] - 0.5 * cy];
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
            let body = self.links.links[l].body();
            (self.links.cells[c] as usize, self.body_grain[body], rho)
        })
    }
}

/// Which image of `grain` (index among the frame's images, see `nearest_image_at`) the
/// link from the cell centred at `centre` along −c_i meets, and its centre: the one nearest
/// to the link's midpoint, where the half-way wall sits.
#[inline]
fn link_image(
    f: &super::map::SlabFrame,
    centre: [f64; 2],
    i: usize,
    grain: &GrainView,
) -> (usize, [f64; 2]) {
    let mid = [
        centre[0] - 0.5 * CX[i] as f64,
        centre[1] - 0.5 * CY[i] as f64,
    ];
    nearest_image_at(f, grain, mid)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coupling::map::{cover, nearest_image, NONE};
    use crate::coupling::test_slabs::{next, slab};
    use crate::coupling::Refill;
    use crate::lbm::d2q9::W;

    /// Every planned link names the grain that covers the cell it comes from, and its wall
    /// term and fraction are those of that grain's rigid motion about the image nearest to
    /// the link's midpoint (computed here independently, to the bit), on slabs with and
    /// without periodic seams, grains crossing them.
    #[test]
    fn planned_links_carry_their_grains_motion() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        for case in 0..4 {
            for scheme in [Scheme::BounceBack, Scheme::Interpolated] {
                let (f, solid) = slab(case);
                let fluid = |k: usize| !solid[k];
                let views: Vec<GrainView> = (0..30)
                    .map(|_| GrainView {
                        centre: [
                            f.x0 as f64 - 6.0 + next(&mut seed) * (f.nx as f64 + 12.0),
                            -3.0 + next(&mut seed) * 66.0,
                        ],
                        radius: 2.0 + 4.0 * next(&mut seed),
                        velocity: [next(&mut seed) - 0.5, next(&mut seed) - 0.5],
                        omega: 0.2 * (next(&mut seed) - 0.5),
                    })
                    .collect();
                let ids: Vec<u64> = (0..views.len() as u64).collect();
                let mut c = Coupler::new(scheme, Refill::default(), f);
                let (mut touched, mut inner) = (Vec::new(), Vec::new());
                cover(&f, &views, fluid, &mut c.owner, &mut touched, &mut inner);
                c.lists.clear();
                c.lists.follow(&ids);
                c.group_lists(&fluid, &views);
                c.plan_links(&views);
                let plan = &c.links;
                let (mut links, mut images) = (0, 0);
                for y in 0..f.ny {
                    for n in plan.rows[y] as usize..plan.rows[y + 1] as usize {
                        let k = plan.cells[n] as usize;
                        let centre = f.centre_in_row(k, y);
                        for l in plan.start[n] as usize..plan.start[n + 1] as usize {
                            let link = plan.links[l];
                            let i = link.dir();
                            let g = c.owner[neighbour(&f, k, i, -1)];
                            assert_ne!(g, NONE, "case {case}: a link from an uncovered cell");
                            assert_eq!(c.body_grain[link.body()], g, "case {case}");
                            let (cx, cy) = (CX[i] as f64, CY[i] as f64);
                            let mid = [centre[0] - 0.5 * cx, centre[1] - 0.5 * cy];
                            let grain = views[g as usize];
                            let image = nearest_image(&f, &grain, mid);
                            assert_eq!(plan.bodies[link.body()].centre, image, "case {case}");
                            images += (image != grain.centre) as usize;
                            let u = GrainView {
                                centre: image,
                                ..grain
                            }
                            .surface_velocity(mid);
                            // Ladd 1994, eq. 3.3: 2 w_i (c_i·u_w)/c_s².
                            let wall = 6.0 * W[i] * (cx * u[0] + cy * u[1]);
                            assert_eq!(plan.wall(f.stride, k, y, link).to_bits(), wall.to_bits());
                            let q = plan.q(l);
                            if scheme == Scheme::BounceBack {
                                assert_eq!(q, 0.5);
                            } else {
                                let exact = crate::coupling::geometry::link_fraction(
                                    centre,
                                    [-cx, -cy],
                                    image,
                                    grain.radius,
                                );
                                assert!(q == exact || q == 0.5, "case {case}: q {q}");
                            }
                            links += 1;
                        }
                    }
                }
                assert!(links > 1000, "case {case}: only {links} links");
                if f.periodic_x {
                    assert!(images > 0, "case {case}: no link meets a periodic image");
                }
            }
        }
    }
}
