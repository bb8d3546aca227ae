//! Rate-dependent friction of dense granular flow: the μ(I) law of Jop, Forterre &
//! Pouliquen (2006) applied to the Mohr–Coulomb friction angle.
//!
//! A rate-independent Mohr–Coulomb material has one friction whatever the shear rate. In a
//! dense granular flow the friction grows with the inertial number I = γ̇ d / √(P/ρ_s), the
//! ratio of the time a grain takes to fall into a hole under the pressure P to the time
//! the shear takes to move it by one grain (GDR MiDi 2004). The law
//! μ(I) = μ_s + (μ₂ − μ_s) I / (I₀ + I)
//! gives the ratio of shear to normal stress on the shear plane of a steady simple shear,
//! which is what inclined-plane experiments measure (tan θ of the slope, Jop et al. 2005).
//!
//! **Which Mohr–Coulomb angle carries μ(I).** A plane-strain Mohr–Coulomb material with
//! dilation angle ψ = 0 flows in steady simple shear with its principal axes at 45° to the
//! shear plane (the plastic strain rate is coaxial with the stress and isochoric). The shear
//! plane is then the plane of largest shear stress, where τ/σ_n = sin φ, not tan φ (the
//! ψ = 0 case of Davis 1968's sin φ cos ψ / (1 − sin φ sin ψ); Vermeer & de Borst 1984).
//! So the law sets sin φ(I) = μ(I), with the static μ_s = sin φ of the scene's friction
//! angle, and P is the normal stress on the shear plane, the in-plane mean −(σxx + σyy)/2
//! (the out-of-plane σzz of plane strain does not press on it). Setting tan φ(I) = μ(I)
//! instead, as an earlier version did, lets a layer flow steadily on a slope of only
//! atan(sin φ(I)): on a 25° incline its steady I is twice Bagnold's, and a layer started on
//! Bagnold's profile runs 45 % past its surface speed within 0.3 s
//! (`tests/mpm_inertial_flow.rs`).
//!
//! The law is evaluated explicitly, from the point's stress at the start of the step and
//! the step's velocity gradient; the return mapping then uses the friction angle of that I.

/// Parameters of the μ(I) law for one material (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InertialFriction {
    /// Friction coefficient μ₂ = tan φ₂ approached at high inertial number (–), above the
    /// static μ_s = sin φ and below 1 (sin φ(I) = μ(I) must stay a sine).
    pub limit_friction: f64,
    /// I₀ (–): the inertial number at which half of μ₂ − μ_s is mobilised.
    pub reference_inertial_number: f64,
    /// Mean grain diameter d (m).
    pub grain_diameter_m: f64,
    /// Density of the grains' solid ρ_s (kg/m³), not the bulk density.
    pub grain_density_kg_m3: f64,
}

impl InertialFriction {
    /// Shear rate γ̇ = √(2 D′:D′) (1/s) of the velocity gradient `l` = [∂vx/∂x, ∂vx/∂y,
    /// ∂vy/∂x, ∂vy/∂y] (1/s) in plane strain (D_zz = 0); γ̇ is the rate of simple shear
    /// u_x = γ̇ y (Jop et al. 2006, |γ̇| = √(½ γ̇_ij γ̇_ij) with γ̇_ij = 2 D′_ij).
    #[inline]
    pub fn shear_rate(l: [f64; 4]) -> f64 {
        let tr3 = (l[0] + l[3]) / 3.0;
        let (dxx, dyy, dzz) = (l[0] - tr3, l[3] - tr3, -tr3);
        let dxy = 0.5 * (l[1] + l[2]);
        (2.0 * (dxx * dxx + dyy * dyy + dzz * dzz + 2.0 * dxy * dxy)).sqrt()
    }

