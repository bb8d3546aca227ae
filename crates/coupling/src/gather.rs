//! Building variable-length lists in parallel without locks or per-task allocations: the
//! start of every source's items is known first (counted, or grouped by row with
//! [`group_by_row`]), then each task writes its sources' items into their own slices of
//! the output ([`Shared`], [`row_of`]). The output is in source order whatever the thread
//! count.

/// A stable counting sort of `n` items by the rows each spans (`span(i)` = first and last
/// row, inclusive, last < `rows`): `order` receives the item indices grouped by row, an item
/// once in each row it spans, in their original order within a row, and `offsets` the start
/// of each row's group (rows + 1 values).
pub fn group_by_rows(
    n: usize,
    rows: usize,
    span: impl Fn(usize) -> [u32; 2],
    offsets: &mut Vec<u32>,
    order: &mut Vec<u32>,
) {
    offsets.clear();
    offsets.resize(rows + 1, 0);
    for i in 0..n {
        let [a, b] = span(i);
        for y in a..=b {
            offsets[y as usize + 1] += 1;
        }
    }
    for y in 0..rows {
        offsets[y + 1] += offsets[y];
    }
    order.clear();
    order.resize(offsets[rows] as usize, 0);
    // offsets[r] serves as row r's cursor, then everything moves back by one row.
    for i in 0..n {
        let [a, b] = span(i);
        for y in a as usize..=b as usize {
            order[offsets[y] as usize] = i as u32;
            offsets[y] += 1;
        }
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
    fn rows_keep_their_order() {
        let rows_of = [2u32, 0, 2, 1, 0, 2];
        let (mut off, mut order) = (Vec::new(), Vec::new());
        group_by_rows(6, 3, |i| [rows_of[i]; 2], &mut off, &mut order);
        assert_eq!(order, [1, 4, 3, 0, 2, 5]);
        assert_eq!(off, [0, 2, 3, 6]);
    }

    #[test]
    fn an_item_comes_once_in_every_row_it_spans() {
        let spans = [[1u32, 3], [0, 0], [2, 3], [0, 1]];
        let (mut off, mut order) = (Vec::new(), Vec::new());
        group_by_rows(4, 4, |i| spans[i], &mut off, &mut order);
        // Row 0: items 1, 3; row 1: 0, 3; row 2: 0, 2; row 3: 0, 2.
        assert_eq!(order, [1, 3, 0, 3, 0, 2, 0, 2]);
        assert_eq!(off, [0, 2, 4, 6, 8]);
    }
}
