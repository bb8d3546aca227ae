//! Validation of MPM scenes and their conversion to solver parameters and points.

use super::context::{positive, validate_checks, Context};
use super::grains::GrainAnalysis;
use super::grains_check::{non_negative, rectangle};
use super::mpm::*;
use super::mpm_material_check::{in_range, material};
use super::SceneError;
use mpm::{
    critical_dt, fill, GridSpec, Material, MpmSetup, Points, Shape, ShapeKind, Side, VelocityUpdate,
};
use std::path::{Path, PathBuf};

/// An MPM scene that passed validation, with its derived solver setup.
#[derive(Debug, Clone)]
pub struct ValidMpmScene {
    /// The parsed scene.
    pub scene: MpmScene,
    /// Solver parameters derived from the scene (the one place lattice-free MPM
    /// parameters are derived: grid size, materials, time step).
    pub setup: MpmSetup,
    /// The CFL limit h / c (s).
    pub critical_dt: f64,
    /// The material points of every body, ids in body order (filled once, here).
    pub points: Points,
    /// Non-fatal findings.
    pub warnings: Vec<String>,
    /// Path of the scene file.
    pub path: PathBuf,
}

/// Names of the results an MPM scene produces (what checks may refer to).
pub fn mpm_result_names(s: &MpmScene) -> Vec<String> {
    let mut names = Vec::new();
    for a in &s.analyses {
        let GrainAnalysis::ColumnCollapse {
            front_min_height_m, ..
        } = a;
        for q in crate::collapse_names::QUANTITIES {
            names.push(format!("collapse.{q}"));
        }
        if front_min_height_m.is_some() {
            for q in crate::collapse_names::THICK_QUANTITIES {
                names.push(format!("collapse.{q}"));
            }
        }
    }
    names
}

impl ValidMpmScene {
    /// The simulated time the scene runs (s): its `end_time_s`, or its `steps` times the
    /// time step.
    pub fn end_time_s(&self) -> f64 {
        let r = &self.scene.run;
        r.end_time_s
            .unwrap_or(r.steps.unwrap_or(0) as f64 * self.setup.dt)
    }
}

/// Parse and validate an MPM scene.
pub fn parse_mpm(text: &str, path: &Path) -> Result<ValidMpmScene, SceneError> {
    super::screen_raw(text, path)?;
    let scene: MpmScene = super::locate::strict(text, path)?;
    super::unknown::refuse_ignored(text, &scene, path)?;
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let ctx = Context {
        text,
        path,
        base_dir: &base_dir,
    };
    let (setup, critical_dt, warnings) = validate(&scene, &ctx)?;
    let points = build_points(&scene, &setup, &ctx)?;
    Ok(ValidMpmScene {
        scene,
        setup,
        critical_dt,
        points,
        warnings,
        path: path.to_owned(),
    })
}

/// Validate an MPM scene section by section; returns the solver's set-up, the CFL limit
/// h / c (s) and the warnings.
fn validate(s: &MpmScene, ctx: &Context) -> Result<(MpmSetup, f64, Vec<String>), SceneError> {
    let warnings = Vec::new();
    let m = &s.mpm;
    let (h, cells, size) = validate_grid(s, ctx)?;
    validate_transfer(m, ctx)?;
    validate_walls(&s.boundaries, ctx)?;
    let (materials, dt_cr, dt) = validate_materials(m, h, ctx)?;
    validate_bodies(m, size, ctx)?;
    validate_run_and_checks(s, ctx)?;
    let setup = MpmSetup {
        spec: GridSpec {
            nx: cells[0],
            ny: cells[1],
            h,
        },
        shape: m.shape_functions,
        scheme: m.update,
        boundaries: s.boundaries.sides(),
        gravity: m.gravity_m_s2,
        dt,
        damping: m.local_damping,
        velocity_update: match m.velocity_transfer {
            VelocityTransfer::Flip => VelocityUpdate::Flip {
                pic: m.pic_fraction,
            },
            VelocityTransfer::Apic => VelocityUpdate::Apic,
        },
        volumetric_averaging: m.volumetric_averaging,
        materials,
        side_walls: m.side_walls,
    };
    Ok((setup, dt_cr, warnings))
}

