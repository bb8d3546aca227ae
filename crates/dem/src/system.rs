//! A DEM system: grains, walls, contact law, gravity and the velocity-Verlet step.
//!
//! The grains of one rank are stored owned first, then ghosts (read-only copies of other
//! ranks' grains near a slab face, see [`super::parallel`]). Only owned grains are
//! integrated and get forces; ghosts only take part in contacts.

use super::cells::CellList;
use super::contact::{ContactForce, ContactModel, DemError};
use super::grains::Grains;
use super::walls::Wall;
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Multiplicative hash for the (id, id) contact keys: SipHash's DoS resistance buys nothing
/// here and cost a third of the step.
#[derive(Default, Clone, Copy)]
pub struct PairHasher(u64);

impl Hasher for PairHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(*b as u64);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// Tangential stretch per contact, keyed by (smaller id, larger id) for grain pairs and by
/// (grain id, [`WALL_KEY`] | wall index) for grain–wall contacts. The stretch of a pair is
/// that of the smaller-id grain as body 1.
pub type HistoryMap = HashMap<(u64, u64), f64, BuildHasherDefault<PairHasher>>;

/// Key bit that marks a grain–wall contact in the history (wall index in the low bits).
pub const WALL_KEY: u64 = 1 << 63;

/// One grain–wall contact: wall index, unit normal from the wall to the grain, force, overlap.
pub(crate) type WallHit = (usize, [f64; 2], ContactForce, f64);

/// Result of one candidate pair (a, b), id(a) < id(b): force on b (global frame, N/m), the
/// torques on a and on b (N), and the elastic energy stored in it (J/m; 0 when the pair
/// does not touch).
pub(crate) type PairResult = [f64; 5];

/// Grains per task of a one-pass update of the owned grains: one chunk per thread, at least
/// 2048 grains each (a task costs the pool a wake-up).
fn pass_chunk(n: usize) -> usize {
    n.div_ceil(rayon::current_num_threads()).max(2048)
}

/// The largest stable time step λ·Δt_cr for `grains` in contact under `model` (s): the
/// critical step of seed eq. 5.59 for the lightest grain, times λ (eq. 5.60; around 0.1).
pub fn stable_time_step(grains: &Grains, model: &ContactModel, lambda: f64) -> f64 {
    let m_min = grains.m.iter().cloned().fold(f64::INFINITY, f64::min);
    lambda * model.critical_time_step(m_min)
}

/// Everything but the grains that a DEM system is built from.
#[derive(Debug, Clone)]
pub struct DemSetup {
    /// The walls.
    pub walls: Vec<Wall>,
    /// Contact law between grains.
    pub model: ContactModel,
    /// Gravity (m/s²).
    pub gravity: [f64; 2],
    /// Time step (s).
    pub dt: f64,
    /// The stability fraction λ that `dt` must respect: dt ≤ λ Δt_cr (eq. 5.60).
    pub lambda: f64,
    /// Ids of the grains held in place (neither moving nor turning; forces on them are
    /// still computed and reported), sorted, every one of them on every rank.
    pub fixed: Vec<u64>,
}

