//! What a coupled scene will do, known before it runs (for `grainflow check`): grain size
//! in cells, the DEM time step and the sub-steps per fluid step.

use crate::error::RunError;
use coupling::Scheme;
use dem::{load_csv, Grains};
use scene::coupling_check::{grain_scene, radius_range};
use scene::{SampleSpec, ValidScene};

/// The coupling parameters a scene implies.
#[derive(Debug, Clone, PartialEq)]
pub struct CouplingPlan {
    /// Interface scheme.
    pub scheme: Scheme,
    /// Grain count, when the scene lists them (list or CSV samples).
    pub grains: Option<usize>,
    /// Smallest and largest grain diameter, in lattice cells.
    pub cells_per_diameter: (f64, f64),
    /// DEM time step Δt_D = λ Δt_cr of the lightest grain, or the fixed one (s; seed
    /// eqs. 5.59–5.60).
    pub dem_time_step_s: f64,
    /// DEM sub-steps per fluid step, n_s = ⌊Δt/Δt_D⌋ + 1 (seed eq. 5.61) unless the scene
    /// sets it.
    pub substeps: u32,
    /// Whether the force of two steps is averaged.
    pub force_averaging: bool,
    /// The DEM step actually taken (Δt / n_s) as a fraction of the lightest grain's
    /// critical step: the effective λ of seed eq. 5.60.
    pub dem_lambda: f64,
}

/// The plan of a coupled scene; `None` for a fluid-only scene.
pub fn plan(scene: &ValidScene) -> Result<Option<CouplingPlan>, RunError> {
    let s = &scene.scene;
    let (Some(spec), Some(c)) = (&s.grains, &s.coupling) else {
        return Ok(None);
    };
    let gs = grain_scene(s, spec, &scene.base_dir, &scene.path);
    let (count, (rmin, rmax)) = match &spec.sample {
        SampleSpec::Csv { file } => {
            let g = load_csv(&scene.base_dir.join(file), spec.density_kg_m3)?;
            let lo = g.r.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = g.r.iter().cloned().fold(0.0, f64::max);
            (Some(g.len()), (lo, hi))
        }
        SampleSpec::List { grains } => (
            Some(grains.len()),
            radius_range(&spec.sample).expect("listed"),
        ),
        SampleSpec::Pack { .. } => (None, radius_range(&spec.sample).expect("sized")),
    };
    let mut lightest = Grains::default();
    lightest.push([0.0, 0.0], rmin, spec.density_kg_m3, false);
    let dt_d = gs.time_step(&lightest);
    let substeps = c
        .substeps
        .unwrap_or_else(|| (scene.units.dt_s / dt_d).floor() as u32 + 1);
    let dt_cr = dem::stable_time_step(&lightest, &gs.contact_model(), 1.0);
    Ok(Some(CouplingPlan {
        dem_lambda: scene.units.dt_s / substeps as f64 / dt_cr,
        scheme: c.scheme,
        grains: count,
        cells_per_diameter: {
            // The fluid sees the hydrodynamic radius.
            let k = c.hydrodynamic_radius_ratio() * 2.0 / scene.units.dx_m;
            (k * rmin, k * rmax)
        },
        dem_time_step_s: dt_d,
        substeps,
        force_averaging: c.force_averaging.unwrap_or(c.scheme == Scheme::BounceBack),
    }))
}
