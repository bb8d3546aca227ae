//! Slab partition of a 2-D lattice along x.

use thiserror::Error;

/// Why a partition could not be built.
#[derive(Debug, Error, PartialEq)]
pub enum PartitionError {
    /// More ranks than columns: some slab would be empty.
    #[error(
        "cannot split {columns} columns over {ranks} ranks: every rank needs at least one column"
    )]
    TooManyRanks {
        /// Global columns.
        columns: usize,
        /// Ranks asked for.
        ranks: usize,
    },
    /// The cost vector does not match the number of columns or holds a non-positive cost.
    #[error("column cost vector is invalid: {0}")]
    BadCosts(String),
    /// Slabs of the least width asked for do not fit in the columns.
    #[error(
        "cannot split {columns} columns over {ranks} ranks of at least {min_width} columns each"
    )]
    TooNarrow {
        /// Global columns.
        columns: usize,
        /// Ranks asked for.
        ranks: usize,
        /// The least width of a slab (columns).
        min_width: usize,
    },
}

/// One rank's slab: the half-open range of global columns `[x_begin, x_end)` it owns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slab {
    /// First owned global column.
    pub x_begin: usize,
    /// One past the last owned global column.
    pub x_end: usize,
}

impl Slab {
    /// Number of owned columns.
    pub fn width(&self) -> usize {
        self.x_end - self.x_begin
    }
    /// Global column → local column (0-based within the slab), if owned.
    pub fn to_local(&self, x: usize) -> Option<usize> {
        (self.x_begin..self.x_end)
            .contains(&x)
            .then(|| x - self.x_begin)
    }
    /// Local column → global column. Precondition: `local < width()`.
    pub fn to_global(&self, local: usize) -> usize {
        debug_assert!(local < self.width());
        self.x_begin + local
    }
}

/// A partition of `columns` global lattice columns into contiguous slabs, one per rank.
#[derive(Debug, Clone, PartialEq)]
pub struct SlabPartition {
    columns: usize,
    slabs: Vec<Slab>,
}

impl SlabPartition {
    /// Equal-width slabs (widths differ by at most one; wider slabs go to lower ranks).
    pub fn uniform(columns: usize, ranks: usize) -> Result<Self, PartitionError> {
        Self::weighted(&vec![1.0; columns], ranks)
    }

    /// Slabs of (nearly) equal total cost, where `costs[x] > 0` is the cost of column `x`
    /// (e.g. fluid cells plus grain work). Every slab gets at least one column.
    pub fn weighted(costs: &[f64], ranks: usize) -> Result<Self, PartitionError> {
        let columns = costs.len();
        if ranks == 0 || ranks > columns {
            return Err(PartitionError::TooManyRanks { columns, ranks });
        }
        if let Some(x) = costs.iter().position(|c| !(c.is_finite() && *c > 0.0)) {
            return Err(PartitionError::BadCosts(format!(
                "column {x} has cost {}; costs must be finite and positive",
                costs[x]
            )));
        }
        let total: f64 = costs.iter().sum();
        let mut slabs = Vec::with_capacity(ranks);
        let mut begin = 0usize;
        let mut acc = 0.0;
        for r in 0..ranks {
            // Cut where the running cost first reaches r+1 shares, leaving at least one
            // column for each remaining rank.
            let target = total * (r + 1) as f64 / ranks as f64;
            let max_end = columns - (ranks - r - 1);
            let mut end = begin + 1;
            acc += costs[begin];
            while end < max_end && acc + 0.5 * costs[end] < target {
                acc += costs[end];
                end += 1;
            }
            if r == ranks - 1 {
                end = columns;
            }
            slabs.push(Slab {
                x_begin: begin,
                x_end: end,
            });
            begin = end;
        }
        Ok(Self { columns, slabs })
    }

    /// [`SlabPartition::weighted`] with every slab at least `min_width` columns wide: the
    /// cuts of the balanced partition move no further than that needs (a forward pass
    /// pushes each cut right of its predecessor's plus `min_width`, a backward pass pulls
    /// each left of its successor's minus `min_width`). Errors when `ranks × min_width`
    /// exceeds the columns.
    pub fn weighted_min_width(
        costs: &[f64],
        ranks: usize,
        min_width: usize,
    ) -> Result<Self, PartitionError> {
        let columns = costs.len();
        let min_width = min_width.max(1);
        if ranks.saturating_mul(min_width) > columns {
            return Err(PartitionError::TooNarrow {
                columns,
                ranks,
                min_width,
            });
        }
        let p = Self::weighted(costs, ranks)?;
        let mut begins: Vec<usize> = p.slabs.iter().map(|s| s.x_begin).collect();
        begins.push(columns);
        for r in 1..ranks {
            begins[r] = begins[r].max(begins[r - 1] + min_width);
        }
        for r in (1..ranks).rev() {
            begins[r] = begins[r].min(begins[r + 1] - min_width);
        }
        let slabs = begins
            .windows(2)
            .map(|w| Slab {
                x_begin: w[0],
                x_end: w[1],
            })
            .collect();
        Ok(Self { columns, slabs })
    }

