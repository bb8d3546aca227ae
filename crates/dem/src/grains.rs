//! Grain state, structure of arrays.

use decomposition::PackRows;

/// The grains of one rank: every per-grain quantity in its own array, index-aligned.
#[derive(Debug, Clone, Default)]
pub struct Grains {
    /// Centre x (m).
    pub x: Vec<f64>,
    /// Centre y (m).
    pub y: Vec<f64>,
    /// Velocity x (m/s).
    pub vx: Vec<f64>,
    /// Velocity y (m/s).
    pub vy: Vec<f64>,
    /// Angle (rad, counter-clockwise).
    pub theta: Vec<f64>,
    /// Angular velocity (rad/s).
    pub omega: Vec<f64>,
    /// Radius (m).
    pub r: Vec<f64>,
    /// Mass per metre of depth (kg/m).
    pub m: Vec<f64>,
    /// 1 / moment of inertia (0 for a grain whose rotation is locked).
    pub inv_inertia: Vec<f64>,
    /// Force x of the last evaluation (N/m).
    pub fx: Vec<f64>,
    /// Force y of the last evaluation (N/m).
    pub fy: Vec<f64>,
    /// Torque of the last evaluation (N).
    pub torque: Vec<f64>,
    /// Stable identity, unique over all ranks (survives reordering and migration). Contact
    /// pairs are oriented and forces summed by id, which makes results independent of the
    /// storage order, the thread count and the rank count.
    pub id: Vec<u64>,
}

impl Grains {
    /// Number of grains.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True when there are no grains.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Add a disk of radius `r` (m) and density `rho` (kg/m³) at rest at `pos` (m); its
    /// rotation is locked when `lock_rotation` (a sliding block). Returns its index.
    pub fn push(&mut self, pos: [f64; 2], r: f64, rho: f64, lock_rotation: bool) -> usize {
        let m = rho * std::f64::consts::PI * r * r;
        // Disk: I = ½ m r².
        let inv_i = if lock_rotation {
            0.0
        } else {
            1.0 / (0.5 * m * r * r)
        };
        let id = self.len() as u64;
        self.x.push(pos[0]);
        self.y.push(pos[1]);
        self.vx.push(0.0);
        self.vy.push(0.0);
        self.theta.push(0.0);
        self.omega.push(0.0);
        self.r.push(r);
        self.m.push(m);
        self.inv_inertia.push(inv_i);
        self.fx.push(0.0);
        self.fy.push(0.0);
        self.torque.push(0.0);
        self.id.push(id);
        self.len() - 1
    }

    /// Kinetic energy, translational plus rotational (J/m).
    pub fn kinetic_energy(&self) -> f64 {
        self.kinetic_energy_of(self.len())
    }

    /// Kinetic energy of the first `n` grains (J/m).
    pub fn kinetic_energy_of(&self, n: usize) -> f64 {
        (0..n).map(|i| self.kinetic_energy_of_grain(i)).sum()
    }

    /// Kinetic energy of grain `i`, translational plus rotational (J/m).
    pub fn kinetic_energy_of_grain(&self, i: usize) -> f64 {
        let rot = if self.inv_inertia[i] > 0.0 {
            0.5 * self.omega[i] * self.omega[i] / self.inv_inertia[i]
        } else {
            0.0
        };
        0.5 * self.m[i] * (self.vx[i] * self.vx[i] + self.vy[i] * self.vy[i]) + rot
    }

    /// Reorder the first `order.len()` grains so that new grain k is old grain `order[k]`;
    /// the rest keep their places. Precondition: `order` is a permutation of
    /// `0..order.len()`.
    pub fn permute_prefix(&mut self, order: &[u32]) {
        fn apply<T: Copy>(v: &mut [T], order: &[u32], tmp: &mut Vec<T>) {
            tmp.clear();
            tmp.extend(order.iter().map(|&o| v[o as usize]));
            v[..order.len()].copy_from_slice(tmp);
        }
        let mut t = Vec::with_capacity(order.len());
        for v in self.reals_mut() {
            apply(v, order, &mut t);
        }
        apply(&mut self.id, order, &mut Vec::with_capacity(order.len()));
    }

    /// Keep the first `n` grains.
    pub fn truncate(&mut self, n: usize) {
        for v in self.reals_mut() {
            v.truncate(n);
        }
        self.id.truncate(n);
    }

    /// Keep grain i where `keep[i]`, in order (`keep` covers every grain).
    pub fn retain(&mut self, keep: &[bool]) {
        for v in self.reals_mut() {
            let mut k = keep.iter();
            v.retain(|_| *k.next().unwrap_or(&true));
        }
        let mut k = keep.iter();
        self.id.retain(|_| *k.next().unwrap_or(&true));
    }

    /// Every f64 array: the packed ones in [`PackRows::pack_row`] order, then fx, fy, torque.
    fn reals_mut(&mut self) -> [&mut Vec<f64>; 12] {
        [
            &mut self.x,
            &mut self.y,
            &mut self.vx,
            &mut self.vy,
            &mut self.theta,
            &mut self.omega,
            &mut self.r,
            &mut self.m,
            &mut self.inv_inertia,
            &mut self.fx,
            &mut self.fy,
            &mut self.torque,
        ]
    }

    /// Total momentum (kg m/s per m).
    pub fn momentum(&self) -> [f64; 2] {
        self.momentum_of(self.len())
    }

    /// Momentum of the first `n` grains (kg m/s per m).
    pub fn momentum_of(&self, n: usize) -> [f64; 2] {
        let mut p = [0.0; 2];
        for i in 0..n {
            p[0] += self.m[i] * self.vx[i];
            p[1] += self.m[i] * self.vy[i];
        }
        p
    }
}

/// A grain travels (migration, ghosts, checkpoints) as 10 words: everything but the forces,
/// which are recomputed after a move; the id as its bit pattern.
impl PackRows for Grains {
    const WORDS: usize = 10;

    fn pack_row(&self, i: usize, out: &mut Vec<f64>) {
        out.extend_from_slice(&[
            self.x[i],
            self.y[i],
            self.vx[i],
            self.vy[i],
            self.theta[i],
            self.omega[i],
            self.r[i],
            self.m[i],
            self.inv_inertia[i],
            f64::from_bits(self.id[i]),
        ]);
    }

    /// Forces zero.
    fn push_row(&mut self, p: &[f64]) {
        // reals_mut: the 9 packed values in order, then the three forces.
        for (k, v) in self.reals_mut().into_iter().enumerate() {
            v.push(if k < Self::WORDS - 1 { p[k] } else { 0.0 });
        }
        self.id.push(p[9].to_bits());
    }
}
