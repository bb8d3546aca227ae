//! Which grains may overlap: for each grain, the others whose disks, before or after a
//! move, can reach its own, found on a grid of buckets (`cover_update.rs` needs them).

use super::map::{GrainView, SlabFrame};
use rayon::prelude::*;

/// Each grain's possible neighbours, and the grid that finds them (kept for its
/// allocations).
#[derive(Debug, Default)]
pub struct GrainNeighbours {
    /// Per grain: start of its neighbours in `near` (one more entry than grains).
    start: Vec<u32>,
    /// Neighbours, grain by grain, in increasing index.
    near: Vec<u32>,
    /// Grains sorted by grid bucket, and each bucket's start in that list.
    by_bucket: Vec<u32>,
    bucket_start: Vec<u32>,
    /// Per task of the parallel search: its grains' neighbours and their counts.
    parts: Vec<(Vec<u32>, Vec<u32>)>,
}

impl GrainNeighbours {
    /// The neighbours of grain `g` found by the last [`GrainNeighbours::find`], in
    /// increasing index.
    pub fn of(&self, g: usize) -> &[u32] {
        &self.near[self.start[g] as usize..self.start[g + 1] as usize]
    }

    /// Find, for each grain of `new` (moved from `old`, in the same order), the others
    /// whose centres (nearest images, after the move) are closer than their radii plus both
    /// moves: every pair whose disks may overlap before or after. `reach` is the width of
    /// the grid's buckets and must exceed every such distance.
    pub fn find(&mut self, f: &SlabFrame, old: &[GrainView], new: &[GrainView], reach: f64) {
        let n = new.len();
        let lengths = [f.global_nx as f64, f.ny as f64];
        let periodic = [f.periodic_x, f.periodic_y];
        // Buckets per axis: along a periodic one they tile the lattice (each at least
        // `reach` wide), along the others the span of the centres.
        let mut lo = [0.0f64; 2];
        let mut count = [1usize; 2];
        let mut width = [reach; 2];
        for a in 0..2 {
            if periodic[a] {
                count[a] = ((lengths[a] / reach).floor() as usize).max(1);
                width[a] = lengths[a] / count[a] as f64;
            } else {
                let (mut mn, mut mx) = (f64::INFINITY, f64::NEG_INFINITY);
                for v in new {
                    mn = mn.min(v.centre[a]);
                    mx = mx.max(v.centre[a]);
                }
                lo[a] = if n > 0 { mn } else { 0.0 };
                count[a] = if n > 0 {
                    ((mx - mn) / reach).floor() as usize + 1
                } else {
                    1
                };
            }
        }
        let bucket_axis = |a: usize, v: f64| -> usize {
            let t = if periodic[a] {
                v.rem_euclid(lengths[a]) / width[a]
            } else {
                (v - lo[a]) / width[a]
            };
            (t.floor().max(0.0) as usize).min(count[a] - 1)
        };
        let bucket =
            |v: &GrainView| bucket_axis(1, v.centre[1]) * count[0] + bucket_axis(0, v.centre[0]);
        // Counting sort of the grains by bucket (stable: increasing index within one).
        let buckets = count[0] * count[1];
        self.bucket_start.clear();
        self.bucket_start.resize(buckets + 1, 0);
        for v in new {
            self.bucket_start[bucket(v) + 1] += 1;
        }
        for b in 0..buckets {
            self.bucket_start[b + 1] += self.bucket_start[b];
        }
        self.by_bucket.clear();
        self.by_bucket.resize(n, 0);
        // bucket_start[b] serves as bucket b's cursor, then moves back by one bucket.
        for (g, v) in new.iter().enumerate() {
            let b = bucket(v);
            self.by_bucket[self.bucket_start[b] as usize] = g as u32;
            self.bucket_start[b] += 1;
        }
        for b in (1..=buckets).rev() {
            self.bucket_start[b] = self.bucket_start[b - 1];
        }
        self.bucket_start[0] = 0;
        // Each grain's neighbours, in parallel over ranges of grains (each list is the
        // grain's own, sorted, so the result does not depend on the ranges).
        let (by_bucket, bucket_start) = (&self.by_bucket, &self.bucket_start);
        let neighbours_of = |g: usize, out: &mut Vec<u32>| {
            let v = &new[g];
            let (bx, by) = (bucket_axis(0, v.centre[0]), bucket_axis(1, v.centre[1]));
            let from = out.len();
            for j in around(by, count[1], periodic[1]) {
                if j == usize::MAX {
                    continue;
                }
                for i in around(bx, count[0], periodic[0]) {
                    if i == usize::MAX {
                        continue;
                    }
                    let b = j * count[0] + i;
                    for &h in &by_bucket[bucket_start[b] as usize..bucket_start[b + 1] as usize] {
                        if h as usize == g {
                            continue;
                        }
                        let w = &new[h as usize];
                        let mut d = [w.centre[0] - v.centre[0], w.centre[1] - v.centre[1]];
                        for a in 0..2 {
                            if periodic[a] {
                                d[a] -= (d[a] / lengths[a]).round() * lengths[a];
                            }
                        }
                        let limit = v.radius
                            + w.radius
                            + moved(&old[g], v)
                            + moved(&old[h as usize], w)
                            + 1e-6;
                        if d[0] * d[0] + d[1] * d[1] < limit * limit {
                            out.push(h);
                        }
                    }
                }
            }
            out[from..].sort_unstable();
        };
        // Few grains: one task (waking the pool would cost more than their search).
        let tasks = if n >= 512 {
            rayon::current_num_threads().clamp(1, 64)
        } else {
            1
        };
        self.parts.resize_with(tasks, Default::default);
        self.parts
            .par_iter_mut()
            .enumerate()
            .for_each(|(t, (near, lens))| {
                near.clear();
                lens.clear();
                for g in n * t / tasks..n * (t + 1) / tasks {
                    let before = near.len();
                    neighbours_of(g, near);
                    lens.push((near.len() - before) as u32);
                }
            });
        self.start.clear();
        self.near.clear();
        self.start.push(0);
        for (near, lens) in &self.parts[..tasks] {
            self.near.extend_from_slice(near);
            for &l in lens {
                let last = *self.start.last().expect("starts with 0");
                self.start.push(last + l);
            }
        }
    }
}

