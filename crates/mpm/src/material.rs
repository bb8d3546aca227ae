//! Materials of material points: one enum, one stress update. The objective (Jaumann)
//! rotation is applied here, before the constitutive update, for every model, and so is the
//! rate-dependent friction angle of μ(I) (see [`super::inertial`]).

use super::mohr_coulomb::{MohrCoulomb, Prepared};

/// A material: its density, constitutive model and separation threshold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Density (kg/m³).
    pub density: f64,
    /// Constitutive model.
    pub model: Model,
    /// Volume ratio J = V/V₀ above which a point has lost contact with its neighbours and
    /// carries no stress until compressed back below it (a granular material below its
    /// loosest packing; Dunatunga & Kamrin 2015). `f64::INFINITY`: never.
    pub separation_volume_ratio: f64,
}

/// Constitutive models.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Model {
    /// Isotropic linear elasticity (plane strain).
    LinearElastic {
        /// Young's modulus (Pa).
        youngs_modulus_pa: f64,
        /// Poisson's ratio.
        poisson_ratio: f64,
    },
    /// Mohr–Coulomb elastoplasticity.
    MohrCoulomb(MohrCoulomb),
}

/// Lamé parameters (λ, G) in Pa from Young's modulus and Poisson's ratio.
pub fn lame(e: f64, nu: f64) -> (f64, f64) {
    // λ = Eν / ((1+ν)(1−2ν)), G = E / (2(1+ν)).
    (
        e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        e / (2.0 * (1.0 + nu)),
    )
}

impl Material {
    /// A linear elastic material that never separates: Young's modulus (Pa), Poisson's
    /// ratio (< ½) and density (kg/m³).
    pub fn linear_elastic(youngs_modulus_pa: f64, poisson_ratio: f64, density: f64) -> Self {
        Material {
            density,
            separation_volume_ratio: f64::INFINITY,
            model: Model::LinearElastic {
                youngs_modulus_pa,
                poisson_ratio,
            },
        }
    }

    /// Young's modulus and Poisson's ratio of the elastic part.
    pub fn elastic(&self) -> (f64, f64) {
        match self.model {
            Model::LinearElastic {
                youngs_modulus_pa,
                poisson_ratio,
            } => (youngs_modulus_pa, poisson_ratio),
            Model::MohrCoulomb(m) => (m.youngs_modulus_pa, m.poisson_ratio),
        }
    }

    /// P-wave (constrained) modulus λ + 2G (Pa).
    pub fn p_wave_modulus(&self) -> f64 {
        let (e, nu) = self.elastic();
        let (l, g) = lame(e, nu);
        l + 2.0 * g
    }

    /// Dilatational wave speed √((λ + 2G)/ρ) (m/s) at the initial density.
    pub fn wave_speed(&self) -> f64 {
        (self.p_wave_modulus() / self.density).sqrt()
    }

    /// The largest wave speed (m/s) of a stress-carrying point: at volume ratio J its
    /// density is ρ/J, so c √J; with separation, J is at most the separation ratio.
    pub fn max_wave_speed(&self) -> f64 {
        self.wave_speed() * self.separation_volume_ratio.max(1.0).sqrt()
    }

    /// Run constants of the material (see [`Material::update`]).
    pub fn prepare(&self) -> Prepared {
        match &self.model {
            Model::MohrCoulomb(mc) => mc.prepare(),
            Model::LinearElastic {
                youngs_modulus_pa,
                poisson_ratio,
            } => {
                let (lam, g) = lame(*youngs_modulus_pa, *poisson_ratio);
                Prepared {
                    lam,
                    g,
                    sin_phi: 0.0,
                    cos_phi: 1.0,
                    sin_psi: 0.0,
                }
            }
        }
    }

