//! The distributed side of an MPM system: slabs of whole cell columns, the exchange of
//! grid strips across slab faces (the halo reduction), migration of points to their new
//! owner, rebalancing, and partition-independent global sums.
//!
//! A rank owns the points whose cell column lies in its slab `[c0, c1)`. Its nodes are the
//! node columns `c0 − 1 ..= c1 + 1`, whose sums need the strips of cell columns
//! `c0 − 3 .. c1 + 3`: each rank sends the strips of its first and last three columns to the
//! neighbour on that side, unsummed, so a shared node is summed from the same operands in
//! the same order on both ranks — and as on one rank. Results are therefore bit-identical
//! on any number of ranks.

pub use super::balance::{balanced_columns, column_counts, MIN_COLUMNS, REBALANCE_EVERY};
use super::error::MpmError;
use super::system::MpmSystem;
use super::transfer::{Strip, Q};
use decomposition::{reproducible_sums, swap_neighbours_varlen, Comm};
use decomposition::{unpack_rows, PackRows};

const TAG_STRIP: (u16, u16) = (300, 310);
const TAG_MIGRATE: (u16, u16) = (320, 330);

/// Totals over every rank, summed exactly (`reproducible_sums`): the same bits on any rank
/// count, in any storage order, and after a restart.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Totals {
    /// Number of points.
    pub points: u64,
    /// Mass (kg/m).
    pub mass: f64,
    /// Kinetic energy (J/m).
    pub kinetic_energy: f64,
    /// Momentum (kg/s per metre).
    pub momentum: [f64; 2],
}

impl MpmSystem {
    /// Keep only the points in this rank's slab.
    pub(super) fn keep_own(&mut self) {
        let (own, h) = (self.own_columns(), self.setup.spec.h);
        let keep: Vec<bool> = self
            .points
            .pos
            .iter()
            .map(|p| own.contains(&((p[0] / h).floor().max(0.0) as usize)))
            .collect();
        self.points.retain(&keep);
        self.invalidate_order();
    }

    fn peers(&self) -> [Option<usize>; 2] {
        let ranks = self.bounds.len() - 1;
        [
            self.rank.checked_sub(1),
            (self.rank + 1 < ranks).then_some(self.rank + 1),
        ]
    }

    /// Send the strips of the first and last [`MIN_COLUMNS`] own columns to the
    /// neighbours and receive theirs (one message per neighbour).
    pub(super) fn exchange_strips(&mut self, comm: &dyn Comm) {
        if comm.size() == 1 {
            return;
        }
        let own = self.own_columns();
        // Each strip: first row, row count, number of side-wall slots (0 or 4 × rows), the
        // slots, then the side-wall slots.
        let pack = |cols: std::ops::Range<usize>, strips: &[Strip]| {
            let mut out = Vec::new();
            for s in &strips[cols] {
                out.push(s.row_lo as f64);
                out.push(s.rows as f64);
                out.push(s.wall.len() as f64);
                for slot in &s.data[..s.rows * 4] {
                    out.extend_from_slice(slot);
                }
                out.extend_from_slice(&s.wall);
            }
            out
        };
        let left = pack(own.start..own.start + MIN_COLUMNS, &self.strips);
        let right = pack(own.end - MIN_COLUMNS..own.end, &self.strips);
        let (got, wait) = swap_neighbours_varlen(comm, self.peers(), TAG_STRIP, [&left, &right]);
        self.comm_seconds += wait;
        let targets = [own.start - MIN_COLUMNS.min(own.start), own.end];
        for (side, msg) in got.iter().enumerate() {
            if self.peers()[side].is_none() {
                continue;
            }
            let mut at = 0;
            for c in targets[side]..targets[side] + MIN_COLUMNS {
                let s = &mut self.strips[c];
                s.row_lo = msg[at] as i64;
                s.rows = msg[at + 1] as usize;
                let walls = msg[at + 2] as usize;
                at += 3;
                s.data.clear();
                for slot in msg[at..at + s.rows * 4 * Q].chunks_exact(Q) {
                    let mut v = [0.0; Q];
                    v.copy_from_slice(slot);
                    s.data.push(v);
                }
                at += s.rows * 4 * Q;
                s.wall.clear();
                s.wall.extend_from_slice(&msg[at..at + walls]);
                at += walls;
            }
        }
    }

    /// Forget the canonical order (the storage changed); the next sort rebuilds it.
    pub(super) fn invalidate_order(&mut self) {
        self.columns.order.clear();
        self.columns.cell.clear();
    }