/// How far a grain's centre moved (cells).
pub fn moved(a: &GrainView, b: &GrainView) -> f64 {
    ((b.centre[0] - a.centre[0]).powi(2) + (b.centre[1] - a.centre[1]).powi(2)).sqrt()
}

/// The buckets next to bucket `i` of `count` along an axis (itself included), wrapped
/// when `periodic`, each once: up to three, the rest `usize::MAX`.
fn around(i: usize, count: usize, periodic: bool) -> [usize; 3] {
    let mut v = [usize::MAX; 3];
    let mut n = 0;
    for d in -1..=1i64 {
        let j = i as i64 + d;
        let j = if periodic {
            j.rem_euclid(count as i64)
        } else if (0..count as i64).contains(&j) {
            j
        } else {
            continue;
        } as usize;
        if !v[..n].contains(&j) {
            v[n] = j;
            n += 1;
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_slabs::{next, slab};

    /// Every pair whose disks may overlap before or after the move is listed, and no other
    /// (against a brute-force search with nearest images), the same lists on 1, 2 and 5
    /// threads, on slabs periodic on both axes and on none.
    #[test]
    fn neighbours_match_a_brute_force_search_on_any_thread_count() {
        let mut seed = 0x853c_49e6_748f_ea9bu64;
        for case in [0, 1] {
            let (f, _) = slab(case);
            let (lx, ly) = (f.global_nx as f64, f.ny as f64);
            let old: Vec<GrainView> = (0..700)
                .map(|_| GrainView {
                    centre: [next(&mut seed) * lx, next(&mut seed) * ly],
                    radius: 2.0 + 4.0 * next(&mut seed),
                    velocity: [0.0; 2],
                    omega: 0.0,
                })
                .collect();
            let new: Vec<GrainView> = old
                .iter()
                .map(|g| GrainView {
                    centre: [
                        g.centre[0] + next(&mut seed) - 0.5,
                        g.centre[1] + next(&mut seed) - 0.5,
                    ],
                    ..*g
                })
                .collect();
            let reach = 2.0 * 6.0 + 2.0 * 0.75 + 0.5;
            let lists: Vec<Vec<Vec<u32>>> = [1, 2, 5]
                .into_iter()
                .map(|threads| {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .expect("pool");
                    let mut nb = GrainNeighbours::default();
                    pool.install(|| nb.find(&f, &old, &new, reach));
                    (0..new.len()).map(|g| nb.of(g).to_vec()).collect()
                })
                .collect();
            assert_eq!(lists[0], lists[1], "slab {case}: 1 and 2 threads");
            assert_eq!(lists[0], lists[2], "slab {case}: 1 and 5 threads");
            let mut pairs = 0;
            for (g, v) in new.iter().enumerate() {
                let want: Vec<u32> = (0..new.len())
                    .filter(|&h| h != g)
                    .filter(|&h| {
                        let w = &new[h];
                        let mut d = [w.centre[0] - v.centre[0], w.centre[1] - v.centre[1]];
                        for (a, l) in [(0, lx), (1, ly)] {
                            let periodic = [f.periodic_x, f.periodic_y][a];
                            if periodic {
                                d[a] -= (d[a] / l).round() * l;
                            }
                        }
                        let limit =
                            v.radius + w.radius + moved(&old[g], v) + moved(&old[h], w) + 1e-6;
                        d[0] * d[0] + d[1] * d[1] < limit * limit
                    })
                    .map(|h| h as u32)
                    .collect();
                pairs += want.len();
                assert_eq!(lists[0][g], want, "slab {case}, grain {g}");
            }
            assert!(pairs > 1000, "slab {case}: only {pairs} pairs");
        }
    }
}
