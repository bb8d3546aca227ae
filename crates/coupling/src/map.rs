//! Grains seen by the lattice: their lattice-unit state, which cells each covers (the
//! bounce-back schemes) and how much of each cell it fills (the partially saturated
//! method).

use super::geometry::covers;
use lbm::moving::RigidMotion;

/// No grain covers the cell.
pub const NONE: u32 = u32::MAX;

/// One grain in lattice units of this slab's frame (global x, cells; velocities in cells
/// per step; ω in radians per step).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrainView {
    /// Centre (cells, global frame: cell (x, y) spans [x, x+1) × [y, y+1)).
    pub centre: [f64; 2],
    /// Radius (cells).
    pub radius: f64,
    /// Velocity of the centre (cells per step).
    pub velocity: [f64; 2],
    /// Angular velocity (radians per step, counter-clockwise).
    pub omega: f64,
}

impl GrainView {
    /// The grain's rigid motion about `centre` (itself or one of its periodic images).
    #[inline]
    pub fn motion(&self, centre: [f64; 2]) -> RigidMotion {
        RigidMotion {
            velocity: self.velocity,
            omega: self.omega,
            centre,
        }
    }

    /// Velocity of the rigid body at point `p` (global lattice coordinates): v + ω × r
    /// (seed eq. 5.46).
    #[inline]
    pub fn surface_velocity(&self, p: [f64; 2]) -> [f64; 2] {
        self.motion(self.centre).velocity_at(p)
    }
}

/// The geometry of one slab (interior `nx × ny` cells starting at global column `x0`, with a
/// one-cell halo) and how its x and y faces wrap.
#[derive(Debug, Clone, Copy)]
pub struct SlabFrame {
    /// Interior columns of this slab.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
    /// Global column of local column 0.
    pub x0: usize,
    /// Columns of the whole lattice.
    pub global_nx: usize,
    /// Padded row length.
    pub stride: usize,
    /// The x faces are periodic.
    pub periodic_x: bool,
    /// The y faces are periodic.
    pub periodic_y: bool,
}

impl SlabFrame {
    /// Padded index of local cell (x, y), x ∈ [−1, nx], y ∈ [−1, ny].
    #[inline]
    pub fn padded(&self, x: i64, y: i64) -> usize {
        (y + 1) as usize * self.stride + (x + 1) as usize
    }

    /// Local (x, y) of padded index `k`.
    #[inline]
    pub fn local(&self, k: usize) -> (i64, i64) {
        ((k % self.stride) as i64 - 1, (k / self.stride) as i64 - 1)
    }

    /// Centre of padded cell `k` in global lattice coordinates.
    #[inline]
    pub fn centre(&self, k: usize) -> [f64; 2] {
        let (x, y) = self.local(k);
        [(x + self.x0 as i64) as f64 + 0.5, y as f64 + 0.5]
    }

    /// Local x of padded cell `k`, known to lie in local row `y` (no division).
    #[inline]
    pub fn x_in_row(&self, k: usize, y: usize) -> i64 {
        k as i64 - ((y + 1) * self.stride) as i64 - 1
    }

    /// [`SlabFrame::centre`] of padded cell `k`, known to lie in local row `y`.
    #[inline]
    pub fn centre_in_row(&self, k: usize, y: usize) -> [f64; 2] {
        lbm::moving::cell_centre(self.stride, self.x0 as i64, k, y)
    }

    /// Visit, in plan order, the cells of a row-grouped plan (`rows`: where each local
    /// row's cells start, ny + 1 values, or empty; `cells`: padded indices) whose global
    /// column lies in `band`: `visit(c, column, centre)` with the plan index, the global
    /// column and the cell's centre (global lattice coordinates). The collects' walk: one
    /// task per band of columns, each adding its columns' loads in the serial order.
    #[inline]
    pub fn band_cells(
        &self,
        rows: &[u32],
        cells: &[u32],
        band: &std::ops::Range<usize>,
        mut visit: impl FnMut(usize, usize, [f64; 2]),
    ) {
        for y in 0..rows.len().saturating_sub(1) {
            for c in rows[y] as usize..rows[y + 1] as usize {
                let k = cells[c] as usize;
                let col = (self.x_in_row(k, y) + self.x0 as i64) as usize;
                if band.contains(&col) {
                    visit(c, col, self.centre_in_row(k, y));
                }
            }
        }
    }

