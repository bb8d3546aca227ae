//! Strict validation of a parsed scene: every impossible value is an error that names the
//! key, its line and the fix.

use super::context::{positive, Context};
use super::schema::*;
use super::SceneError;
use lbm::units::{derive, TimeStepChoice, Units};

/// Validate and derive units. Returns the warnings.
pub(crate) fn validate(s: &Scene, ctx: &Context) -> Result<(Units, Vec<String>), SceneError> {
    validate_lattice(s, ctx)?;
    let units = validate_units(s, ctx)?;
    validate_initial(s, &units, ctx)?;
    let mut warnings = stability_warnings(&s.fluid, &units);
    validate_operator(&s.fluid, ctx)?;
    validate_boundaries(s, ctx)?;
    validate_obstacles(s, ctx)?;
    validate_run(s, ctx, &units)?;
    // The run's end (s): as given, or its steps times the derived time step.
    let run_end_s = s
        .run
        .end_time_s
        .unwrap_or(s.run.steps.unwrap_or(0) as f64 * units.dt_s);
    super::probes_check::validate_probes_and_analyses(s, ctx, run_end_s)?;
    warnings.extend(super::coupling_check::validate(s, &units, ctx)?);
    Ok((units, warnings))
}

/// `[domain]`: at least 2 × 2 cells, no more than any machine holds, a positive spacing.
fn validate_lattice(s: &Scene, ctx: &Context) -> Result<(), SceneError> {
    let [nx, ny] = s.domain.cells;
    if nx < 2 || ny < 2 {
        return Err(ctx.err(
            "cells",
            0,
            format!("the lattice needs at least 2 × 2 cells, got {nx} × {ny}"),
        ));
    }
    if super::limits::cell_count([nx.saturating_add(2), ny.saturating_add(2)]).is_none() {
        return Err(ctx.err(
            "cells",
            0,
            format!(
                "{nx} × {ny} cells is more than any machine holds (at most {} cells); use a \
                 coarser spacing_m",
                super::limits::MAX_CELLS
            ),
        ));
    }
    positive(ctx, "spacing_m", s.domain.spacing_m, "the lattice spacing")?;
    Ok(())
}

/// `[fluid]`'s density, viscosity, reference velocity and length: each a positive number.
pub(crate) fn fluid_figures(f: &Fluid, ctx: &Context) -> Result<(), SceneError> {
    positive(ctx, "density_kg_m3", f.density_kg_m3, "the density")?;
    positive(
        ctx,
        "viscosity_m2_s",
        f.viscosity_m2_s,
        "the kinematic viscosity",
    )?;
    positive(
        ctx,
        "reference_velocity_m_s",
        f.reference_velocity_m_s,
        "the reference velocity",
    )?;
    positive(
        ctx,
        "reference_length_m",
        f.reference_length_m,
        "the reference length",
    )
}

/// `[fluid]`'s physical figures and its one time-step choice; returns the derived lattice
/// units (τ > ½, Ma < 0.3 unless allowed).
fn validate_units(s: &Scene, ctx: &Context) -> Result<Units, SceneError> {
    let f = &s.fluid;
    fluid_figures(f, ctx)?;
    let choices = [
        ("time_step_s", f.time_step_s.map(TimeStepChoice::TimeStep)),
        (
            "lattice_velocity",
            f.lattice_velocity.map(TimeStepChoice::LatticeVelocity),
        ),
        (
            "relaxation_time",
            f.relaxation_time.map(TimeStepChoice::RelaxationTime),
        ),
    ];
    let mut given: Vec<_> = choices.iter().filter(|c| c.1.is_some()).collect();
    // With size_m, τ and u_lb together fixed the spacing (domain.rs): τ sets Δt.
    if s.domain.size_m.is_some() && given.len() == 2 {
        given.retain(|c| c.0 == "relaxation_time");
    }
    if given.len() != 1 {
        return Err(ctx.err(
            "fluid",
            0,
            format!(
                "set exactly one of time_step_s, lattice_velocity or relaxation_time in [fluid] (found {}), or relaxation_time and lattice_velocity together with [domain] size_m = [width, height] instead of cells and spacing_m",
                given.len()
            ),
        ));
    }
    let (dt_key, choice) = (given[0].0, given[0].1.expect("filtered"));
    let v = match choice {
        TimeStepChoice::TimeStep(v)
        | TimeStepChoice::LatticeVelocity(v)
        | TimeStepChoice::RelaxationTime(v) => v,
    };
    positive(ctx, dt_key, v, dt_key)?;
    let units = derive(
        s.domain.spacing_m,
        f.density_kg_m3,
        f.viscosity_m2_s,
        f.reference_velocity_m_s,
        f.reference_length_m,
        choice,
    );
    if units.tau <= 0.5 {
        return Err(ctx.err(
            dt_key,
            0,
            format!(
                "relaxation time τ = {:.6} ≤ ½ is unstable (τ = 3νΔt/Δx² + ½); increase the time step, coarsen spacing_m or raise viscosity_m2_s so that τ > 0.5 (0.51–2 is typical)",
                units.tau
            ),
        ));
    }
    if units.mach >= 0.3 && !f.allow_high_mach {
        return Err(ctx.err(
            dt_key,
            0,
            format!(
                "Mach number {:.3} ≥ 0.3: compressibility errors (∝ Ma²) dominate; reduce the time step or lattice_velocity, or set allow_high_mach = true",
                units.mach
            ),
        ));
    }
    Ok(units)
}

