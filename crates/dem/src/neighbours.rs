//! The Verlet neighbour list of a [`DemSystem`]: when it is stale, how it is rebuilt with
//! the tangential history carried over, and the spatial sort of the owned grains.

use super::cells::CellList;
use super::system::{DemSystem, HistoryMap};
use super::walls::WallGrid;
use rayon::prelude::*;

impl DemSystem {
    /// Skin of the Verlet list for the largest radius `rmax` (m): 30 % of it. The list is
    /// rebuilt when any grain has moved half the skin.
    pub fn skin_for(rmax: f64) -> f64 {
        0.3 * rmax
    }

    /// Whether some owned grain or some wall moved more than half the skin since the list
    /// was built (always true before the first build or after grains were added or
    /// removed).
    pub fn list_is_stale(&self) -> bool {
        let g = &self.grains;
        if self.built_at.0.len() != self.owned || self.walls_built_at.len() != self.walls.len() {
            return true;
        }
        let half = 0.5 * self.skin;
        let wall_moved = self.walls.iter().zip(&self.walls_built_at).any(|(w, a)| {
            let (dx, dy) = (w.a[0] - a[0], w.a[1] - a[1]);
            dx * dx + dy * dy > half * half
        });
        if wall_moved {
            return true;
        }
        (0..self.owned).into_par_iter().with_min_len(4096).any(|i| {
            let (dx, dy) = (g.x[i] - self.built_at.0[i], g.y[i] - self.built_at.1[i]);
            dx * dx + dy * dy > half * half
        })
    }

    /// The tangential stretch of every live pair contact, keyed by ids.
    pub(crate) fn pair_history(&self) -> HistoryMap {
        let id = &self.grains.id;
        self.candidates
            .iter()
            .zip(&self.stretch)
            .filter(|(_, s)| **s != 0.0)
            .map(|(&(a, b), &s)| ((id[a as usize], id[b as usize]), s))
            .collect()
    }

    /// The live contact history this rank accounts for: pairs whose smaller-id grain is
    /// owned, and the owned grains' wall contacts. Over all ranks, every contact once.
    pub fn owned_history(&self) -> Vec<((u64, u64), f64)> {
        let id = &self.grains.id;
        let mut out: Vec<((u64, u64), f64)> = self
            .candidates
            .iter()
            .zip(&self.stretch)
            .filter(|(&(a, _), s)| (a as usize) < self.owned && **s != 0.0)
            .map(|(&(a, b), &s)| ((id[a as usize], id[b as usize]), s))
            .collect();
        out.extend(self.history.iter().map(|(k, v)| (*k, *v)));
        out
    }

    /// Rebuild the Verlet list over the current grains (owned and ghosts) with skin
    /// [`DemSystem::skin_for`] of the largest radius here, carrying the tangential stretch
    /// of every live contact over to it.
    pub(crate) fn rebuild_list(&mut self) {
        let rmax = self.grains.r.iter().cloned().fold(0.0, f64::max);
        let live = self.pair_history();
        self.rebuild_from(&live, Self::skin_for(rmax), rmax);
    }