/// Grains, walls and the contact law of one rank, advanced by velocity Verlet.
#[derive(Debug, Clone)]
pub struct DemSystem {
    /// The grains: `grains[..owned()]` are this rank's, the rest are ghosts.
    pub grains: Grains,
    /// The walls.
    pub walls: Vec<Wall>,
    /// Contact law between grains (walls use their own friction).
    pub model: ContactModel,
    /// Gravity (m/s²).
    pub gravity: [f64; 2],
    /// Global viscous damping α (1/s): the force −α m v, seed eq. 5.57 with c = α m. Off (0)
    /// by default.
    pub global_damping: f64,
    /// Time step (s).
    pub dt: f64,
    /// Simulated time (s).
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
    /// Reorder the owned grains by cell at every list rebuild, so that neighbours sit close
    /// in memory (on by default; results do not depend on it).
    pub spatial_sort: bool,
    /// Owned grains (the first `owned` of `grains`).
    pub(crate) owned: usize,
    /// Verlet list: pairs (a, b) with id(a) < id(b), at least one owned, within
    /// r_a + r_b + skin of each other when it was built; rebuilt once a grain has moved
    /// skin/2.
    pub(crate) candidates: Vec<(u32, u32)>,
    /// Tangential stretch per candidate (0 when not in contact), for body a of (a, b).
    pub(crate) stretch: Vec<f64>,
    /// Per owned grain, its candidates: `adj[adj_start[g]..adj_start[g + 1]]` holds
    /// k << 1 | role (role 1: the grain is b of pair k), sorted by the partner's id.
    pub(crate) adj_start: Vec<u32>,
    pub(crate) adj: Vec<u32>,
    /// Owned positions when the list was built.
    pub(crate) built_at: (Vec<f64>, Vec<f64>),
    /// Verlet skin (m).
    pub(crate) skin: f64,
    /// List rebuilds so far.
    pub(crate) rebuilds: u64,
    /// Tangential stretch of every grain–wall contact.
    pub(crate) history: HistoryMap,
    /// The previous step's map, kept for its allocation.
    pub(crate) spare: HistoryMap,
    /// Per candidate: its result (buffer reused every step).
    pub(crate) pair_results: Vec<PairResult>,
    /// Per owned grain, the walls within reach at the last build:
    /// `wall_cand[wall_start[g]..wall_start[g + 1]]`, increasing wall index.
    pub(crate) wall_start: Vec<u32>,
    pub(crate) wall_cand: Vec<u32>,
    /// Wall positions (end a) when the list was built.
    pub(crate) walls_built_at: Vec<[f64; 2]>,
    /// Per wall candidate: the contact, if touching (buffer reused every step).
    pub(crate) wall_hits: Vec<Option<WallHit>>,
    /// Force (N/m) and torque (N·m/m) from outside the DEM (the fluid) on each owned grain,
    /// held over the steps until it is set again; empty when nothing acts from outside.
    pub(crate) external: Vec<[f64; 3]>,
    /// Whether [`DemSystem::set_external`] was ever called (the forces then travel with
    /// their grains when they migrate).
    pub(crate) external_on: bool,
    /// Values that travel with each owned grain when it migrates or is reordered, `carry_width`
    /// per grain (for state kept outside the DEM, e.g. a coupling's force history).
    pub(crate) carry: Vec<f64>,
    /// Values per grain in `carry` (0: none).
    pub(crate) carry_width: usize,
    /// Ids of the grains held in place, sorted ([`DemSetup::fixed`]).
    pub(crate) fixed: Vec<u64>,
}

