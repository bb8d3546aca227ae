//! Bounce-back schemes: the fluid cells next to a grain (its *boundary*), the plan of their
//! links to it, and the loads they hand to each grain.

use super::gather::Shared;
use super::geometry::link_fraction;
use super::interface::Common;
use super::link_cells::{LinkCells, LinkRule};
use super::map::neighbour;
use super::map::{nearest_image_at, GrainView, SlabFrame};
use lbm::d2q9::{CX, CY};
use lbm::moving::MovingLink;
use lbm::{Lattice, Real};
use rayon::prelude::*;

impl<R: LinkRule> LinkCells<R> {
    /// The link plan's cells and links from the boundary lists of `owner` (for the grains
    /// `views` it was built from), grouped by row: the interior fluid cells no grain covers
    /// that neighbour a covered cell, each listed with the first grain among its
    /// neighbours' owners (`boundary_lists::boundary_of`); within a row, grain by grain (id
    /// order), each grain's cells in scan order; each cell's links in direction order, each
    /// naming its grain's rigid motion (one per grain view, or per image of it in a
    /// periodic frame). Each grain's cells are rescanned only where the last remap could
    /// have changed them (see `boundary_lists.rs`). The map is read only for links to a
    /// grain other than the one a cell is listed with: the lists hold the rest.
    pub(super) fn rebuild_lists<T: Real>(
        &mut self,
        f: &SlabFrame,
        lat: &Lattice<T>,
        views: &[GrainView],
    ) {
        self.group_lists(f, &|k: usize| lat.is_fluid_at(k), views);
    }

    /// [`LinkCells::rebuild_lists`] with `fluid(k)` telling whether padded cell k is fluid.
    pub(super) fn group_lists(
        &mut self,
        f: &SlabFrame,
        fluid: &(impl Fn(usize) -> bool + Sync),
        views: &[GrainView],
    ) {
        self.lists.rebuild(f, &self.owner, fluid, views);
        self.plan_bodies(f, views);
        self.scatter_plan(f, views);
    }

    /// Place the boundary lists' entries into the link plan, grouped by row (a stable
    /// counting sort): the grains are split into one contiguous range per thread, each
    /// range counts its cells and links per row, and each then writes its own slots, which
    /// follow the rows' and ranges' order. The plan is the same for any thread count.
    fn scatter_plan(&mut self, f: &SlabFrame, views: &[GrainView]) {
        let f = *f;
        let ny = f.ny;
        let lists = self.lists.per_grain();
        // Ranges of grains with about equal numbers of entries.
        let total: usize = lists.iter().map(Vec::len).sum();
        let parts = rayon::current_num_threads().clamp(1, 64);
        let ranges = &mut self.part_grains;
        ranges.clear();
        ranges.push(0);
        let mut seen = 0;
        for (g, list) in lists.iter().enumerate() {
            seen += list.len();
            if seen * parts >= total * ranges.len() && ranges.len() < parts {
                ranges.push(g + 1);
            }
        }
        while ranges.len() <= parts {
            ranges.push(lists.len());
        }
        // Each range's cells and links per row (range-major, ny values each).
        let counts = &mut self.part_counts;
        counts.clear();
        counts.resize(2 * parts * ny, 0);
        let (cell_counts, link_counts) = counts.split_at_mut(parts * ny);
        let ranges = &*ranges;
        cell_counts
            .par_chunks_mut(ny)
            .zip(link_counts.par_chunks_mut(ny))
            .enumerate()
            .for_each(|(t, (cc, lc))| {
                for list in &lists[ranges[t]..ranges[t + 1]] {
                    for e in list {
                        cc[e.row as usize] += 1;
                        lc[e.row as usize] += e.links.count_ones();
                    }
                }
            });
        // Where each row, and each range within it, starts (the counts become starts).
        let rows = &mut self.links.rows;
        rows.clear();
        let (mut cells, mut links) = (0u32, 0u32);
        for y in 0..ny {
            rows.push(cells);
            for t in 0..parts {
                let (c, l) = (cell_counts[t * ny + y], link_counts[t * ny + y]);
                (cell_counts[t * ny + y], link_counts[t * ny + y]) = (cells, links);
                (cells, links) = (cells + c, links + l);
            }
        }
        rows.push(cells);
        let (n, nl) = (cells as usize, links as usize);
        let plan = &mut self.links;
        plan.cells.resize(n, 0);
        plan.start.resize(n + 1, 0);
        plan.start[n] = nl as u32;
        plan.links.resize(nl, MovingLink::default());
        let interpolated = R::INTERPOLATED;
        plan.fractions
            .resize(if interpolated { nl } else { 0 }, 0.5);
        let periodic = f.periodic_x || f.periodic_y;
        let (owner, body_start) = (&self.owner, &self.body_start);
        let (p_cells, p_start, p_links, p_fractions) = (
            Shared(plan.cells.as_mut_ptr()),
            Shared(plan.start.as_mut_ptr()),
            Shared(plan.links.as_mut_ptr()),
            Shared(plan.fractions.as_mut_ptr()),
        );
        let bodies = &plan.bodies;
        cell_counts
            .par_chunks_mut(ny)
            .zip(link_counts.par_chunks_mut(ny))
            .enumerate()
            .for_each(|(t, (next_cell, next_link))| {
                for (g, list) in lists.iter().enumerate().take(ranges[t + 1]).skip(ranges[t]) {
                    for e in list {
                        let y = e.row as usize;
                        let slot = next_cell[y] as usize;
                        next_cell[y] += 1;
                        let mut l = next_link[y] as usize;
                        let k = e.cell as usize;
                        // SAFETY: the slots a range takes (its share of each row) are
                        // disjoint from every other range's, and inside the vectors.
                        unsafe {
                            *p_cells.get().add(slot) = e.cell;
                            *p_start.get().add(slot) = l as u32;
                        }
                        let centre = f.centre_in_row(k, y);
                        let mut bits = e.links;
                        while bits != 0 {
                            // Directions in increasing order.
                            let i = bits.trailing_zeros() as usize + 1;
                            bits &= bits - 1;
                            let grain = if e.foreign & (1 << (i - 1)) != 0 {
                                owner[neighbour(&f, k, i, -1)] as usize
                            } else {
                                g
                            };
                            let image = if periodic {
                                link_image(&f, centre, i, &views[grain]) as u32
                            } else {
                                0
                            };
                            let body = body_start[grain] + image;
                            let link = MovingLink::new(i, body);
                            // SAFETY: as above, for the range's links.
                            unsafe { *p_links.get().add(l) = link };
                            if interpolated {
                                let (cx, cy) = (CX[i] as f64, CY[i] as f64);
                                let (at, radius) =
                                    (bodies[body as usize].centre, views[grain].radius);
                                let q = link_fraction(centre, [-cx, -cy], at, radius);
                                // Interpolation below ½ needs a plain fluid cell upstream.
                                // Both tests are combined without a branch: which way
                                // `q < 0.5` goes is unpredictable, and it waits on a square
                                // root.
                                let half = (q < 0.5) & (e.plain & (1 << (i - 1)) == 0);
                                // SAFETY: as above, for the range's links.
                                unsafe { *p_fractions.get().add(l) = [q, 0.5][half as usize] };
                            }
                            l += 1;
                        }
                        next_link[y] = l as u32;
                    }
                }
            });
    }