    /// Advance `stress` by the velocity gradient `l` = [∂vx/∂x, ∂vx/∂y, ∂vy/∂x, ∂vy/∂y]
    /// (1/s) over `dt` (s): Jaumann rotation, then the model's update with the strain
    /// increment sym(L) dt. Returns the strain increment [Δεxx, Δεyy, Δεxy] and whether
    /// the point yielded; `eps_p` accumulates plastic strain. `k` is [`Material::prepare`].
    #[inline]
    pub fn update(
        &self,
        k: &Prepared,
        stress: &mut [f64; 4],
        l: [f64; 4],
        dt: f64,
        eps_p: &mut f64,
    ) -> ([f64; 3], bool) {
        let d = [l[0] * dt, l[3] * dt, 0.5 * (l[1] + l[2]) * dt];
        // μ(I): the inertial number of the stress at the start of the step (explicit).
        let inertial = match &self.model {
            Model::MohrCoulomb(MohrCoulomb {
                inertial_friction: Some(r),
                ..
            }) => Some(r.inertial_number(l, stress)),
            _ => None,
        };
        // Jaumann: σ̇ = σ̊ + Wσ − σW, W_xy = ½(∂vx/∂y − ∂vy/∂x) (e.g. Belytschko et al. 2000, eq. 5.4.11).
        let w = 0.5 * (l[1] - l[2]) * dt;
        let [sxx, syy, sxy, _] = *stress;
        stress[0] += 2.0 * w * sxy;
        stress[1] -= 2.0 * w * sxy;
        stress[2] += w * (syy - sxx);
        let yielded = match &self.model {
            Model::LinearElastic { .. } => {
                let (lam, g) = (k.lam, k.g);
                let tr = d[0] + d[1];
                // Hooke, plane strain: Δσ = λ tr(Δε) I + 2G Δε, Δε_zz = 0.
                stress[0] += lam * tr + 2.0 * g * d[0];
                stress[1] += lam * tr + 2.0 * g * d[1];
                stress[2] += 2.0 * g * d[2];
                stress[3] += lam * tr;
                false
            }
            Model::MohrCoulomb(mc) => match (mc.inertial_friction, inertial) {
                (Some(r), Some(i)) => {
                    // sin φ(I) = μ(I) from the static sin φ (Jop, Forterre & Pouliquen 2006,
                    // eq. 4; sine: ψ = 0 plane-strain shear mobilises sin φ, see `inertial`).
                    // Without softening the return takes φ from `k` only.
                    let sin_phi = r.friction(k.sin_phi, i).min(1.0);
                    let cos_phi = (1.0 - sin_phi * sin_phi).sqrt();
                    let k = Prepared {
                        sin_phi,
                        cos_phi,
                        ..*k
                    };
                    mc.update_prepared(&k, stress, d, eps_p).yielded
                }
                _ => mc.update_prepared(k, stress, d, eps_p).yielded,
            },
        };
        (d, yielded)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_rotation_rotates_stress_without_straining() {
        // Uniaxial σxx = s rotated counter-clockwise by θ = Ω dt: σxy → s θ, σxx, σyy unchanged
        // to first order.
        let m = Material {
            density: 1000.0,
            separation_volume_ratio: f64::INFINITY,
            model: Model::LinearElastic {
                youngs_modulus_pa: 1e6,
                poisson_ratio: 0.3,
            },
        };
        let (omega, dt, s) = (2.0, 1e-4, -1000.0);
        let mut st = [s, 0.0, 0.0, 0.0];
        let mut ep = 0.0;
        let (d, _) = m.update(
            &m.prepare(),
            &mut st,
            [0.0, -omega, omega, 0.0],
            dt,
            &mut ep,
        );
        assert_eq!(d, [0.0, 0.0, 0.0]);
        assert!((st[2] - s * omega * dt).abs() < 1e-12, "{st:?}");
        assert_eq!(st[0], s);
    }

    #[test]
    fn plane_strain_hooke() {
        let m = Material {
            density: 1000.0,
            separation_volume_ratio: f64::INFINITY,
            model: Model::LinearElastic {
                youngs_modulus_pa: 1e6,
                poisson_ratio: 0.25,
            },
        };
        let mut st = [0.0; 4];
        let mut ep = 0.0;
        m.update(&m.prepare(), &mut st, [1e-3, 0.0, 0.0, 0.0], 1.0, &mut ep);
        // λ = 0.4 MPa, G = 0.4 MPa: σxx = (λ+2G) ε = 1200 Pa, σyy = σzz = λ ε = 400 Pa.
        assert!((st[0] - 1200.0).abs() < 1e-9 && (st[1] - 400.0).abs() < 1e-9);
        assert!((st[3] - 400.0).abs() < 1e-9 && st[2] == 0.0);
        assert!((m.wave_speed() - (1.2e6f64 / 1000.0).sqrt()).abs() < 1e-9);
    }

    #[test]
    fn inertial_friction_mobilises_the_friction_of_the_shear_rate() {
        // Simple shear u_x = γ̇ y of a cohesionless Mohr–Coulomb point with μ(I) (glass beads,
        // Jop et al. 2005: φ₂ = 32.76°, I₀ = 0.279, d = 1.15 mm, ρ_s = 2500 kg/m³). Once it
        // flows, every step ends on the yield surface of sin φ(I) = μ(I), with I from the
        // in-plane pressure at the start of the step (hand formula below), and the mobilised
        // angle grows with γ̇.
        let (phi_s, d, rho_s, i0) = (22.2f64, 1.15e-3, 2500.0, 0.279);
        let (mu_s, mu_2) = (phi_s.to_radians().sin(), 32.76f64.to_radians().tan());
        let m = Material {
            density: 1925.0,
            separation_volume_ratio: f64::INFINITY,
            model: Model::MohrCoulomb(MohrCoulomb {
                inertial_friction: Some(crate::InertialFriction {
                    limit_friction: mu_2,
                    reference_inertial_number: i0,
                    grain_diameter_m: d,
                    grain_density_kg_m3: rho_s,
                }),
                ..MohrCoulomb::cohesionless(1.98e6, 0.3, phi_s)
            }),
        };
        let k = m.prepare();
        let mut mobilised = Vec::new();
        for rate in [0.0, 20.0, 200.0] {
            let mut s = [-500.0, -500.0, 0.0, -500.0];
            let (mut ep, mut last) = (0.0, phi_s);
            // Rate 0: quasi-static, γ̇ = 1e-4 1/s in steps of 1 s (I ≈ 2.6e-7).
            let (l, dt) = if rate == 0.0 {
                ([0.0, 1e-4, 0.0, 0.0], 1.0)
            } else {
                ([0.0, rate, 0.0, 0.0], 1e-4 / rate)
            };
            let mut flowed = 0;
            for _ in 0..400 {
                let p = -0.5 * (s[0] + s[1]);
                let gamma = l[1];
                let i = gamma * d / (p / rho_s).sqrt();
                // Jop, Forterre & Pouliquen (2006), eq. 4.
                let phi = (mu_s + (mu_2 - mu_s) * i / (i0 + i)).asin().to_degrees();
                let (_, yielded) = m.update(&k, &mut s, l, dt, &mut ep);
                if yielded {
                    let f = MohrCoulomb::yield_value(&s, phi, 0.0);
                    assert!(
                        f.abs() <= 1e-9 * 500.0,
                        "rate {rate}: f = {f} at φ(I) = {phi}"
                    );
                    flowed += 1;
                    last = phi;
                }
            }
            assert!(flowed > 100, "rate {rate}: flowed {flowed} of 400 steps");
            mobilised.push(last);
        }
        // Quasi-static: the static angle (I ~ 1e-7); faster: higher, below asin μ₂ (40.0°).
        assert!((mobilised[0] - phi_s).abs() < 1e-3, "{mobilised:?}");
        assert!(mobilised[1] > phi_s + 1.0 && mobilised[2] > mobilised[1] + 1.0);
        assert!(mobilised[2] < mu_2.asin().to_degrees(), "{mobilised:?}");
    }
}