/// `[fluid.initial]`: an initial speed the lattice can carry.
fn validate_initial(s: &Scene, units: &Units, ctx: &Context) -> Result<(), SceneError> {
    let f = &s.fluid;
    let initial = match f.initial {
        Initial::Rest => None,
        Initial::Uniform { velocity_m_s } => {
            Some(("velocity_m_s", velocity_m_s[0].hypot(velocity_m_s[1])))
        }
        Initial::TaylorGreen { amplitude_m_s } => Some(("amplitude_m_s", amplitude_m_s.abs())),
    };
    if let Some((key, speed)) = initial {
        // Ma = |u_lb| √3, with u_lb = u Δt/Δx.
        let ma = units.velocity_to_lattice(speed) * 3f64.sqrt();
        if ma >= 1.0 || (ma >= 0.3 && !f.allow_high_mach) {
            return Err(ctx.err(
                key,
                0,
                format!(
                    "the initial speed {speed} m/s is Mach {ma:.3} on this lattice (≥ {}): the \
                     run cannot stay stable; lower it, or shorten the time step",
                    if ma >= 1.0 {
                        "1"
                    } else {
                        "0.3; allow_high_mach lifts this"
                    }
                ),
            ));
        }
    }
    Ok(())
}

/// Warnings on the Mach number and on τ near ½, by operator.
fn stability_warnings(f: &Fluid, units: &Units) -> Vec<String> {
    let mut warnings = Vec::new();
    if units.mach > 0.1 {
        warnings.push(format!(
            "Mach number {:.3} > 0.1: expect compressibility errors of order Ma² = {:.1e}",
            units.mach,
            units.mach * units.mach
        ));
    }
    if units.tau < 0.51 {
        let advice = match f.collision {
            CollisionModel::Bgk => "BGK may go unstable; consider TRT or MRT",
            CollisionModel::Trt { .. } => "TRT may go unstable; consider MRT or a longer τ",
            CollisionModel::Mrt { .. } => "MRT may go unstable; consider a longer τ",
        };
        warnings.push(format!("τ = {:.4} is close to ½: {advice}", units.tau));
    }
    warnings
}

/// The collision operator's parameters, Smagorinsky's constant and the body force.
fn validate_operator(f: &Fluid, ctx: &Context) -> Result<(), SceneError> {
    match &f.collision {
        CollisionModel::Bgk => {}
        CollisionModel::Trt { magic } => {
            positive(ctx, "magic", *magic, "the TRT magic parameter Λ")?
        }
        CollisionModel::Mrt { s_e, s_eps, s_q } => {
            for (k, v) in [("s_e", Some(*s_e)), ("s_eps", Some(*s_eps)), ("s_q", *s_q)] {
                if let Some(v) = v {
                    if !(v > 0.0 && v < 2.0) {
                        return Err(ctx.err(
                            k,
                            0,
                            format!("MRT relaxation rates must lie in (0, 2), got {v}"),
                        ));
                    }
                }
            }
        }
    }
    if let Some(c) = f.smagorinsky_constant {
        if !(c > 0.0 && c < 1.0) {
            return Err(ctx.err(
                "smagorinsky_constant",
                0,
                format!("C_s must lie in (0, 1) (typically 0.1–0.17), got {c}"),
            ));
        }
    }
    for v in f.body_acceleration_m_s2 {
        if !v.is_finite() {
            return Err(ctx.err("body_acceleration_m_s2", 0, "must be finite"));
        }
    }
    Ok(())
}