    /// The plan's rigid bodies for `views`: view g's motion about each image that reaches
    /// the slab (only its centre in a frame with no periodic axis), the first at
    /// `body_start[g]`, in the order of `frame.images` (see `nearest_image_at`).
    fn plan_bodies(&mut self, f: &SlabFrame, views: &[GrainView]) {
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
            let motion = |centre| v.motion(centre);
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

    /// Complete the link plan that the last remap built (`rebuild_lists`, which took the
    /// grains' rigid motions and, with interpolated bounce-back, each link's fraction q from
    /// the same `views`): only the slab's offset is set here. Half-way bounce-back needs
    /// nothing more, the sweep computing each link's moving-wall term from its body's rigid
    /// motion.
    pub(super) fn plan_links(&mut self, f: &SlabFrame, views: &[GrainView]) {
        debug_assert_eq!(self.body_start.len(), views.len());
        self.links.x0 = f.x0 as i64;
    }

    /// Add each link's momentum (as the sweep reported it) to its grain's column sums, in
    /// plan order (in parallel over bands of columns): the grain receives −(f*_ī + f_i) c_i
    /// (seed eq. 5.47) at the link's midpoint (torque about the body's centre, eq. 5.48).
    pub(super) fn collect_links(&mut self, c: &mut Common, views: &[GrainView]) {
        let f = c.frame;
        // Each body's window of column sums (its grain's, seen from its image).
        let mut windows = std::mem::take(&mut c.body_windows);
        windows.clear();
        windows.extend(
            self.links
                .bodies
                .iter()
                .zip(&self.body_grain)
                .map(|(b, &g)| {
                    let g = g as usize;
                    c.sums.window(g, views[g].centre[0], b.centre[0])
                }),
        );
        let (plan, momentum) = (&self.links, &self.link_momentum);
        let win = &windows;
        c.sums.fill_by_columns(f.x0, f.x0 + f.nx, |band, sums| {
            f.band_cells(&plan.rows, &plan.cells, &band, |c, col, centre| {
                for l in plan.start[c] as usize..plan.start[c + 1] as usize {
                    let (link, m) = (plan.links[l], momentum[l]);
                    let (i, b) = (link.dir(), link.body());
                    let image = plan.bodies[b].centre;
                    let (cx, cy) = (CX[i] as f64, CY[i] as f64);
                    let mid = [centre[0] - 0.5 * cx, centre[1] - 0.5 * cy];
                    let arm = [mid[0] - image[0], mid[1] - image[1]];
                    let (px, py) = (-m * cx, -m * cy);
                    let load = [px, py, arm[0] * py - arm[1] * px];
                    sums.add_to(&win[b], col, load);
                }
            });
        });
        c.body_windows = windows;
    }
}

/// Which image of `grain` (index among the frame's images, see `nearest_image_at`) the
/// link from the cell centred at `centre` along −c_i meets: the one nearest to the link's
/// midpoint, where the half-way wall sits.
#[inline]
fn link_image(f: &super::map::SlabFrame, centre: [f64; 2], i: usize, grain: &GrainView) -> usize {
    let mid = [
        centre[0] - 0.5 * CX[i] as f64,
        centre[1] - 0.5 * CY[i] as f64,
    ];
    nearest_image_at(f, grain, mid).0
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::link_cells::{Bouzidi, HalfWay};
    use crate::map::{nearest_image, NONE};
    use crate::test_slabs::{next, planned_links, slab};
    use lbm::d2q9::{Q, W};

    /// Every planned link names the grain that covers the cell it comes from, and its wall
    /// term and fraction are those of that grain's rigid motion about the image nearest to
    /// the link's midpoint (computed here independently, to the bit), on slabs with and
    /// without periodic seams, grains crossing them.
    #[test]
    fn planned_links_carry_their_grains_motion() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        // 30 grains, and fewer grains than threads, and none.
        for (case, grains) in [(0, 30), (1, 30), (2, 30), (3, 30), (0, 2), (1, 0)] {
            links_carry_their_grains_motion::<HalfWay>(case, grains, &mut seed);
            links_carry_their_grains_motion::<Bouzidi>(case, grains, &mut seed);
        }
    }