    /// [`SlabFrame::band_cells`] for a plan whose cells increase within each row (the
    /// partially saturated plan), on the rows `y` where `wanted(y)`: each row's cells of the
    /// band are found by bisection, so a task reads only its own band's cells. The same
    /// visits in the same order.
    #[inline]
    pub fn band_cells_sorted(
        &self,
        rows: &[u32],
        cells: &[u32],
        band: &std::ops::Range<usize>,
        wanted: impl Fn(usize) -> bool,
        mut visit: impl FnMut(usize, usize, [f64; 2]),
    ) {
        let (lo, hi) = (
            band.start as i64 - self.x0 as i64,
            band.end as i64 - self.x0 as i64,
        );
        for y in (0..rows.len().saturating_sub(1)).filter(|&y| wanted(y)) {
            let row = &cells[rows[y] as usize..rows[y + 1] as usize];
            debug_assert!(row.windows(2).all(|w| w[0] < w[1]), "row {y} is not sorted");
            // Padded indices of the band's first column and of the column after its last.
            let row0 = ((y + 1) * self.stride) as i64 + 1;
            let (ka, kb) = ((row0 + lo).max(0) as u32, (row0 + hi).max(0) as u32);
            let from = row.partition_point(|&k| k < ka);
            let to = from + row[from..].partition_point(|&k| k < kb);
            for (n, &k) in row[from..to].iter().enumerate() {
                let (k, c) = (k as usize, rows[y] as usize + from + n);
                let col = (self.x_in_row(k, y) + self.x0 as i64) as usize;
                visit(c, col, self.centre_in_row(k, y));
            }
        }
    }

    /// The periodic images of a grain's centre that can reach this padded slab: the centre
    /// itself, shifted by ± the lattice size along periodic axes.
    pub fn images(&self, g: &GrainView) -> impl Iterator<Item = [f64; 2]> + '_ {
        let sx: &[f64] = if self.periodic_x {
            &[0.0, 1.0, -1.0]
        } else {
            &[0.0]
        };
        let sy: &[f64] = if self.periodic_y {
            &[0.0, 1.0, -1.0]
        } else {
            &[0.0]
        };
        let (gnx, ny) = (self.global_nx as f64, self.ny as f64);
        let centre = g.centre;
        let reach = g.radius + 2.0;
        let (lo, hi) = (self.x0 as f64 - 1.0, (self.x0 + self.nx) as f64 + 1.0);
        sx.iter()
            .flat_map(move |&a| {
                sy.iter()
                    .map(move |&b| [centre[0] + a * gnx, centre[1] + b * ny])
            })
            .filter(move |c| c[0] + reach >= lo && c[0] - reach <= hi)
    }

    /// Padded cells within the bounding box of a disk at `c` with radius `r` (global frame),
    /// clipped to the padded slab; calls `f(k, local x, local y)`.
    pub fn for_box(&self, c: [f64; 2], r: f64, mut f: impl FnMut(usize, i64, i64)) {
        let x0 = self.x0 as i64;
        let xa = ((c[0] - r).floor() as i64 - x0).max(-1);
        let xb = ((c[0] + r).floor() as i64 - x0).min(self.nx as i64);
        let ya = ((c[1] - r).floor() as i64).max(-1);
        let yb = ((c[1] + r).floor() as i64).min(self.ny as i64);
        for y in ya..=yb {
            for x in xa..=xb {
                f(self.padded(x, y), x, y);
            }
        }
    }
}

/// Which grain covers each padded cell, for the bounce-back schemes: a cell whose centre
/// lies inside a grain belongs to it (the nearest centre when two overlap, the lower index
/// on a tie). Only plain fluid cells of the lattice can be covered.
///
/// `touched` holds, on entry, the cells this map set last time (they are cleared, so the
/// cost follows the grains' area, not the lattice's); on exit, the cells set now, grain by
/// grain and row by row (a fixed order). `inner` receives the interior ones among them, in
/// the same order.
pub fn cover(
    frame: &SlabFrame,
    grains: &[GrainView],
    fluid: impl Fn(usize) -> bool,
    owner: &mut [u32],
    touched: &mut Vec<u32>,
    inner: &mut Vec<u32>,
) {
    for &k in touched.iter() {
        owner[k as usize] = NONE;
    }
    touched.clear();
    inner.clear();
    let (nx, ny) = (frame.nx as i64, frame.ny as i64);
    for (g, grain) in grains.iter().enumerate() {
        for c in frame.images(grain) {
            frame.for_box(c, grain.radius, |k, x, y| {
                let gx = x + frame.x0 as i64;
                if !fluid(k) || !covers(c, grain.radius, gx, y) {
                    return;
                }
                let o = owner[k];
                if o == NONE {
                    owner[k] = g as u32;
                    touched.push(k as u32);
                    if x >= 0 && y >= 0 && x < nx && y < ny {
                        inner.push(k as u32);
                    }
                } else if o != g as u32 {
                    let p = frame.centre(k);
                    let d2 = |q: [f64; 2]| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
                    let other = nearest_image(frame, &grains[o as usize], p);
                    if d2(c) < d2(other) {
                        owner[k] = g as u32;
                    }
                }
            });
        }
    }
}

