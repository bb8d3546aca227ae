//! The partially saturated method (Noble & Torczynski 1998; seed eqs. 5.53–5.54): every cell a
//! grain overlaps is collided as a blend of the fluid's operator and the solid's, weighted by
//! the exact solid fraction.

use super::gather::{group_by_rows, row_of, Shared};
use super::geometry::{
    box_lines, column_line, row_line, CellAreas, ColumnLine, RowLine, TABLE_PAD,
};
use super::interface::Common;
use super::map::{share_rows, GrainView, Share, ShareRow, SlabFrame};
use super::partial_cells::{DiskImage, PartialCells};
use super::row_walk::shares_in_row;
use lbm::moving::{SolidShare, NO_SLOT};
use lbm::{Lattice, Real};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

impl PartialCells {
    /// The solid fraction of every interior fluid cell each grain overlaps, row by row
    /// (in parallel over the rows), each row's grains in id order, each grain's images in
    /// turn, cells in increasing x; then each row sorted by cell (a cell's shares keep that
    /// grain order: a row's images come in increasing index, and the sort's key is
    /// (cell, image)). Fills `share_rows`. The exact areas come from per-image tables of
    /// the grid lines around each disk (built in parallel first), so a cell costs no square
    /// root or arcsine.
    pub(super) fn map_shares<T: Real>(
        &mut self,
        f: &SlabFrame,
        lat: &Lattice<T>,
        views: &[GrainView],
    ) {
        let f = *f;
        // The grain images that reach the slab's rows and each one's rows (found in
        // parallel, in grain order), then where its line tables start (a box's lines are
        // counted here, so the tables take one parallel pass: each pass costs the pool a
        // wake-up).
        self.disk_images.clear();
        self.disk_images
            .par_extend(views.par_iter().enumerate().flat_map_iter(|(g, grain)| {
                f.images(grain).filter_map(move |c| {
                    let (ya, yb) = share_rows(&f, c, grain.radius);
                    (ya <= yb).then_some(DiskImage {
                        grain: g as u32,
                        centre: c,
                        rows: [ya as u32, yb as u32],
                    })
                })
            }));
        self.column_start.clear();
        self.row_start.clear();
        let (mut n_columns, mut n_rows) = (0u32, 0u32);
        for d in &self.disk_images {
            let (c, r) = (d.centre, views[d.grain as usize].radius);
            self.column_start.push(n_columns);
            self.row_start.push(n_rows);
            n_columns += (box_lines(c[0], r).1 + TABLE_PAD) as u32;
            n_rows += box_lines(c[1], r).1 as u32;
        }
        self.column_start.push(n_columns);
        self.row_start.push(n_rows);
        // Each image's line tables. Every entry is written below, so only entries beyond
        // the old length need a value first.
        let disks = &self.disk_images;
        let radius = |i: usize| views[disks[i].grain as usize].radius;
        self.column_lines
            .resize(n_columns as usize, ColumnLine::default());
        self.row_lines.resize(n_rows as usize, RowLine::default());
        let (to_columns, to_rows) = (
            Shared(self.column_lines.as_mut_ptr()),
            Shared(self.row_lines.as_mut_ptr()),
        );
        let (column_start, row_start) = (&self.column_start, &self.row_start);
        (0..disks.len())
            .into_par_iter()
            .with_min_len(64)
            .for_each(|i| {
                let (c, r) = (disks[i].centre, radius(i));
                // SAFETY: image i's entries [start[i], start[i + 1]) of each table are
                // disjoint from every other image's and inside the table, which nothing
                // else touches during the pass.
                let (columns, rows) = unsafe {
                    (
                        row_of(&to_columns, column_start, i),
                        row_of(&to_rows, row_start, i),
                    )
                };
                let (x_lo, y_lo) = (box_lines(c[0], r).0, box_lines(c[1], r).0);
                let (box_columns, pad) = columns.split_at_mut(columns.len() - TABLE_PAD);
                for (j, line) in box_columns.iter_mut().enumerate() {
                    *line = column_line(c, r, (x_lo + j as i64) as f64);
                }
                // Read only by lanes past the box, which are dropped: any finite value.
                pad.fill(box_columns[box_columns.len() - 1]);
                for (m, line) in rows.iter_mut().enumerate() {
                    *line = row_line(c, r, (y_lo + m as i64) as f64);
                }
            });
        let (columns, rows) = (
            (&self.column_start, &self.column_lines),
            (&self.row_start, &self.row_lines),
        );
        let areas = |i: usize| {
            let (c, r) = (disks[i].centre, radius(i));
            CellAreas {
                columns: &columns.1[columns.0[i] as usize..columns.0[i + 1] as usize],
                rows: &rows.1[rows.0[i] as usize..rows.0[i + 1] as usize],
                x_lo: box_lines(c[0], r).0,
                y_lo: box_lines(c[1], r).0,
                radius: r,
            }
        };
        group_by_rows(
            disks.len(),
            f.ny,
            |i| disks[i].rows,
            &mut self.image_rows,
            &mut self.image_order,
        );
        let (starts, order) = (&self.image_rows, &self.image_order);
        let in_row = |y: usize| {
            order[starts[y] as usize..starts[y + 1] as usize]
                .iter()
                .map(|&i| i as usize)
        };
        // One pass per row, its shares still in cache when sorted and counted.
        let (avx512, types) = (lbm::lanes::has_avx512(), lat.padded_cell_types());
        self.share_rows.resize_with(f.ny, ShareRow::default);
        self.share_rows
            .par_iter_mut()
            .enumerate()
            .with_min_len(16)
            .for_each(|(y, row)| {
                row.walked.clear();
                row.stretches.clear();
                for i in in_row(y) {
                    let (g, c) = (disks[i].grain as usize, disks[i].centre);
                    let (r, exact) = (views[g].radius, areas(i));
                    let a = row.walked.len();
                    let out = &mut row.walked;
                    shares_in_row(avx512, &f, types, r, i as u32, c, y as i64, &exact, out);
                    if let Some(first) = out.get(a) {
                        let key = (u64::from(first.cell) << 32) | i as u64;
                        row.stretches.push((key, a as u32, out.len() as u32));
                    }
                }
                // Sorted by (cell, image): a cell's shares in image order, which is grain
                // order (images are numbered in grain order).
                row.sort_walked();
                let out = &row.shares;
                row.cells = out
                    .iter()
                    .enumerate()
                    .filter(|&(j, sh)| j == 0 || out[j - 1].cell != sh.cell)
                    .count() as u32;
            });
    }

