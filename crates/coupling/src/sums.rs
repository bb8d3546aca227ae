//! Per-grain sums that give the same bits on any number of ranks.
//!
//! A grain's force is a sum over the cells around it, and those cells may lie on several
//! ranks. Floating-point sums depend on their order, so the cells are never summed across
//! a rank face directly: each grain keeps one partial sum per lattice *column* (a column
//! lies wholly on one rank), filled in the order the cells were listed (the restriction of
//! a rank-independent order, see `exchange.rs`), and the grain's owner adds the partial sums
//! in global column order, its own and those that other ranks sent it alike.

use super::gather::Shared;
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
    /// Per slot: its sum, meaningful only where `used` marks it (a reset keeps old values).
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
        // Only the marks are cleared: a slot's first load overwrites whatever it held
        // (see `accumulate`), so the sums need no zeroing, only room.
        if self.sums.len() < n {
            self.sums.resize(n, [0.0; 3]);
        }
        self.used.clear();
        self.used.resize(n, false);
    }

    /// Add `load` to grain `g`'s partial sum of column `column` (global, 0 ≤ column < nx)
    /// of the image whose centre is `image_x` (the grain's own centre, or that shifted by
    /// a lattice width across a periodic face).
    #[inline]
    pub fn add(&mut self, g: usize, grain_x: f64, image_x: f64, column: usize, load: Load) {
        let at = self.slot(g, grain_x, image_x, column);
        accumulate(&mut self.sums[at], &mut self.used[at], load);
    }

    /// The slot of grain `g`'s partial sum of `column` (as [`ColumnSums::add`]), inside the
    /// grain's own window (panics otherwise). Different columns of one slab give different
    /// slots: they differ by less than a lattice width.
    #[inline]
    fn slot(&self, g: usize, grain_x: f64, image_x: f64, column: usize) -> usize {
        // The column as seen from the grain's own centre (undo the image's shift).
        let shift = if grain_x == image_x {
            0
        } else {
            ((grain_x - image_x) / self.global_nx as f64).round() as i64 * self.global_nx
        };
        let slot = column as i64 + shift - self.base[g];
        let width = (self.first[g + 1] - self.first[g]) as i64;
        assert!(
            (0..width).contains(&slot),
            "column outside the grain's window"
        );
        self.first[g] + slot as usize
    }

    /// Grain `g`'s window of slots as seen from its image at `image_x` (the grain's own
    /// centre at `grain_x`, or that shifted by a lattice width): for [`Adder::add_to`], which
    /// then needs neither the grain nor the shift per load.
    pub fn window(&self, g: usize, grain_x: f64, image_x: f64) -> Window {
        let shift = if grain_x == image_x {
            0
        } else {
            ((grain_x - image_x) / self.global_nx as f64).round() as i64 * self.global_nx
        };
        Window {
            offset: self.first[g] as i64 + shift - self.base[g],
            first: self.first[g],
            end: self.first[g + 1],
        }
    }

    /// Add `load` to the slot of global column `column` in the window `w` (from
    /// [`ColumnSums::window`]): as [`Adder::add_to`], serially.
    #[inline]
    pub fn add_in(&mut self, w: &Window, column: usize, load: Load) {
        let at = w.offset + column as i64;
        assert!(
            at >= w.first as i64 && (at as usize) < w.end,
            "column outside the grain's window"
        );
        let at = at as usize;
        accumulate(&mut self.sums[at], &mut self.used[at], load);
    }

    /// Fill the sums in parallel, one task per band of the global columns `lo..hi`:
    /// `fill(band, adder)` adds (with [`Adder::add`]) the loads of the band's columns, in
    /// the order one serial fill would add them. Bands hold different columns, hence
    /// different slots, so every slot gets its loads in the serial order: the same bits.
    pub fn fill_by_columns<F>(&mut self, lo: usize, hi: usize, fill: F)
    where
        F: Fn(std::ops::Range<usize>, &Adder<'_>) + Sync,
    {
        use rayon::prelude::*;
        let bands = rayon::current_num_threads().clamp(1, (hi - lo).max(1));
        let (sums, used) = (
            Shared(self.sums.as_mut_ptr()),
            Shared(self.used.as_mut_ptr()),
        );
        let this = &*self;
        (0..bands).into_par_iter().for_each(|b| {
            let band = lo + (hi - lo) * b / bands..lo + (hi - lo) * (b + 1) / bands;
            let adder = Adder {
                sums: this,
                band: band.clone(),
                out: (sums, used),
            };
            fill(band, &adder);
        });
    }

    /// Grain `g`'s total when its window does not wrap around a periodic face: its used
    /// slots added in window order, which is then increasing global column, so the bits of
    /// [`total`] of [`ColumnSums::partials`] without listing or sorting them. `None` when
    /// the window wraps (columns of both sides of the face: list them and sort).
    #[inline]
    pub fn total_in_order(&self, g: usize) -> Option<Load> {
        let (first, end) = (self.first[g], self.first[g + 1]);
        let base = self.base[g];
        if base < 0 || base + (end - first) as i64 > self.global_nx {
            return None;
        }
        let mut t = [0.0; 3];
        for (s, &used) in self.sums[first..end].iter().zip(&self.used[first..end]) {
            if used {
                t[0] += s[0];
                t[1] += s[1];
                t[2] += s[2];
            }
        }
        Some(t)
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

/// One grain image's slots (see [`ColumnSums::window`]): column c's slot is `offset + c`,
/// which must lie in `first..end`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Window {
    offset: i64,
    first: usize,
    end: usize,
}

/// Adds loads to the columns of one band of a [`ColumnSums::fill_by_columns`].
pub struct Adder<'a> {
    sums: &'a ColumnSums,
    band: std::ops::Range<usize>,
    out: (Shared<Load>, Shared<bool>),
}

