//! Validation of `[[mpm.materials]]`: ranges of every constant, with the field named.

use super::context::{positive, Context};
use super::grains_check::non_negative;
use super::mpm::*;
use super::SceneError;
use mpm::mohr_coulomb::Softening;
use mpm::{InertialFriction, Material, Model, MohrCoulomb};

/// Where a value sits in the scene: its key and the occurrence of that key.
pub(super) type At<'a> = (&'a str, usize);

/// `v` must lie in `[lo, hi]`, or `[lo, hi)` when `open_hi`; `hint` explains the range.
pub(super) fn in_range(
    ctx: &Context,
    (key, nth): At,
    v: f64,
    (lo, hi, open_hi): (f64, f64, bool),
    hint: &str,
) -> Result<(), SceneError> {
    let ok = v.is_finite() && v >= lo && if open_hi { v < hi } else { v <= hi };
    if ok {
        Ok(())
    } else {
        let close = if open_hi { ")" } else { "]" };
        Err(ctx.err(
            key,
            nth,
            format!("must be in [{lo}, {hi}{close}{hint}, got {v}"),
        ))
    }
}

pub(super) fn material(ctx: &Context, n: usize, m: &MaterialSpec) -> Result<Material, SceneError> {
    let (density, e, nu) = match *m {
        MaterialSpec::LinearElastic {
            density_kg_m3,
            youngs_modulus_pa,
            poisson_ratio,
            ..
        }
        | MaterialSpec::MohrCoulomb {
            density_kg_m3,
            youngs_modulus_pa,
            poisson_ratio,
            ..
        } => (density_kg_m3, youngs_modulus_pa, poisson_ratio),
    };
    positive(ctx, "density_kg_m3", density, "the material density")?;
    positive(ctx, "youngs_modulus_pa", e, "Young's modulus")?;
    in_range(ctx, ("poisson_ratio", n), nu, (0.0, 0.5, true), "")?;
    let model = match *m {
        MaterialSpec::LinearElastic { .. } => Model::LinearElastic {
            youngs_modulus_pa: e,
            poisson_ratio: nu,
        },
        MaterialSpec::MohrCoulomb {
            friction_deg,
            dilation_deg,
            cohesion_pa,
            tension_cutoff_pa,
            softening,
            inertial_friction,
            ..
        } => {
            if !(friction_deg > 0.0 && friction_deg < 90.0) {
                return Err(ctx.err(
                    "friction_deg",
                    n,
                    format!("the friction angle must be in (0, 90) degrees, got {friction_deg}"),
                ));
            }
            in_range(
                ctx,
                ("dilation_deg", n),
                dilation_deg,
                (0.0, friction_deg, false),
                " (0 ≤ ψ ≤ φ)",
            )?;
            non_negative(ctx, "cohesion_pa", cohesion_pa)?;
            let apex = cohesion_pa / friction_deg.to_radians().tan();
            let cutoff = tension_cutoff_pa.unwrap_or(apex);
            in_range(
                ctx,
                ("tension_cutoff_pa", n),
                cutoff,
                (0.0, apex, false),
                " (at most the Mohr–Coulomb apex c cot φ)",
            )?;
            let softening = match softening {
                None => None,
                Some(s) => {
                    in_range(
                        ctx,
                        ("residual_friction_deg", n),
                        s.residual_friction_deg,
                        (0.0, friction_deg, false),
                        " (positive, at most the peak)",
                    )?;
                    if s.residual_friction_deg <= 0.0 {
                        return Err(ctx.err(
                            "residual_friction_deg",
                            n,
                            "the residual friction angle must be above 0",
                        ));
                    }
                    in_range(
                        ctx,
                        ("residual_cohesion_pa", n),
                        s.residual_cohesion_pa,
                        (0.0, cohesion_pa, false),
                        " (at most the peak cohesion)",
                    )?;
                    non_negative(ctx, "plastic_strain_start", s.plastic_strain_start)?;
                    if !(s.plastic_strain_end > s.plastic_strain_start) {
                        return Err(ctx.err(
                            "plastic_strain_end",
                            n,
                            format!(
                                "must exceed plastic_strain_start ({}), got {}",
                                s.plastic_strain_start, s.plastic_strain_end
                            ),
                        ));
                    }
                    Some(Softening {
                        residual_friction_deg: s.residual_friction_deg,
                        residual_cohesion_pa: s.residual_cohesion_pa,
                        plastic_strain_start: s.plastic_strain_start,
                        plastic_strain_end: s.plastic_strain_end,
                    })
                }
            };
            let inertial_friction = match inertial_friction {
                None => None,
                Some(r) => Some(inertial(ctx, n, r, friction_deg, density)?),
            };
            if inertial_friction.is_some() && softening.is_some() {
                return Err(ctx.err(
                    "inertial_friction",
                    n,
                    "cannot be combined with `softening` in one material: remove one of them",
                ));
            }
            Model::MohrCoulomb(MohrCoulomb {
                youngs_modulus_pa: e,
                poisson_ratio: nu,
                friction_deg,
                dilation_deg,
                cohesion_pa,
                tension_cutoff_pa: cutoff,
                softening,
                inertial_friction,
            })
        }
    };
    let separation_volume_ratio = match *m {
        MaterialSpec::MohrCoulomb {
            separation_volume_ratio: Some(r),
            ..
        } => {
            if !(r > 1.0 && r <= 10.0) {
                return Err(ctx.err(
                    "separation_volume_ratio",
                    n,
                    format!(
                        "must be in (1, 10] (about 1.1–1.5: loosest over initial packing), got {r}"
                    ),
                ));
            }
            r
        }
        _ => f64::INFINITY,
    };
    Ok(Material {
        density,
        model,
        separation_volume_ratio,
    })
}

/// Check a μ(I) block of material `n` whose static friction is `friction_deg` (deg) and
/// bulk density `density` (kg/m³).
fn inertial(
    ctx: &Context,
    n: usize,
    r: InertialFrictionSpec,
    friction_deg: f64,
    density: f64,
) -> Result<InertialFriction, SceneError> {
    // sin φ(I) = μ(I) reaches tan φ₂, which must stay below 1 (see `mpm::inertial`).
    if !(r.limit_friction_deg > friction_deg && r.limit_friction_deg < 45.0) {
        return Err(ctx.err(
            "limit_friction_deg",
            n,
            format!(
                "must lie above the static friction_deg ({friction_deg}) and below 45 \
                 (μ₂ = tan φ₂ is reached as sin φ), got {}",
                r.limit_friction_deg
            ),
        ));
    }
    positive(
        ctx,
        "reference_inertial_number",
        r.reference_inertial_number,
        "I₀ of the μ(I) law (glass beads: 0.279)",
    )?;
    positive(
        ctx,
        "grain_diameter_m",
        r.grain_diameter_m,
        "the grain diameter",
    )?;
    if !(r.grain_density_kg_m3.is_finite() && r.grain_density_kg_m3 >= density) {
        return Err(ctx.err(
            "grain_density_kg_m3",
            n,
            format!(
                "the density of the grains' solid must be at least the bulk density_kg_m3 \
                 ({density}), got {}",
                r.grain_density_kg_m3
            ),
        ));
    }
    Ok(InertialFriction {
        limit_friction: r.limit_friction_deg.to_radians().tan(),
        reference_inertial_number: r.reference_inertial_number,
        grain_diameter_m: r.grain_diameter_m,
        grain_density_kg_m3: r.grain_density_kg_m3,
    })
}
