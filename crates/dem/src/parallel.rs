//! DEM over MPI slabs: each rank owns the grains whose centre lies in its x-range
//! `[lo, hi)`, keeps ghost copies of its neighbours' grains within the contact cutoff of
//! its faces, and hands grains that crossed a face to the neighbour.
//!
//! Protocol (LAMMPS-like): between Verlet-list rebuilds the ghost set is fixed and every
//! step sends only the ghosts' positions and velocities, one message per neighbour. When
//! any rank's list is stale (a global decision), every rank migrates its leavers with
//! their contact history, rebuilds its ghost set and its list — one message per neighbour
//! per phase, never one per grain.
//!
//! Results match one rank bit for bit: a pair is evaluated with its smaller-id grain as
//! body 1 on whichever rank(s) hold it, each grain sums its contacts by partner id, and
//! the list skin and rebuild steps are global, so every grain sees the same arithmetic in
//! the same order whatever the partition.

use super::contact::DemError;
use super::grains::Grains;
use super::system::{DemSetup, DemSystem, HistoryMap, WALL_KEY};
use decomposition::Comm;
use decomposition::{pack_rows, unpack_rows};

/// Values sent per ghost every step: x, y, vx, vy, ω.
const FORWARD: usize = 5;
/// Message tags (distinct from the lattice halo's).
const TAG_COUNT: u16 = 200;
const TAG_DATA: u16 = 210;
const TAG_FORWARD: u16 = 220;

mod migration;

use decomposition::swap_neighbours as swap;
use migration::{join, split};

/// One rank's share of a distributed DEM system.
#[derive(Debug)]
pub struct SlabDem {
    /// The local system: owned grains, then ghosts.
    pub system: DemSystem,
    /// x-boundaries of every rank's slab: this rank owns `[bounds[rank], bounds[rank + 1])`.
    bounds: Vec<f64>,
    rank: usize,
    /// Largest radius over all ranks (m): sets the skin and the ghost cutoff.
    rmax: f64,
    /// Owned grains whose state goes to the left / right neighbour every step.
    send: [Vec<u32>; 2],
    /// Ghosts received from the left / right neighbour (stored in that order).
    recv: [usize; 2],
    /// Grains this rank has sent away so far.
    pub migrated: u64,
    /// Check the load balance every this many list rebuilds (0: never) and move the slab
    /// boundaries when the most loaded rank holds over 10 % more grains than the mean.
    pub rebalance_every: u64,
    /// Times the slab boundaries moved.
    pub rebalances: u64,
    /// List rebuilds so far.
    rebuilds: u64,
    /// Seconds waiting for messages (exposed communication).
    pub comm_seconds: f64,
    /// Reusable send/receive buffers of the per-step ghost update.
    bufs: [Vec<f64>; 4],
}

impl SlabDem {
    /// Split `all` (the same global grains on every rank, ids unique) over the ranks of
    /// `comm` by the x-boundaries `bounds` (`comm.size() + 1` increasing values; grains
    /// beyond the outer ones belong to the first/last rank) and start the system: the
    /// checks of [`DemSystem::new`] run on the global set, so every rank reports the same
    /// error. Errors also when a slab is narrower than the ghost cutoff 2 r_max + skin.
    pub fn new(
        all: Grains,
        bounds: &[f64],
        setup: DemSetup,
        allow_overlap: bool,
        comm: &dyn Comm,
    ) -> Result<Self, DemError> {
        assert_eq!(bounds.len(), comm.size() + 1, "one boundary per rank face");
        // Every check on the global set, so every rank reports the same error.
        let check = DemSetup {
            walls: Vec::new(),
            ..setup.clone()
        };
        DemSystem::unstarted(all.clone(), check, allow_overlap)?;
        let mut s = Self::assemble(all, bounds, setup, comm)?;
        s.rebuild(comm, HistoryMap::default());
        s.system.compute_forces(None);
        Ok(s)
    }

    /// Continue a checkpointed system: `all` holds every grain with the forces of its last
    /// evaluation, `history` every live contact's stretch (pairs and walls), `setup.walls`
    /// their state then, `time` and `steps` the clock. Forces are not recomputed (see
    /// `io::grains_checkpoint`). Collective.
    pub fn restore(
        all: Grains,
        history: HistoryMap,
        bounds: &[f64],
        setup: DemSetup,
        (time, steps): (f64, u64),
        comm: &dyn Comm,
    ) -> Result<Self, DemError> {
        let mut s = Self::assemble(all, bounds, setup, comm)?;
        s.system.time = time;
        s.system.steps = steps;
        let (pairs, walls): (HistoryMap, HistoryMap) =
            history.into_iter().partition(|(k, _)| k.1 & WALL_KEY == 0);
        s.system.history = walls;
        s.rebuild(comm, pairs);
        Ok(s)
    }

