//! Contact laws: linear spring–dashpot normal force with damping from a coefficient of
//! restitution, Cundall–Strack tangential spring with Coulomb friction.

use thiserror::Error;

/// Why a DEM system cannot be built or advanced.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum DemError {
    /// The time step exceeds the stable limit of eq. 5.59–5.60.
    #[error("DEM time step {dt:e} s exceeds λ·Δt_cr = {limit:e} s (Δt_cr = 2(√(1+ξ²) − ξ)/ω of the lightest grain, λ = {lambda}); use a time step ≤ {limit:e} s, softer contacts or heavier grains")]
    TimeStepTooLarge {
        /// Requested step (s).
        dt: f64,
        /// λ Δt_cr (s).
        limit: f64,
        /// λ used.
        lambda: f64,
    },
    /// Two grains overlap in the input.
    #[error("grains {a} and {b} overlap by {overlap:e} m in the input; move them apart or allow overlaps")]
    Overlap {
        /// First grain id.
        a: u64,
        /// Second grain id.
        b: u64,
        /// Overlap (m).
        overlap: f64,
    },
    /// A grain file could not be read.
    #[error("{path}:{line}: {message}")]
    Input {
        /// File.
        path: String,
        /// 1-based line (0: the whole file).
        line: usize,
        /// What is wrong and what to do.
        message: String,
    },
    /// A parameter is out of range.
    #[error("DEM parameter `{name}` = {value}: {why}")]
    Parameter {
        /// Parameter name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What is allowed.
        why: &'static str,
    },
}

/// Contact parameters shared by all grain pairs (and, with the wall's own friction, walls).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactModel {
    /// Normal stiffness k_n (N/m per m of depth).
    pub kn: f64,
    /// Tangential stiffness k_t (N/m per m of depth).
    pub kt: f64,
    /// Coefficient of restitution e in (0, 1].
    pub restitution: f64,
    /// Coulomb friction coefficient μ between grains.
    pub friction: f64,
    /// Rolling friction coefficient μ_r: a torque μ_r R* |F_n| against the relative
    /// rotation (R* = r_i r_j / (r_i + r_j), r for a wall), never reversing it within a step
    /// (constant directional torque, Ai et al. 2011, model A). 0 switches it off.
    pub rolling_friction: f64,
    /// Tangential dashpot as a fraction β of the normal one: c_t = β c_n (0 = none, the
    /// default; LAMMPS's `gran/hooke/history` commonly uses γ_t = γ_n / 2).
    pub tangential_damping: f64,
}

impl ContactModel {
    /// Check the ranges: k > 0, 0 < e ≤ 1, μ ≥ 0.
    pub fn validate(&self) -> Result<(), DemError> {
        let bad = |name, value, why| Err(DemError::Parameter { name, value, why });
        if !(self.kn > 0.0) {
            return bad("kn", self.kn, "must be > 0");
        }
        if !(self.kt >= 0.0) {
            return bad("kt", self.kt, "must be ≥ 0");
        }
        if !(self.restitution > 0.0 && self.restitution <= 1.0) {
            return bad("restitution", self.restitution, "must be in (0, 1]");
        }
        if !(self.friction >= 0.0) {
            return bad("friction", self.friction, "must be ≥ 0");
        }
        if !(self.rolling_friction >= 0.0) {
            return bad("rolling_friction", self.rolling_friction, "must be ≥ 0");
        }
        if !(0.0..=1.0).contains(&self.tangential_damping) {
            return bad(
                "tangential_damping",
                self.tangential_damping,
                "must be in [0, 1]",
            );
        }
        Ok(())
    }

    /// Damping ratio ζ = −ln e / √(π² + ln² e) that gives restitution e for a linear
    /// spring–dashpot (e = exp(−ζπ/√(1 − ζ²))).
    pub fn damping_ratio(&self) -> f64 {
        let l = self.restitution.ln();
        -l / (std::f64::consts::PI * std::f64::consts::PI + l * l).sqrt()
    }

    /// Normal damping coefficient c_n = 2ζ√(m* k_n) for effective mass m* (kg/m).
    pub fn damping(&self, m_eff: f64) -> f64 {
        self.damping_with(self.damping_ratio(), m_eff)
    }

    /// c_n for a precomputed damping ratio ζ (saves a logarithm per contact).
    #[inline]
    pub fn damping_with(&self, zeta: f64, m_eff: f64) -> f64 {
        2.0 * zeta * (m_eff * self.kn).sqrt()
    }

    /// Critical time step of the lightest mass `m_min`: Δt_cr = 2(√(1+ξ²) − ξ)/ω with
    /// ω = √(k/m) and ξ = c/(2mω) (seed eq. 5.59, He et al. 1997). The stiffer of k_n and
    /// k_t sets ω.
    pub fn critical_time_step(&self, m_min: f64) -> f64 {
        let k = self.kn.max(self.kt);
        let omega = (k / m_min).sqrt();
        let xi = self.damping(m_min) / (2.0 * m_min * omega);
        2.0 * ((1.0 + xi * xi).sqrt() - xi) / omega
    }
}