    /// Plan the partially saturated collision from the map's rows (cells in increasing x,
    /// each cell's shares in grain order): the order is the restriction of a
    /// partition-independent one (rows, then global x). Each share's body is its grain
    /// image, whose rigid motion the sweep takes the solid's velocity from.
    pub(super) fn plan_psm<T: Real>(
        &mut self,
        f: &SlabFrame,
        lat: &Lattice<T>,
        views: &[GrainView],
    ) {
        let f = *f;
        let tau = lat.tau0();
        let plan = &mut self.psm;
        let disks = &self.disk_images;
        let rows = &self.share_rows;
        plan.x0 = f.x0 as i64;
        plan.bodies.clear();
        plan.bodies.extend(
            disks
                .iter()
                .map(|d| views[d.grain as usize].motion(d.centre)),
        );
        // Where each row's cells and shares start.
        plan.rows.clear();
        self.offsets.clear();
        let (mut cells, mut shares) = (0u32, 0u32);
        for r in rows {
            plan.rows.push(cells);
            self.offsets.push(shares);
            cells += r.cells;
            shares += r.shares.len() as u32;
        }
        plan.rows.push(cells);
        self.offsets.push(shares);
        let (cells, shares) = (cells as usize, shares as usize);
        plan.cells.resize(cells, 0);
        plan.start.resize(cells + 1, 0);
        plan.start[cells] = shares as u32;
        plan.total.resize(cells, 0.0);
        plan.shares.resize(shares, SolidShare::default());
        // Then each row's cells, their weights and their shares, in parallel over rows.
        let (cell_rows, offsets) = (&plan.rows, &self.offsets);
        let (p_cells, p_start, p_total, p_shares) = (
            Shared(plan.cells.as_mut_ptr()),
            Shared(plan.start.as_mut_ptr()),
            Shared(plan.total.as_mut_ptr()),
            Shared(plan.shares.as_mut_ptr()),
        );
        (0..f.ny).into_par_iter().with_min_len(16).for_each(|y| {
            // SAFETY: row y's cells (`cell_rows`) and shares (`offsets`) are disjoint
            // ranges of the plan's vectors, each taken by one task; the vectors are not
            // otherwise touched during the pass.
            let (cells, start, total, out) = unsafe {
                (
                    row_of(&p_cells, cell_rows, y),
                    row_of(&p_start, cell_rows, y),
                    row_of(&p_total, cell_rows, y),
                    row_of(&p_shares, offsets, y),
                )
            };
            plan_row(&rows[y].shares, tau, offsets[y], cells, start, total, out);
        });
    }

