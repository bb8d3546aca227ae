//! Analytic and tabulated reference flows: Poiseuille, Couette, Taylor–Green, Ghia cavity.

use super::{err, AnalysisError, Inputs, Results};
use lbm::fields::Fields;
use scene::{BoundarySpec, Initial};
use std::f64::consts::PI;

/// The whole lattice's final fields, which the run gathers (on rank 0) only for scenes whose
/// analyses read them ([`super::needs_fields`]).
fn fields<'a>(inp: &Inputs<'a>, analysis: &str) -> Result<&'a Fields, AnalysisError> {
    inp.fields.ok_or_else(|| {
        err(
            analysis,
            "the final fields were not gathered for this analysis",
        )
    })
}

/// Body-force Poiseuille between walls at y = 0 and y = H: u(y) = g/(2ν) y (H − y)
/// (lattice units, half-way walls at the domain edges). Profile taken at the middle column.
pub fn poiseuille(inp: &Inputs, r: &mut Results) -> Result<(), AnalysisError> {
    let s = &inp.scene.scene;
    if !(s.boundaries.south == BoundarySpec::Wall && s.boundaries.north == BoundarySpec::Wall) {
        return Err(err("poiseuille", "needs no-slip walls on south and north"));
    }
    let u = &inp.scene.units;
    let g = u.acceleration_to_lattice(s.fluid.body_acceleration_m_s2[0]);
    let f = fields(inp, "poiseuille")?;
    let (nx, ny) = (f.nx, f.ny);
    let h = ny as f64;
    let nu = u.nu_lattice;
    let umax = g * h * h / (8.0 * nu);
    let x = nx / 2;
    let (mut emax, mut num, mut den) = (0.0f64, 0.0, 0.0);
    for y in 0..ny {
        let yy = y as f64 + 0.5;
        let exact = g / (2.0 * nu) * yy * (h - yy);
        let v = f.ux[y * nx + x];
        emax = emax.max((v - exact).abs());
        num += (v - exact).powi(2);
        den += exact * exact;
    }
    // Centreline velocity at y = H/2: the middle cell for odd ny; for even ny, quadratic
    // (Lagrange) interpolation through the three cells around it, exact for a parabola.
    let col = |y: usize| f.ux[y * nx + x];
    let centre = if ny % 2 == 1 {
        col(ny / 2)
    } else {
        let j = ny / 2;
        // Nodes at offsets −½, +½, +3/2 from the centreline; weights of L(0).
        0.375 * col(j - 1) + 0.75 * col(j) - 0.125 * col(j + 1)
    };
    r.insert("poiseuille.max_rel_error".into(), emax / umax);
    r.insert("poiseuille.l2_rel_error".into(), (num / den).sqrt());
    r.insert(
        "poiseuille.peak_rel_error".into(),
        (centre - umax).abs() / umax,
    );
    r.insert(
        "poiseuille.centreline_velocity_m_s".into(),
        u.velocity_to_si(centre),
    );
    Ok(())
}

/// Couette: linear profile between the south and north wall velocities.
pub fn couette(inp: &Inputs, r: &mut Results) -> Result<(), AnalysisError> {
    let s = &inp.scene.scene;
    let wall_u = |b: &BoundarySpec| match b {
        BoundarySpec::Wall => Some(0.0),
        BoundarySpec::MovingWall { velocity_m_s } => Some(velocity_m_s[0]),
        _ => None,
    };
    let (Some(us), Some(un)) = (wall_u(&s.boundaries.south), wall_u(&s.boundaries.north)) else {
        return Err(err(
            "couette",
            "needs walls (fixed or moving) on south and north",
        ));
    };
    let u = &inp.scene.units;
    let (us, un) = (u.velocity_to_lattice(us), u.velocity_to_lattice(un));
    let f = fields(inp, "couette")?;
    let (mut num, mut den) = (0.0, 0.0);
    for y in 0..f.ny {
        let exact = us + (un - us) * (y as f64 + 0.5) / f.ny as f64;
        for x in 0..f.nx {
            num += (f.ux[y * f.nx + x] - exact).powi(2) + f.uy[y * f.nx + x].powi(2);
            den += exact * exact;
        }
    }
    r.insert("couette.l2_rel_error".into(), (num / den).sqrt());
    Ok(())
}

/// The Taylor–Green velocity field at time `t` (lattice units) of amplitude `u0` on an
/// `nx` × `ny` periodic box: u = U e^{−ν(kx²+ky²)t} (−cos kx x sin ky y, (kx/ky) sin kx x cos ky y).
pub fn taylor_green_velocity(
    nx: usize,
    ny: usize,
    u0: f64,
    nu: f64,
    t: f64,
    x: f64,
    y: f64,
) -> [f64; 2] {
    let (kx, ky) = (2.0 * PI / nx as f64, 2.0 * PI / ny as f64);
    // Taylor & Green (1937): viscous decay at rate ν |k|².
    let a = u0 * (-nu * (kx * kx + ky * ky) * t).exp();
    [
        -a * (kx * x).cos() * (ky * y).sin(),
        a * kx / ky * (kx * x).sin() * (ky * y).cos(),
    ]
}

