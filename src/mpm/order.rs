//! Keeping the points in canonical order: by cell column, cell row, then id. The order
//! fixes the summation order of every node sum (see [`super::transfer`]), so that results
//! do not depend on threads, ranks or where a point was stored before.

use super::grid::GridSpec;
use super::points::{PermuteScratch, Points};
use super::transfer::Columns;
use rayon::prelude::*;

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
    order: Vec<u32>,
    keys: Vec<u64>,
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

/// Recompute every point's cell, restore the canonical order if any point moved out of
/// it (a stable counting sort by cell, then ids within each cell), and rebuild the column
/// starts. Returns whether the points were permuted, or the first point outside the grid.
pub fn sort_points(
    points: &mut Points,
    spec: &GridSpec,
    columns: &mut Columns,
    scratch: &mut OrderScratch,
) -> Result<bool, Outside> {
    let n = points.len();
    columns.cell.resize(n, [0; 2]);
    let bad = columns
        .cell
        .par_iter_mut()
        .zip(points.pos.par_iter())
        .map(|(c, &p)| match cell_of(p, spec) {
            Some(cell) => {
                *c = cell;
                None
            }
            None => Some(p),
        })
        .enumerate()
        .find_first(|(_, p)| p.is_some());
    if let Some((i, Some(pos))) = bad {
        return Err(Outside {
            id: points.id[i],
            pos,
        });
    }
    let key = |c: [u32; 2]| c[0] as u64 * spec.ny as u64 + c[1] as u64;
    let sorted = (1..n).into_par_iter().all(|i| {
        let (a, b) = (key(columns.cell[i - 1]), key(columns.cell[i]));
        a < b || (a == b && points.id[i - 1] < points.id[i])
    });
    let mut permuted = false;
    if !sorted {
        let cells = spec.nx * spec.ny;
        let OrderScratch {
            counts,
            order,
            keys,
            permute,
        } = scratch;
        keys.clear();
        keys.extend(columns.cell.iter().map(|&c| key(c)));
        counts.clear();
        counts.resize(cells + 1, 0);
        for &k in keys.iter() {
            counts[k as usize + 1] += 1;
        }
        for c in 0..cells {
            counts[c + 1] += counts[c];
        }
        order.clear();
        order.resize(n, 0);
        for (i, &k) in keys.iter().enumerate() {
            let slot = &mut counts[k as usize];
            order[*slot] = i as u32;
            *slot += 1;
        }
        // Within a cell, ascending id (cells hold a handful of points: insertion sort).
        let mut s = 0;
        while s < n {
            let k = keys[order[s] as usize];
            let mut e = s + 1;
            while e < n && keys[order[e] as usize] == k {
                e += 1;
            }
            for i in s + 1..e {
                let mut j = i;
                while j > s && points.id[order[j - 1] as usize] > points.id[order[j] as usize] {
                    order.swap(j - 1, j);
                    j -= 1;
                }
            }
            s = e;
        }
        points.permute(order, permute);
        let cell = std::mem::take(&mut columns.cell);
        columns.cell = order.iter().map(|&o| cell[o as usize]).collect();
        permuted = true;
    }
    columns.start.clear();
    columns.start.resize(spec.nx + 1, 0);
    for c in columns.cell.iter() {
        columns.start[c[0] as usize + 1] += 1;
    }
    for c in 0..spec.nx {
        columns.start[c + 1] += columns.start[c];
    }
    Ok(permuted)
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
        assert_eq!(
            sort_points(&mut p, &spec, &mut cols, &mut scratch),
            Ok(true)
        );
        assert_eq!(p.id, vec![7, 8, 9, 5, 6, 10]);
        assert_eq!(cols.start, vec![0, 3, 4, 6]);
        assert_eq!(
            sort_points(&mut p, &spec, &mut cols, &mut scratch),
            Ok(false)
        );
        p.pos[0] = [3.5, 0.0];
        assert_eq!(
            sort_points(&mut p, &spec, &mut cols, &mut scratch),
            Err(Outside {
                id: 7,
                pos: [3.5, 0.0]
            })
        );
    }
}
