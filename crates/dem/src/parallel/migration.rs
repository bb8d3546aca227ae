//! Moving grains between slabs: one migration round with both neighbours, the slab
//! rebalancing, and the message plumbing (a swap with both neighbours, variable-length
//! messages as sizes then payloads).

use super::{balanced_bounds, cutoff_for, SlabDem, TAG_COUNT, TAG_DATA};
use crate::grains::Grains;
use crate::system::{HistoryMap, WALL_KEY};
use decomposition::PackRows;
use decomposition::{swap_neighbours_varlen, Comm};
use std::collections::HashMap;

impl SlabDem {
    /// One migration round: grains outside this slab go to the neighbour on that side, with
    /// their contact history. Returns whether this rank still holds grains outside its slab
    /// afterwards (they arrived from two slabs away after a rebalance).
    pub(super) fn migrate_round(&mut self, comm: &dyn Comm, live: &mut HistoryMap) -> bool {
        let (slab, peers) = (self.slab(), self.peers());
        let sys = &mut self.system;
        let mut dest: HashMap<u64, usize> = HashMap::new();
        let mut grains_out = [Vec::new(), Vec::new()];
        let mut extras_out = [Vec::new(), Vec::new()];
        let mut keep = vec![true; sys.owned];
        let g = &sys.grains;
        for i in 0..sys.owned {
            let Some(side) = leaves_to(g.x[i], slab, peers) else {
                continue;
            };
            g.pack_row(i, &mut grains_out[side]);
            sys.pack_extras(i, &mut extras_out[side]);
            dest.insert(g.id[i], side);
            keep[i] = false;
        }
        let mut hist_out = [Vec::new(), Vec::new()];
        if !dest.is_empty() {
            let entries = live.iter().chain(sys.history.iter());
            for (&(a, b), &s) in entries {
                let mut sides = [false; 2];
                for id in [a, b] {
                    if let Some(&d) = dest.get(&id) {
                        sides[d] = true;
                    }
                }
                for (d, out) in hist_out.iter_mut().enumerate() {
                    if sides[d] {
                        out.extend_from_slice(&[f64::from_bits(a), f64::from_bits(b), s]);
                    }
                }
            }
        }
        self.migrated += dest.len() as u64;
        sys.grains.retain(&keep);
        sys.retain_extras(&keep);
        sys.owned = sys.grains.len();
        let msgs = [0, 1].map(|s| join(&[&grains_out[s], &hist_out[s], &extras_out[s]]));
        let got = self.exchange_varlen(comm, &msgs);
        let sys = &mut self.system;
        let width = sys.extras_width();
        for msg in got.iter() {
            let [grains, hist, extras] = split(msg);
            for (k, p) in grains.chunks_exact(Grains::WORDS).enumerate() {
                sys.grains.push_row(p);
                sys.push_extras(&extras[k * width..(k + 1) * width]);
            }
            for h in hist.chunks_exact(3) {
                let key = (h[0].to_bits(), h[1].to_bits());
                if key.1 & WALL_KEY != 0 {
                    sys.history.insert(key, h[2]);
                } else {
                    live.insert(key, h[2]);
                }
            }
        }
        sys.owned = sys.grains.len();
        let g = &sys.grains;
        (0..sys.owned).any(|i| leaves_to(g.x[i], slab, peers).is_some())
    }

    /// New slab boundaries that balance the owned grain counts (quantiles of all centres,
    /// each slab at least one cutoff wide), when the most loaded rank holds over 10 % more
    /// than the mean. Collective; the grains then migrate in rounds.
    pub(super) fn rebalance(&mut self, comm: &dyn Comm) {
        let counts = comm.all_gather_f64(&[self.system.owned as f64]);
        let mean = counts.iter().sum::<f64>() / counts.len() as f64;
        let max = counts.iter().cloned().fold(0.0, f64::max);
        if counts.len() < 2 || max <= 1.1 * mean {
            return;
        }
        let x = comm.all_gather_f64(&self.system.grains.x[..self.system.owned]);
        let last = self.bounds.len() - 1;
        let bounds = balanced_bounds(
            &x,
            self.bounds[0],
            self.bounds[last],
            counts.len(),
            cutoff_for(self.rmax),
        );
        self.bounds = bounds;
        self.rebalances += 1;
    }

    /// Variable-length messages with both neighbours (sizes, then payloads).
    pub(super) fn exchange_varlen(
        &mut self,
        comm: &dyn Comm,
        msgs: &[Vec<f64>; 2],
    ) -> [Vec<f64>; 2] {
        let peers = self.peers();
        let (got, wait) =
            swap_neighbours_varlen(comm, peers, (TAG_COUNT, TAG_DATA), [&msgs[0], &msgs[1]]);
        self.comm_seconds += wait;
        got
    }
}

/// Which neighbour (0 left, 1 right) a grain at `x` must go to, if it is outside the slab
/// `(lo, hi)` on a side that has a neighbour in `peers`.
pub(super) fn leaves_to(
    x: f64,
    (lo, hi): (f64, f64),
    [left, right]: [Option<usize>; 2],
) -> Option<usize> {
    if x < lo && left.is_some() {
        Some(0)
    } else if x >= hi && right.is_some() {
        Some(1)
    } else {
        None
    }
}

/// `[n_0, n_1, part 0…, part 1…, part 2…]`: three parts in one message.
pub(super) fn join(parts: &[&[f64]; 3]) -> Vec<f64> {
    let mut v = Vec::with_capacity(2 + parts.iter().map(|p| p.len()).sum::<usize>());
    v.extend_from_slice(&[parts[0].len() as f64, parts[1].len() as f64]);
    for p in parts {
        v.extend_from_slice(p);
    }
    v
}

/// Inverse of [`join`] (an empty message is three empty parts).
pub(super) fn split(msg: &[f64]) -> [&[f64]; 3] {
    if msg.is_empty() {
        return [&[], &[], &[]];
    }
    let (a, b) = (msg[0] as usize, msg[1] as usize);
    [&msg[2..2 + a], &msg[2 + a..2 + a + b], &msg[2 + a + b..]]
}