/// The state of one contact that the next step needs: the tangential spring stretch ξ
/// (m) along the contact tangent (in 2-D a scalar, so it follows the tangent as it turns).
pub type History = f64;

/// Force of one contact on its second body (the first gets the opposite force), in the
/// contact frame, and the updated tangential stretch.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactForce {
    /// Normal force along n (N/m), from body 1 to body 2.
    pub fn_: f64,
    /// Tangential force along t = (−n_y, n_x) (N/m).
    pub ft: f64,
    /// Updated stretch.
    pub stretch: History,
}

/// The contact law for overlap `delta` (m), normal relative velocity `vn` (m/s, negative
/// when approaching), tangential relative velocity `vt`, normal damping `cn` (from
/// [`ContactModel::damping`]), friction `mu`, previous stretch `stretch`, over `dt` (s).
/// Normal: F_n = k_n δ − c_n v_n (seed eq. 5.58 plus the dashpot); tangential: ξ += v_t Δt,
/// F_t = −k_t ξ − c_t v_t capped at μ|F_n| (Cundall & Strack 1979), the spring reset on sliding.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn contact_force(
    model: &ContactModel,
    delta: f64,
    vn: f64,
    vt: f64,
    cn: f64,
    mu: f64,
    stretch: History,
    dt: f64,
) -> ContactForce {
    let fn_ = model.kn * delta - cn * vn;
    let mut xi = stretch + vt * dt;
    // Spring plus the optional tangential dashpot c_t = β c_n.
    let ct = model.tangential_damping * cn;
    let mut ft = -model.kt * xi - ct * vt;
    let limit = mu * fn_.abs();
    if ft.abs() > limit {
        // Sliding: the force sits on the Coulomb limit and the spring keeps the part of it
        // the dashpot does not carry (Cundall & Strack 1979; as LAMMPS gran/hooke/history).
        ft = limit * ft.signum();
        xi = if model.kt > 0.0 {
            -(ft + ct * vt) / model.kt
        } else {
            0.0
        };
    }
    ContactForce {
        fn_,
        ft,
        stretch: xi,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn damping_ratio_reproduces_restitution() {
        for e in [0.1, 0.5, 0.9, 1.0] {
            let m = ContactModel {
                kn: 1e5,
                kt: 0.0,
                restitution: e,
                friction: 0.0,
                rolling_friction: 0.0,
                tangential_damping: 0.0,
            };
            let z = m.damping_ratio();
            let back = (-z * std::f64::consts::PI / (1.0 - z * z).sqrt()).exp();
            assert!((back - e).abs() < 1e-12, "{e} -> {back}");
        }
    }

    #[test]
    fn friction_caps_the_tangential_force() {
        let m = ContactModel {
            kn: 1e4,
            kt: 1e4,
            restitution: 1.0,
            friction: 0.5,
            rolling_friction: 0.0,
            tangential_damping: 0.0,
        };
        let c = contact_force(&m, 1e-3, 0.0, 1.0, m.damping(1.0), 0.5, 0.0, 1e-3);
        assert!((c.fn_ - 10.0).abs() < 1e-12);
        assert!((c.ft + 5.0).abs() < 1e-12, "{}", c.ft);
        assert!((c.stretch - 5e-4).abs() < 1e-15);
    }

    /// The tangential dashpot adds −c_t v_t with c_t = β c_n; when sliding, the spring keeps
    /// the part of the Coulomb force the dashpot does not carry.
    #[test]
    fn tangential_dashpot_adds_and_sliding_keeps_the_limit() {
        let m = ContactModel {
            kn: 1e4,
            kt: 1e4,
            restitution: 0.5,
            friction: 0.5,
            rolling_friction: 0.0,
            tangential_damping: 0.5,
        };
        let cn = m.damping(1.0);
        let ct = 0.5 * cn;
        // Sticking: overlap 1e-3 (F_n = 10 N/m), small tangential slip.
        let (vt, dt) = (1e-3, 1e-4);
        let c = contact_force(&m, 1e-3, 0.0, vt, cn, 0.5, 0.0, dt);
        let xi = vt * dt;
        assert!((c.ft - (-m.kt * xi - ct * vt)).abs() < 1e-12, "{}", c.ft);
        assert!((c.stretch - xi).abs() < 1e-18);
        // Sliding: the total sits on μ F_n, spring + dashpot make it up.
        let c = contact_force(&m, 1e-3, 0.0, 10.0, cn, 0.5, 0.0, 1e-3);
        assert!((c.ft + 5.0).abs() < 1e-12, "{}", c.ft);
        assert!((-m.kt * c.stretch - ct * 10.0 - c.ft).abs() < 1e-9);
    }
}