impl Adder<'_> {
    /// As [`ColumnSums::add`], for a column of this band (panics otherwise).
    #[inline]
    pub fn add(&self, g: usize, grain_x: f64, image_x: f64, column: usize, load: Load) {
        assert!(self.band.contains(&column), "column outside the band");
        let at = self.sums.slot(g, grain_x, image_x, column);
        self.put(at, load);
    }

    /// [`ColumnSums::window`] of the sums this adds to.
    #[inline]
    pub fn window(&self, g: usize, grain_x: f64, image_x: f64) -> Window {
        self.sums.window(g, grain_x, image_x)
    }

    /// As [`Adder::add`], for the grain image whose slots are `w` (from
    /// [`ColumnSums::window`]): the same slot.
    #[inline]
    pub fn add_to(&self, w: &Window, column: usize, load: Load) {
        assert!(self.band.contains(&column), "column outside the band");
        let at = w.offset + column as i64;
        assert!(
            at >= w.first as i64 && (at as usize) < w.end,
            "column outside the grain's window"
        );
        self.put(at as usize, load);
    }

    /// Add `load` to slot `at`, which lies in a grain's window (checked by the caller), of a
    /// column of this band.
    #[inline(always)]
    fn put(&self, at: usize, load: Load) {
        // SAFETY: `at` is in bounds, in a grain's window (checked by the caller); only
        // this band's task adds to columns of the band, and their slots are no other
        // column's (see `slot`); nothing else reads the sums during the fill.
        unsafe {
            accumulate(
                &mut *self.out.0.get().add(at),
                &mut *self.out.1.get().add(at),
                load,
            )
        }
    }
}

