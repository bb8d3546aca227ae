//! A fluid `[domain]` given by its size: when `[fluid]` fixes the relaxation time τ and the
//! lattice velocity u_lb together, they fix the spacing too, and the cells follow from the
//! domain's size in metres.
//!
//! With ν_lb = (τ − ½)/3 = ν Δt/Δx² and u_lb = U Δt/Δx, dividing one by the other gives
//! Δx = ν u_lb / (U ν_lb). The width then holds n_x = round(L_x/Δx) cells; the spacing is
//! taken as L_x/n_x so the width is exact, τ is kept exact (the stability verdict is keyed
//! on it), and u_lb moves by the rounding (a warning says by how much).

use super::context::{positive, Context};
use super::schema::Scene;
use super::SceneError;

/// Fill `[domain] cells` and `spacing_m` from `size_m`, when it is given, and return the
/// warnings. Errors name the key: `size_m` without both τ and u_lb, with `cells` or
/// `spacing_m` beside it, or a lattice too small or too large.
pub(crate) fn resolve(s: &mut Scene, ctx: &Context) -> Result<Vec<String>, SceneError> {
    let Some([lx, ly]) = s.domain.size_m else {
        let d = &s.domain;
        for (missing, key) in [
            (d.cells == [0, 0], "cells"),
            (d.spacing_m == 0.0, "spacing_m"),
        ] {
            if missing && super::context::line_of_key(ctx.text, key, 0).is_none() {
                return Err(ctx.err(
                    "domain",
                    0,
                    format!(
                        "[domain] is missing `{key}`: give cells = [nx, ny] and spacing_m, or \
                         size_m = [width, height] (m) when [fluid] gives relaxation_time and \
                         lattice_velocity together"
                    ),
                ));
            }
        }
        return Ok(Vec::new());
    };
    if s.domain.cells != [0, 0] || s.domain.spacing_m != 0.0 {
        return Err(ctx.err(
            "size_m",
            0,
            "size_m derives cells and spacing_m: give either size_m or cells with spacing_m, \
             not both",
        ));
    }
    positive(ctx, "size_m", lx, "the domain's width")?;
    positive(ctx, "size_m", ly, "the domain's height")?;
    let f = &s.fluid;
    let (Some(tau), Some(u_lb), None) = (f.relaxation_time, f.lattice_velocity, f.time_step_s)
    else {
        return Err(ctx.err(
            "size_m",
            0,
            "size_m needs relaxation_time and lattice_velocity in [fluid] (and no \
             time_step_s): the two fix the spacing; otherwise give cells and spacing_m",
        ));
    };
    positive(ctx, "lattice_velocity", u_lb, "lattice_velocity")?;
    super::validate::fluid_figures(f, ctx)?;
    if !(tau > 0.5 && tau.is_finite()) {
        return Err(ctx.err(
            "relaxation_time",
            0,
            format!(
                "relaxation time τ = {tau} must be a finite number above ½ (0.51–2 is typical)"
            ),
        ));
    }
    let nu_lb = (tau - 0.5) / 3.0;
    let dx = f.viscosity_m2_s * u_lb / (f.reference_velocity_m_s * nu_lb);
    let (fx, fy) = (lx / dx, ly / dx);
    let most = super::limits::MAX_CELLS as f64;
    // With the one-cell halo, as validate_lattice counts them.
    if !((fx.round() + 2.0) * (fy.round() + 2.0) <= most) {
        return Err(ctx.err(
            "size_m",
            0,
            format!(
                "τ = {tau} and u_lb = {u_lb} give Δx = {dx:.3e} m, so {fx:.3e} × {fy:.3e} \
                 cells: more than any machine holds; lower τ or raise lattice_velocity (Δx ∝ u_lb/(τ − ½))"
            ),
        ));
    }
    let (nx, ny) = (fx.round() as usize, fy.round() as usize);
    if nx < 2 || ny < 2 {
        return Err(ctx.err(
            "size_m",
            0,
            format!(
                "τ = {tau} and u_lb = {u_lb} give Δx = {dx:.3e} m, so {fx:.2} × {fy:.2} cells: \
                 the lattice needs at least 2 × 2; raise τ or lower lattice_velocity (Δx ∝ u_lb/(τ − ½))"
            ),
        ));
    }
    let spacing = lx / nx as f64;
    s.domain.cells = [nx, ny];
    s.domain.spacing_m = spacing;
    let mut warnings = vec![format!(
        "size_m: τ = {tau} and u_lb = {u_lb} give Δx = {dx:.6e} m; the lattice is {nx} × {ny} \
         cells of {spacing:.6e} m"
    )];
    let height = ny as f64 * spacing;
    if ((height - ly) / ly).abs() > 1e-9 {
        warnings.push(format!(
            "size_m: the height is {ny} cells = {height:.6} m (asked {ly} m): not a whole \
             number of cells"
        ));
    }
    let u_now = u_lb * spacing / dx;
    if ((u_now - u_lb) / u_lb).abs() > 1e-9 {
        warnings.push(format!(
            "size_m: lattice_velocity is {u_now:.6} (asked {u_lb}) so the width is a whole \
             number of cells; τ is kept"
        ));
    }
    Ok(warnings)
}
