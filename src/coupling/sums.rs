//! Per-grain sums that give the same bits on any number of ranks.
//!
//! A grain's force is a sum over the cells around it, and those cells may lie on several
//! ranks. Floating-point sums depend on their order, so the cells are never summed across
//! a rank face directly: each grain keeps one partial sum per lattice *column* (a column
//! lies wholly on one rank), filled in the order the cells were listed (the restriction of
//! a rank-independent order, see `exchange.rs`), and the grain's owner adds the partial sums
//! in global column order, its own and those that other ranks sent it alike.

use super::map::GrainView;

/// Momentum (x, y) and torque handed to a grain, lattice units.
pub type Load = [f64; 3];

/// Per grain, per column partial sums (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct ColumnSums {
    /// Per grain: the unwrapped column of its first slot.
    base: Vec<i64>,
    /// Per grain: its first slot; one more entry than grains.
    first: Vec<usize>,
    sums: Vec<Load>,
    used: Vec<bool>,
    /// Columns of the whole lattice (for wrapping unwrapped columns).
    global_nx: i64,
}

impl ColumnSums {
    /// Empty sums for `grains` (their windows of columns) on a lattice `global_nx` wide,
    /// keeping the allocations.
    pub fn reset(&mut self, grains: &[GrainView], global_nx: usize) {
        self.global_nx = global_nx as i64;
        self.base.clear();
        self.first.clear();
        self.first.push(0);
        let mut n = 0;
        for g in grains {
            // Cells within r + 2 of the centre, one halo column and one for rounding.
            let lo = (g.centre[0] - g.radius).floor() as i64 - 3;
            let hi = (g.centre[0] + g.radius).floor() as i64 + 3;
            self.base.push(lo);
            n += (hi - lo + 1) as usize;
            self.first.push(n);
        }
        self.sums.clear();
        self.sums.resize(n, [0.0; 3]);
        self.used.clear();
        self.used.resize(n, false);
    }

    /// Add `load` to grain `g`'s partial sum of column `column` (global, 0 ≤ column < nx)
    /// of the image whose centre is `image_x` (the grain's own centre, or that shifted by
    /// a lattice width across a periodic face).
    #[inline]
    pub fn add(&mut self, g: usize, grain_x: f64, image_x: f64, column: usize, load: Load) {
        // The column as seen from the grain's own centre (undo the image's shift).
        let shift = if grain_x == image_x {
            0
        } else {
            ((grain_x - image_x) / self.global_nx as f64).round() as i64 * self.global_nx
        };
        let slot = column as i64 + shift - self.base[g];
        let at = self.first[g] + slot as usize;
        debug_assert!(at < self.first[g + 1], "column outside the grain's window");
        let s = &mut self.sums[at];
        s[0] += load[0];
        s[1] += load[1];
        s[2] += load[2];
        self.used[at] = true;
    }

    /// Grain `g`'s partial sums as (global column, load), in increasing column.
    pub fn partials(&self, g: usize, out: &mut Vec<(u32, Load)>) {
        out.clear();
        for at in self.first[g]..self.first[g + 1] {
            if self.used[at] {
                let col = (self.base[g] + (at - self.first[g]) as i64).rem_euclid(self.global_nx);
                out.push((col as u32, self.sums[at]));
            }
        }
        out.sort_unstable_by_key(|p| p.0);
    }
}

/// The left fold from zero of `partials` sorted by column (stable for equal columns, which
/// cannot happen when every column is summed on one rank): a grain's total, the same bits
/// wherever its partial sums were made.
pub fn total(partials: &mut [(u32, Load)]) -> Load {
    partials.sort_by_key(|p| p.0);
    let mut t = [0.0; 3];
    for (_, p) in partials.iter() {
        t[0] += p[0];
        t[1] += p[1];
        t[2] += p[2];
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grain(x: f64) -> GrainView {
        GrainView {
            centre: [x, 10.0],
            radius: 4.0,
            velocity: [0.0; 2],
            omega: 0.0,
        }
    }

    /// Column partials summed on "two ranks" and merged give the bits of one rank.
    #[test]
    fn split_sums_match_one_sum() {
        let g = [grain(1.0)];
        // Columns 0..5 and, across the periodic face, 96..99 of a 100-wide lattice.
        let cells: Vec<(usize, f64, Load)> = (0..40)
            .map(|k| {
                let col = [0, 1, 2, 3, 4, 97, 98, 99][k % 8];
                let image = if col > 50 { 101.0 } else { 1.0 };
                (
                    col,
                    image,
                    [0.1 * k as f64, 1.0 / (k + 3) as f64, (k as f64).sqrt()],
                )
            })
            .collect();
        let mut one = ColumnSums::default();
        one.reset(&g, 100);
        for &(c, img, l) in &cells {
            one.add(0, 1.0, img, c, l);
        }
        let mut p = Vec::new();
        one.partials(0, &mut p);
        assert_eq!(
            p.iter().map(|x| x.0).collect::<Vec<_>>(),
            [0, 1, 2, 3, 4, 97, 98, 99]
        );
        let whole = total(&mut p);
        // Rank A holds columns < 50, rank B the rest.
        let (mut a, mut b) = (one.clone(), one.clone());
        a.reset(&g, 100);
        b.reset(&g, 100);
        for &(c, img, l) in &cells {
            if c < 50 { &mut a } else { &mut b }.add(0, 1.0, img, c, l);
        }
        let (mut pa, mut pb) = (Vec::new(), Vec::new());
        a.partials(0, &mut pa);
        b.partials(0, &mut pb);
        let mut merged: Vec<_> = pb.into_iter().chain(pa).collect();
        let split = total(&mut merged);
        assert_eq!(whole.map(f64::to_bits), split.map(f64::to_bits));
    }
}