/// The cells set in `owner` (a map of the grains `views`, as [`cover`] builds it), grain by
/// grain, each grain's images row by row: every cell a grain owns lies in its box.
/// `mark` is a per-cell scratch, all false on entry and exit.
pub fn set_cells(
    frame: &SlabFrame,
    views: &[GrainView],
    owner: &[u32],
    mark: &mut [bool],
    out: &mut Vec<u32>,
) {
    out.clear();
    for_owned(frame, views, owner, |k, _, _| {
        if !mark[k] {
            mark[k] = true;
            out.push(k as u32);
        }
    });
    for &k in out.iter() {
        mark[k as usize] = false;
    }
}

/// Visit every cell each grain of `views` owns in `owner` (padded index, local x, y),
/// grain by grain, each image's box row by row; a cell seen through two images of one
/// grain (on a lattice smaller than a grain's box) is visited twice.
pub fn for_owned(
    frame: &SlabFrame,
    views: &[GrainView],
    owner: &[u32],
    mut visit: impl FnMut(usize, i64, i64),
) {
    for (g, grain) in views.iter().enumerate() {
        for c in frame.images(grain) {
            frame.for_box(c, grain.radius, |k, x, y| {
                if owner[k] == g as u32 {
                    visit(k, x, y);
                }
            });
        }
    }
}

/// The image of grain `g` nearest to point `p`.
#[inline]
pub fn nearest_image(frame: &SlabFrame, g: &GrainView, p: [f64; 2]) -> [f64; 2] {
    nearest_image_at(frame, g, p).1
}

/// The image of grain `g` nearest to point `p` and its index among `frame.images(g)` (the
/// first of equally near ones); `(0, g.centre)` in a frame with no periodic axis or where
/// no image reaches the slab.
#[inline]
pub fn nearest_image_at(frame: &SlabFrame, g: &GrainView, p: [f64; 2]) -> (usize, [f64; 2]) {
    if !frame.periodic_x && !frame.periodic_y {
        return (0, g.centre);
    }
    let (mut best, mut at) = (g.centre, 0);
    let mut bd = f64::INFINITY;
    for (j, c) in frame.images(g).enumerate() {
        let d = (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2);
        if d < bd {
            bd = d;
            best = c;
            at = j;
        }
    }
    (at, best)
}

/// One grain's share of one cell for the partially saturated method (16 bytes: the map
/// writes ~250 k of them per step on the seed's Table 5.3 case, and the plan reads them
/// back).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[repr(C)] // the AVX-512 row walk writes shares as two u64: fraction, then cell | image << 32
pub struct Share {
    /// Solid fraction ε of the cell covered by this grain (exact disk–square area).
    pub fraction: f64,
    /// Padded cell index.
    pub cell: u32,
    /// The grain image (its index in the map's list of images that reach the slab, each
    /// a grain and the centre the cell sees).
    pub image: u32,
}

/// The interior rows (first, last; empty when first > last) a disk at `c` with radius `r`
/// can overlap.
pub fn share_rows(frame: &SlabFrame, c: [f64; 2], r: f64) -> (i64, i64) {
    (
        ((c[1] - r).floor() as i64).max(0),
        ((c[1] + r).floor() as i64).min(frame.ny as i64 - 1),
    )
}

/// One row's partially saturated shares, kept from the map to the plan (and read by
/// `Coupler::solid_fraction` in between).
#[derive(Debug, Clone, Default)]
pub struct ShareRow {
    /// The row's shares, sorted by cell, a cell's shares in grain order.
    pub(super) shares: Vec<Share>,
    /// How many distinct cells they cover.
    pub(super) cells: u32,
    /// Scratch of the map: the row's shares as each image's walk gave them.
    pub(super) walked: Vec<Share>,
    /// Scratch of the map: each image's stretch of `walked`, keyed by its first cell.
    pub(super) stretches: Vec<(u64, u32, u32)>,
}