    /// Inertial number I = γ̇ d / √(P / ρ_s) (GDR MiDi 2004) of a point with velocity
    /// gradient `l` (1/s) and stress `stress` = [σxx, σyy, σxy, σzz] (Pa, tension positive),
    /// P = −(σxx + σyy)/2, the normal stress on the plane of largest in-plane shear stress
    /// (see the module docs). A point without pressure (P ≤ 0) has I = ∞ (no contacts hold
    /// it); a point at rest under pressure has I = 0.
    #[inline]
    pub fn inertial_number(&self, l: [f64; 4], stress: &[f64; 4]) -> f64 {
        let p = -0.5 * (stress[0] + stress[1]);
        let rate = Self::shear_rate(l);
        if rate == 0.0 {
            return 0.0;
        }
        if p <= 0.0 {
            return f64::INFINITY;
        }
        rate * self.grain_diameter_m / (p / self.grain_density_kg_m3).sqrt()
    }

    /// Friction coefficient μ(I) = μ_s + (μ₂ − μ_s) I / (I₀ + I) (Jop, Forterre &
    /// Pouliquen 2006, eq. 4) for the static friction `mu_s` (–) and inertial number `i`
    /// (–, may be ∞). The caller takes it as sin φ(I) (see the module docs).
    #[inline]
    pub fn friction(&self, mu_s: f64, i: f64) -> f64 {
        if i.is_infinite() {
            return self.limit_friction;
        }
        mu_s + (self.limit_friction - mu_s) * i / (self.reference_inertial_number + i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn beads() -> InertialFriction {
        // Glass beads, Jop, Forterre & Pouliquen (2005): μ₂ = tan 32.76°, I₀ = 0.279.
        InertialFriction {
            limit_friction: 32.76f64.to_radians().tan(),
            reference_inertial_number: 0.279,
            grain_diameter_m: 1.15e-3,
            grain_density_kg_m3: 2500.0,
        }
    }

    #[test]
    fn shear_rate_of_simple_shear_and_of_pure_shear() {
        // u_x = γ̇ y: γ̇.
        assert!((InertialFriction::shear_rate([0.0, 3.0, 0.0, 0.0]) - 3.0).abs() < 1e-14);
        // Pure shear ε̇xx = −ε̇yy = e is simple shear at γ̇ = 2e rotated by 45°.
        assert!((InertialFriction::shear_rate([1.5, 0.0, 0.0, -1.5]) - 3.0).abs() < 1e-14);
        // Rigid rotation and isotropic expansion do not shear (in the plane; the
        // plane-strain constraint D_zz = 0 makes a planar expansion deviatoric).
        assert_eq!(InertialFriction::shear_rate([0.0, 2.0, -2.0, 0.0]), 0.0);
    }

    #[test]
    fn inertial_number_and_friction_follow_the_law() {
        let m = beads();
        // γ̇ = 100 1/s, P = 250 Pa: I = 100 · 1.15e-3 / √(0.1) = 0.3637. σzz does not count.
        let i = m.inertial_number([0.0, 100.0, 0.0, 0.0], &[-200.0, -300.0, 0.0, -900.0]);
        assert!((i - 0.115 / 0.1f64.sqrt()).abs() < 1e-12, "{i}");
        let mu_s = 22.2f64.to_radians().sin();
        let mu = m.friction(mu_s, i);
        let expect = mu_s + (m.limit_friction - mu_s) / (0.279 / i + 1.0);
        assert!((mu - expect).abs() < 1e-14);
        // Limits: static at rest, μ₂ without pressure, half way at I = I₀.
        assert_eq!(m.friction(mu_s, 0.0), mu_s);
        assert_eq!(m.friction(mu_s, f64::INFINITY), m.limit_friction);
        let half = m.friction(mu_s, 0.279);
        assert!((half - 0.5 * (mu_s + m.limit_friction)).abs() < 1e-14);
        assert_eq!(m.inertial_number([0.0; 4], &[-1.0, -1.0, 0.0, -1.0]), 0.0);
        assert!(m
            .inertial_number([0.0, 1.0, 0.0, 0.0], &[0.0; 4])
            .is_infinite());
    }
}
