//! Loads summed by the fluid backend itself, per body and column
//! ([`lbm::moving::BodyColumns`]): a device
//! backend then sends back about a dozen loads per grain instead of one momentum per link or
//! share, and the host's collect becomes one addition per grain and column. The CPU's
//! in-place sweep sums the partially saturated loads of the bodies inside one block of its
//! rows, with the host collect's arithmetic (the same bits); the host collects the rest.
//!
//! The slot of a group of bodies and a column holds what the serial collect (`links.rs`,
//! `psm.rs`) would have added to that grain's column sum: the same terms in the same order
//! (the column's cells in increasing row, each cell's links or shares in plan order), so the
//! column sums, and the totals the owners fold from them (`sums.rs`), stay independent of
//! the ranks. The backend's arithmetic may differ from the host's by rounding (the device
//! sums with compensation and takes each arm from the cell holding the body's centre): the
//! same bits on any rank count, not the CPU backend's bits (the CPU's own sums are).
//!
//! Only where every grain is small against the lattice (a diameter plus the boxes' margins
//! under its height and width): a grain's images then never share rows, and a link's body
//! (the image nearest to its midpoint) is the image that covers its cell. Otherwise the
//! backend reports one momentum per link or share as before.

use super::exchange::Coupler;
use super::interface::Interface;
use super::map::GrainView;
use lbm::moving::NO_SLOT;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Margin (cells) of a body's box around its disk's cells: link cells lie one cell outside
/// the covered ones; one more for rounding.
const MARGIN: i64 = 2;

impl Coupler {
    /// Body `b` of the current plan: its grain (view) and centre (the grain's or an image's).
    fn body(&self, b: usize) -> (usize, [f64; 2]) {
        self.cells.body(b)
    }

    /// Fill the boxes and groups of the body columns (`Common::body_columns`) for the plan
    /// just built from `views`, when the fluid backend sums per body (`wanted`) and every
    /// grain is small against the lattice (see the module docs); otherwise leave them empty. A group is a run of bodies of one grain with one centre x: the
    /// grain's images across a periodic y face (`SlabFrame::images` lists them together).
    pub(super) fn box_bodies(&mut self, views: &[GrainView], wanted: bool) {
        let mut out = std::mem::take(&mut self.common.body_columns);
        out.clear();
        let bodies = self.cells.bodies();
        let f = self.common.frame;
        let room = f.ny.min(f.global_nx) as f64;
        let small = views
            .iter()
            .all(|v| 2.0 * (v.radius + (MARGIN + 2) as f64) < room);
        if wanted && small {
            // Local columns or rows of the disk's cells, widened and clipped to the slab.
            let span = |lo: f64, hi: f64, n: usize| -> [u32; 2] {
                let a = (lo.floor() as i64 - MARGIN).max(0);
                let e = (hi.floor() as i64 + MARGIN).min(n as i64 - 1);
                if a > e {
                    [0, 0]
                } else {
                    [a as u32, (e - a + 1) as u32]
                }
            };
            for b in 0..bodies {
                let (g, c) = self.body(b);
                let r = views[g].radius;
                let x0 = f.x0 as f64;
                let [xa, xn] = span(c[0] - r - x0, c[0] + r - x0, f.nx);
                let [ya, yn] = span(c[1] - r, c[1] + r, f.ny);
                let xn = if yn == 0 { 0 } else { xn };
                out.boxes.push([xa, xn, ya, yn]);
                let joins = b > 0 && {
                    let (h, d) = self.body(b - 1);
                    h == g && d[0] == c[0]
                };
                if !joins {
                    out.groups.push(b as u32);
                }
                out.members.push(b as u32);
            }
            out.groups.push(bodies as u32);
            // Each group's bodies in increasing first row; their columns agree (those with
            // an empty box have none), and the group has a slot per column.
            out.first.push(0);
            for j in 0..out.groups.len() - 1 {
                let (a, e) = (out.groups[j] as usize, out.groups[j + 1] as usize);
                let boxes = &out.boxes;
                out.members[a..e].sort_by_key(|&b| boxes[b as usize][2]);
                let columns = out.columns(j);
                debug_assert!(out.members[a..e].iter().all(|&b| {
                    let bx = boxes[b as usize];
                    bx[1] == 0 || [bx[0], bx[1]] == columns
                }));
                let slots = out.first[j] + columns[1];
                out.first.push(slots);
            }
        }
        self.common.body_columns = out;
    }