impl ShareRow {
    /// Fill `shares` with the row's shares sorted by (cell, image), from the shares of each
    /// image in turn already in `walked`, each image's cells in increasing x (the
    /// stretches `stretches` of `walked`: key (first cell, image), first and end index):
    /// the stretches in order of their keys, then an insertion sort that only has to move
    /// the few shares where neighbouring disks' stretches overlap. The result is a sort of
    /// the keys (cell, image), unique in a row: the same order whatever the input order.
    pub(super) fn sort_walked(&mut self) {
        self.stretches.sort_unstable_by_key(|s| s.0);
        self.shares.clear();
        for &(_, a, b) in &self.stretches {
            self.shares
                .extend_from_slice(&self.walked[a as usize..b as usize]);
        }
        let key = |sh: &Share| (u64::from(sh.cell) << 32) | u64::from(sh.image);
        let v = &mut self.shares;
        // Moves beyond a few per share mean stretches that overlap widely (disks deep in
        // each other): a general sort is then the cheaper one.
        let (mut moves, budget) = (0usize, 8 * v.len() + 64);
        for i in 1..v.len() {
            let (x, kx) = (v[i], key(&v[i]));
            let mut j = i;
            while j > 0 && key(&v[j - 1]) > kx {
                v[j] = v[j - 1];
                j -= 1;
            }
            v[j] = x;
            moves += i - j;
            if moves > budget {
                v.sort_unstable_by_key(key);
                return;
            }
        }
    }
}

/// Padded index of the neighbour of `k` at `sign · c_i`.
#[inline]
pub(super) fn neighbour(f: &SlabFrame, k: usize, i: usize, sign: i64) -> usize {
    use lbm::d2q9::{CX, CY};
    (k as i64 + sign * (CX[i] as i64 + CY[i] as i64 * f.stride as i64)) as usize
}

#[cfg(test)]
mod tests {
    use super::{Share, ShareRow};
    use crate::test_slabs::{next, slab};

    /// `ShareRow::sort_walked` gives a full sort by (cell, image) of stretches that each
    /// increase, in any image order, overlapping by a few cells (touching disks) or widely
    /// (the general sort's fallback).
    #[test]
    fn sorting_the_walked_stretches_is_a_full_sort() {
        let mut rng = 12345u64;
        let mut draw = |m: u64| {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (rng >> 33) % m
        };
        for (case, spread) in [4000u64, 400, 8].into_iter().cycle().take(30).enumerate() {
            let mut row = ShareRow::default();
            let images = 1 + draw(300) as u32;
            for image in 0..images {
                let (first, len) = (draw(spread) as u32, 1 + draw(12) as u32);
                let a = row.walked.len() as u32;
                for c in first..first + len {
                    let fraction = draw(1000) as f64 / 1000.0;
                    row.walked.push(Share {
                        fraction,
                        cell: c,
                        image,
                    });
                }
                let key = (u64::from(first) << 32) | u64::from(image);
                row.stretches.push((key, a, row.walked.len() as u32));
            }
            let mut expected = row.walked.clone();
            expected.sort_unstable_by_key(|sh| (u64::from(sh.cell) << 32) | u64::from(sh.image));
            row.sort_walked();
            let got: Vec<_> = row
                .shares
                .iter()
                .map(|s| (s.cell, s.image, s.fraction.to_bits()))
                .collect();
            let want: Vec<_> = expected
                .iter()
                .map(|s| (s.cell, s.image, s.fraction.to_bits()))
                .collect();
            assert_eq!(got, want, "case {case} (spread {spread})");
        }
    }

    /// The sorted-row walk visits exactly the cells the full walk visits, in its order,
    /// for any band, rows empty or not, cells at the slab's first and last columns.
    #[test]
    fn sorted_band_walk_matches_the_full_walk() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        for case in 0..3 {
            let (f, _) = slab(case);
            // Random interior cells per row, increasing, both edge columns in row 0.
            let mut rows = vec![0u32];
            let mut cells = Vec::new();
            for y in 0..f.ny as i64 {
                for x in 0..f.nx as i64 {
                    let edge = y == 0 && (x == 0 || x == f.nx as i64 - 1);
                    if edge || (y % 7 != 3 && next(&mut seed) < 0.3) {
                        cells.push(f.padded(x, y) as u32);
                    }
                }
                rows.push(cells.len() as u32);
            }
            let (lo, hi) = (f.x0, f.x0 + f.nx);
            let mut bands = vec![lo..hi, lo..lo + 1, hi - 1..hi, lo + 5..lo + 5];
            for _ in 0..20 {
                let a = lo + (next(&mut seed) * f.nx as f64) as usize;
                let b = a + (next(&mut seed) * (hi - a) as f64) as usize;
                bands.push(a..b.max(a));
            }
            for band in bands {
                let (mut full, mut sorted) = (Vec::new(), Vec::new());
                f.band_cells(&rows, &cells, &band, |c, col, p| full.push((c, col, p)));
                f.band_cells_sorted(
                    &rows,
                    &cells,
                    &band,
                    |_| true,
                    |c, col, p| sorted.push((c, col, p)),
                );
                assert_eq!(full, sorted, "slab {case}, band {band:?}");
            }
        }
    }
}
