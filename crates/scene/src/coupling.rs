//! The `[coupling]` table of a fluid scene with `[grains]`, and its validation.

use super::grains::{GrainRun, GrainScene, GrainsSpec, Region, SampleSpec};
use super::grains_check::{size_distribution, ValidGrainScene};
use super::schema::{BoundarySpec, Scene};
use super::validate::Context;
use super::{SceneError, Units};
use serde::{Deserialize, Serialize};

/// How the fluid and the grains exchange momentum.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CouplingSpec {
    /// The interface scheme: `"bounce-back"` (Ladd), `"interpolated"` (Bouzidi) or `"psm"`
    /// (Noble–Torczynski partially saturated cells).
    pub scheme: coupling::Scheme,
    /// How a cell a grain uncovers is refilled (bounce-back schemes): `"equilibrium"`
    /// (default) or `"extrapolation"`.
    #[serde(default)]
    pub refill: coupling::Refill,
    /// DEM sub-steps per fluid step; default ⌊Δt/Δt_D⌋ + 1 (seed eq. 5.61).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub substeps: Option<u32>,
    /// Hold the average of the last two steps' hydrodynamic forces (Ladd 1994) instead of
    /// the last one: damps the oscillation that makes explicit coupling unstable for light
    /// grains. Default: on for `bounce-back`, off for the others.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_averaging: Option<bool>,
    /// Short-range repulsion between grains, and between grains and walls, that stops them
    /// touching where the lattice no longer resolves the gap (Glowinski et al. 2001); off
    /// when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repulsion: Option<RepulsionSpec>,
}

/// Glowinski et al. (2001) short-range repulsion: F = s · W · ((r_i + r_j + ζ − d)/ζ)² along
/// the line of centres for gaps below ζ, with W the lighter grain's submerged weight.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RepulsionSpec {
    /// Range ζ (m): the gap below which it acts (typically one or two lattice cells).
    pub range_m: f64,
    /// Strength s: the force at touching, in submerged weights.
    pub strength: f64,
}

/// The grains part of a coupled scene as a grains scene over the fluid domain (so the
/// DEM's own validation and sample preparation apply unchanged).
pub fn grain_scene(
    scene: &Scene,
    spec: &GrainsSpec,
    base_dir: &std::path::Path,
    path: &std::path::Path,
) -> ValidGrainScene {
    let d = &scene.domain;
    ValidGrainScene {
        scene: GrainScene {
            title: scene.title.clone(),
            region: Region {
                min_m: [0.0, 0.0],
                max_m: [
                    d.cells[0] as f64 * d.spacing_m,
                    d.cells[1] as f64 * d.spacing_m,
                ],
            },
            grains: spec.clone(),
            run: GrainRun {
                end_time_s: 1.0,
                output_every_s: 0.0,
                pictures: false,
                stop_below_kinetic_energy_j_m: 0.0,
                checkpoint_every: 0,
                checkpoint_at_end: false,
            },
            analyses: Vec::new(),
            checks: Vec::new(),
        },
        warnings: Vec::new(),
        base_dir: base_dir.to_owned(),
        path: path.to_owned(),
    }
}

/// Radius range (m) of a sample, when the scene alone says it (not for CSV files).
pub fn radius_range(sample: &SampleSpec) -> Option<(f64, f64)> {
    match sample {
        SampleSpec::Pack { sizes, .. } => {
            let d = size_distribution(sizes);
            Some((d.min_radius(), d.max_radius()))
        }
        SampleSpec::List { grains } => Some(grains.iter().fold((f64::INFINITY, 0.0), |a, g| {
            (a.0.min(g.radius_m), a.1.max(g.radius_m))
        })),
        SampleSpec::Csv { .. } => None,
    }
}

pub use coupling::MIN_CELLS_PER_DIAMETER;
/// Cells per diameter below which `check` warns that the drag is under-resolved.
pub const WARN_CELLS_PER_DIAMETER: f64 = 8.0;

