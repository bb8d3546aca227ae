//! Validation of a scene's probes and analyses: each names what exists and each key is
//! possible, with the key, its line and the fix in the error.

use super::context::{positive, validate_checks, Context};
use super::schema::*;
use super::SceneError;

/// Probes (unique names, inside the domain, naming what exists) and analyses (each with the
/// probes and keys it needs).
/// `run_end_s` is the run's end time (s), for windows that must lie within the run.
pub(super) fn validate_probes_and_analyses(
    s: &Scene,
    ctx: &Context,
    run_end_s: f64,
) -> Result<(), SceneError> {
    validate_probes(s, ctx)?;
    for a in &s.analyses {
        validate_analysis(s, a, ctx, run_end_s)?;
    }
    validate_checks(&s.checks, ctx)
}

/// `[[probes]]`: unique names, points inside the domain, naming what exists.
fn validate_probes(s: &Scene, ctx: &Context) -> Result<(), SceneError> {
    let lx = s.domain.cells[0] as f64 * s.domain.spacing_m;
    let ly = s.domain.cells[1] as f64 * s.domain.spacing_m;
    for (n, p) in s.probes.iter().enumerate() {
        if s.probes[..n].iter().any(|q| q.name() == p.name()) {
            return Err(ctx.err(
                "name",
                s.obstacles.len() + n,
                format!("probe name `{}` is used twice", p.name()),
            ));
        }
        match p {
            Probe::Point { position_m, name } => {
                if !(position_m[0] >= 0.0
                    && position_m[0] < lx
                    && position_m[1] >= 0.0
                    && position_m[1] < ly)
                {
                    return Err(ctx.err(
                        "position_m",
                        0,
                        format!("probe `{name}` lies outside the domain [0, {lx}) × [0, {ly}) m"),
                    ));
                }
            }
            Probe::Force { obstacle, name } => {
                if !s.obstacles.iter().any(|o| o.name() == obstacle) {
                    return Err(ctx.err("obstacle", 0, format!("force probe `{name}` names obstacle `{obstacle}`, which the scene does not define")));
                }
            }
            Probe::Grain { name, .. } => {
                if s.grains.is_none() {
                    return Err(ctx.err(
                        "id",
                        0,
                        format!("grain probe `{name}` needs grains: add [grains] and [coupling]"),
                    ));
                }
            }
            Probe::Deposit { name, .. } => {
                if s.grains.is_none() {
                    return Err(ctx.err(
                        "kind",
                        0,
                        format!("deposit probe `{name}` needs grains: add [grains] and [coupling]"),
                    ));
                }
            }
            // Every fluid scene has kinetic energy (its grains' part is zero without grains).
            Probe::KineticEnergy { .. } => {}
        }
    }
    Ok(())
}

/// One `[[analyses]]` entry: the probes and keys it needs, its windows within the run
/// (which ends at `run_end_s`, s).
fn validate_analysis(
    s: &Scene,
    a: &Analysis,
    ctx: &Context,
    run_end_s: f64,
) -> Result<(), SceneError> {
    let probe_kind = |name: &str| s.probes.iter().find(|p| p.name() == name);
    // `key` names a probe `name` of the kind `is` accepts, or the error says `needs`.
    let need = |key: &str, name: &str, is: fn(&Probe) -> bool, needs: &str| {
        if probe_kind(name).is_some_and(is) {
            Ok(())
        } else {
            Err(ctx.err(key, 0, format!("{needs} `{name}`")))
        }
    };
    match a {
        Analysis::ForceCoefficients {
            probe,
            velocity_m_s,
            length_m,
            ..
        } => {
            need(
                "probe",
                probe,
                |p| matches!(p, Probe::Force { .. } | Probe::Grain { .. }),
                "force-coefficients needs a force probe (an obstacle) or a grain probe named",
            )?;
            positive(ctx, "velocity_m_s", *velocity_m_s, "the reference velocity")?;
            positive(ctx, "length_m", *length_m, "the reference length")?;
        }
        Analysis::PressureDifference {
            upstream,
            downstream,
            average_last_s,
        } => {
            for (key, p) in [("upstream", upstream), ("downstream", downstream)] {
                need(
                    key,
                    p,
                    |p| matches!(p, Probe::Point { .. }),
                    "pressure-difference needs a point probe named",
                )?;
            }
            if !(*average_last_s >= 0.0) {
                return Err(ctx.err(
                    "average_last_s",
                    0,
                    format!("the window must be 0 or positive, got {average_last_s}"),
                ));
            }
            within_run(ctx, *average_last_s, run_end_s)?;
        }
        Analysis::Strouhal {
            probe,
            velocity_m_s,
            length_m,
            skip_s,
            ..
        } => {
            need(
                "probe",
                probe,
                |p| matches!(p, Probe::Point { .. }),
                "strouhal needs a point probe named",
            )?;
            positive(ctx, "velocity_m_s", *velocity_m_s, "the reference velocity")?;
            positive(ctx, "length_m", *length_m, "the reference length")?;
            if *skip_s >= run_end_s {
                return Err(ctx.err(
                    "skip_s",
                    0,
                    format!(
                        "strouhal skips {skip_s} s of transient, but the run ends at \
                         {run_end_s} s: shorten skip_s or lengthen the run"
                    ),
                ));
            }
        }
        Analysis::Settling {
            probe,
            average_last_s,
        } => {
            need(
                "probe",
                probe,
                |p| matches!(p, Probe::Grain { .. }),
                "settling needs a grain probe named",
            )?;
            positive(
                ctx,
                "average_last_s",
                *average_last_s,
                "the averaging window",
            )?;
            within_run(ctx, *average_last_s, run_end_s)?;
        }
        Analysis::DraftKissTumble {
            lower,
            upper,
            contact_gap_m,
            average_last_s,
            fall_window_s,
            terminal_velocity_m_s,
        } => {
            for p in [lower, upper] {
                need(
                    "lower",
                    p,
                    |p| matches!(p, Probe::Grain { .. }),
                    "draft-kiss-tumble needs a grain probe named",
                )?;
            }
            positive(ctx, "contact_gap_m", *contact_gap_m, "the contact gap")?;
            positive(
                ctx,
                "average_last_s",
                *average_last_s,
                "the averaging window",
            )?;
            within_run(ctx, *average_last_s, run_end_s)?;
            fall_window(run_end_s, ctx, *fall_window_s, *terminal_velocity_m_s)?;
        }
        Analysis::ColumnCollapse {
            deposit,
            pore_pressure,
            ..
        } => {
            if s.grains.is_none() {
                return Err(ctx.err(
                    "kind",
                    0,
                    "column-collapse in a fluid scene needs grains: add [grains] and [coupling]",
                ));
            }
            need(
                "deposit",
                deposit,
                |p| matches!(p, Probe::Deposit { .. }),
                "column-collapse needs a deposit probe named",
            )?;
            if let Some(p) = pore_pressure {
                need(
                    "pore_pressure",
                    p,
                    |p| matches!(p, Probe::Point { .. }),
                    "column-collapse needs a point probe named",
                )?;
            }
        }
        Analysis::Permeability => permeability_scene(ctx, s)?,
        Analysis::MomentumBalance if s.grains.is_none() => {
            return Err(ctx.err(
                "kind",
                0,
                "momentum-balance needs grains: add [grains] and [coupling]",
            ));
        }
        Analysis::Ghia {
            u_reference,
            v_reference,
            ..
        } => {
            for (k, f) in [("u_reference", u_reference), ("v_reference", v_reference)] {
                if !ctx.base_dir.join(f).is_file() {
                    return Err(ctx.err(
                        k,
                        0,
                        format!(
                            "reference file {} does not exist",
                            ctx.base_dir.join(f).display()
                        ),
                    ));
                }
            }
        }
        _ => {}
    }
    Ok(())
}