    /// Add each share's momentum (as the sweep reported it) to its grain's column sums, in
    /// plan order (in parallel over bands of columns).
    pub(super) fn collect_psm(&mut self, c: &mut Common, views: &[GrainView]) {
        self.collect_psm_where(c, views, None);
    }

    /// [`PartialCells::collect_psm`] for the shares of the bodies the backend did not sum
    /// (`BodyColumns::body_slot` is `NO_SLOT`), on the rows their boxes reach. Returns how
    /// many shares it added.
    pub(super) fn collect_psm_unslotted(&mut self, c: &mut Common, views: &[GrainView]) -> usize {
        let mut rows = std::mem::take(&mut self.rest_rows);
        rows.clear();
        rows.resize(c.frame.ny, false);
        let cols = &c.body_columns;
        for (bx, &slot) in cols.boxes.iter().zip(&cols.body_slot) {
            if slot == NO_SLOT {
                rows[bx[2] as usize..(bx[2] + bx[3]) as usize].fill(true);
            }
        }
        let n = self.collect_psm_where(c, views, Some(&rows));
        self.rest_rows = rows;
        n
    }

    /// [`PartialCells::collect_psm`], or with `rows` only the shares of the bodies the backend
    /// did not sum, on the rows marked there. Returns how many shares it added.
    fn collect_psm_where(
        &mut self,
        c: &mut Common,
        views: &[GrainView],
        rows: Option<&[bool]>,
    ) -> usize {
        let f = c.frame;
        // Each grain image's window of its grain's column sums.
        let mut windows = std::mem::take(&mut c.body_windows);
        windows.clear();
        windows.extend(self.disk_images.iter().map(|d| {
            let g = d.grain as usize;
            c.sums.window(g, views[g].centre[0], d.centre[0])
        }));
        let (plan, momentum) = (&self.psm, &self.share_momentum);
        let (disks, win) = (&self.disk_images, &windows);
        let slots = &c.body_columns.body_slot;
        let added = AtomicUsize::new(0);
        c.sums.fill_by_columns(f.x0, f.x0 + f.nx, |band, sums| {
            let mut n = 0;
            let wanted = |y: usize| rows.is_none_or(|r| r[y]);
            f.band_cells_sorted(&plan.rows, &plan.cells, &band, wanted, |c, col, centre| {
                for s in plan.start[c] as usize..plan.start[c + 1] as usize {
                    // Plan share s: its grain and the image it sees.
                    let (i, p) = (plan.shares[s].body as usize, momentum[s]);
                    if rows.is_some() && slots[i] != NO_SLOT {
                        continue;
                    }
                    let image = disks[i].centre;
                    let arm = [centre[0] - image[0], centre[1] - image[1]];
                    // The grain receives what the fluid gains, negated (seed eqs. 5.53–5.54).
                    let load = [p[0], p[1], arm[0] * p[1] - arm[1] * p[0]];
                    sums.add_to(&win[i], col, load);
                    n += 1;
                }
            });
            added.fetch_add(n, Ordering::Relaxed);
        });
        c.body_windows = windows;
        added.into_inner()
    }
}

