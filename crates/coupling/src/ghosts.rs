//! Grains of the coupling over slabs: the rank whose fluid slab holds a grain's centre owns
//! it; its neighbours hold a *ghost* of it (position, velocity, size) when the grain reaches
//! their slab plus halo, so that they can build their cells around it. After the fluid
//! side of a step, each rank sends its per-column partial loads on ghosts back to the rank
//! they came from (see `sums.rs`). One message per neighbour per phase, across a periodic x
//! face too.

use decomposition::{swap_neighbours_varlen, unpack_rows, Comm, Record, SlabPartition};

/// Message tags (distinct from the lattice's, the DEM's and the MPM's).
const TAG_STATE: (u16, u16) = (400, 410);
const TAG_LOADS: (u16, u16) = (420, 430);

/// One grain's state as its ghosts see it (SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GhostState {
    /// Grain id.
    pub id: u64,
    /// Centre (m).
    pub x: [f64; 2],
    /// Radius (m).
    pub r: f64,
    /// Mass per depth (kg/m).
    pub m: f64,
    /// Velocity (m/s).
    pub v: [f64; 2],
    /// Angular velocity (rad/s).
    pub omega: f64,
}

/// A ghost's state travels as 8 words: id (bits), x, y, r, m, vx, vy, ω (SI).
impl Record for GhostState {
    const WORDS: usize = 8;

    fn pack(&self, out: &mut Vec<f64>) {
        out.extend_from_slice(&[
            f64::from_bits(self.id),
            self.x[0],
            self.x[1],
            self.r,
            self.m,
            self.v[0],
            self.v[1],
            self.omega,
        ]);
    }

    fn unpack(p: &[f64]) -> Self {
        Self {
            id: p[0].to_bits(),
            x: [p[1], p[2]],
            r: p[3],
            m: p[4],
            v: [p[5], p[6]],
            omega: p[7],
        }
    }
}

/// Neighbours of one rank's slab for the coupling's ghost grains.
#[derive(Debug, Clone)]
pub struct GrainHalo {
    /// Left and right neighbour ranks; a periodic x face wraps. Both may be the same rank
    /// (two ranks, periodic): a grain that reaches it both ways arrives twice, and the
    /// receiver keeps one.
    peers: [Option<usize>; 2],
    /// x-range (m) of each side's neighbour slab with its halo column.
    reach_of: [(f64, f64); 2],
    /// Domain width (m) when x is periodic.
    period: Option<f64>,
    /// How far beyond its radius a grain reaches (m).
    margin: f64,
    /// Seconds spent waiting for messages.
    pub wait_s: f64,
}

impl GrainHalo {
    /// The halo of `rank` in `partition` with cells `dx` wide; `periodic` when the x faces
    /// wrap; `margin` (m) beyond a grain's radius that a neighbour must see it (its cells'
    /// reach plus any short-range force).
    pub fn new(
        partition: &SlabPartition,
        rank: usize,
        dx: f64,
        periodic: bool,
        margin: f64,
    ) -> Self {
        let n = partition.ranks();
        let wrap = periodic && n > 1;
        let left = if rank > 0 {
            Some(rank - 1)
        } else {
            wrap.then_some(n - 1)
        };
        let right = if rank + 1 < n {
            Some(rank + 1)
        } else {
            wrap.then_some(0)
        };
        let peers = [left, right];
        let reach_of = peers.map(|p| {
            p.map(|p| {
                let s = partition.slab(p);
                ((s.x_begin as f64 - 1.0) * dx, (s.x_end as f64 + 1.0) * dx)
            })
            .unwrap_or((0.0, 0.0))
        });
        Self {
            peers,
            reach_of,
            period: periodic.then(|| partition.columns() as f64 * dx),
            margin,
            wait_s: 0.0,
        }
    }

    /// Whether this rank has neighbours to exchange with.
    pub fn has_peers(&self) -> bool {
        self.peers.iter().any(Option::is_some)
    }

    /// Whether a grain at `x` with radius `r` reaches the slab of side `side`'s neighbour.
    fn reaches(&self, side: usize, x: f64, r: f64) -> bool {
        let (lo, hi) = self.reach_of[side];
        let shifts: &[f64] = match self.period {
            Some(_) => &[0.0, 1.0, -1.0],
            None => &[0.0],
        };
        let l = self.period.unwrap_or(0.0);
        let reach = r + self.margin;
        shifts
            .iter()
            .any(|s| x + s * l + reach >= lo && x + s * l - reach <= hi)
    }

    /// Send every owned grain in `owned` to the neighbours it reaches and receive theirs:
    /// the ghosts, each with the side it came from (ids unique). Collective.
    pub fn exchange_states(
        &mut self,
        comm: &dyn Comm,
        owned: &[GhostState],
    ) -> Vec<(GhostState, usize)> {
        let mut out = [Vec::new(), Vec::new()];
        for g in owned {
            for (side, msg) in out.iter_mut().enumerate() {
                if self.peers[side].is_some() && self.reaches(side, g.x[0], g.r) {
                    g.pack(msg);
                }
            }
        }
        let (got, wait) = swap_neighbours_varlen(comm, self.peers, TAG_STATE, [&out[0], &out[1]]);
        self.wait_s += wait;
        let mut ghosts = Vec::new();
        for (side, msg) in got.iter().enumerate() {
            let mut states: Vec<GhostState> = Vec::new();
            unpack_rows(&mut states, msg);
            ghosts.extend(states.into_iter().map(|g| (g, side)));
        }
        ghosts
    }

    /// Send `loads[side]` (flattened per-column partial loads of the ghosts that came from
    /// that side) back and receive what the neighbours computed for this rank's grains.
    /// Collective.
    pub fn return_loads(&mut self, comm: &dyn Comm, loads: [&[f64]; 2]) -> [Vec<f64>; 2] {
        let (got, wait) = swap_neighbours_varlen(comm, self.peers, TAG_LOADS, loads);
        self.wait_s += wait;
        got
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn periodic_two_ranks_see_each_other_both_ways() {
        let p = SlabPartition::uniform(100, 2).unwrap();
        let h = GrainHalo::new(&p, 0, 1.0, true, 3.0);
        assert_eq!(h.peers, [Some(1), Some(1)]);
        // A grain at x = 1 reaches rank 1's slab across the periodic face.
        assert!(h.reaches(0, 1.0, 2.0));
        assert!(!h.reaches(0, 25.0, 2.0));
        let h = GrainHalo::new(&p, 0, 1.0, false, 3.0);
        assert_eq!(h.peers, [None, Some(1)]);
        assert!(h.reaches(1, 47.0, 1.0));
        assert!(!h.reaches(1, 40.0, 1.0));
    }
}
