//! The sum of each owned grain's load over the lattice columns its cells cover, on this
//! rank and on the neighbours that hold its ghosts.

use super::{LbmDem, Source};
use crate::sums::{total, ColumnSums, Load};
use decomposition::Comm;
use rayon::prelude::*;

impl LbmDem {
    /// Each owned grain's total of `sums` (per-column partial sums over views): the ghosts'
    /// partial sums go back to the ranks they came from, and every owner adds its grains'
    /// columns in order. Collective.
    pub(super) fn reduce(&mut self, which: Which, comm: &dyn Comm) -> Vec<Load> {
        let sums: &ColumnSums = match which {
            Which::Exchange => self.coupler.loads(),
            Which::Handover => self.coupler.handover_loads(),
        };
        let mut remote: Vec<(u64, u32, Load)> = Vec::new();
        if self.halo.has_peers() {
            let mut out = [Vec::new(), Vec::new()];
            for (v, src) in self.source.iter().enumerate() {
                if let Source::Ghost(side) = *src {
                    sums.partials(v, &mut self.partials);
                    let msg = &mut out[side as usize];
                    msg.extend_from_slice(&[
                        f64::from_bits(self.ids[v]),
                        self.partials.len() as f64,
                    ]);
                    for (c, l) in &self.partials {
                        msg.extend_from_slice(&[*c as f64, l[0], l[1], l[2]]);
                    }
                }
            }
            let got = self.halo.return_loads(comm, [&out[0], &out[1]]);
            for msg in &got {
                let mut at = 0;
                while at < msg.len() {
                    let (id, n) = (msg[at].to_bits(), msg[at + 1] as usize);
                    for e in msg[at + 2..at + 2 + 4 * n].chunks_exact(4) {
                        remote.push((id, e[0] as u32, [e[1], e[2], e[3]]));
                    }
                    at += 2 + 4 * n;
                }
            }
            remote.sort_by_key(|r| (r.0, r.1));
        }
        // Each owned grain's total on its own: the same bits in any order. In parallel over
        // the grains when there are threads to share it (on one thread a parallel region
        // only adds the pool's wake-up).
        let owned = self.dem.system.owned();
        let (view_of, ids, remote) = (&self.view_of, &self.ids, &remote);
        let grain_total = |partials: &mut Vec<(u32, Load)>, i: usize| {
            let v = view_of[i] as usize;
            let id = ids[v];
            let from = remote.partition_point(|r| r.0 < id);
            let to = remote.partition_point(|r| r.0 <= id);
            if from == to {
                // All its columns here: added in window order when that is column order.
                if let Some(t) = sums.total_in_order(v) {
                    return t;
                }
            }
            sums.partials(v, partials);
            partials.extend(remote[from..to].iter().map(|r| (r.1, r.2)));
            total(partials)
        };
        let mut totals = Vec::with_capacity(owned);
        if rayon::current_num_threads() > 1 {
            (0..owned)
                .into_par_iter()
                .with_min_len(256)
                .map_init(Vec::new, grain_total)
                .collect_into_vec(&mut totals);
        } else {
            let partials = &mut self.partials;
            totals.extend((0..owned).map(|i| grain_total(partials, i)));
        }
        totals
    }
}

/// Which per-column sums to reduce.
#[derive(Clone, Copy)]
pub(super) enum Which {
    Exchange,
    Handover,
}
