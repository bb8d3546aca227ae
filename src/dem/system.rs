//! A DEM system: grains, walls, contact law, gravity and the velocity-Verlet step.

use super::cells::CellList;
use super::contact::{contact_force, ContactForce, ContactModel, DemError};
use super::grains::Grains;
use super::walls::Wall;
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Multiplicative hash for the (id, id) contact keys: SipHash's DoS resistance buys nothing
/// here and cost a third of the step.
#[derive(Default, Clone, Copy)]
struct PairHasher(u64);

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

/// Tangential stretch per contact.
type HistoryMap = HashMap<(u64, u64), f64, BuildHasherDefault<PairHasher>>;

/// Key bit that marks a grain–wall contact in the history (wall index in the low bits).
const WALL_KEY: u64 = 1 << 63;

/// One grain–wall contact: wall index, unit normal from the wall to the grain, force, overlap.
type WallHit = (usize, [f64; 2], ContactForce, f64);

/// One grain–grain contact: unit normal from i to j, force on j, overlap, rolling torque on i.
type PairHit = ([f64; 2], ContactForce, f64, f64);

/// The largest stable time step λ·Δt_cr for `grains` in contact under `model` (s): the
/// critical step of seed eq. 5.59 for the lightest grain, times λ (eq. 5.60; around 0.1).
pub fn stable_time_step(grains: &Grains, model: &ContactModel, lambda: f64) -> f64 {
    let m_min = grains.m.iter().cloned().fold(f64::INFINITY, f64::min);
    lambda * model.critical_time_step(m_min)
}