    fn links_carry_their_grains_motion<R: LinkRule>(case: usize, grains: usize, seed: &mut u64) {
        let (f, solid) = slab(case);
        let fluid = |k: usize| !solid[k];
        let views: Vec<GrainView> = (0..grains)
            .map(|_| GrainView {
                centre: [
                    f.x0 as f64 - 6.0 + next(seed) * (f.nx as f64 + 12.0),
                    -3.0 + next(seed) * 66.0,
                ],
                radius: 2.0 + 4.0 * next(seed),
                velocity: [next(seed) - 0.5, next(seed) - 0.5],
                omega: 0.2 * (next(seed) - 0.5),
            })
            .collect();
        // The plan built on 1, 2 and 5 threads: the same, slot for slot.
        let plans: Vec<LinkCells<R>> = [1, 2, 5]
            .into_iter()
            .map(|threads| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| planned_links::<R>(f, &views, &fluid))
            })
            .collect();
        for other in &plans[1..] {
            let (a, b) = (&plans[0].links, &other.links);
            assert_eq!(a.rows, b.rows, "case {case}");
            assert_eq!(a.cells, b.cells, "case {case}");
            assert_eq!(a.start, b.start, "case {case}");
            assert_eq!(a.links, b.links, "case {case}");
            assert_eq!(a.fractions, b.fractions, "case {case}");
        }
        let c = &plans[1];
        let plan = &c.links;
        // Every boundary cell is planned, with one link per covered neighbour.
        let (mut cells, mut covered) = (0, 0);
        for y in 0..f.ny as i64 {
            for x in 0..f.nx as i64 {
                let k = f.padded(x, y);
                let n = (1..Q)
                    .filter(|&i| c.owner[neighbour(&f, k, i, -1)] != NONE)
                    .count();
                if c.owner[k] == NONE && fluid(k) && n > 0 {
                    (cells, covered) = (cells + 1, covered + n);
                }
            }
        }
        assert_eq!((plan.cells.len(), plan.links.len()), (cells, covered));
        let (mut links, mut images, mut halved, mut below) = (0, 0, 0, 0);
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
                    if !R::INTERPOLATED {
                        assert_eq!(q, 0.5);
                    } else {
                        let exact =
                            crate::geometry::link_fraction(centre, [-cx, -cy], image, grain.radius);
                        // Below ½ only with a plain, uncovered fluid cell upstream.
                        let ahead = neighbour(&f, k, i, 1);
                        let open = c.owner[ahead] == NONE && fluid(ahead);
                        let want = if exact < 0.5 && !open { 0.5 } else { exact };
                        assert_eq!(q.to_bits(), want.to_bits(), "case {case}");
                        halved += (exact < 0.5 && !open) as usize;
                        below += (q < 0.5) as usize;
                    }
                    links += 1;
                }
            }
        }
        if grains < 30 {
            assert_eq!(links > 0, grains > 0, "case {case}, {grains} grains");
            return;
        }
        assert!(links > 1000, "case {case}: only {links} links");
        if f.periodic_x {
            assert!(images > 0, "case {case}: no link meets a periodic image");
        }
        if R::INTERPOLATED {
            assert!(
                halved > 0 && below > 0,
                "case {case}: {halved} halved, {below}"
            );
        }
    }
}