/// Taylor–Green pressure (lattice units, ρ₀ = 1) matching [`taylor_green_velocity`] at t = 0.
pub fn taylor_green_pressure(nx: usize, ny: usize, u0: f64, x: f64, y: f64) -> f64 {
    let (kx, ky) = (2.0 * PI / nx as f64, 2.0 * PI / ny as f64);
    -0.25 * u0 * u0 * ((2.0 * kx * x).cos() + (kx / ky).powi(2) * (2.0 * ky * y).cos())
}

/// L2 error of the decayed vortex against the analytic field.
pub fn taylor_green(inp: &Inputs, r: &mut Results) -> Result<(), AnalysisError> {
    let Initial::TaylorGreen { amplitude_m_s } = inp.scene.scene.fluid.initial else {
        return Err(err(
            "taylor-green",
            "needs initial = { kind = \"taylor-green\", … }",
        ));
    };
    let u = &inp.scene.units;
    let f = fields(inp, "taylor-green")?;
    let u0 = u.velocity_to_lattice(amplitude_m_s);
    let (mut num, mut den) = (0.0, 0.0);
    for y in 0..f.ny {
        for x in 0..f.nx {
            let e = taylor_green_velocity(
                f.nx,
                f.ny,
                u0,
                u.nu_lattice,
                inp.steps as f64,
                x as f64 + 0.5,
                y as f64 + 0.5,
            );
            let k = y * f.nx + x;
            num += (f.ux[k] - e[0]).powi(2) + (f.uy[k] - e[1]).powi(2);
            den += e[0] * e[0] + e[1] * e[1];
        }
    }
    r.insert("taylor_green.l2_rel_error".into(), (num / den).sqrt());
    Ok(())
}

/// Read a reference CSV (`#` comments, a header, numeric rows) and return (coordinate, column).
fn read_reference(path: &std::path::Path, column: &str) -> Result<Vec<(f64, f64)>, AnalysisError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| err("ghia", format!("{}: {e}", path.display())))?;
    let mut lines = text
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'));
    let header: Vec<&str> = lines
        .next()
        .unwrap_or("")
        .split(',')
        .map(str::trim)
        .collect();
    let c = header.iter().position(|h| *h == column).ok_or_else(|| {
        err(
            "ghia",
            format!(
                "{} has no column `{column}` (has {header:?})",
                path.display()
            ),
        )
    })?;
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').filter_map(|x| x.trim().parse().ok()).collect();
            if v.len() != header.len() {
                return Err(err(
                    "ghia",
                    format!("{}: malformed row `{l}`", path.display()),
                ));
            }
            Ok((v[0], v[c]))
        })
        .collect()
}

/// Linear interpolation of a cell-centred line `vals` (n cells on [0, 1]) with wall values
/// `lo`, `hi` at the ends.
fn interpolate_line(vals: &[f64], lo: f64, hi: f64, s: f64) -> f64 {
    let n = vals.len();
    let p = s * n as f64 - 0.5;
    if p <= 0.0 {
        let t = s * n as f64 / 0.5;
        return lo + (vals[0] - lo) * t.clamp(0.0, 1.0);
    }
    if p >= (n - 1) as f64 {
        let t = (1.0 - s) * n as f64 / 0.5;
        return hi + (vals[n - 1] - hi) * t.clamp(0.0, 1.0);
    }
    let i = p.floor() as usize;
    let t = p - i as f64;
    vals[i] * (1.0 - t) + vals[i + 1] * t
}

/// Centreline velocities of the lid-driven cavity against Ghia, Ghia & Shin (1982).
pub fn ghia(
    inp: &Inputs,
    u_ref: &str,
    v_ref: &str,
    column: &str,
    r: &mut Results,
) -> Result<(), AnalysisError> {
    let s = &inp.scene.scene;
    let BoundarySpec::MovingWall { velocity_m_s } = s.boundaries.north else {
        return Err(err("ghia", "needs a moving-wall lid on the north face"));
    };
    let units = &inp.scene.units;
    let lid = units.velocity_to_lattice(velocity_m_s[0]);
    let f = fields(inp, "ghia")?;
    let (nx, ny) = (f.nx, f.ny);
    // Centrelines at x = L/2 and y = L/2 (averaging the two straddling cells for even sizes).
    let line = |n: usize, at: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..n).map(at).collect() };
    let mid = |n: usize| {
        if n.is_multiple_of(2) {
            (n / 2 - 1, n / 2)
        } else {
            (n / 2, n / 2)
        }
    };
    let (xa, xb) = mid(nx);
    let (ya, yb) = mid(ny);
    let u_line = line(ny, &|y| 0.5 * (f.ux[y * nx + xa] + f.ux[y * nx + xb]) / lid);
    let v_line = line(nx, &|x| 0.5 * (f.uy[ya * nx + x] + f.uy[yb * nx + x]) / lid);
    let base = &inp.scene.base_dir;
    let du = read_reference(&base.join(u_ref), column)?
        .iter()
        .map(|&(y, uref)| (interpolate_line(&u_line, 0.0, 1.0, y) - uref).abs())
        .fold(0.0, f64::max);
    let dv = read_reference(&base.join(v_ref), column)?
        .iter()
        .map(|&(x, vref)| (interpolate_line(&v_line, 0.0, 0.0, x) - vref).abs())
        .fold(0.0, f64::max);
    r.insert("ghia.max_u_deviation".into(), du);
    r.insert("ghia.max_v_deviation".into(), dv);
    Ok(())
}