/// Validate `[grains]` + `[coupling]` of a fluid scene. Returns warnings.
pub(super) fn validate(
    scene: &Scene,
    units: &Units,
    ctx: &Context,
) -> Result<Vec<String>, SceneError> {
    let mut warnings = Vec::new();
    let (spec, coupling) =
        match (&scene.grains, &scene.coupling) {
            (None, None) => return Ok(warnings),
            (Some(_), None) => {
                return Err(ctx.err(
                    "grains",
                    0,
                    "a scene with [fluid] and [grains] runs coupled: add a [coupling] table with \
                 scheme = \"bounce-back\", \"interpolated\" or \"psm\"",
                ))
            }
            (None, Some(_)) => return Err(ctx.err(
                "coupling",
                0,
                "[coupling] needs grains to couple: add a [grains] table, or remove [coupling] \
                 for a fluid-only run",
            )),
            (Some(g), Some(c)) => (g, c),
        };
    let rho_f = scene.fluid.density_kg_m3;
    if !(spec.density_kg_m3 > rho_f) {
        return Err(ctx.err(
            "density_kg_m3",
            1,
            format!(
                "the grain density ({} kg/m³) must exceed the fluid's ({rho_f} kg/m³): \
                 neutrally buoyant and light grains are not supported",
                spec.density_kg_m3
            ),
        ));
    }
    let gs = grain_scene(scene, spec, ctx.base_dir, ctx.path);
    warnings.extend(super::grains_check::validate(&gs.scene, ctx)?);
    warnings.retain(|w| !w.contains("output_every_s"));
    if let SampleSpec::Pack { min_m, max_m, .. } = &spec.sample {
        let hi = gs.scene.region.max_m;
        if min_m[0] < 0.0 || min_m[1] < 0.0 || max_m[0] > hi[0] || max_m[1] > hi[1] {
            return Err(ctx.err(
                "min_m",
                0,
                format!(
                    "the packing rectangle {min_m:?}–{max_m:?} reaches outside the fluid \
                     domain [0, 0]–{hi:?}; move it inside"
                ),
            ));
        }
    }
    if let Some((rmin, _)) = radius_range(&spec.sample) {
        let cells = 2.0 * rmin / units.dx_m;
        if cells < MIN_CELLS_PER_DIAMETER {
            return Err(ctx.err(
                "sample",
                0,
                format!(
                    "the smallest grain is {cells:.2} cells across; the coupling needs at least \
                     {MIN_CELLS_PER_DIAMETER}: refine the lattice (spacing_m) or use larger grains"
                ),
            ));
        }
        if cells < WARN_CELLS_PER_DIAMETER {
            warnings.push(format!(
                "the smallest grain is {cells:.1} cells across (below {WARN_CELLS_PER_DIAMETER}): \
                 its drag is under-resolved"
            ));
        }
    }
    if coupling.substeps == Some(0) {
        return Err(ctx.err(
            "substeps",
            0,
            "must be at least 1 DEM sub-step per fluid step",
        ));
    }
    if let Some(r) = &coupling.repulsion {
        if !(r.range_m > 0.0 && r.range_m.is_finite()) {
            return Err(ctx.err(
                "range_m",
                0,
                format!("must be a positive length, got {}", r.range_m),
            ));
        }
        if !(r.strength > 0.0 && r.strength.is_finite()) {
            return Err(ctx.err(
                "strength",
                0,
                format!("must be positive, got {}", r.strength),
            ));
        }
    }
    if !scene.obstacles.is_empty() {
        warnings.push(
            "grains do not collide with obstacles (only with [[grains.walls]] and the fluid's \
             wall faces): keep them apart"
                .into(),
        );
    }
    let b = &scene.boundaries;
    if [&b.west, &b.east, &b.south, &b.north].iter().any(|f| {
        matches!(
            f,
            BoundarySpec::Velocity { .. } | BoundarySpec::Pressure { .. } | BoundarySpec::Outflow
        )
    }) {
        warnings.push(
            "grains must stay at least two cells away from open (velocity, pressure, outflow) \
             faces; a grain that reaches the domain's edge stops the run"
                .into(),
        );
    }
    Ok(warnings)
}