    /// The collect from the backend's per-group sums: each used slot is added to its
    /// grain's column sum (in group order; a grain's groups reach different columns); where
    /// the backend summed only some bodies (`BodyColumns::body_slot`), the others' shares
    /// are collected one by one ([`Interface::collect_unslotted`]). Checks that the two
    /// hold every link or share of the plan.
    pub(super) fn collect_bodies(&mut self, views: &[GrainView]) {
        let f = self.common.frame;
        let cols = std::mem::take(&mut self.common.body_columns);
        // The slots by bands of columns in parallel: a band's task adds its columns' slots
        // in group order, and a column's slot is no other column's, so every sum takes its
        // loads in the serial order.
        let mut column_sums = std::mem::take(&mut self.common.sums);
        let seen = AtomicUsize::new(0);
        column_sums.fill_by_columns(f.x0, f.x0 + f.nx, |band, sums| {
            let mut n_band = 0;
            for j in 0..cols.groups.len() - 1 {
                // The group's slots are its columns from its box's first, in order.
                let (first, end) = (cols.first[j] as usize, cols.first[j + 1] as usize);
                let column0 = f.x0 + cols.columns(j)[0] as usize;
                let from = first + band.start.saturating_sub(column0);
                let to = end.min(first + band.end.saturating_sub(column0));
                if from >= to {
                    continue;
                }
                // The group's window of its grain's sums.
                let (g, image) = self.body(cols.group(j)[0] as usize);
                let w = sums.window(g, views[g].centre[0], image[0]);
                for s in from..to {
                    let n = cols.counts[s];
                    if n != 0 {
                        n_band += n as usize;
                        sums.add_to(&w, column0 + s - first, cols.sums[s]);
                    }
                }
            }
            seen.fetch_add(n_band, Ordering::Relaxed);
        });
        self.common.sums = column_sums;
        let mut seen = seen.into_inner();
        // The bodies the backend did not sum, if any, one share at a time.
        let unslotted = cols.body_slot.contains(&NO_SLOT);
        self.common.body_columns = cols;
        if unslotted {
            seen += self.cells.collect_unslotted(&mut self.common, views);
        }
        let planned = self.cells.planned();
        assert_eq!(
            seen, planned,
            "the per-body sums must hold every link or share of the plan"
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link_cells::{Bouzidi, HalfWay, LinkRule};
    use crate::map::SlabFrame;
    use crate::sums::ColumnSums;
    use crate::test_slabs::{grains_at_rest, next, planned, slab};
    use lbm::d2q9::{CX, CY};
    use lbm::moving::BodyColumns;

    /// What a backend puts in `cols` (here serially, with the per-link collect's arithmetic):
    /// body by body, column by column, the column's cells in increasing row, each cell's
    /// links or shares in plan order. `load(j, centre)` is plan entry j's body and load at
    /// its cell's centre.
    fn backend_sums(
        f: &SlabFrame,
        plan: (&[u32], &[u32], &[u32]),
        load: impl Fn(usize, [f64; 2]) -> (usize, [f64; 3]),
        cols: &mut BodyColumns,
    ) {
        let (rows, cells, start) = plan;
        cols.sums = vec![[0.0; 3]; cols.slots()];
        cols.counts = vec![0; cols.slots()];
        for j in 0..cols.groups.len() - 1 {
            let [x_lo, width] = cols.columns(j);
            for x in 0..width as usize {
                let slot = cols.first[j] as usize + x;
                for b in cols.group(j).to_vec() {
                    let bx = cols.boxes[b as usize];
                    for y in bx[2] as usize..(bx[2] + bx[3]) as usize {
                        let k = f.padded((x_lo as usize + x) as i64, y as i64);
                        let Some(c) =
                            (rows[y]..rows[y + 1]).find(|&c| cells[c as usize] as usize == k)
                        else {
                            continue;
                        };
                        let c = c as usize;
                        for e in start[c] as usize..start[c + 1] as usize {
                            let (body, v) = load(e, f.centre_in_row(k, y));
                            if body == b as usize {
                                let s = &mut cols.sums[slot];
                                for a in 0..3 {
                                    s[a] += v[a];
                                }
                                cols.counts[slot] += 1;
                            }
                        }
                    }
                }
            }
        }
        cols.made = true;
    }

    /// Every grain's column sums, bit patterns, as (grain, column, load bits).
    fn all_partials(sums: &ColumnSums, grains: usize) -> Vec<(usize, u32, [u64; 3])> {
        let mut out = Vec::new();
        let mut p = Vec::new();
        for g in 0..grains {
            sums.partials(g, &mut p);
            out.extend(p.iter().map(|(c, l)| (g, *c, l.map(f64::to_bits))));
        }
        out
    }

    /// The collect from per-body sums gives every grain's column sums to the bit of the
    /// per-link collect, on slabs with and without periodic seams and grains crossing them:
    /// the boxes hold every link, and each sum lands in its grain's column.
    #[test]
    fn per_body_sums_give_the_per_link_column_sums() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        for case in 0..4 {
            per_body_sums_match::<HalfWay>(case, &mut seed);
            per_body_sums_match::<Bouzidi>(case, &mut seed);
        }
    }

    fn per_body_sums_match<R: LinkRule>(case: usize, seed: &mut u64) {
        let (f, solid) = slab(case);
        let fluid = |k: usize| !solid[k];
        let views = grains_at_rest(&f, 30, seed);
        let mut c = planned::<R>(f, &views, &fluid);
        let links = R::of(&mut c.cells).links.links.len();
        assert!(links > 500, "case {case}: {links} links");
        R::of(&mut c.cells).link_momentum = (0..links).map(|_| next(seed) - 0.5).collect();
        c.common.sums.reset(&views, f.global_nx);
        c.cells.collect(&mut c.common, &views);
        let want = all_partials(&c.common.sums, views.len());
        // The same from per-body sums.
        c.box_bodies(&views, true);
        let cells = R::of(&mut c.cells);
        let (plan, m) = (&cells.links, &cells.link_momentum);
        let load = |l: usize, centre: [f64; 2]| {
            let (i, b) = (plan.links[l].dir(), plan.links[l].body());
            let image = plan.bodies[b].centre;
            let (cx, cy) = (CX[i] as f64, CY[i] as f64);
            let mid = [centre[0] - 0.5 * cx, centre[1] - 0.5 * cy];
            let arm = [mid[0] - image[0], mid[1] - image[1]];
            let (px, py) = (-m[l] * cx, -m[l] * cy);
            (b, [px, py, arm[0] * py - arm[1] * px])
        };
        let mut cols = std::mem::take(&mut c.common.body_columns);
        backend_sums(&f, (&plan.rows, &plan.cells, &plan.start), load, &mut cols);
        c.common.body_columns = cols;
        c.common.sums.reset(&views, f.global_nx);
        c.collect_bodies(&views);
        let got = all_partials(&c.common.sums, views.len());
        assert_eq!(got.len(), want.len(), "case {case}");
        assert!(got == want, "case {case}: the column sums differ");
        // A plan entry outside every box is caught, not lost.
        let slot = c
            .common
            .body_columns
            .counts
            .iter()
            .position(|&n| n > 0)
            .unwrap();
        c.common.body_columns.counts[slot] = 0;
        let lost = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            c.common.sums.reset(&views, f.global_nx);
            c.collect_bodies(&views)
        }));
        assert!(lost.is_err(), "case {case}: a lost link went unnoticed");
        // A grain too large for its lattice's height: no sums wanted, the backend
        // reports each link's momentum.
        let mut big = views.clone();
        big[0].radius = 0.5 * f.ny as f64 - 4.0;
        c.box_bodies(&big, true);
        assert!(!c.common.body_columns.wanted(), "case {case}");
    }
}
