//! Grain state, structure of arrays.

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
    /// Stable identity (survives reordering and, later, migration between ranks).
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
        (0..self.len())
            .map(|i| {
                let rot = if self.inv_inertia[i] > 0.0 {
                    0.5 * self.omega[i] * self.omega[i] / self.inv_inertia[i]
                } else {
                    0.0
                };
                0.5 * self.m[i] * (self.vx[i] * self.vx[i] + self.vy[i] * self.vy[i]) + rot
            })
            .sum()
    }

    /// Total momentum (kg m/s per m).
    pub fn momentum(&self) -> [f64; 2] {
        let mut p = [0.0; 2];
        for i in 0..self.len() {
            p[0] += self.m[i] * self.vx[i];
            p[1] += self.m[i] * self.vy[i];
        }
        p
    }
}