/// Plan one row from its mapped shares `row` (sorted by cell, a cell's shares in grain
/// order), in a lattice of relaxation time `tau`, the row's first share being the plan's
/// share `first`: each cell's padded index, where its shares start and its total weight B
/// go to `cells`, `start` and `total` (one entry per cell), each share's weight B_s and body
/// to `out` (Noble & Torczynski 1998, eq. 9: B = ε(τ − ½) / ((1 − ε) + (τ − ½)), split
/// among the solids by their fractions, B_s = B ε_s / ε). Runs of eight cells of one share
/// each (the common case) take the same arithmetic in lanes, so that their divisions
/// overlap: the same bits.
fn plan_row(
    row: &[Share],
    tau: f64,
    first: u32,
    cells: &mut [u32],
    start: &mut [u32],
    total: &mut [f64],
    out: &mut [SolidShare],
) {
    /// Cells planned together.
    const LANES: usize = 8;
    let weight = |e: f64| e * (tau - 0.5) / ((1.0 - e) + (tau - 0.5));
    // B_s of a share of fraction f in a cell of ε and B; a cell whose overlap rounds to
    // nothing stays plain fluid (the quotient is taken either way, so lanes can divide).
    let split = |b: f64, f: f64, eps: f64| {
        let q = b * f / eps;
        if eps > 0.0 {
            q
        } else {
            0.0
        }
    };
    let first = first as usize;
    // As many cells as shares (the map counted them): every cell has one share (the row
    // of most grains apart), and no run of the row needs checking.
    let one_share_row = cells.len() == row.len();
    let (mut c, mut j) = (0, 0);
    while j < row.len() {
        // The next eight shares and the one after them: each of the eight is its cell's
        // only share when no two neighbours share a cell (the first starts a cell).
        let ahead = &row[j..(j + LANES + 1).min(row.len())];
        if ahead.len() >= LANES
            && (one_share_row || ahead.windows(2).all(|w| w[0].cell != w[1].cell))
        {
            let next = &ahead[..LANES];
            let f: [f64; LANES] = std::array::from_fn(|i| next[i].fraction);
            // A one-share cell's ε, summed as the general case sums it.
            let eps: [f64; LANES] = std::array::from_fn(|i| std::iter::once(f[i]).sum::<f64>());
            let b: [f64; LANES] = std::array::from_fn(|i| weight(eps[i].min(1.0)));
            let bs: [f64; LANES] = std::array::from_fn(|i| split(b[i], f[i], eps[i]));
            let (o, ce, st, to) = (
                &mut out[j..j + LANES],
                &mut cells[c..c + LANES],
                &mut start[c..c + LANES],
                &mut total[c..c + LANES],
            );
            for i in 0..LANES {
                o[i] = SolidShare {
                    b: bs[i],
                    body: next[i].image,
                };
                (ce[i], st[i], to[i]) = (next[i].cell, (first + j + i) as u32, b[i]);
            }
            (c, j) = (c + LANES, j + LANES);
            continue;
        }
        let mut end = j + 1;
        while end < row.len() && row[end].cell == row[j].cell {
            end += 1;
        }
        let group = &row[j..end];
        let eps: f64 = group.iter().map(|sh| sh.fraction).sum();
        let b = weight(eps.min(1.0));
        for (s, sh) in group.iter().enumerate() {
            out[j + s] = SolidShare {
                b: split(b, sh.fraction, eps),
                body: sh.image,
            };
        }
        (cells[c], start[c], total[c]) = (row[j].cell, (first + j) as u32, b);
        (c, j) = (c + 1, end);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eq. 9 cell by cell, as the seed writes it: a row's plan from its shares, against
    /// [`plan_row`] (runs of one-share cells in lanes), bit for bit, on rows with cells of
    /// several shares and of no overlap anywhere among runs of one-share cells.
    #[test]
    fn a_rows_plan_in_lanes_matches_eq_9_cell_by_cell() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let tau = 0.53;
        for case in 0..200 {
            let mut row = Vec::new();
            let mut cell = 1000u32;
            let n = 1 + case % 40;
            for _ in 0..n {
                let r = lbm::test_rng::next(&mut seed);
                let shares = if r < 0.15 {
                    2 + (r * 20.0) as u32 % 2
                } else {
                    1
                };
                for g in 0..shares {
                    let f = lbm::test_rng::next(&mut seed);
                    let fraction = match (f * 10.0) as u32 {
                        0 => 0.0,
                        1 | 2 => 1.0,
                        _ => f,
                    };
                    row.push(Share {
                        fraction,
                        cell,
                        image: 7 * g + (cell % 5),
                    });
                }
                cell += 1 + (lbm::test_rng::next(&mut seed) < 0.2) as u32;
            }
            let cells_n = row
                .iter()
                .map(|s| s.cell)
                .collect::<std::collections::BTreeSet<_>>();
            let (mut cells, mut start, mut total) = (
                vec![0; cells_n.len()],
                vec![0; cells_n.len()],
                vec![0.0; cells_n.len()],
            );
            let mut out = vec![SolidShare::default(); row.len()];
            plan_row(&row, tau, 17, &mut cells, &mut start, &mut total, &mut out);
            let mut j = 0;
            for (c, &k) in cells_n.iter().enumerate() {
                let group: Vec<_> = row.iter().filter(|s| s.cell == k).collect();
                let eps: f64 = group.iter().map(|s| s.fraction).sum();
                let e = eps.min(1.0);
                let b = e * (tau - 0.5) / ((1.0 - e) + (tau - 0.5));
                assert_eq!((cells[c], start[c]), (k, 17 + j as u32), "case {case}");
                assert_eq!(total[c].to_bits(), b.to_bits(), "case {case}, cell {k}");
                for s in &group {
                    let want = if eps > 0.0 { b * s.fraction / eps } else { 0.0 };
                    assert_eq!(out[j].b.to_bits(), want.to_bits(), "case {case}, share {j}");
                    assert_eq!(out[j].body, s.image);
                    j += 1;
                }
            }
        }
    }
}