fn validate_boundaries(s: &Scene, ctx: &Context) -> Result<(), SceneError> {
    let b = &s.boundaries;
    for (a, b_, an, bn) in [
        (&b.west, &b.east, "west", "east"),
        (&b.south, &b.north, "south", "north"),
    ] {
        let (pa, pb) = (*a == BoundarySpec::Periodic, *b_ == BoundarySpec::Periodic);
        if pa != pb {
            let key = if pa { an } else { bn };
            return Err(ctx.err(key, 0, format!("periodic boundaries come in pairs: make both {an} and {bn} periodic, or neither")));
        }
    }
    for (spec, name, normal) in [
        (&b.west, "west", 0),
        (&b.east, "east", 0),
        (&b.south, "south", 1),
        (&b.north, "north", 1),
    ] {
        if let BoundarySpec::MovingWall { velocity_m_s } = spec {
            if velocity_m_s[normal] != 0.0 {
                return Err(ctx.err(
                    name,
                    0,
                    "a moving wall must move tangentially: set its normal velocity component to 0",
                ));
            }
        }
        if let BoundarySpec::Velocity { ramp_time_s, .. } = spec {
            if !(ramp_time_s.is_finite() && *ramp_time_s >= 0.0) {
                return Err(ctx.err(
                    "ramp_time_s",
                    0,
                    format!("ramp_time_s must be ≥ 0 s, got {ramp_time_s}"),
                ));
            }
        }
        if let BoundarySpec::Velocity { velocity_m_s, .. }
        | BoundarySpec::MovingWall { velocity_m_s } = spec
        {
            let speed = velocity_m_s[0].hypot(velocity_m_s[1]);
            if !speed.is_finite() || speed > 1.5 * s.fluid.reference_velocity_m_s + 1e-12 {
                return Err(ctx.err(
                    name,
                    0,
                    format!(
                        "boundary speed {speed} m/s exceeds 1.5 × reference_velocity_m_s; raise reference_velocity_m_s so the Mach check sees it"
                    ),
                ));
            }
        }
    }
    Ok(())
}

fn validate_obstacles(s: &Scene, ctx: &Context) -> Result<(), SceneError> {
    let lx = s.domain.cells[0] as f64 * s.domain.spacing_m;
    let ly = s.domain.cells[1] as f64 * s.domain.spacing_m;
    let eps = 1e-9 * lx.max(ly);
    for (n, o) in s.obstacles.iter().enumerate() {
        if s.obstacles[..n].iter().any(|p| p.name() == o.name()) {
            return Err(ctx.err(
                "name",
                n,
                format!(
                    "obstacle name `{}` is used twice; names must be unique",
                    o.name()
                ),
            ));
        }
        let pts: Vec<[f64; 2]> = match o {
            Obstacle::Rectangle { min_m, max_m, .. } => {
                if !(max_m[0] > min_m[0] && max_m[1] > min_m[1]) {
                    return Err(ctx.err(
                        "max_m",
                        nth_key(s, n, "max_m"),
                        "max_m must exceed min_m in both x and y",
                    ));
                }
                vec![*min_m, *max_m]
            }
            Obstacle::Circle {
                centre_m,
                radius_m,
                wall,
                ..
            } => {
                positive(ctx, "radius_m", *radius_m, "the radius")?;
                if s.grains.is_some() && *wall == Some(CircleWall::Interpolated) {
                    return Err(ctx.err(
                        "wall",
                        nth_key(s, n, "wall"),
                        "wall = \"interpolated\" is for scenes without grains (the coupling \
                         owns the curved links of a coupled run): leave `wall` out for a \
                         staircased obstacle, or make the cylinder a grain held in place \
                         ([[grains.sample]] with fixed = true, [coupling] scheme = \
                         \"interpolated\")",
                    ));
                }
                let r = *radius_m;
                vec![
                    [centre_m[0] - r, centre_m[1] - r],
                    [centre_m[0] + r, centre_m[1] + r],
                ]
            }
            Obstacle::Polygon { vertices_m, .. } => {
                if vertices_m.len() < 3 {
                    return Err(ctx.err(
                        "vertices_m",
                        nth_key(s, n, "vertices_m"),
                        "a polygon needs at least 3 vertices",
                    ));
                }
                vertices_m.clone()
            }
            Obstacle::Mask { image, .. } => {
                let p = ctx.base_dir.join(image);
                if !p.is_file() {
                    return Err(ctx.err(
                        "image",
                        nth_key(s, n, "image"),
                        format!("mask image {} does not exist", p.display()),
                    ));
                }
                vec![]
            }
        };
        for p in pts {
            if !(p[0] >= -eps && p[0] <= lx + eps && p[1] >= -eps && p[1] <= ly + eps) {
                return Err(ctx.err(
                    "name",
                    n,
                    format!(
                        "obstacle `{}` extends outside the domain [0, {lx}] × [0, {ly}] m (point ({}, {})); move or shrink it",
                        o.name(),
                        p[0],
                        p[1]
                    ),
                ));
            }
        }
        if let Obstacle::Circle {
            centre_m,
            radius_m,
            wall,
            ..
        } = o
        {
            if s.grains.is_none() && *wall != Some(CircleWall::Staircase) {
                curved_clearance(s, ctx, n, o.name(), *centre_m, *radius_m)?;
            }
        }
    }
    Ok(())
}