/// `[domain]`: the cell size and counts; returns h (m), the counts and the size (m).
fn validate_grid(s: &MpmScene, ctx: &Context) -> Result<(f64, [usize; 2], [f64; 2]), SceneError> {
    let d = &s.domain;
    if d.size_m.is_some() {
        return Err(ctx.err(
            "size_m",
            0,
            "an MPM grid is given by cells = [nx, ny] and spacing_m (size_m is for a fluid \
             scene whose relaxation_time and lattice_velocity fix the spacing, or a grains \
             scene)",
        ));
    }
    if d.cells == [0, 0] {
        return Err(ctx.err(
            "domain",
            0,
            "[domain] needs cells = [nx, ny] and spacing_m (the grid cell size h, m)",
        ));
    }
    positive(ctx, "spacing_m", d.spacing_m, "the cell size")?;
    let h = d.spacing_m;
    let cells = d.cells;
    if cells.iter().any(|&n| n < 2) {
        return Err(ctx.err(
            "cells",
            0,
            format!("the grid needs at least 2 cells along each axis, got {cells:?}"),
        ));
    }
    let size = [cells[0] as f64 * h, cells[1] as f64 * h];
    if cells[0].saturating_mul(cells[1]) > 400_000_000 {
        return Err(ctx.err(
            "cells",
            0,
            format!(
                "{} × {} cells is more than this build supports (4e8); use larger cells",
                cells[0], cells[1]
            ),
        ));
    }
    Ok((h, cells, size))
}

/// The velocity transfer, damping, side walls and gravity of `[mpm]`.
fn validate_transfer(m: &MpmSpec, ctx: &Context) -> Result<(), SceneError> {
    in_range(
        ctx,
        ("local_damping", 0),
        m.local_damping,
        (0.0, 1.0, true),
        "",
    )?;
    in_range(
        ctx,
        ("pic_fraction", 0),
        m.pic_fraction,
        (0.0, 1.0, false),
        "",
    )?;
    if m.velocity_transfer == VelocityTransfer::Apic && m.shape_functions == ShapeKind::Linear {
        return Err(ctx.err(
            "velocity_transfer",
            0,
            "\"apic\" needs GIMP shape functions (\"gimp\" or \"cp-gimp\"): with linear ones \
             the APIC matrix D vanishes when a point sits on a node",
        ));
    }
    if m.velocity_transfer == VelocityTransfer::Apic && m.pic_fraction != 0.0 {
        return Err(ctx.err(
            "pic_fraction",
            0,
            "is a FLIP setting: remove it with velocity_transfer = \"apic\"",
        ));
    }
    if let Some(w) = m.side_walls {
        if !(w.gap_m > 0.0 && w.gap_m.is_finite()) {
            return Err(ctx.err(
                "side_walls",
                0,
                format!(
                    "`gap_m` must be a positive distance between the walls (m), got {}",
                    w.gap_m
                ),
            ));
        }
        if !(w.friction >= 0.0 && w.friction.is_finite()) {
            return Err(ctx.err(
                "side_walls",
                0,
                format!(
                    "`friction` must be a Coulomb coefficient ≥ 0 (tan of the wall \
                     friction angle), got {}",
                    w.friction
                ),
            ));
        }
    }
    super::grains_check::bounded(
        ctx,
        "gravity_m_s2",
        &m.gravity_m_s2,
        super::limits::MAX_GRAVITY_M_S2,
    )?;
    Ok(())
}

