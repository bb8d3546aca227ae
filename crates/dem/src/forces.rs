//! Contact forces of a [`DemSystem`]: every candidate pair in parallel, then every owned
//! grain gathers its own in an order fixed by ids, so the sums are the same at any thread
//! count, storage order and rank count.

use super::contact::contact_force;
use super::grains::Grains;
use super::system::{DemSystem, PairResult, WallHit, WALL_KEY};
use rayon::prelude::*;

impl DemSystem {
    /// Forces and torques on every owned grain at the current positions (velocities as
    /// they are, i.e. at the half step inside a step); then, with `kick = Some(h)`, each
    /// owned grain's velocities advanced by h (s) under them (a half kick, done in the same
    /// pass). Precondition: the Verlet list is current.
    pub(crate) fn compute_forces(&mut self, kick: Option<f64>) {
        let g = &self.grains;
        let (model, dt) = (&self.model, self.dt);
        let zeta = model.damping_ratio();
        let mu_r = model.rolling_friction;
        let mut results = std::mem::take(&mut self.pair_results);
        let (kn, kt) = (model.kn, model.kt);
        // Pass 1, per candidate (a, b), id(a) < id(b): the contact law with a as body 1.
        // The stretch is read and written in place.
        self.candidates
            .par_iter()
            .zip(self.stretch.par_iter_mut())
            .with_min_len(512)
            .map(|(&(a, b), xi)| -> PairResult {
                let (i, j) = (a as usize, b as usize);
                let (dx, dy) = (g.x[j] - g.x[i], g.y[j] - g.y[i]);
                let reach = g.r[i] + g.r[j];
                let d2 = dx * dx + dy * dy;
                if d2 >= reach * reach {
                    *xi = 0.0;
                    return [0.0; 5];
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
                let c = contact_force(model, delta, vn, vt, cn, model.friction, *xi, dt);
                *xi = c.stretch;
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
                let pf = [
                    c.fn_ * nrm[0] - c.ft * nrm[1],
                    c.fn_ * nrm[1] + c.ft * nrm[0],
                ];
                let elastic = 0.5 * kn * delta * delta + 0.5 * kt * c.stretch * c.stretch;
                // Friction turns both bodies the same way (−r F_t); the rolling torque acts
                // on a and, reversed, on b. A touching pair always stores energy > 0.
                [
                    pf[0],
                    pf[1],
                    -g.r[i] * c.ft + roll,
                    -g.r[j] * c.ft - roll,
                    elastic.max(f64::MIN_POSITIVE),
                ]
            })
            .collect_into_vec(&mut results);
        let mut wall_hits = std::mem::take(&mut self.wall_hits);
        let wall_owner = |k: usize| self.wall_start.partition_point(|&s| s as usize <= k) - 1;
        (0..self.wall_cand.len())
            .into_par_iter()
            .with_min_len(256)
            .map(|k| self.wall_contact(wall_owner(k), self.wall_cand[k] as usize, zeta))
            .collect_into_vec(&mut wall_hits);
        // Pass 2, per owned grain: gravity and global damping, its pair contacts by
        // increasing partner id, then its walls by index; then its half kick.
        let owned = self.owned;
        let Grains {
            fx,
            fy,
            torque,
            m,
            vx,
            vy,
            r,
            omega,
            inv_inertia,
            ..
        } = &mut self.grains;
        let (m, r, inv_inertia) = (&*m, &*r, &*inv_inertia);
        let (adj_start, adj) = (&self.adj_start, &self.adj);
        let wall_start = &self.wall_start;
        let (gravity, alpha) = (self.gravity, self.global_damping);
        let (results_ref, hits_ref) = (&results, &wall_hits);
        let external = &self.external;
        (
            fx[..owned].par_iter_mut(),
            fy[..owned].par_iter_mut(),
            torque[..owned].par_iter_mut(),
            vx[..owned].par_iter_mut(),
            vy[..owned].par_iter_mut(),
            omega[..owned].par_iter_mut(),
        )
            .into_par_iter()
            .enumerate()
            .with_min_len(1024)
            .for_each(|(i, (fxi, fyi, ti, vxi, vyi, wi))| {
                let mut f = [
                    m[i] * (gravity[0] - alpha * *vxi),
                    m[i] * (gravity[1] - alpha * *vyi),
                ];
                let mut t = 0.0;
                for &e in &adj[adj_start[i] as usize..adj_start[i + 1] as usize] {
                    let res = &results_ref[(e >> 1) as usize];
                    if res[4] == 0.0 {
                        continue;
                    }
                    // Body b (role 1) gets +F, body a −F.
                    if e & 1 == 1 {
                        f[0] += res[0];
                        f[1] += res[1];
                        t += res[3];
                    } else {
                        f[0] -= res[0];
                        f[1] -= res[1];
                        t += res[2];
                    }
                }
                let mine = &hits_ref[wall_start[i] as usize..wall_start[i + 1] as usize];
                for &(_, nrm, c, _) in mine.iter().flatten() {
                    f[0] += c.fn_ * nrm[0] - c.ft * nrm[1];
                    f[1] += c.fn_ * nrm[1] + c.ft * nrm[0];
                    t -= r[i] * c.ft;
                    if mu_r > 0.0 {
                        let limit = mu_r * r[i] * c.fn_.abs();
                        t += rolling_torque(limit, *wi, inv_inertia[i], dt);
                    }
                }
                if let Some(e) = external.get(i) {
                    f[0] += e[0];
                    f[1] += e[1];
                    t += e[2];
                }
                *fxi = f[0];
                *fyi = f[1];
                *ti = t;
                if let Some(h) = kick {
                    *vxi += h * f[0] / m[i];
                    *vyi += h * f[1] / m[i];
                    *wi += h * t * inv_inertia[i];
                }
            });
        let mut history = std::mem::take(&mut self.spare);
        history.clear();
        for i in 0..owned {
            let mine = &wall_hits[self.wall_start[i] as usize..self.wall_start[i + 1] as usize];
            for &(w, _, c, _) in mine.iter().flatten() {
                history.insert((self.grains.id[i], WALL_KEY | w as u64), c.stretch);
            }
        }
        self.spare = std::mem::replace(&mut self.history, history);
        // Keep the buffers for the next step (no allocation in the time loop).
        self.pair_results = results;
        self.wall_hits = wall_hits;
    }

    /// Contact of grain `i` with wall `w`, if they touch: (wall, normal from wall to
    /// grain, force, overlap).
    fn wall_contact(&self, i: usize, w: usize, zeta: f64) -> Option<WallHit> {
        let g = &self.grains;
        let wall = &self.walls[w];
        let c = wall.closest_point([g.x[i], g.y[i]]);
        let (dx, dy) = (g.x[i] - c[0], g.y[i] - c[1]);
        let dist = (dx * dx + dy * dy).sqrt();
        let delta = g.r[i] - dist;
        if !(delta > 0.0) || dist == 0.0 {
            return None;
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
        Some((w, nrm, f, delta))
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
