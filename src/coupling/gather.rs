//! Building variable-length lists in parallel without locks or per-task allocations: every
//! source first says how many items it will produce, then writes them into its own slice
//! of the output. The output is in source order whatever the thread count.

use rayon::prelude::*;

/// Fill `out` with the items of sources `0..n`, in source order: source s produces
/// `count(s)` items, written by `fill(s, slice)` into a slice of exactly that length.
/// `offsets` receives the start of each source's items (n + 1 values). Both vectors keep
/// their allocations between calls.
pub fn gather<I, C, F>(n: usize, offsets: &mut Vec<u32>, out: &mut Vec<I>, count: C, fill: F)
where
    I: Send + Copy + Default,
    C: Fn(usize) -> usize + Sync,
    F: Fn(usize, &mut [I]) + Sync,
{
    let mut none: Vec<()> = Vec::new();
    gather2(n, offsets, out, &mut none, count, |s, a, _| fill(s, a));
}

/// [`gather`] into two parallel outputs at once (`a[j]` and `b[j]` belong together).
pub fn gather2<A, B, C, F>(
    n: usize,
    offsets: &mut Vec<u32>,
    a: &mut Vec<A>,
    b: &mut Vec<B>,
    count: C,
    fill: F,
) where
    A: Send + Copy + Default,
    B: Send + Copy + Default,
    C: Fn(usize) -> usize + Sync,
    F: Fn(usize, &mut [A], &mut [B]) + Sync,
{
    (0..n)
        .into_par_iter()
        .with_min_len(64)
        .map(|s| count(s) as u32)
        .collect_into_vec(offsets);
    let mut total = 0u32;
    for o in offsets.iter_mut() {
        let c = *o;
        *o = total;
        total += c;
    }
    offsets.push(total);
    // Every slot is written by `fill`, so only slots beyond the old length need a value
    // first: keeping the old ones saves rewriting the whole output every call.
    let len = total as usize;
    a.resize(len, A::default());
    b.resize(len, B::default());
    let (pa, pb) = (Shared(a.as_mut_ptr()), Shared(b.as_mut_ptr()));
    let offsets = &*offsets;
    (0..n).into_par_iter().with_min_len(64).for_each(|s| {
        let (lo, hi) = (offsets[s] as usize, offsets[s + 1] as usize);
        // SAFETY: the ranges [lo, hi) of different sources are disjoint and inside both
        // outputs, which are not otherwise touched during the pass.
        let (sa, sb) = unsafe {
            (
                std::slice::from_raw_parts_mut(pa.get().add(lo), hi - lo),
                std::slice::from_raw_parts_mut(pb.get().add(lo), hi - lo),
            )
        };
        fill(s, sa, sb);
    });
}

/// A stable counting sort of `n` items by row (`row(i)` < `rows`): `order` receives the
/// item indices grouped by row, in their original order within a row, and `offsets` the
/// start of each row's group (rows + 1 values).
pub fn group_by_row(
    n: usize,
    rows: usize,
    row: impl Fn(usize) -> usize,
    offsets: &mut Vec<u32>,
    order: &mut Vec<u32>,
) {
    offsets.clear();
    offsets.resize(rows + 1, 0);
    for i in 0..n {
        offsets[row(i) + 1] += 1;
    }
    for y in 0..rows {
        offsets[y + 1] += offsets[y];
    }
    order.clear();
    order.resize(n, 0);
    // offsets[r] serves as row r's cursor, then everything moves back by one row.
    for i in 0..n {
        let r = row(i);
        order[offsets[r] as usize] = i as u32;
        offsets[r] += 1;
    }
    for r in (1..=rows).rev() {
        offsets[r] = offsets[r - 1];
    }
    offsets[0] = 0;
}

/// A raw pointer that tasks writing disjoint ranges may share.
#[derive(Clone, Copy)]
pub(super) struct Shared<I>(pub(super) *mut I);
// SAFETY: only used for disjoint writes (see `gather`).
unsafe impl<I> Send for Shared<I> {}
unsafe impl<I> Sync for Shared<I> {}

impl<I> Shared<I> {
    /// The pointer (a method, so closures capture the whole `Send` wrapper).
    pub(super) fn get(&self) -> *mut I {
        self.0
    }
}

/// Row `y` of a vector grouped by row (`offsets`: where each row starts, ny + 1 values) that
/// `base` points into.
///
/// # Safety
/// `offsets[y + 1]` is within the vector, and no one else reads or writes row y while the
/// slice lives.
#[allow(clippy::mut_from_ref)]
pub(super) unsafe fn row_of<'a, I>(base: &Shared<I>, offsets: &[u32], y: usize) -> &'a mut [I] {
    let (a, b) = (offsets[y] as usize, offsets[y + 1] as usize);
    std::slice::from_raw_parts_mut(base.get().add(a), b - a)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_come_in_source_order() {
        let (mut off, mut out) = (Vec::new(), Vec::new());
        gather(
            500,
            &mut off,
            &mut out,
            |s| s % 4,
            |s, slice| {
                for (k, v) in slice.iter_mut().enumerate() {
                    *v = (s, k);
                }
            },
        );
        let expect: Vec<(usize, usize)> = (0..500)
            .flat_map(|s| (0..s % 4).map(move |k| (s, k)))
            .collect();
        assert_eq!(out, expect);
        assert_eq!(off.len(), 501);
        assert_eq!(off[500] as usize, expect.len());
        // A second, shorter call reuses the output without a stale item left over.
        gather(
            7,
            &mut off,
            &mut out,
            |s| s % 3,
            |s, slice| {
                for (k, v) in slice.iter_mut().enumerate() {
                    *v = (s + 1000, k);
                }
            },
        );
        let expect: Vec<(usize, usize)> = (0..7)
            .flat_map(|s| (0..s % 3).map(move |k| (s + 1000, k)))
            .collect();
        assert_eq!(out, expect);
    }

    #[test]
    fn rows_keep_their_order() {
        let rows_of = [2usize, 0, 2, 1, 0, 2];
        let (mut off, mut order) = (Vec::new(), Vec::new());
        group_by_row(6, 3, |i| rows_of[i], &mut off, &mut order);
        assert_eq!(order, [1, 4, 3, 0, 2, 5]);
        assert_eq!(off, [0, 2, 3, 6]);
    }
}