/// Add `load` to the slot `s` with its mark `used` (set here): the first load goes on 0.0
/// (not on what the slot held before its reset), so the sum has the bits of a sum from zero
/// (0.0 + x is x except for x = −0.0, which gives +0.0, as it always did here).
#[inline(always)]
fn accumulate(s: &mut Load, used: &mut bool, load: Load) {
    if *used {
        s[0] += load[0];
        s[1] += load[1];
        s[2] += load[2];
    } else {
        *s = [0.0 + load[0], 0.0 + load[1], 0.0 + load[2]];
        *used = true;
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

    /// A grain's total added in window order is the sorted partials' total, to the bit,
    /// with stale sums from before the reset in the unused slots; a window that wraps
    /// around the periodic face is left to the sort.
    #[test]
    fn in_order_total_matches_the_sorted_total() {
        // Windows across the left face (x = 1), starting at column 0 (x = 7: the first
        // that does not wrap), inside, ending at column 99 (x = 93) and across the right
        // face (x = 98.5).
        let gs: Vec<GrainView> = [1.0, 7.0, 30.0, 55.0, 93.0, 98.5]
            .into_iter()
            .map(grain)
            .collect();
        // Loads on columns around each grain; with `skip`, none on the column right of
        // its centre, so an unused slot sits between used ones.
        let fill = |s: &mut ColumnSums, skip: bool, scale: f64| {
            s.reset(&gs, 100);
            for k in 0..600 {
                let g = (k * 7) % gs.len();
                let c = gs[g].centre[0].floor() as i64 - 6 + (k % 13) as i64;
                if skip && c == gs[g].centre[0].floor() as i64 + 1 {
                    continue;
                }
                let v = scale / (k as f64 + 0.3);
                // A column across the face belongs to the image shifted by the width.
                let x = gs[g].centre[0];
                let image = x - 100.0 * c.div_euclid(100) as f64;
                s.add(
                    g,
                    x,
                    image,
                    c.rem_euclid(100) as usize,
                    [v, -3.3 * v, v * v],
                );
            }
        };
        // Every slot filled first, then reset and refilled: the skipped slots keep stale
        // sums that an unmarked read would add.
        let mut s = ColumnSums::default();
        fill(&mut s, false, 7.0);
        fill(&mut s, true, 1.0);
        let mut p = Vec::new();
        let mut in_order = 0;
        for g in 0..gs.len() {
            s.partials(g, &mut p);
            let want = total(&mut p).map(f64::to_bits);
            match s.total_in_order(g) {
                Some(t) => {
                    assert_eq!(t.map(f64::to_bits), want, "grain {g}");
                    in_order += 1;
                }
                None => {
                    let c = gs[g].centre[0];
                    assert!(
                        !(8.0..92.0).contains(&c),
                        "grain {g} at {c} left to the sort"
                    );
                }
            }
        }
        assert_eq!(in_order, 3, "the three inner windows are added in order");
    }

    /// Loads added in parallel over bands of columns give the bits of one serial fill,
    /// whatever the number of bands; a load outside its band is refused.
    #[test]
    fn banded_fill_matches_a_serial_fill() {
        let gs: Vec<GrainView> = (0..7).map(|n| grain(8.0 + 13.0 * n as f64)).collect();
        // (grain, column, load), several per slot, in one fixed order.
        let loads: Vec<(usize, usize, Load)> = (0..3000)
            .map(|k| {
                let g = (k * 7919) % gs.len();
                let col = (gs[g].centre[0] as i64 - 5 + ((k * 31) % 11) as i64) as usize;
                let v = 1.0 / (k as f64 + 1.7);
                (g, col, [v, -v * 3.1, (k as f64).sqrt() * v])
            })
            .collect();
        let mut serial = ColumnSums::default();
        serial.reset(&gs, 100);
        for &(g, c, l) in &loads {
            serial.add(g, gs[g].centre[0], gs[g].centre[0], c, l);
        }
        let mut want = Vec::new();
        for threads in [1, 2, 3, 5] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            let mut banded = ColumnSums::default();
            banded.reset(&gs, 100);
            pool.install(|| {
                banded.fill_by_columns(0, 100, |band, adder| {
                    for &(g, c, l) in loads.iter().filter(|x| band.contains(&x.1)) {
                        adder.add(g, gs[g].centre[0], gs[g].centre[0], c, l);
                    }
                })
            });
            for g in 0..gs.len() {
                let (mut a, mut b) = (Vec::new(), Vec::new());
                serial.partials(g, &mut a);
                banded.partials(g, &mut b);
                want.push(a.len());
                let bits = |p: &[(u32, Load)]| -> Vec<(u32, [u64; 3])> {
                    p.iter().map(|x| (x.0, x.1.map(f64::to_bits))).collect()
                };
                assert_eq!(bits(&a), bits(&b), "{threads} threads, grain {g}");
            }
        }
        assert!(want.iter().all(|&n| n > 5));
        let refused = std::panic::catch_unwind(|| {
            let mut s = ColumnSums::default();
            s.reset(&gs, 100);
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(2)
                .build()
                .expect("pool");
            pool.install(|| {
                s.fill_by_columns(0, 100, |_, adder| adder.add(0, 8.0, 8.0, 7, [1.0; 3]))
            });
        });
        assert!(refused.is_err(), "a load outside its band is added");
        // Left of the grain's window (columns 14..=28 for the disk at x = 21, r = 4):
        // refused, not added to the last slot of the grain before it.
        let outside = std::panic::catch_unwind(|| {
            let mut s = ColumnSums::default();
            s.reset(&gs, 100);
            s.add(1, 21.0, 21.0, 13, [1.0; 3]);
        });
        assert!(outside.is_err(), "a load left of the window is added");
    }
}
