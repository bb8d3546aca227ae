//! Validation of `[grains]` + `[coupling]` in a fluid scene, and the grains part of a
//! coupled scene seen as a grains scene.

use super::context::Context;
use super::coupling::{MIN_CELLS_PER_DIAMETER, WARN_CELLS_PER_DIAMETER};
use super::grains::{GrainRun, GrainScene, GrainsSpec, SampleSpec};
use super::grains_check::{size_distribution, ValidGrainScene};
use super::output::{GrainDomain, Output};
use super::schema::{BoundarySpec, Scene};
use super::{SceneError, Units};

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
            domain: GrainDomain {
                size_m: None,
                cells: Some(d.cells),
                spacing_m: Some(d.spacing_m),
            },
            grains: spec.clone(),
            run: GrainRun {
                steps: None,
                end_time_s: Some(1.0),
                stop_below_kinetic_energy_j_m: 0.0,
            },
            output: Output::default(),
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
    let run_end_s = scene
        .run
        .end_time_s
        .or(scene.run.steps.map(|n| n as f64 * units.dt_s));
    super::gates::validate(spec, run_end_s, ctx)?;
    // A wall may overhang the domain by a grain radius or a cell (its ends are rounded in
    // the file); a bed that reaches further is not the domain's.
    let size = gs.scene.domain.size();
    let slack = radius_range(&spec.sample)
        .map_or(0.0, |r| r.1)
        .max(units.dx_m);
    let outside = |p: &[f64; 2]| (0..2).any(|k| p[k] < -slack || p[k] > size[k] + slack);
    if let Some((n, w)) = spec
        .walls
        .iter()
        .enumerate()
        .find(|(_, w)| outside(&w.from_m) || outside(&w.to_m))
    {
        return Err(ctx.err(
            if outside(&w.from_m) { "from_m" } else { "to_m" },
            n,
            format!(
                "wall `{}` ({:?}–{:?} m) reaches outside the fluid domain [0, 0]–{size:?} m, \
                 where no grain can be: shorten it, or enlarge the domain",
                w.name, w.from_m, w.to_m
            ),
        ));
    }
    if let SampleSpec::Pack { min_m, max_m, .. } = &spec.sample {
        let hi = gs.scene.domain.size();
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
    if let Some(k) = coupling.hydrodynamic_radius_ratio {
        if !(k > 0.0 && k <= 1.0) {
            return Err(ctx.err(
                "hydrodynamic_radius_ratio",
                0,
                format!("r_h / r must lie in (0, 1], got {k}"),
            ));
        }
    }
    if let Some(t) = coupling.rebalance_tolerance {
        if !(0.0..=10.0).contains(&t) {
            return Err(ctx.err(
                "rebalance_tolerance",
                0,
                format!(
                    "the tolerated imbalance must lie in [0, 10] (0.1: the busiest rank 10 % \
                     above the mean), got {t}"
                ),
            ));
        }
    }
    if let Some((rmin, _)) = radius_range(&spec.sample) {
        // The fluid sees the hydrodynamic radius.
        let cells = 2.0 * rmin * coupling.hydrodynamic_radius_ratio() / units.dx_m;
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
    if let Some(n) = coupling
        .substeps
        .filter(|&n| n > super::limits::MAX_SUBSTEPS)
    {
        return Err(ctx.err(
            "substeps",
            0,
            format!(
                "{n} DEM sub-steps per fluid step is more than grainflow runs ({}); the fluid \
                 step is too long for these contacts: refine the lattice or stiffen less",
                super::limits::MAX_SUBSTEPS
            ),
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
    warnings.extend(speed_warning(scene, spec, units));
    // The fluid's faces are walls for the grains too: the face gravity points to may be the
    // floor (or periodic: the grains then fall through it and come back).
    let g = spec.gravity_m_s2;
    let b = &scene.boundaries;
    let below = if g[1].abs() >= g[0].abs() {
        if g[1] < 0.0 {
            &b.south
        } else {
            &b.north
        }
    } else if g[0] < 0.0 {
        &b.west
    } else {
        &b.east
    };
    let floor_face = matches!(
        below,
        BoundarySpec::Wall
            | BoundarySpec::MovingWall { .. }
            | BoundarySpec::FreeSlip
            | BoundarySpec::Periodic
    );
    if !floor_face {
        warnings.extend(super::grains_check::no_floor(spec));
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

/// The speed the largest grain may reach (m/s): its terminal speed as a 2-D disk (White's
/// cylinder drag C_D = 1 + 10 Re^(−2/3), U_t = √(π g d (ρ_s/ρ − 1) / (2 C_D))), or free fall
/// under reduced gravity across the domain, √(2 g (1 − ρ/ρ_s) L), whichever is smaller;
/// and when a gate releases a packed mass of height H, at least the speed of its collapse,
/// √(g (1 − ρ/ρ_s) H) (the front's speed scale in column collapses, Lajeunesse, Monnier &
/// Homsy 2005; the mass and the liquid it drives move together, faster than one grain
/// settles). `None` without gravity or a known grain size.
pub fn grain_speed_estimate(scene: &Scene, spec: &GrainsSpec) -> Option<f64> {
    let g = spec.gravity_m_s2[0].hypot(spec.gravity_m_s2[1]);
    let (_, r) = radius_range(&spec.sample)?;
    if !(g > 0.0 && r > 0.0) {
        return None;
    }
    let (rho, rho_s, nu) = (
        scene.fluid.density_kg_m3,
        spec.density_kg_m3,
        scene.fluid.viscosity_m2_s,
    );
    let d = 2.0 * r;
    let mut u = 1e-6f64;
    for _ in 0..100 {
        let re = (u * d / nu).max(1e-9);
        let c_d = 1.0 + 10.0 * re.powf(-2.0 / 3.0);
        u = (std::f64::consts::PI * g * d * (rho_s / rho - 1.0) / (2.0 * c_d)).sqrt();
    }
    let dm = &scene.domain;
    let dir = [
        spec.gravity_m_s2[0].abs() / g,
        spec.gravity_m_s2[1].abs() / g,
    ];
    let length = (dm.cells[0] as f64 * dir[0] + dm.cells[1] as f64 * dir[1]) * dm.spacing_m;
    let reduced = g * (1.0 - rho / rho_s);
    let fall = (2.0 * reduced * length).sqrt();
    let gate = spec.walls.iter().any(|w| w.remove_at_s.is_some());
    let collapse = match (&spec.sample, gate) {
        (
            SampleSpec::Pack {
                min_m,
                max_m,
                settle,
                ..
            },
            true,
        ) => {
            let top = settle
                .as_ref()
                .and_then(|s| s.trim_above_m)
                .map_or(max_m[1], |t| t.min(max_m[1]));
            (reduced * (top - min_m[1]).max(0.0)).sqrt()
        }
        _ => 0.0,
    };
    Some(u.min(fall).max(collapse))
}

/// A warning when the grains may move faster than the reference velocity the lattice was
/// set for, by enough that the lattice Mach number passes 0.3 (the run stops as unstable
/// once a grain reaches the speed of sound, 1/√3 cells per step).
fn speed_warning(scene: &Scene, spec: &GrainsSpec, units: &Units) -> Option<String> {
    let u = grain_speed_estimate(scene, spec)?;
    let lattice = u * units.dt_s / units.dx_m;
    let mach = lattice * 3f64.sqrt();
    (mach > 0.3 && u > scene.fluid.reference_velocity_m_s).then(|| {
        format!(
            "the grains may reach about {u:.3e} m/s (terminal speed of the largest, free fall \
             across the domain, or a released mass collapsing), {lattice:.3} cells per step (Ma {mach:.2}), against \
             reference_velocity_m_s = {}: expect large compressibility errors{}; set \
             reference_velocity_m_s near {u:.2e}",
            scene.fluid.reference_velocity_m_s,
            if mach >= 1.0 {
                ", and the run to stop when a grain passes the speed of sound"
            } else {
                ""
            }
        )
    })
}