/// A curved circle (obstacle `n`) keeps at least one cell from every face that is not a
/// wall: across a periodic, open or free-slip face the lattice reads the cells inside the
/// circle (which stay fluid cells for the sweep) as fluid.
fn curved_clearance(
    s: &Scene,
    ctx: &Context,
    n: usize,
    name: &str,
    centre: [f64; 2],
    r: f64,
) -> Result<(), SceneError> {
    let dx = s.domain.spacing_m;
    let (lx, ly) = (s.domain.cells[0] as f64 * dx, s.domain.cells[1] as f64 * dx);
    let b = &s.boundaries;
    let faces = [
        ("west", &b.west, centre[0] - r),
        ("east", &b.east, lx - centre[0] - r),
        ("south", &b.south, centre[1] - r),
        ("north", &b.north, ly - centre[1] - r),
    ];
    for (face, spec, gap) in faces {
        let wall = matches!(spec, BoundarySpec::Wall | BoundarySpec::MovingWall { .. });
        if !wall && gap < dx {
            return Err(ctx.err(
                "name",
                n,
                format!(
                    "circle `{name}` has a curved wall and comes within {gap:.3e} m of the \
                     {face} face, which is not a wall: keep it at least one cell ({dx} m) \
                     away, or give it wall = \"staircase\""
                ),
            ));
        }
    }
    Ok(())
}

/// Occurrence index of `key` belonging to obstacle `n` (counts that key in earlier obstacles).
fn nth_key(s: &Scene, n: usize, key: &str) -> usize {
    s.obstacles[..n]
        .iter()
        .filter(|o| match key {
            "max_m" => matches!(o, Obstacle::Rectangle { .. }),
            "vertices_m" => matches!(o, Obstacle::Polygon { .. }),
            "image" => matches!(o, Obstacle::Mask { .. }),
            "wall" => matches!(o, Obstacle::Circle { wall: Some(_), .. }),
            _ => false,
        })
        .count()
}

fn validate_run(s: &Scene, ctx: &Context, units: &Units) -> Result<(), SceneError> {
    let r = &s.run;
    match (r.steps, r.end_time_s) {
        (Some(0), None) => return Err(ctx.err("steps", 0, "steps must be at least 1")),
        (Some(_), None) => {}
        (None, Some(t)) => {
            positive(ctx, "end_time_s", t, "the end time")?;
            if t < units.dt_s {
                return Err(ctx.err(
                    "end_time_s",
                    0,
                    format!(
                        "end_time_s is shorter than one time step ({} s)",
                        units.dt_s
                    ),
                ));
            }
        }
        _ => return Err(ctx.err("run", 0, "set exactly one of steps or end_time_s in [run]")),
    }
    super::output::validate_output(&s.output, super::output::SceneKind::Fluid, ctx)
}