    /// This rank's grains of `all` in a system with no list yet.
    fn assemble(
        all: Grains,
        bounds: &[f64],
        setup: DemSetup,
        comm: &dyn Comm,
    ) -> Result<Self, DemError> {
        let (rank, size) = (comm.rank(), comm.size());
        let rmax = all.r.iter().cloned().fold(0.0, f64::max);
        let cutoff = cutoff_for(rmax);
        if size > 1 && bounds.windows(2).any(|w| w[1] - w[0] < cutoff) {
            return Err(DemError::Parameter {
                name: "ranks",
                value: size as f64,
                why: "too many ranks: a slab is narrower than the ghost cutoff 2 r_max + skin; \
                      use fewer ranks or a wider region",
            });
        }
        let keep: Vec<bool> = (0..all.len())
            .map(|i| owner(all.x[i], bounds) == rank)
            .collect();
        let mut mine = all;
        mine.retain(&keep);
        let system = DemSystem::unstarted(mine, setup, true)?;
        Ok(Self {
            system,
            bounds: bounds.to_vec(),
            rank,
            rmax,
            send: [Vec::new(), Vec::new()],
            recv: [0, 0],
            migrated: 0,
            rebalance_every: 20,
            rebalances: 0,
            rebuilds: 0,
            comm_seconds: 0.0,
            bufs: Default::default(),
        })
    }

    /// This rank's slab `[lo, hi)` (m).
    fn slab(&self) -> (f64, f64) {
        (self.bounds[self.rank], self.bounds[self.rank + 1])
    }

    /// The left and right neighbour ranks, where they exist.
    fn peers(&self) -> [Option<usize>; 2] {
        let ranks = self.bounds.len() - 1;
        [
            self.rank.checked_sub(1),
            (self.rank + 1 < ranks).then_some(self.rank + 1),
        ]
    }

    /// One velocity-Verlet step on every rank (collective).
    pub fn step(&mut self, comm: &dyn Comm) {
        self.system.first_half();
        if comm.any(self.system.list_is_stale()) {
            let live = self.system.pair_history();
            self.rebuild(comm, live);
        } else {
            self.forward(comm);
        }
        self.system.second_half();
    }

    /// Global owned-grain count (collective).
    pub fn global_count(&self, comm: &dyn Comm) -> usize {
        let mut v = [self.system.owned() as f64];
        comm.sum_f64(&mut v);
        v[0] as usize
    }

    /// The x-boundaries of every rank's slab (m).
    pub fn bounds(&self) -> &[f64] {
        &self.bounds
    }

    /// Send the ghosts' new positions and velocities (fixed ghost set).
    fn forward(&mut self, comm: &dyn Comm) {
        let peers = self.peers();
        let g = &self.system.grains;
        let [out_l, out_r, in_l, in_r] = &mut self.bufs;
        for (list, out) in self.send.iter().zip([&mut *out_l, &mut *out_r]) {
            out.clear();
            for &i in list {
                let i = i as usize;
                out.extend_from_slice(&[g.x[i], g.y[i], g.vx[i], g.vy[i], g.omega[i]]);
            }
        }
        in_l.resize(self.recv[0] * FORWARD, 0.0);
        in_r.resize(self.recv[1] * FORWARD, 0.0);
        let wait = swap(
            comm,
            peers,
            TAG_FORWARD,
            [out_l.as_slice(), out_r.as_slice()],
            [in_l.as_mut_slice(), in_r.as_mut_slice()],
        );
        self.comm_seconds += wait;
        let g = &mut self.system.grains;
        let mut at = self.system.owned;
        for inc in [&*in_l, &*in_r] {
            for v in inc.chunks_exact(FORWARD) {
                g.x[at] = v[0];
                g.y[at] = v[1];
                g.vx[at] = v[2];
                g.vy[at] = v[3];
                g.omega[at] = v[4];
                at += 1;
            }
        }
    }

    /// Migrate leavers with their history, rebuild the ghosts and the Verlet list.
    /// `live` is the pair history taken before the grains change.
    fn rebuild(&mut self, comm: &dyn Comm, mut live: HistoryMap) {
        let sys = &mut self.system;
        sys.grains.truncate(sys.owned);
        self.rebuilds += 1;
        if self.rebalance_every > 0 && self.rebuilds.is_multiple_of(self.rebalance_every) {
            self.rebalance(comm);
        }
        // 1. Leavers, one message per neighbour per round; a grain moves one slab per
        // round, so rounds repeat until no rank has leavers (one round unless the slabs
        // were just rebalanced).
        loop {
            let leaving = self.migrate_round(comm, &mut live);
            if !comm.any(leaving) {
                break;
            }
        }
        // 2. Ghosts: owned grains within the cutoff of a face go to that neighbour.
        let ((lo, hi), [left, right]) = (self.slab(), self.peers());
        let cutoff = cutoff_for(self.rmax);
        let sys = &mut self.system;
        let g = &sys.grains;
        let mut send = [Vec::new(), Vec::new()];
        for i in 0..sys.owned {
            if left.is_some() && g.x[i] < lo + cutoff {
                send[0].push(i as u32);
            }
            if right.is_some() && g.x[i] >= hi - cutoff {
                send[1].push(i as u32);
            }
        }
        let msgs = send.clone().map(|list| {
            let out = pack_rows(g, list.iter().map(|&i| i as usize));
            join(&[&out, &[], &[]])
        });
        let got = self.exchange_varlen(comm, &msgs);
        let sys = &mut self.system;
        for (side, msg) in got.iter().enumerate() {
            let [grains, _, _] = split(msg);
            self.recv[side] = unpack_rows(&mut sys.grains, grains);
        }
        // 3. The list; the spatial sort renumbers owned grains, so follow it.
        let order = sys.rebuild_from(&live, DemSystem::skin_for(self.rmax), self.rmax);
        if !order.is_empty() {
            let mut new_of = vec![0u32; order.len()];
            for (k, &o) in order.iter().enumerate() {
                new_of[o as usize] = k as u32;
            }
            for list in &mut send {
                for i in list.iter_mut() {
                    *i = new_of[*i as usize];
                }
            }
        }
        self.send = send;
    }
}

