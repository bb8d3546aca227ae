//! The canonical order of the points: by cell column, cell row, then id. It fixes the
//! summation order of every node sum (see [`super::transfer`]), so that results do not
//! depend on threads, ranks or where a point happens to be stored.
//!
//! The order is kept as an index list over the storage ([`Columns::order`]); the point
//! arrays themselves are permuted into it only every [`REORDER_EVERY`] steps, for memory
//! locality. The per-point sweeps run in storage order, which does not affect results.

use super::grid::GridSpec;
use super::points::{PermuteScratch, Points};
use super::transfer::Columns;
use rayon::prelude::*;

/// Steps between physical reorders of the point arrays into the canonical order.
pub const REORDER_EVERY: u64 = 50;

/// A point outside the grid (it left the domain through an open side, or the run went
/// unstable).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outside {
    /// The point's id.
    pub id: u64,
    /// Its position (m).
    pub pos: [f64; 2],
}

/// Scratch of the sort, reused every step.
#[derive(Debug, Default)]
pub struct OrderScratch {
    counts: Vec<usize>,
    next: Vec<u32>,
    permute: PermuteScratch,
}

/// Cell of a position; `None` when outside the grid or not finite.
#[inline(always)]
pub fn cell_of(pos: [f64; 2], spec: &GridSpec) -> Option<[u32; 2]> {
    let cx = (pos[0] / spec.h).floor();
    let cy = (pos[1] / spec.h).floor();
    if cx >= 0.0 && cy >= 0.0 && cx < spec.nx as f64 && cy < spec.ny as f64 {
        Some([cx as u32, cy as u32])
    } else {
        None
    }
}

/// Recompute every point's cell and bring [`Columns`] up to date: the canonical order
/// (rebuilt by a stable counting sort by column of the previous order, then an insertion
/// sort by row and id within each column, only when some point changed cell) and the
/// column starts. With `reorder`, the point arrays are then permuted into that order.
/// Returns the first point outside the grid as an error.
pub fn sort_points(
    points: &mut Points,
    spec: &GridSpec,
    columns: &mut Columns,
    scratch: &mut OrderScratch,
    reorder: bool,
) -> Result<(), Outside> {
    let n = points.len();
    let fresh = columns.cell.len() != n || columns.order.len() != n;
    columns.cell.resize(n, [u32::MAX; 2]);
    let found = columns
        .cell
        .par_iter_mut()
        .zip(points.pos.par_iter())
        .enumerate()
        .map(|(i, (c, &p))| match cell_of(p, spec) {
            Some(cell) => {
                let moved = *c != cell;
                *c = cell;
                (moved, None)
            }
            None => (false, Some(i)),
        })
        .reduce(
            || (false, None),
            |a, b| {
                let first = match (a.1, b.1) {
                    (Some(x), Some(y)) => Some(x.min(y)),
                    (x, y) => x.or(y),
                };
                (a.0 || b.0, first)
            },
        );
    if let (_, Some(i)) = found {
        return Err(Outside {
            id: points.id[i],
            pos: points.pos[i],
        });
    }
    if fresh {
        columns.order.clear();
        columns.order.extend(0..n as u32);
    }
    if found.0 || fresh {
        rebuild_order(points, spec, columns, scratch);
    }
    if reorder {
        points.permute(&columns.order, &mut scratch.permute);
        let cells: Vec<[u32; 2]> = columns
            .order
            .iter()
            .map(|&o| columns.cell[o as usize])
            .collect();
        columns.cell = cells;
        for (k, o) in columns.order.iter_mut().enumerate() {
            *o = k as u32;
        }
    }
    Ok(())
}

fn rebuild_order(
    points: &Points,
    spec: &GridSpec,
    columns: &mut Columns,
    scratch: &mut OrderScratch,
) {
    let Columns { start, cell, order } = columns;
    let OrderScratch { counts, next, .. } = scratch;
    counts.clear();
    counts.resize(spec.nx + 1, 0);
    for &o in order.iter() {
        counts[cell[o as usize][0] as usize + 1] += 1;
    }
    for c in 0..spec.nx {
        counts[c + 1] += counts[c];
    }
    start.clear();
    start.extend_from_slice(counts);
    next.clear();
    next.resize(order.len(), 0);
    for &o in order.iter() {
        let slot = &mut counts[cell[o as usize][0] as usize];
        next[*slot] = o;
        *slot += 1;
    }
    std::mem::swap(order, next);
    // Within a column: ascending (row, id). The previous order was canonical, so each
    // column is nearly sorted and insertion sort does little work.
    let key = |o: u32| (cell[o as usize][1], points.id[o as usize]);
    let mut rest: &mut [u32] = order;
    let mut pieces = Vec::with_capacity(spec.nx);
    for c in 0..spec.nx {
        let (head, tail) = rest.split_at_mut(start[c + 1] - start[c]);
        pieces.push(head);
        rest = tail;
    }
    pieces.into_par_iter().for_each(|col| {
        for i in 1..col.len() {
            let mut j = i;
            while j > 0 && key(col[j - 1]) > key(col[j]) {
                col.swap(j - 1, j);
                j -= 1;
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sorts_by_column_row_then_id() {
        let spec = GridSpec {
            nx: 3,
            ny: 2,
            h: 1.0,
        };
        let mut p = Points::default();
        let spots = [
            [2.5, 0.5],
            [0.2, 1.5],
            [0.7, 1.2],
            [0.5, 0.5],
            [2.1, 0.1],
            [1.5, 1.5],
        ];
        for (i, &s) in spots.iter().enumerate() {
            p.push(10 - i as u64, s, 1.0, 1.0, 0.25, 0);
        }
        let mut cols = Columns::default();
        let mut scratch = OrderScratch::default();
        sort_points(&mut p, &spec, &mut cols, &mut scratch, false).unwrap();
        let ids: Vec<u64> = cols.order.iter().map(|&o| p.id[o as usize]).collect();
        assert_eq!(ids, vec![7, 8, 9, 5, 6, 10]);
        assert_eq!(cols.start, vec![0, 3, 4, 6]);
        // A point moves to another cell: the order follows.
        p.pos[3] = [2.9, 1.9]; // id 7 → column 2, row 1
        sort_points(&mut p, &spec, &mut cols, &mut scratch, true).unwrap();
        assert_eq!(p.id, vec![8, 9, 5, 6, 10, 7]);
        assert_eq!(cols.order, vec![0, 1, 2, 3, 4, 5]);
        assert_eq!(cols.start, vec![0, 2, 3, 6]);
        assert_eq!(cols.cell[5], [2, 1]);
        p.pos[0] = [3.5, 0.0];
        assert_eq!(
            sort_points(&mut p, &spec, &mut cols, &mut scratch, false),
            Err(Outside {
                id: 8,
                pos: [3.5, 0.0]
            })
        );
    }
}