    /// Build the Verlet list with `skin` for grains of radius up to `rmax` (the distributed
    /// driver passes the global ones, so that every rank builds the same pairs), taking the
    /// stretch of each pair from `live` (see [`DemSystem::pair_history`]: take it before
    /// grains are added, removed or reordered). Owned grains are first reordered by cell
    /// when `spatial_sort`.
    /// Returns the reordering applied (new grain k is old grain `order[k]`), empty if none.
    pub(crate) fn rebuild_from(&mut self, live: &HistoryMap, skin: f64, rmax: f64) -> Vec<u32> {
        self.skin = skin;
        let mut cells = CellList::build(&self.grains, 2.0 * rmax + skin);
        let mut order = Vec::new();
        if self.spatial_sort && self.owned > 1 {
            order = cells.owned_order(self.owned);
            self.grains.permute_prefix(&order);
            self.permute_extras(&order);
            cells.renumber(&order);
        }
        let g = &self.grains;
        let owned = self.owned;
        let candidates: Vec<(u32, u32)> = cells
            .pairs_within(g, skin)
            .into_par_iter()
            .filter(|&(i, j)| (i as usize) < owned || (j as usize) < owned)
            .map(|(i, j)| {
                if g.id[i as usize] < g.id[j as usize] {
                    (i, j)
                } else {
                    (j, i)
                }
            })
            .collect();
        self.stretch = candidates
            .par_iter()
            .with_min_len(1024)
            .map(|&(a, b)| {
                live.get(&(g.id[a as usize], g.id[b as usize]))
                    .copied()
                    .unwrap_or(0.0)
            })
            .collect();
        // Adjacency of the owned grains, each sorted by its partner's id: the force sum of a
        // grain then runs in an order that depends only on ids.
        let mut start = vec![0u32; owned + 1];
        for &(a, b) in &candidates {
            for who in [a, b] {
                if (who as usize) < owned {
                    start[who as usize + 1] += 1;
                }
            }
        }
        for k in 0..owned {
            start[k + 1] += start[k];
        }
        let mut fill = start.clone();
        let mut adj = vec![0u32; start[owned] as usize];
        for (k, &(a, b)) in candidates.iter().enumerate() {
            for (who, role) in [(a, 0u32), (b, 1u32)] {
                if (who as usize) < owned {
                    adj[fill[who as usize] as usize] = (k as u32) << 1 | role;
                    fill[who as usize] += 1;
                }
            }
        }
        let partner = |e: u32| {
            let (a, b) = candidates[(e >> 1) as usize];
            g.id[if e & 1 == 1 { a } else { b } as usize]
        };
        let mut rest = adj.as_mut_slice();
        let mut slices = Vec::with_capacity(owned);
        for i in 0..owned {
            let (mine, tail) = rest.split_at_mut((start[i + 1] - start[i]) as usize);
            slices.push(mine);
            rest = tail;
        }
        slices
            .into_par_iter()
            .with_min_len(1024)
            .for_each(|s| s.sort_unstable_by_key(|&e| partner(e)));
        self.adj_start = start;
        self.adj = adj;
        self.candidates = candidates;
        // Walls within r + skin of each owned grain, from a grid of the walls over the
        // owned grains' bounding box.
        let walls = &self.walls;
        let fold = |v: &[f64]| {
            v.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                })
        };
        let ((x0, x1), (y0, y1)) = (fold(&g.x[..owned]), fold(&g.y[..owned]));
        let grid = (owned > 0)
            .then(|| WallGrid::build(walls, [x0, y0], [x1, y1], rmax + skin, 4 * owned + 64));
        let near: Vec<Vec<u32>> = (0..owned)
            .into_par_iter()
            .with_min_len(1024)
            .map(|i| {
                let Some(grid) = &grid else { return Vec::new() };
                grid.near([g.x[i], g.y[i]])
                    .iter()
                    .copied()
                    .filter(|&w| {
                        let c = walls[w as usize].closest_point([g.x[i], g.y[i]]);
                        let reach = g.r[i] + skin;
                        (g.x[i] - c[0]).powi(2) + (g.y[i] - c[1]).powi(2) < reach * reach
                    })
                    .collect()
            })
            .collect();
        self.wall_start.clear();
        self.wall_start.push(0);
        self.wall_cand.clear();
        for list in near {
            self.wall_cand.extend(list);
            self.wall_start.push(self.wall_cand.len() as u32);
        }
        self.walls_built_at = walls.iter().map(|w| w.a).collect();
        self.built_at = (g.x[..owned].to_vec(), g.y[..owned].to_vec());
        self.pair_results.clear();
        self.rebuilds += 1;
        order
    }
}