/// Ghost cutoff from a slab face for grains of radius up to `rmax`: 2 r_max + skin (m).
fn cutoff_for(rmax: f64) -> f64 {
    2.0 * rmax + DemSystem::skin_for(rmax)
}

/// The rank of `bounds` whose range holds `x` (the outer ranks take everything beyond).
pub fn owner(x: f64, bounds: &[f64]) -> usize {
    let ranks = bounds.len() - 1;
    bounds[1..ranks].partition_point(|&b| b <= x)
}

/// x-boundaries that give each of `ranks` ranks about the same number of grains (quantiles
/// of the centres), widened where needed so that no slab is narrower than `min_width`
/// (m), over the domain `[x0, x1]`.
pub fn balanced_bounds(x: &[f64], x0: f64, x1: f64, ranks: usize, min_width: f64) -> Vec<f64> {
    let mut sorted = x.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mut b = vec![x0];
    for r in 1..ranks {
        let q = if sorted.is_empty() {
            x0 + (x1 - x0) * r as f64 / ranks as f64
        } else {
            sorted[(r * sorted.len() / ranks).min(sorted.len() - 1)]
        };
        let prev = *b.last().unwrap_or(&x0);
        let room = x1 - min_width * (ranks - r) as f64;
        b.push(q.max(prev + min_width).min(room));
    }
    b.push(x1);
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{closed_box, ContactModel};
    use decomposition::SingleProcess;

    /// On one rank the distributed driver is the serial system, bit for bit.
    #[test]
    fn one_rank_matches_the_serial_system() {
        let mut g = Grains::default();
        let mut rng = crate::sample::Rng::new(7);
        for k in 0..200 {
            let (col, row) = ((k % 20) as f64, (k / 20) as f64);
            let r = 0.4e-3 + 0.1e-3 * rng.uniform();
            g.push(
                [1.2e-3 * (col + 1.0), 1.2e-3 * (row + 1.0)],
                r,
                2500.0,
                false,
            );
        }
        let walls = closed_box([0.0, 0.0], [0.03, 0.03], 0.3);
        let model = ContactModel {
            kn: 1e4,
            kt: 0.5e4,
            restitution: 0.5,
            friction: 0.5,
            rolling_friction: 0.05,
            tangential_damping: 0.0,
        };
        let dt = crate::stable_time_step(&g, &model, 0.1);
        let mut serial = DemSystem::new(
            g.clone(),
            walls.clone(),
            model,
            [0.0, -9.81],
            dt,
            0.1,
            false,
        )
        .unwrap();
        let comm = SingleProcess;
        let setup = DemSetup {
            walls,
            model,
            gravity: [0.0, -9.81],
            dt,
            lambda: 0.1,
            fixed: Vec::new(),
        };
        let mut dist = SlabDem::new(g, &[0.0, 0.03], setup, false, &comm).unwrap();
        for _ in 0..2000 {
            serial.step();
            dist.step(&comm);
        }
        assert!(serial.list_rebuilds() > 2);
        let (a, b) = (&serial.grains, &dist.system.grains);
        assert_eq!(a.id, b.id);
        assert_eq!(a.x, b.x);
        assert_eq!(a.vy, b.vy);
        assert_eq!(a.omega, b.omega);
    }

    #[test]
    fn owners_and_balanced_bounds() {
        let b = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(owner(-5.0, &b), 0);
        assert_eq!(owner(0.99, &b), 0);
        assert_eq!(owner(1.0, &b), 1);
        assert_eq!(owner(9.0, &b), 2);
        let x: Vec<f64> = (0..100).map(|i| i as f64 * 0.01).collect();
        let q = balanced_bounds(&x, 0.0, 10.0, 4, 0.1);
        assert_eq!(q.len(), 5);
        assert!((q[2] - 0.5).abs() < 1e-12, "{q:?}");
        assert!(q.windows(2).all(|w| w[1] - w[0] >= 0.1 - 1e-12), "{q:?}");
    }
}