impl DemSystem {
    /// Build a system. Errors when a parameter is out of range, when `dt` exceeds λ·Δt_cr
    /// (eq. 5.59–5.60 for the lightest grain), or when grains overlap and `allow_overlap`
    /// is false. Forces are evaluated once, so the first step starts from them.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        grains: Grains,
        walls: Vec<Wall>,
        model: ContactModel,
        gravity: [f64; 2],
        dt: f64,
        lambda: f64,
        allow_overlap: bool,
    ) -> Result<Self, DemError> {
        let setup = DemSetup {
            walls,
            model,
            gravity,
            dt,
            lambda,
            fixed: Vec::new(),
        };
        let mut s = Self::unstarted(grains, setup, allow_overlap)?;
        s.rebuild_list();
        s.compute_forces(None);
        Ok(s)
    }

    /// [`DemSystem::new`] without the first list build and force evaluation (the
    /// distributed driver adds ghosts first).
    pub(crate) fn unstarted(
        grains: Grains,
        setup: DemSetup,
        allow_overlap: bool,
    ) -> Result<Self, DemError> {
        let DemSetup {
            walls,
            model,
            gravity,
            dt,
            lambda,
            mut fixed,
        } = setup;
        model.validate()?;
        fixed.sort_unstable();
        fixed.dedup();
        if !(lambda > 0.0 && lambda <= 1.0) {
            return Err(DemError::Parameter {
                name: "lambda",
                value: lambda,
                why: "must be in (0, 1]",
            });
        }
        let limit = stable_time_step(&grains, &model, lambda);
        let stable = dt > 0.0 && dt <= limit;
        if !grains.is_empty() && !stable {
            return Err(DemError::TimeStepTooLarge { dt, limit, lambda });
        }
        if !allow_overlap {
            if let Some((a, b, overlap)) = first_overlap(&grains) {
                return Err(DemError::Overlap { a, b, overlap });
            }
        }
        Ok(Self {
            owned: grains.len(),
            grains,
            walls,
            model,
            gravity,
            global_damping: 0.0,
            dt,
            time: 0.0,
            steps: 0,
            spatial_sort: true,
            candidates: Vec::new(),
            stretch: Vec::new(),
            adj_start: vec![0],
            adj: Vec::new(),
            built_at: (Vec::new(), Vec::new()),
            skin: 0.0,
            rebuilds: 0,
            history: HistoryMap::default(),
            spare: HistoryMap::default(),
            pair_results: Vec::new(),
            wall_start: vec![0],
            wall_cand: Vec::new(),
            walls_built_at: Vec::new(),
            wall_hits: Vec::new(),
            external: Vec::new(),
            external_on: false,
            carry: Vec::new(),
            carry_width: 0,
            fixed,
        })
    }

    /// The largest stable time step λ·Δt_cr for these grains and contacts.
    pub fn stable_time_step(&self, lambda: f64) -> f64 {
        stable_time_step(&self.grains, &self.model, lambda)
    }

    /// Hold `force` (per owned grain, by index: fx, fy in N/m, torque in N·m/m) on the
    /// grains from now on, until it is set again. The forces of the last evaluation are
    /// corrected at once, so the next half kick already uses it: over k steps the grains
    /// receive exactly k·Δt·force (the sub-cycling of seed eq. 5.61). Precondition: one
    /// entry per owned grain, and the grains are not re-sorted (`spatial_sort = false`).
    pub fn set_external(&mut self, force: &[[f64; 3]]) {
        assert_eq!(
            force.len(),
            self.owned,
            "one external force per owned grain"
        );
        if !self.external_on {
            self.external = vec![[0.0; 3]; self.owned];
            self.external_on = true;
        }
        let g = &mut self.grains;
        for (i, (new, old)) in force.iter().zip(&mut self.external).enumerate() {
            g.fx[i] += new[0] - old[0];
            g.fy[i] += new[1] - old[1];
            g.torque[i] += new[2] - old[2];
            *old = *new;
        }
    }

    /// The external force and torque held on each owned grain (empty when none was set).
    pub fn external(&self) -> &[[f64; 3]] {
        &self.external
    }

    /// Restore the external force held on each owned grain (a restart), without touching
    /// the forces of the last evaluation (which already include it).
    pub fn restore_external(&mut self, force: Vec<[f64; 3]>) {
        assert_eq!(
            force.len(),
            self.owned,
            "one external force per owned grain"
        );
        self.external = force;
        self.external_on = true;
    }

    /// Give every owned grain `width` values that travel with it (migration, reordering),
    /// all zero. See [`DemSystem::carry`].
    pub fn enable_carry(&mut self, width: usize) {
        self.carry_width = width;
        self.carry = vec![0.0; width * self.owned];
    }

    /// Owned grain `i`'s carried values.
    pub fn carry(&self, i: usize) -> &[f64] {
        let w = self.carry_width;
        &self.carry[i * w..(i + 1) * w]
    }

    /// Owned grain `i`'s carried values, for writing.
    pub fn carry_mut(&mut self, i: usize) -> &mut [f64] {
        let w = self.carry_width;
        &mut self.carry[i * w..(i + 1) * w]
    }

    /// Values per grain that travel beside [`Grains::pack`] when it migrates: the external
    /// force (when on) and the carried values.
    pub(crate) fn extras_width(&self) -> usize {
        3 * self.external_on as usize + self.carry_width
    }

    /// Append owned grain `i`'s travelling values ([`DemSystem::extras_width`] of them).
    pub(crate) fn pack_extras(&self, i: usize, out: &mut Vec<f64>) {
        if self.external_on {
            out.extend_from_slice(&self.external[i]);
        }
        out.extend_from_slice(self.carry(i));
    }

    /// Append a newly owned grain's travelling values (as packed by
    /// [`DemSystem::pack_extras`]); call once per grain pushed, in the same order.
    pub(crate) fn push_extras(&mut self, v: &[f64]) {
        let mut v = v;
        if self.external_on {
            self.external.push([v[0], v[1], v[2]]);
            v = &v[3..];
        }
        self.carry.extend_from_slice(&v[..self.carry_width]);
    }

    /// Keep the travelling values of owned grain i where `keep[i]` (as [`Grains::retain`]).
    pub(crate) fn retain_extras(&mut self, keep: &[bool]) {
        if self.external_on {
            let mut k = keep.iter();
            self.external.retain(|_| *k.next().unwrap_or(&true));
        }
        let w = self.carry_width;
        if w > 0 {
            let mut out = Vec::with_capacity(self.carry.len());
            for (i, c) in self.carry.chunks_exact(w).enumerate() {
                if keep.get(i).copied().unwrap_or(true) {
                    out.extend_from_slice(c);
                }
            }
            self.carry = out;
        }
    }

    /// Reorder the travelling values like [`Grains::permute_prefix`].
    pub(crate) fn permute_extras(&mut self, order: &[u32]) {
        if self.external_on {
            self.external = order.iter().map(|&o| self.external[o as usize]).collect();
        }
        let w = self.carry_width;
        if w > 0 {
            let mut out = Vec::with_capacity(self.carry.len());
            for &o in order {
                out.extend_from_slice(&self.carry[o as usize * w..(o as usize + 1) * w]);
            }
            self.carry = out;
        }
    }

    /// Grains owned by this system (the first `owned()` of `grains`; the rest are ghosts).
    pub fn owned(&self) -> usize {
        self.owned
    }

    /// One velocity-Verlet step: half kick, drift, walls move, forces, half kick.
    pub fn step(&mut self) {
        self.first_half();
        if self.list_is_stale() {
            self.rebuild_list();
        }
        self.second_half();
    }

    /// Half kick and drift of the owned grains, walls move, time advances. One pass over
    /// the grains (each grain's kick, then its drift: element-wise, so the same bits at any
    /// thread count).
    pub(crate) fn first_half(&mut self) {
        let dt = self.dt;
        let h = 0.5 * dt;
        let n = self.owned;
        let fixed = &self.fixed;
        let Grains {
            x,
            y,
            theta,
            vx,
            vy,
            omega,
            fx,
            fy,
            torque,
            m,
            inv_inertia,
            id,
            ..
        } = &mut self.grains;
        let c = pass_chunk(n);
        (
            (
                x[..n].par_chunks_mut(c),
                y[..n].par_chunks_mut(c),
                theta[..n].par_chunks_mut(c),
            ),
            (
                vx[..n].par_chunks_mut(c),
                vy[..n].par_chunks_mut(c),
                omega[..n].par_chunks_mut(c),
            ),
            (
                fx[..n].par_chunks(c),
                fy[..n].par_chunks(c),
                torque[..n].par_chunks(c),
            ),
            (
                m[..n].par_chunks(c),
                inv_inertia[..n].par_chunks(c),
                id[..n].par_chunks(c),
            ),
        )
            .into_par_iter()
            .for_each(|((x, y, th), (vx, vy, w), (fx, fy, t), (m, inv, id))| {
                for k in 0..x.len() {
                    vx[k] += h * fx[k] / m[k];
                    vy[k] += h * fy[k] / m[k];
                    w[k] += h * t[k] * inv[k];
                    if !fixed.is_empty() && fixed.binary_search(&id[k]).is_ok() {
                        (vx[k], vy[k], w[k]) = (0.0, 0.0, 0.0);
                    }
                    x[k] += dt * vx[k];
                    y[k] += dt * vy[k];
                    th[k] += dt * w[k];
                }
            });
        for w in &mut self.walls {
            w.advance(dt);
        }
        self.time += dt;
    }

    /// Forces at the new positions, then the second half kick (in the forces' last pass).
    pub(crate) fn second_half(&mut self) {
        self.compute_forces(Some(0.5 * self.dt));
        self.hold_fixed();
        self.steps += 1;
    }

    /// Zero the velocities of the owned grains held in place (none when nothing is fixed).
    fn hold_fixed(&mut self) {
        if self.fixed.is_empty() {
            return;
        }
        let g = &mut self.grains;
        for i in 0..self.owned {
            if self.fixed.binary_search(&g.id[i]).is_ok() {
                g.vx[i] = 0.0;
                g.vy[i] = 0.0;
                g.omega[i] = 0.0;
            }
        }
    }

    /// Whether grain `id` is held in place.
    pub fn is_fixed(&self, id: u64) -> bool {
        self.fixed.binary_search(&id).is_ok()
    }

    /// Contacts active at the last force evaluation that this rank accounts for: grain
    /// pairs whose smaller-id grain is owned, and the owned grains' wall contacts. Summed
    /// over ranks, every contact counts once.
    pub fn contacts(&self) -> usize {
        let pairs = self
            .candidates
            .iter()
            .zip(&self.pair_results)
            .filter(|(&(a, _), r)| (a as usize) < self.owned && r[4] > 0.0)
            .count();
        pairs + self.wall_hits.iter().flatten().count()
    }

    /// The touching grain pairs this rank accounts for (see [`DemSystem::contacts`]) as
    /// (id a, id b, contact point (m), force on b (N/m)), id a < id b; the force on a is the
    /// opposite. As of the last force evaluation.
    pub fn contact_list(&self) -> Vec<(u64, u64, [f64; 2], [f64; 2])> {
        let g = &self.grains;
        self.candidates
            .iter()
            .zip(&self.pair_results)
            .filter(|(&(a, _), r)| (a as usize) < self.owned && r[4] > 0.0)
            .map(|(&(a, b), r)| {
                let (a, b) = (a as usize, b as usize);
                let (dx, dy) = (g.x[b] - g.x[a], g.y[b] - g.y[a]);
                let d = dx.hypot(dy).max(1e-300);
                let p = [g.x[a] + dx / d * g.r[a], g.y[a] + dy / d * g.r[a]];
                (g.id[a], g.id[b], p, [r[0], r[1]])
            })
            .collect()
    }

    /// Kinetic + gravitational potential + elastic contact energy of what this rank owns
    /// (J/m; pairs as in [`DemSystem::contacts`]).
    pub fn energy(&self) -> f64 {
        let g = &self.grains;
        let potential: f64 = (0..self.owned)
            .map(|i| -g.m[i] * (self.gravity[0] * g.x[i] + self.gravity[1] * g.y[i]))
            .sum();
        let (kn, kt) = (self.model.kn, self.model.kt);
        let mut elastic: f64 = self
            .candidates
            .iter()
            .zip(&self.pair_results)
            .filter(|(&(a, _), _)| (a as usize) < self.owned)
            .map(|(_, r)| r[4])
            .sum();
        for (_, _, c, delta) in self.wall_hits.iter().flatten() {
            elastic += 0.5 * kn * delta * delta + 0.5 * kt * c.stretch * c.stretch;
        }
        self.owned_kinetic_energy() + potential + elastic
    }

    /// Kinetic energy of the owned grains (J/m).
    pub fn owned_kinetic_energy(&self) -> f64 {
        self.grains.kinetic_energy_of(self.owned)
    }

    /// Verlet-list rebuilds so far.
    pub fn list_rebuilds(&self) -> u64 {
        self.rebuilds
    }

    /// Remove wall `w` (it keeps its index): from the next list rebuild on, which this
    /// forces, it touches nothing.
    pub fn remove_wall(&mut self, w: usize) {
        self.walls[w].removed = true;
        self.walls_built_at.clear();
    }
}

/// The first overlapping pair of `grains` (ids and overlap in m), if any.
pub(crate) fn first_overlap(grains: &Grains) -> Option<(u64, u64, f64)> {
    let rmax = grains.r.iter().cloned().fold(0.0, f64::max);
    let &(i, j) = CellList::build(grains, 2.0 * rmax)
        .touching_pairs(grains)
        .first()?;
    let (a, b) = (i as usize, j as usize);
    let d = (grains.x[b] - grains.x[a]).hypot(grains.y[b] - grains.y[a]);
    Some((grains.id[a], grains.id[b], grains.r[a] + grains.r[b] - d))
}