    /// Global number of columns.
    pub fn columns(&self) -> usize {
        self.columns
    }
    /// Number of slabs (ranks).
    pub fn ranks(&self) -> usize {
        self.slabs.len()
    }
    /// The slab of `rank`. Precondition: `rank < ranks()`.
    pub fn slab(&self, rank: usize) -> Slab {
        self.slabs[rank]
    }
    /// The rank that owns global column `x`, or `None` outside the lattice.
    pub fn owner_of_column(&self, x: usize) -> Option<usize> {
        if x >= self.columns {
            return None;
        }
        Some(self.slabs.partition_point(|s| s.x_end <= x))
    }
    /// The rank that owns a point at lattice coordinate `x` (cell `i` spans `[i, i+1)`),
    /// or `None` outside the lattice.
    pub fn owner_of_point(&self, x: f64) -> Option<usize> {
        if !(x >= 0.0) || x >= self.columns as f64 {
            return None;
        }
        self.owner_of_column(x.floor() as usize)
    }
    /// Left and right neighbour ranks of `rank`; with `periodic` the ends wrap around
    /// (a single rank is then its own neighbour on both sides).
    pub fn neighbours(&self, rank: usize, periodic: bool) -> (Option<usize>, Option<usize>) {
        let n = self.ranks();
        let left = if rank > 0 {
            Some(rank - 1)
        } else {
            periodic.then_some(n - 1)
        };
        let right = if rank + 1 < n {
            Some(rank + 1)
        } else {
            periodic.then_some(0)
        };
        (left, right)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_covers_every_column_once() {
        for ranks in 1..=7 {
            let p = SlabPartition::uniform(23, ranks).unwrap();
            let mut next = 0;
            for r in 0..ranks {
                let s = p.slab(r);
                assert_eq!(s.x_begin, next);
                assert!(
                    s.width() >= 23 / ranks && s.width() <= 23usize.div_ceil(ranks),
                    "{s:?}"
                );
                next = s.x_end;
            }
            assert_eq!(next, 23);
            for x in 0..23 {
                let r = p.owner_of_column(x).unwrap();
                assert_eq!(p.slab(r).to_global(p.slab(r).to_local(x).unwrap()), x);
            }
        }
    }

    #[test]
    fn weighted_balances_cost() {
        // Right half is three times as expensive: the cut moves left of the middle.
        let costs: Vec<f64> = (0..100).map(|x| if x < 50 { 1.0 } else { 3.0 }).collect();
        let p = SlabPartition::weighted(&costs, 2).unwrap();
        let left: f64 = costs[..p.slab(0).x_end].iter().sum();
        let right: f64 = costs[p.slab(1).x_begin..].iter().sum();
        assert!((left - right).abs() <= 3.0, "{left} vs {right}");
    }

    #[test]
    fn weighted_min_width_keeps_every_slab_wide_enough() {
        // All the cost in the first ten columns: unconstrained, three slabs crowd there.
        let costs: Vec<f64> = (0..100).map(|x| if x < 10 { 100.0 } else { 1.0 }).collect();
        let free = SlabPartition::weighted(&costs, 4).unwrap();
        assert!(free.slab(0).width() < 8, "{free:?}");
        let p = SlabPartition::weighted_min_width(&costs, 4, 8).unwrap();
        let mut next = 0;
        for r in 0..4 {
            let s = p.slab(r);
            assert_eq!(s.x_begin, next);
            assert!(s.width() >= 8, "{p:?}");
            next = s.x_end;
        }
        assert_eq!(next, 100);
        // Cuts the constraint does not touch stay where the balance put them.
        assert_eq!(p.slab(3).x_begin, free.slab(3).x_begin.max(24));
        assert_eq!(
            SlabPartition::weighted_min_width(&costs, 4, 26),
            Err(PartitionError::TooNarrow {
                columns: 100,
                ranks: 4,
                min_width: 26
            })
        );
    }

    #[test]
    fn owners_and_errors() {
        let p = SlabPartition::uniform(10, 3).unwrap();
        assert_eq!(p.owner_of_point(9.99), Some(2));
        assert_eq!(p.owner_of_point(-0.1), None);
        assert_eq!(p.owner_of_point(f64::NAN), None);
        assert_eq!(p.owner_of_column(10), None);
        assert_eq!(p.neighbours(0, true), (Some(2), Some(1)));
        assert_eq!(p.neighbours(0, false), (None, Some(1)));
        assert_eq!(
            SlabPartition::uniform(1, 1).unwrap().neighbours(0, true),
            (Some(0), Some(0))
        );
        assert!(matches!(
            SlabPartition::uniform(2, 3),
            Err(PartitionError::TooManyRanks { .. })
        ));
        assert!(matches!(
            SlabPartition::weighted(&[1.0, 0.0], 1),
            Err(PartitionError::BadCosts(_))
        ));
    }
}