    /// One migration round: points outside this slab go to the neighbour on that side.
    /// Returns whether this rank still holds points outside its slab (they came from two
    /// slabs away after a rebalance).
    fn migrate_round(&mut self, comm: &dyn Comm) -> bool {
        let (own, h, peers) = (self.own_columns(), self.setup.spec.h, self.peers());
        let side_of = |x: f64| {
            let c = (x / h).floor();
            if c < own.start as f64 && peers[0].is_some() {
                Some(0)
            } else if c >= own.end as f64 && peers[1].is_some() {
                Some(1)
            } else {
                None
            }
        };
        let mut out = [Vec::new(), Vec::new()];
        // Usually nobody leaves: scan first, allocate only for leavers.
        let leaving = (0..self.points.len())
            .filter(|&i| side_of(self.points.pos[i][0]).is_some())
            .count();
        if leaving > 0 {
            let mut keep = vec![true; self.points.len()];
            for i in 0..self.points.len() {
                if let Some(side) = side_of(self.points.pos[i][0]) {
                    self.points.pack_row(i, &mut out[side]);
                    keep[i] = false;
                }
            }
            self.points.retain(&keep);
        }
        self.migrated += leaving as u64;
        let (got, wait) = swap_neighbours_varlen(comm, peers, TAG_MIGRATE, [&out[0], &out[1]]);
        self.comm_seconds += wait;
        let (kept, mut arrived) = (self.points.len(), 0);
        for msg in &got {
            arrived += unpack_rows(&mut self.points, msg);
        }
        if leaving + arrived > 0 {
            self.invalidate_order();
        }
        // Those kept are home; only arrivals can still be out (from two slabs away).
        self.points.pos[kept..]
            .iter()
            .any(|p| side_of(p[0]).is_some())
    }

    /// Hand the points that left this slab to their new owners (collective).
    pub(super) fn migrate(&mut self, comm: &dyn Comm) {
        while comm.any(self.migrate_round(comm)) {}
    }

    /// Move the slab boundaries to balance the point counts when the most loaded rank
    /// holds more than 10 % above the mean (collective).
    pub(super) fn rebalance(&mut self, comm: &dyn Comm) {
        if comm.size() == 1 {
            return;
        }
        let Ok(mut counts) = column_counts(&self.points, &self.setup.spec) else {
            return; // a point outside the grid: the sort reports it
        };
        comm.sum_f64(&mut counts);
        let ranks = comm.size();
        let loads: Vec<f64> = (0..ranks)
            .map(|r| counts[self.bounds[r]..self.bounds[r + 1]].iter().sum())
            .collect();
        let mean = loads.iter().sum::<f64>() / ranks as f64;
        let max = loads.iter().cloned().fold(0.0, f64::max);
        if max <= 1.1 * mean {
            return;
        }
        let Ok(bounds) = balanced_columns(&counts, ranks, self.setup.spec.nx) else {
            return;
        };
        if bounds != self.bounds {
            self.bounds = bounds;
            self.rebalances += 1;
            self.migrate(comm);
        }
    }

    /// Global totals (collective): the points are sorted, then each column is summed in
    /// canonical order and the columns are added in order.
    pub fn totals(&mut self, comm: &dyn Comm) -> Result<Totals, MpmError> {
        self.sort(comm, false)?;
        let p = &self.points;
        let own: Vec<usize> = self
            .own_columns()
            .flat_map(|c| {
                self.columns.order[self.columns.start[c]..self.columns.start[c + 1]]
                    .iter()
                    .map(|&i| i as usize)
            })
            .collect();
        let column = |f: &dyn Fn(usize) -> f64| own.iter().map(|&i| f(i)).collect::<Vec<f64>>();
        let (m, v) = (&p.mass, &p.vel);
        let cols = [
            column(&|i| m[i]),
            column(&|i| 0.5 * m[i] * (v[i][0] * v[i][0] + v[i][1] * v[i][1])),
            column(&|i| m[i] * v[i][0]),
            column(&|i| m[i] * v[i][1]),
        ];
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        let t = reproducible_sums(&refs, comm);
        let mut count = [own.len() as f64];
        comm.sum_f64(&mut count);
        Ok(Totals {
            points: count[0] as u64,
            mass: t[0],
            kinetic_energy: t[1],
            momentum: [t[2], t[3]],
        })
    }

    /// Slab boundaries in cell columns (length ranks + 1).
    pub fn slab_columns(&self) -> &[usize] {
        &self.bounds
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn balanced_columns_are_wide_enough_and_balanced() {
        let mut counts = vec![0.0; 40];
        for c in 0..10 {
            counts[c] = 100.0;
        }
        let b = balanced_columns(&counts, 4, 40).unwrap();
        assert_eq!(b[0], 0);
        assert_eq!(b[4], 40);
        for r in 0..4 {
            assert!(b[r + 1] - b[r] >= MIN_COLUMNS, "{b:?}");
        }
        // The loaded first ten columns are split between the first ranks.
        assert!(b[1] <= 4 && b[2] <= 7, "{b:?}");
        assert!(balanced_columns(&counts, 14, 40).is_err());
        assert_eq!(balanced_columns(&counts, 1, 40).unwrap(), vec![0, 40]);
    }
}
