//! Permeability of a periodic array of fixed grains: Stokes flow driven by the fluid's body
//! acceleration, compared with the drag on square arrays of cylinders of Sangani & Acrivos
//! (1982).

use super::{err, AnalysisError, Inputs, Results};
use std::f64::consts::PI;

/// Sangani & Acrivos (1982), Table 1: the dimensionless drag K = F / (μ U) on each cylinder
/// of a square array against its solid fraction c (U the superficial velocity), from their
/// numerical solution.
pub const SANGANI_ACRIVOS_SQUARE: [(f64, f64); 9] = [
    (0.05, 15.56),
    (0.10, 24.83),
    (0.20, 51.53),
    (0.30, 102.90),
    (0.40, 217.89),
    (0.50, 532.55),
    (0.60, 1.763e3),
    (0.70, 1.352e4),
    (0.75, 1.263e5),
];

/// The drag K = F / (μ U) on each cylinder of a square array at solid fraction `c`: for
/// c < 0.05, Sangani & Acrivos' dilute expansion; from 0.05 to 0.75, their Table 1
/// ([`SANGANI_ACRIVOS_SQUARE`]) interpolated linearly in ln K; `None` beyond 0.75 (close
/// packing is π/4 ≈ 0.785).
pub fn sangani_acrivos_square(c: f64) -> Option<f64> {
    let t = &SANGANI_ACRIVOS_SQUARE;
    if c > 0.0 && c < t[0].0 {
        // Sangani & Acrivos 1982, dilute expansion for square arrays:
        // K = 4π / (−½ ln c − 0.738 + c − 0.887 c² + 2.038 c³).
        return Some(4.0 * PI / (-0.5 * c.ln() - 0.738 + c - 0.887 * c * c + 2.038 * c * c * c));
    }
    t.windows(2).find(|w| c >= w[0].0 && c <= w[1].0).map(|w| {
        let s = (c - w[0].0) / (w[1].0 - w[0].0);
        (w[0].1.ln() * (1.0 - s) + w[1].1.ln() * s).exp()
    })
}

/// From the final fields of a run whose fluid is driven through fixed grains by a uniform
/// body acceleration G (a stand-in for the pressure gradient −dp/dx = ρ G, which gives the
/// same velocity field):
/// - `permeability.superficial_velocity_m_s`: U, the flux along G over the whole domain
///   area A, grains included;
/// - `permeability.permeability_m2`: Darcy's k = ν U / |G|;
/// - `permeability.solid_fraction`: c = Σ π r_h² / A, with r_h the radius the fluid sees;
/// - `permeability.drag_factor`: K = F / (μ U) per grain, F = ρ |G| A / N by the force
///   balance;
/// - `permeability.sangani_acrivos_ratio`: K over [`sangani_acrivos_square`] at c (absent
///   beyond c = 0.75);
/// - `permeability.reynolds`: U (2 r_h) / ν of the largest grain (Stokes flow needs ≪ 1).
pub fn permeability(inp: &Inputs, r: &mut Results) -> Result<(), AnalysisError> {
    const NAME: &str = "permeability";
    let f = inp
        .fields
        .ok_or_else(|| err(NAME, "the run gathered no fields"))?;
    let sc = &inp.scene.scene;
    let g = sc.fluid.body_acceleration_m_s2;
    let g_abs = g[0].hypot(g[1]);
    if g_abs == 0.0 {
        return Err(err(NAME, "the fluid has no body acceleration to drive it"));
    }
    let ratio = sc
        .coupling
        .as_ref()
        .map(|c| c.hydrodynamic_radius_ratio())
        .ok_or_else(|| err(NAME, "the scene has no grains"))?;
    if inp.grain_radius.is_empty() {
        return Err(err(NAME, "the scene has no grains"));
    }
    let u = &inp.scene.units;
    let dir = [g[0] / g_abs, g[1] / g_abs];
    let (mut flux, mut mass, mut fluid) = (0.0, 0.0, 0usize);
    for k in 0..f.rho.len() {
        if f.fluid[k] {
            flux += f.rho[k] * (f.ux[k] * dir[0] + f.uy[k] * dir[1]);
            mass += f.rho[k];
            fluid += 1;
        }
    }
    let cells = (f.nx * f.ny) as f64;
    // Mass flux over the mean density: the volume flux through the whole domain.
    let u_lattice = flux / (mass / fluid as f64) / cells;
    let velocity = u.velocity_to_si(u_lattice);
    let area = cells * u.dx_m * u.dx_m;
    let n = inp.grain_radius.len() as f64;
    let radii = inp.grain_radius.iter().map(|(_, rc)| ratio * rc);
    let c = radii.clone().map(|rh| PI * rh * rh).sum::<f64>() / area;
    let r_max = radii.fold(0.0, f64::max);
    let nu = sc.fluid.viscosity_m2_s;
    let drag_factor = g_abs * area / (n * nu * velocity);
    r.insert(format!("{NAME}.superficial_velocity_m_s"), velocity);
    r.insert(format!("{NAME}.permeability_m2"), nu * velocity / g_abs);
    r.insert(format!("{NAME}.solid_fraction"), c);
    r.insert(format!("{NAME}.drag_factor"), drag_factor);
    if let Some(k_ref) = sangani_acrivos_square(c) {
        r.insert(format!("{NAME}.sangani_acrivos_ratio"), drag_factor / k_ref);
    }
    r.insert(format!("{NAME}.reynolds"), velocity * 2.0 * r_max / nu);
    Ok(())
}

/// The result names of a permeability analysis.
pub const QUANTITIES: [&str; 6] = [
    "superficial_velocity_m_s",
    "permeability_m2",
    "solid_fraction",
    "drag_factor",
    "sangani_acrivos_ratio",
    "reynolds",
];

#[cfg(test)]
mod tests {
    use super::sangani_acrivos_square;

    /// The dilute expansion meets the table at c = 0.05, the table's own points come back,
    /// and K grows with c.
    #[test]
    fn the_reference_is_continuous_and_grows() {
        let below = sangani_acrivos_square(0.05 - 1e-12).unwrap();
        assert!((below / 15.56 - 1.0).abs() < 2e-3, "{below}");
        assert!((sangani_acrivos_square(0.3).unwrap() / 102.9 - 1.0).abs() < 1e-12);
        let k: Vec<f64> = (1..75)
            .map(|i| sangani_acrivos_square(i as f64 * 0.01).unwrap())
            .collect();
        assert!(k.windows(2).all(|w| w[1] > w[0]), "{k:?}");
        assert_eq!(sangani_acrivos_square(0.76), None);
    }
}