/// The frictional faces of `[boundaries]`.
fn validate_walls(b: &MpmBoundaries, ctx: &Context) -> Result<(), SceneError> {
    for (name, side) in [
        ("west", b.west),
        ("east", b.east),
        ("south", b.south),
        ("north", b.north),
    ] {
        if let Side::Frictional { friction } = side {
            if !(friction.is_finite() && friction >= 0.0) {
                return Err(ctx.err(
                    name,
                    0,
                    format!(
                        "friction must be ≥ 0 (tan of the wall friction angle), got {friction}"
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// `[[mpm.materials]]` and `[mpm.time_step]`: the materials, the CFL limit h / c (s) and
/// the time step (s).
fn validate_materials(
    m: &MpmSpec,
    h: f64,
    ctx: &Context,
) -> Result<(Vec<Material>, f64, f64), SceneError> {
    if m.materials.is_empty() {
        return Err(ctx.err("materials", 0, "at least one [[mpm.materials]] is needed"));
    }
    let mut materials = Vec::new();
    for (n, spec) in m.materials.iter().enumerate() {
        if m.materials[..n].iter().any(|o| o.name() == spec.name()) {
            return Err(ctx.err(
                "name",
                n,
                format!("material name `{}` is used twice", spec.name()),
            ));
        }
        materials.push(material(ctx, n, spec)?);
    }
    let dt_cr = critical_dt(&materials, h);
    let dt = match m.time_step {
        MpmTimeStep::Courant { courant } => {
            if !(courant > 0.0 && courant <= 1.0) {
                return Err(ctx.err(
                    "courant",
                    0,
                    format!("the Courant number must be in (0, 1], got {courant}"),
                ));
            }
            courant * dt_cr
        }
        MpmTimeStep::Fixed { time_step_s } => {
            positive(ctx, "time_step_s", time_step_s, "the time step")?;
            if time_step_s > dt_cr {
                return Err(ctx.err("time_step_s", 0, format!(
                    "{time_step_s} s exceeds the CFL limit h / c = {dt_cr:.4e} s (c = {:.1} m/s, the fastest dilatational wave); use at most that, or kind = \"courant\"",
                    h / dt_cr)));
            }
            time_step_s
        }
    };
    Ok((materials, dt_cr, dt))
}

/// `[[mpm.bodies]]`: each names a material, has 1–6 points per cell and lies inside the
/// domain of `size` (m).
fn validate_bodies(m: &MpmSpec, size: [f64; 2], ctx: &Context) -> Result<(), SceneError> {
    if m.bodies.is_empty() {
        return Err(ctx.err("bodies", 0, "at least one [[mpm.bodies]] is needed"));
    }
    for (n, body) in m.bodies.iter().enumerate() {
        if !m.materials.iter().any(|x| x.name() == body.material) {
            let names: Vec<&str> = m.materials.iter().map(|x| x.name()).collect();
            return Err(ctx.err(
                "material",
                n,
                format!(
                    "unknown material `{}`; defined: {}",
                    body.material,
                    names.join(", ")
                ),
            ));
        }
        if !(1..=6).contains(&body.points_per_cell) {
            return Err(ctx.err(
                "points_per_cell",
                n,
                format!(
                    "must be 1 to 6 (n × n points per cell), got {}",
                    body.points_per_cell
                ),
            ));
        }
        super::grains_check::bounded(
            ctx,
            "velocity_m_s",
            &body.velocity_m_s,
            super::limits::MAX_SPEED_M_S,
        )?;
        let shape = body_shape(&body.shape);
        let (lo, hi) = shape.bounds();
        let inside = lo.iter().chain(&hi).all(|v| v.is_finite())
            && lo[0] >= 0.0
            && lo[1] >= 0.0
            && hi[0] <= size[0]
            && hi[1] <= size[1];
        let key = match body.shape {
            ShapeSpec::Rectangle { .. } => "min_m",
            ShapeSpec::Polygon { .. } => "vertices_m",
        };
        if !inside {
            return Err(ctx.err(
                key,
                n,
                format!("body {n} ({lo:?}–{hi:?} m) must lie inside the domain [0, 0]–{size:?} m"),
            ));
        }
        match &body.shape {
            ShapeSpec::Rectangle { min_m, max_m } => rectangle(ctx, "min_m", *min_m, *max_m)?,
            ShapeSpec::Polygon { vertices_m } if vertices_m.len() < 3 => {
                return Err(ctx.err("vertices_m", n, "a polygon needs at least 3 vertices"));
            }
            _ => {}
        }
        if let Some(InitialStress::Geostatic { surface_y_m, k0 }) = body.initial_stress {
            non_negative(ctx, "k0", k0)?;
            if !surface_y_m.is_finite() || surface_y_m < hi[1] - 1e-12 {
                return Err(ctx.err("surface_y_m", n, format!("the free surface ({surface_y_m} m) must be at or above the body's top ({} m)", hi[1])));
            }
        }
    }
    Ok(())
}

/// `[run]`, `[output]`, the analysis and the checks.
fn validate_run_and_checks(s: &MpmScene, ctx: &Context) -> Result<(), SceneError> {
    super::output::validate_length(s.run.steps, s.run.end_time_s, ctx)?;
    super::output::validate_output(&s.output, super::output::SceneKind::Mpm, ctx)?;
    non_negative(
        ctx,
        "stop_below_specific_kinetic_energy_j_kg",
        s.run.stop_below_specific_kinetic_energy_j_kg,
    )?;
    if s.analyses.len() > 1 {
        return Err(ctx.err("kind", 0, "at most one column-collapse analysis per scene"));
    }
    for a in &s.analyses {
        let GrainAnalysis::ColumnCollapse {
            front_min_height_m, ..
        } = a;
        if let Some(v) = *front_min_height_m {
            positive(
                ctx,
                "front_min_height_m",
                v,
                "the deposit thickness that marks the thick front",
            )?;
        }
    }
    validate_checks(&s.checks, ctx)?;
    let names = mpm_result_names(s);
    for (n, c) in s.checks.iter().enumerate() {
        if !names.contains(&c.quantity) {
            let known = if names.is_empty() {
                "nothing".to_string()
            } else {
                names.join(", ")
            };
            return Err(ctx.err(
                "quantity",
                n,
                format!(
                    "check on unknown quantity `{}`; this scene produces: {known}",
                    c.quantity
                ),
            ));
        }
    }
    Ok(())
}

/// The region of a body.
pub fn body_shape(s: &ShapeSpec) -> Shape {
    match s {
        ShapeSpec::Rectangle { min_m, max_m } => Shape::Rectangle {
            min: *min_m,
            max: *max_m,
        },
        ShapeSpec::Polygon { vertices_m } => Shape::Polygon(vertices_m.clone()),
    }
}

/// The material points of every body, ids in body order, with their initial velocity and
/// stress. Errors (naming the body) when a body holds no point or overlaps an earlier one.
fn build_points(scene: &MpmScene, setup: &MpmSetup, ctx: &Context) -> Result<Points, SceneError> {
    let m = &scene.mpm;
    let mut points = Points::default();
    let mut next_id = 0u64;
    let shapes: Vec<Shape> = m.bodies.iter().map(|b| body_shape(&b.shape)).collect();
    // At most the bodies' bounding boxes' cells times n² points each, before any is made.
    let h = setup.spec.h;
    let most: f64 = shapes
        .iter()
        .zip(&m.bodies)
        .map(|(s, b)| {
            let (lo, hi) = s.bounds();
            let n = b.points_per_cell as f64;
            ((hi[0] - lo[0]) / h + 1.0) * ((hi[1] - lo[1]) / h + 1.0) * n * n
        })
        .sum();
    if !(most <= super::limits::MAX_POINTS) {
        return Err(ctx.err(
            "points_per_cell",
            0,
            format!(
                "the bodies would hold up to {most:.3e} material points, more than grainflow \
                 fills ({:.0e}); use larger cells or fewer points per cell",
                super::limits::MAX_POINTS
            ),
        ));
    }
    for (n, body) in m.bodies.iter().enumerate() {
        let mat = m
            .materials
            .iter()
            .position(|x| x.name() == body.material)
            .unwrap_or(0);
        let density = setup.materials[mat].density;
        let start = points.len();
        let k = fill(
            &mut points,
            &shapes[n],
            &setup.spec,
            body.points_per_cell,
            density,
            mat as u16,
            &mut next_id,
        );
        let key = match body.shape {
            ShapeSpec::Rectangle { .. } => "min_m",
            ShapeSpec::Polygon { .. } => "vertices_m",
        };
        if k == 0 {
            return Err(ctx.err(key, n, format!("body {n} holds no material point: it is thinner than a cell's sub-square (h / points_per_cell = {} m)", setup.spec.h / body.points_per_cell as f64)));
        }
        for i in start..points.len() {
            if let Some(o) = shapes[..n].iter().position(|s| s.contains(points.pos[i])) {
                return Err(ctx.err(key, n, format!("body {n} overlaps body {o} at ({:.4}, {:.4}) m; bodies must not share material", points.pos[i][0], points.pos[i][1])));
            }
            points.vel[i] = body.velocity_m_s;
            if let Some(InitialStress::Geostatic { surface_y_m, k0 }) = body.initial_stress {
                // Geostatic stress: σ_yy = ρ g_y (y_s − y) (g_y < 0), σ_xx = σ_zz = K₀ σ_yy.
                let syy = density * m.gravity_m_s2[1] * (surface_y_m - points.pos[i][1]);
                points.stress[i] = [k0 * syy, syy, 0.0, k0 * syy];
            }
        }
    }
    Ok(points)
}
