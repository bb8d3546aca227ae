//! Load balance of the slabs: points per cell column, and slab boundaries that split them
//! evenly.

use super::error::MpmError;
use super::points::Points;
use super::GridSpec;

/// Fewest cell columns in a slab: the strips a node needs come from at most three columns
/// on either side, which must belong to the adjacent rank.
pub const MIN_COLUMNS: usize = 3;

/// Steps between checks of the load balance.
pub const REBALANCE_EVERY: u64 = 200;

/// Points per cell column (every point must lie in the grid).
pub fn column_counts(points: &Points, spec: &GridSpec) -> Result<Vec<f64>, MpmError> {
    let mut counts = vec![0.0; spec.nx];
    for (i, p) in points.pos.iter().enumerate() {
        let c = (p[0] / spec.h).floor();
        if !(c >= 0.0 && c < spec.nx as f64 && p[1] >= 0.0 && p[1] < spec.height()) {
            return Err(MpmError::LeftDomain {
                step: 0,
                id: points.id[i],
                x: p[0],
                y: p[1],
            });
        }
        counts[c as usize] += 1.0;
    }
    Ok(counts)
}

/// Slab boundaries (cell columns, length `ranks + 1`) that split `counts` into contiguous
/// slabs of nearly equal totals, each at least [`MIN_COLUMNS`] wide.
pub fn balanced_columns(counts: &[f64], ranks: usize, nx: usize) -> Result<Vec<usize>, MpmError> {
    if nx < MIN_COLUMNS * ranks {
        return Err(MpmError::TooManyRanks { ranks, columns: nx });
    }
    let total: f64 = counts.iter().sum();
    let mut bounds = vec![0usize; ranks + 1];
    bounds[ranks] = nx;
    let mut acc = 0.0;
    let mut c = 0;
    for r in 1..ranks {
        let target = total * r as f64 / ranks as f64;
        let lo = bounds[r - 1] + MIN_COLUMNS;
        let hi = nx - MIN_COLUMNS * (ranks - r);
        while c < lo || (c < hi && acc + counts[c] * 0.5 < target) {
            acc += counts[c];
            c += 1;
        }
        bounds[r] = c;
    }
    Ok(bounds)
}