/// Grains, walls and the contact law of one rank, advanced by velocity Verlet.
#[derive(Debug, Clone)]
pub struct DemSystem {
    /// The grains.
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
    /// Verlet list: grain pairs (i < j) within r_i + r_j + skin of each other when it was
    /// built; rebuilt once a grain has moved skin/2.
    candidates: Vec<(u32, u32)>,
    /// Tangential stretch per candidate (0 when not in contact), for body i of (i, j).
    stretch: Vec<f64>,
    /// Per grain, its candidates: `adj[adj_start[g]..adj_start[g + 1]]` holds k << 1 | role
    /// (role 1: the grain is j of pair k), in increasing k.
    adj_start: Vec<u32>,
    adj: Vec<u32>,
    /// Positions when the list was built.
    built_at: (Vec<f64>, Vec<f64>),
    /// Verlet skin (m).
    skin: f64,
    /// List rebuilds so far.
    rebuilds: u64,
    /// Tangential stretch of every grain–wall contact, keyed by (grain id, WALL_KEY | wall).
    history: HistoryMap,
    /// The previous step's map, kept for its allocation.
    spare: HistoryMap,
    /// Per candidate: the contact, if touching (buffer reused every step).
    pair_hits: Vec<Option<PairHit>>,
    /// Per grain: its wall contacts (buffer reused every step).
    wall_hits: Vec<Vec<WallHit>>,
    /// Elastic energy stored in the contacts at the last force evaluation (J/m).
    elastic: f64,
    /// Active contacts at the last force evaluation.
    contacts: usize,
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
        model.validate()?;
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
            let rmax = grains.r.iter().cloned().fold(0.0, f64::max);
            if let Some(&(i, j)) = CellList::build(&grains, 2.0 * rmax)
                .touching_pairs(&grains)
                .first()
            {
                let (a, b) = (i as usize, j as usize);
                let d = (grains.x[b] - grains.x[a]).hypot(grains.y[b] - grains.y[a]);
                return Err(DemError::Overlap {
                    a: grains.id[a],
                    b: grains.id[b],
                    overlap: grains.r[a] + grains.r[b] - d,
                });
            }
        }
        let mut s = Self {
            grains,
            walls,
            model,
            gravity,
            global_damping: 0.0,
            dt,
            time: 0.0,
            steps: 0,
            candidates: Vec::new(),
            stretch: Vec::new(),
            adj_start: Vec::new(),
            adj: Vec::new(),
            built_at: (Vec::new(), Vec::new()),
            skin: 0.0,
            rebuilds: 0,
            history: HistoryMap::default(),
            spare: HistoryMap::default(),
            pair_hits: Vec::new(),
            wall_hits: Vec::new(),
            elastic: 0.0,
            contacts: 0,
        };
        s.compute_forces();
        Ok(s)
    }

    /// The largest stable time step λ·Δt_cr for these grains and contacts.
    pub fn stable_time_step(&self, lambda: f64) -> f64 {
        stable_time_step(&self.grains, &self.model, lambda)
    }

    /// One velocity-Verlet step: half kick, drift, walls move, forces, half kick.
    pub fn step(&mut self) {
        let dt = self.dt;
        self.kick(0.5 * dt);
        let g = &mut self.grains;
        let drift = |p: &mut [f64], v: &[f64]| {
            p.par_iter_mut()
                .zip(v.par_iter())
                .with_min_len(4096)
                .for_each(|(p, v)| *p += dt * v)
        };
        drift(&mut g.x, &g.vx);
        drift(&mut g.y, &g.vy);
        drift(&mut g.theta, &g.omega);
        for w in &mut self.walls {
            w.advance(dt);
        }
        self.time += dt;
        self.compute_forces();
        self.kick(0.5 * dt);
        self.steps += 1;
    }

    fn kick(&mut self, h: f64) {
        let g = &mut self.grains;
        // Element-wise, so parallel and still thread-count independent.
        let linear = |v: &mut [f64], f: &[f64], m: &[f64]| {
            v.par_iter_mut()
                .zip(f.par_iter().zip(m.par_iter()))
                .with_min_len(4096)
                .for_each(|(v, (f, m))| *v += h * f / m)
        };
        linear(&mut g.vx, &g.fx, &g.m);
        linear(&mut g.vy, &g.fy, &g.m);
        g.omega
            .par_iter_mut()
            .zip(g.torque.par_iter().zip(g.inv_inertia.par_iter()))
            .with_min_len(4096)
            .for_each(|(w, (t, inv))| *w += h * t * inv);
    }

    /// Contacts active at the last force evaluation.
    pub fn contacts(&self) -> usize {
        self.contacts
    }

    /// Kinetic + gravitational potential + elastic contact energy (J/m).
    pub fn energy(&self) -> f64 {
        let g = &self.grains;
        let potential: f64 = (0..g.len())
            .map(|i| -g.m[i] * (self.gravity[0] * g.x[i] + self.gravity[1] * g.y[i]))
            .sum();
        g.kinetic_energy() + potential + self.elastic
    }

    /// Forces and torques on every grain at the current positions (velocities as they are,
    /// i.e. at the half step inside `step`). Pair forces are computed in parallel and summed
    /// in pair-list order, so the result does not depend on the thread count.
    fn compute_forces(&mut self) {
        if self.list_is_stale() {
            self.rebuild_list();
        }
        let g = &self.grains;
        let n = g.len();
        let (model, dt) = (&self.model, self.dt);
        let stretch = &self.stretch;
        let zeta = model.damping_ratio();
        let mu_r = model.rolling_friction;
        let mut results = std::mem::take(&mut self.pair_hits);
        self.candidates
            .par_iter()
            .enumerate()
            .with_min_len(256)
            .map(|(k, &(i, j))| {
                let (i, j) = (i as usize, j as usize);
                let (dx, dy) = (g.x[j] - g.x[i], g.y[j] - g.y[i]);
                let reach = g.r[i] + g.r[j];
                let d2 = dx * dx + dy * dy;
                if d2 >= reach * reach {
                    return None;
                }
                let dist = d2.sqrt();
                let nrm = [dx / dist, dy / dist];
                let delta = reach - dist;
                // Contact-point velocities: v + ω × (±r n).
                let vi = [
                    g.vx[i] - g.omega[i] * g.r[i] * nrm[1],
                    g.vy[i] + g.omega[i] * g.r[i] * nrm[0],
                ];
                let vj = [
                    g.vx[j] + g.omega[j] * g.r[j] * nrm[1],
                    g.vy[j] - g.omega[j] * g.r[j] * nrm[0],
                ];
                let rel = [vj[0] - vi[0], vj[1] - vi[1]];
                let vn = rel[0] * nrm[0] + rel[1] * nrm[1];
                let vt = -rel[0] * nrm[1] + rel[1] * nrm[0];
                let m_eff = g.m[i] * g.m[j] / (g.m[i] + g.m[j]);
                let cn = model.damping_with(zeta, m_eff);
                let c = contact_force(model, delta, vn, vt, cn, model.friction, stretch[k], dt);
                let roll = if mu_r > 0.0 {
                    let r_eff = g.r[i] * g.r[j] / (g.r[i] + g.r[j]);
                    rolling_torque(
                        mu_r * r_eff * c.fn_.abs(),
                        g.omega[i] - g.omega[j],
                        g.inv_inertia[i] + g.inv_inertia[j],
                        dt,
                    )
                } else {
                    0.0
                };
                Some((nrm, c, delta, roll))
            })
            .collect_into_vec(&mut results);
        let mut wall_hits = std::mem::take(&mut self.wall_hits);
        (0..n)
            .into_par_iter()
            .with_min_len(256)
            .map(|i| self.wall_contacts(i, zeta))
            .collect_into_vec(&mut wall_hits);
        // Per grain, in parallel: gravity and global damping, then its contacts in list
        // order, so the sums do not depend on the thread count.
        {
            let Grains {
                fx,
                fy,
                torque,
                m,
                vx,
                vy,
                r,
                ..
            } = &mut self.grains;
            let (m, vx, vy, r) = (&*m, &*vx, &*vy, &*r);
            let (adj_start, adj) = (&self.adj_start, &self.adj);
            let (gravity, alpha) = (self.gravity, self.global_damping);
            let results = &results;
            fx.par_iter_mut()
                .zip(fy.par_iter_mut())
                .zip(torque.par_iter_mut())
                .enumerate()
                .with_min_len(1024)
                .for_each(|(i, ((fxi, fyi), ti))| {
                    let mut f = [
                        m[i] * (gravity[0] - alpha * vx[i]),
                        m[i] * (gravity[1] - alpha * vy[i]),
                    ];
                    let mut t = 0.0;
                    for &e in &adj[adj_start[i] as usize..adj_start[i + 1] as usize] {
                        let Some((nrm, c, _, roll)) = &results[(e >> 1) as usize] else {
                            continue;
                        };
                        let pf = [
                            c.fn_ * nrm[0] - c.ft * nrm[1],
                            c.fn_ * nrm[1] + c.ft * nrm[0],
                        ];
                        // Body j (bit set) gets +F and −roll; body i the opposite. Friction
                        // turns both the same way: −r F_t.
                        let s = if e & 1 == 1 { 1.0 } else { -1.0 };
                        f[0] += s * pf[0];
                        f[1] += s * pf[1];
                        t += -r[i] * c.ft - s * roll;
                    }
                    *fxi = f[0];
                    *fyi = f[1];
                    *ti = t;
                });
        }
        let (kn, kt) = (self.model.kn, self.model.kt);
        let mut elastic = 0.0;
        let mut contacts = 0;
        for (k, hit) in results.iter().enumerate() {
            match hit {
                None => self.stretch[k] = 0.0,
                Some((_, c, delta, _)) => {
                    self.stretch[k] = c.stretch;
                    elastic += 0.5 * kn * delta * delta + 0.5 * kt * c.stretch * c.stretch;
                    contacts += 1;
                }
            }
        }
        let g = &mut self.grains;
        let mut history = std::mem::take(&mut self.spare);
        history.clear();
        for (i, hits) in wall_hits.iter().enumerate() {
            for &(w, nrm, c, delta) in hits {
                g.fx[i] += c.fn_ * nrm[0] - c.ft * nrm[1];
                g.fy[i] += c.fn_ * nrm[1] + c.ft * nrm[0];
                g.torque[i] -= g.r[i] * c.ft;
                if mu_r > 0.0 {
                    let limit = mu_r * g.r[i] * c.fn_.abs();
                    g.torque[i] += rolling_torque(limit, g.omega[i], g.inv_inertia[i], self.dt);
                }
                history.insert((g.id[i], WALL_KEY | w as u64), c.stretch);
                elastic += 0.5 * kn * delta * delta + 0.5 * kt * c.stretch * c.stretch;
                contacts += 1;
            }
        }
        self.spare = std::mem::replace(&mut self.history, history);
        // Keep the buffers for the next step (no allocation in the time loop).
        self.pair_hits = results;
        self.wall_hits = wall_hits;
        self.elastic = elastic;
        self.contacts = contacts;
    }

    /// Whether some grain moved more than half the skin since the list was built.
    fn list_is_stale(&self) -> bool {
        let g = &self.grains;
        if self.built_at.0.len() != g.len() {
            return true;
        }
        let half = 0.5 * self.skin;
        (0..g.len()).into_par_iter().with_min_len(4096).any(|i| {
            let (dx, dy) = (g.x[i] - self.built_at.0[i], g.y[i] - self.built_at.1[i]);
            dx * dx + dy * dy > half * half
        })
    }

    /// Rebuild the Verlet list (pairs within r_i + r_j + skin) and carry the tangential
    /// stretch of every live contact over to it.
    fn rebuild_list(&mut self) {
        let g = &self.grains;
        let rmax = g.r.iter().cloned().fold(0.0, f64::max);
        // Skin: 30 % of the largest radius; rebuilt when any grain has moved half of it.
        self.skin = 0.3 * rmax;
        let live: HistoryMap = self
            .candidates
            .iter()
            .zip(&self.stretch)
            .filter(|(_, s)| **s != 0.0)
            .map(|(&(i, j), &s)| oriented(g.id[i as usize], g.id[j as usize], s))
            .collect();
        let candidates = CellList::build(g, 2.0 * rmax + self.skin).pairs_within(g, self.skin);
        self.stretch = candidates
            .iter()
            .map(|&(i, j)| {
                let (key, sign) = oriented(g.id[i as usize], g.id[j as usize], 1.0);
                sign * live.get(&key).copied().unwrap_or(0.0)
            })
            .collect();
        let n = g.len();
        let mut start = vec![0u32; n + 1];
        for &(i, j) in &candidates {
            start[i as usize + 1] += 1;
            start[j as usize + 1] += 1;
        }
        for k in 0..n {
            start[k + 1] += start[k];
        }
        let mut fill = start.clone();
        let mut adj = vec![0u32; 2 * candidates.len()];
        for (k, &(i, j)) in candidates.iter().enumerate() {
            for (who, role) in [(i, 0u32), (j, 1u32)] {
                adj[fill[who as usize] as usize] = (k as u32) << 1 | role;
                fill[who as usize] += 1;
            }
        }
        self.adj_start = start;
        self.adj = adj;
        self.candidates = candidates;
        self.built_at = (g.x.clone(), g.y.clone());
        self.rebuilds += 1;
    }

    /// Verlet-list rebuilds so far.
    pub fn list_rebuilds(&self) -> u64 {
        self.rebuilds
    }

    /// Contacts of grain `i` with the walls: (wall, normal from wall to grain, force, overlap).
    fn wall_contacts(&self, i: usize, zeta: f64) -> Vec<WallHit> {
        let g = &self.grains;
        let mut out = Vec::new();
        for (w, wall) in self.walls.iter().enumerate() {
            let c = wall.closest_point([g.x[i], g.y[i]]);
            let (dx, dy) = (g.x[i] - c[0], g.y[i] - c[1]);
            let dist = (dx * dx + dy * dy).sqrt();
            let delta = g.r[i] - dist;
            if !(delta > 0.0) || dist == 0.0 {
                continue;
            }
            let nrm = [dx / dist, dy / dist];
            // The grain's contact point is at −r n from its centre.
            let v = [
                g.vx[i] + g.omega[i] * g.r[i] * nrm[1] - wall.velocity[0],
                g.vy[i] - g.omega[i] * g.r[i] * nrm[0] - wall.velocity[1],
            ];
            let vn = v[0] * nrm[0] + v[1] * nrm[1];
            let vt = -v[0] * nrm[1] + v[1] * nrm[0];
            let old = self
                .history
                .get(&(g.id[i], WALL_KEY | w as u64))
                .copied()
                .unwrap_or(0.0);
            let cn = self.model.damping_with(zeta, g.m[i]);
            let f = contact_force(&self.model, delta, vn, vt, cn, wall.friction, old, self.dt);
            out.push((w, nrm, f, delta));
        }
        out
    }
}

/// Rolling-resistance torque on the first body for relative rotation `omega_rel` (rad/s):
/// magnitude `limit` against the rotation, but no more than stops it within one step (so it
/// never reverses the rotation and chatters). `inv_inertia_sum` is 1/I₁ + 1/I₂.
fn rolling_torque(limit: f64, omega_rel: f64, inv_inertia_sum: f64, dt: f64) -> f64 {
    if omega_rel == 0.0 || inv_inertia_sum == 0.0 {
        return 0.0;
    }
    let stop = omega_rel.abs() / (inv_inertia_sum * dt);
    -limit.min(stop) * omega_rel.signum()
}

/// The history key of the pair (a, b) of grain ids, smaller id first, with `value`
/// (a stretch for body a) re-expressed for the smaller id as body 1.
fn oriented(a: u64, b: u64, value: f64) -> ((u64, u64), f64) {
    if a < b {
        ((a, b), value)
    } else {
        ((b, a), -value)
    }
}