/// A permeability analysis needs fixed grains in a fully periodic fluid driven by a body
/// acceleration.
fn permeability_scene(ctx: &Context, s: &Scene) -> Result<(), SceneError> {
    let fixed = match s.grains.as_ref().map(|g| &g.sample) {
        Some(super::grains::SampleSpec::List { grains }) => grains.iter().all(|g| g.fixed),
        _ => false,
    };
    if !fixed {
        return Err(ctx.err(
            "kind",
            0,
            "permeability needs grains held in place: list them in [grains.sample] \
             (kind = \"list\") with `fixed = true`, and add [coupling]",
        ));
    }
    let b = &s.boundaries;
    let periodic = [&b.west, &b.east, &b.south, &b.north]
        .iter()
        .all(|f| matches!(f, BoundarySpec::Periodic));
    if !periodic {
        return Err(ctx.err(
            "kind",
            0,
            "permeability measures a periodic array: make all four boundaries periodic",
        ));
    }
    if s.fluid.body_acceleration_m_s2 == [0.0, 0.0] {
        return Err(ctx.err(
            "kind",
            0,
            "permeability needs a flow: set [fluid] body_acceleration_m_s2 (it stands in \
             for the pressure gradient)",
        ));
    }
    Ok(())
}

/// An averaging window of `window_s` (s) fits in a run of `run_end_s` (s).
fn within_run(ctx: &Context, window_s: f64, run_end_s: f64) -> Result<(), SceneError> {
    if window_s > run_end_s {
        return Err(ctx.err(
            "average_last_s",
            0,
            format!(
                "the averaging window ({window_s} s) is longer than the run ({run_end_s} s); \
                 shorten it or lengthen the run"
            ),
        ));
    }
    Ok(())
}

/// The draft-kiss-tumble fall-speed window: 0 ≤ from < to ≤ the run's end (`run_end_s`);
/// a terminal velocity needs a window and must be positive.
fn fall_window(
    run_end_s: f64,
    ctx: &Context,
    window: Option<[f64; 2]>,
    terminal: Option<f64>,
) -> Result<(), SceneError> {
    if let Some([from, to]) = window {
        if !(from.is_finite() && to.is_finite() && from >= 0.0 && from < to) {
            return Err(ctx.err(
                "fall_window_s",
                0,
                format!(
                    "fall_window_s must be [from, to] with 0 ≤ from < to (s), got [{from}, {to}]"
                ),
            ));
        }
        if to > run_end_s {
            return Err(ctx.err(
                "fall_window_s",
                0,
                format!("fall_window_s ends at {to} s, after the run (which ends at {run_end_s} s): shorten the window or run longer"),
            ));
        }
    }
    if let Some(u) = terminal {
        positive(ctx, "terminal_velocity_m_s", u, "the terminal velocity")?;
        if window.is_none() {
            return Err(ctx.err(
                "terminal_velocity_m_s",
                0,
                "terminal_velocity_m_s needs fall_window_s = [from, to] (s): the time window after separation to compare the fall speeds in",
            ));
        }
    }
    Ok(())
}
