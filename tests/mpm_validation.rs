//! MPM validation against analytic solutions (run with `cargo test --release`):
//! the speed of a 1-D elastic wave, the geostatic stress of an elastic column, a block
//! sliding on a frictional incline, and a Mohr–Coulomb layer stopping on a rough incline.

use decomposition::SingleProcess;
use grainflow::mpm::mohr_coulomb;
use grainflow::mpm::*;

fn setup(
    spec: GridSpec,
    shape: ShapeKind,
    scheme: Scheme,
    b: Boundaries,
    g: [f64; 2],
    m: Material,
) -> MpmSetup {
    MpmSetup {
        scheme,
        ..MpmSetup::plain(spec, shape, b, g, m)
    }
}

fn rect(points: &mut Points, spec: &GridSpec, min: [f64; 2], max: [f64; 2], n: usize, rho: f64) {
    let mut id = points.len() as u64;
    fill(
        points,
        &Shape::Rectangle { min, max },
        spec,
        n,
        rho,
        0,
        &mut id,
    );
}

/// Fixed–free bar (ν = 0, rollers above and below: 1-D strain) released in its first mode,
/// v(x) = v₀ sin(πx / 2L). Its period is T = 4L / c with c = √(E/ρ); the wave speed from
/// the measured period must be within 1 % of √(E/ρ) (issue 6, validation 1).
fn wave_speed(shape: ShapeKind, scheme: Scheme) -> f64 {
    let (e, rho, len) = (1.0e6, 1000.0, 1.0);
    let spec = GridSpec {
        nx: 120,
        ny: 2,
        h: 0.01,
    };
    let b = Boundaries {
        left: Side::Fixed,
        right: Side::Open,
        bottom: Side::Roller,
        top: Side::Roller,
    };
    let mut pts = Points::default();
    rect(&mut pts, &spec, [0.0, 0.0], [len, 0.02], 2, rho);
    let v0 = 1e-3;
    for i in 0..pts.len() {
        pts.vel[i][0] = v0 * (std::f64::consts::FRAC_PI_2 * pts.pos[i][0] / len).sin();
    }
    let s = setup(
        spec,
        shape,
        scheme,
        b,
        [0.0; 2],
        Material::linear_elastic(e, 0.0, rho),
    );
    let mut sys = MpmSystem::new(s, pts, &SingleProcess).expect("system");
    let c = (e / rho).sqrt();
    let period = 4.0 * len / c;
    // Momentum of the bar ∝ cos(ωt): time its first two downward zero crossings (T/4, 3T/4)
    // by linear interpolation.
    let mut crossings = Vec::new();
    let mut prev = sys.totals(&SingleProcess).unwrap().momentum[0];
    while sys.time < 1.1 * period {
        sys.step(&SingleProcess).expect("step");
        let now = sys.totals(&SingleProcess).unwrap().momentum[0];
        if prev.signum() != now.signum() {
            crossings.push(sys.time - sys.setup.dt * now / (now - prev));
        }
        prev = now;
    }
    assert!(crossings.len() >= 2, "{crossings:?}");
    let measured_period = 2.0 * (crossings[1] - crossings[0]);
    4.0 * len / measured_period / c
}

#[test]
fn elastic_wave_speed_within_1_percent() {
    for (shape, scheme) in [
        (ShapeKind::Gimp, Scheme::Usf),
        (ShapeKind::Gimp, Scheme::Usl),
        (ShapeKind::Gimp, Scheme::Musl),
        (ShapeKind::Linear, Scheme::Musl),
        (ShapeKind::CpGimp, Scheme::Usf),
    ] {
        let ratio = wave_speed(shape, scheme);
        println!("{shape:?} {scheme:?}: c / √(E/ρ) = {ratio:.5}");
        assert!(
            (ratio - 1.0).abs() < 0.01,
            "{shape:?} {scheme:?}: c / √(E/ρ) = {ratio}"
        );
    }
}

/// Elastic column on a fixed base between rollers, loaded by gravity and brought to rest
/// by Cundall damping (issue 6, validation 2). The exact stress at a point of initial height
/// Y is σ_yy = −ρ g (H − Y): the weight above it is the mass above it, whatever the
/// deformation.
///
/// With 2 × 2 points per cell the velocity gradient, hence the stress, is constant within a
/// cell (both GIMP and linear shapes interpolate velocity linearly between the nodes), so
/// the discrete field is the cell average. Checked: (1) the mean σ_yy of each cell's points
/// within 2 % of ρ g (H − Ȳ) at their mean height Ȳ, for every cell between 20 % and 80 %
/// of the height; (2) every point, boundaries included, within ρ g h/4 (the distance from a
/// point to its cell centre) plus 2 % of the local exact value.
#[test]
fn elastic_column_geostatic_stress_within_2_percent() {
    let (e, nu, rho, g, height) = (1.0e7, 0.3, 2000.0, 9.81, 1.0);
    for shape in [ShapeKind::Gimp, ShapeKind::Linear] {
        let spec = GridSpec {
            nx: 4,
            ny: 24,
            h: 0.05,
        };
        let b = Boundaries {
            left: Side::Roller,
            right: Side::Roller,
            bottom: Side::Fixed,
            top: Side::Open,
        };
        let mut pts = Points::default();
        rect(&mut pts, &spec, [0.0, 0.0], [0.2, height], 2, rho);
        let y0: Vec<f64> = pts.pos.iter().map(|p| p[1]).collect();
        let mut s = setup(
            spec,
            shape,
            Scheme::Usf,
            b,
            [0.0, -g],
            Material::linear_elastic(e, nu, rho),
        );
        s.damping = 0.1;
        let mut sys = MpmSystem::new(s, pts, &SingleProcess).expect("system");
        while sys.time < 1.5 {
            sys.step(&SingleProcess).expect("step");
        }
        assert!(
            sys.totals(&SingleProcess).unwrap().kinetic_energy < 1e-6,
            "not at rest: {}",
            sys.totals(&SingleProcess).unwrap().kinetic_energy
        );
        // Per cell (by initial position): Σ σ_yy, Σ Y, count.
        let mut cells = std::collections::BTreeMap::new();
        let (mut worst_cell, mut worst_point): (f64, f64) = (0.0, 0.0);
        for i in 0..sys.points.len() {
            let y = y0[sys.points.id[i] as usize];
            let x = sys.points.pos[i][0];
            let key = ((x / spec.h) as i64, (y / spec.h) as i64);
            let e = cells.entry(key).or_insert([0.0; 3]);
            let syy = sys.points.stress[i][1];
            *e = [e[0] + syy, e[1] + y, e[2] + 1.0];
            let exact = -rho * g * (height - y);
            let bound = rho * g * spec.h / 4.0 + 0.02 * exact.abs();
            worst_point = worst_point.max((syy - exact).abs() / bound);
        }
        for [s, y, n] in cells.values() {
            let (syy, y) = (s / n, y / n);
            if y < 0.2 * height || y > 0.8 * height {
                continue;
            }
            let exact = -rho * g * (height - y);
            worst_cell = worst_cell.max(((syy - exact) / exact).abs());
        }
        println!(
            "{shape:?}: worst cell-mean σ_yy error {:.3} %, worst point error {:.3} of its bound",
            100.0 * worst_cell,
            worst_point
        );
        assert!(
            worst_cell < 0.02,
            "{shape:?}: cell-mean σ_yy off by {:.2} %",
            100.0 * worst_cell
        );
        assert!(
            worst_point < 1.0,
            "{shape:?}: a point's σ_yy is {worst_point:.2} × its bound"
        );
    }
}

/// An elastic block on a frictional base with gravity tilted by θ = 30° (the incline's
/// frame) and μ = 0.3: its centre of mass must follow x(t) = ½ g (sin θ − μ cos θ) t²
/// within 3 % (issue 6, validation 3).
#[test]
fn block_slides_on_frictional_incline_within_3_percent() {
    let (g, theta, mu, rho) = (9.81f64, 30f64.to_radians(), 0.3, 2000.0);
    let accel = g * (theta.sin() - mu * theta.cos());
    for scheme in [Scheme::Usf, Scheme::Usl, Scheme::Musl] {
        let spec = GridSpec {
            nx: 60,
            ny: 8,
            h: 0.02,
        };
        let b = Boundaries::floor(Side::Frictional { friction: mu });
        let mut pts = Points::default();
        rect(&mut pts, &spec, [0.04, 0.0], [0.24, 0.1], 2, rho);
        // Start from the equilibrium normal stress to avoid a drop transient.
        for i in 0..pts.len() {
            let syy = -rho * g * theta.cos() * (0.1 - pts.pos[i][1]);
            pts.stress[i] = [0.3 / 0.7 * syy, syy, 0.0, 0.3 / 0.7 * syy];
        }
        let grav = [g * theta.sin(), -g * theta.cos()];
        let mut sys = MpmSystem::new(
            setup(
                spec,
                ShapeKind::Gimp,
                scheme,
                b,
                grav,
                Material::linear_elastic(5.0e7, 0.3, rho),
            ),
            pts,
            &SingleProcess,
        )
        .expect("system");
        let centre = |s: &MpmSystem| {
            let p = &s.points;
            (0..p.len()).map(|i| p.mass[i] * p.pos[i][0]).sum::<f64>() / p.total_mass()
        };
        let x0 = centre(&sys);
        let mut worst: f64 = 0.0;
        for t_check in [0.2, 0.3, 0.4, 0.5] {
            while sys.time < t_check - 1e-12 {
                sys.step(&SingleProcess).expect("step");
            }
            let exact = 0.5 * accel * sys.time * sys.time;
            let err = (centre(&sys) - x0 - exact) / exact;
            worst = worst.max(err.abs());
        }
        println!(
            "{scheme:?}: worst displacement error {:.3} %",
            100.0 * worst
        );
        assert!(
            worst < 0.03,
            "{scheme:?}: displacement off by {:.2} %",
            100.0 * worst
        );
    }
}

/// Deceleration (m/s²) of a Mohr–Coulomb layer (φ = 22.2°, ψ = 0, glass-bead constants of
/// the collapse) sliding at 0.5 m/s down a rough (no-slip) incline of θ = 15° under the
/// velocity update `update`: the mean velocity (m/s) of the points that start in the middle
/// tenth, at each of the `times` (s, ascending).
fn layer_velocity(update: VelocityUpdate, times: &[f64]) -> Vec<f64> {
    let (g, theta, rho, depth) = (9.81f64, 15f64.to_radians(), 1925.0, 0.02);
    let spec = GridSpec {
        nx: 300,
        ny: 10,
        h: 0.004,
    };
    let b = Boundaries::floor(Side::Fixed);
    let m = Material {
        density: rho,
        separation_volume_ratio: 1.15,
        model: Model::MohrCoulomb(mohr_coulomb::MohrCoulomb::cohesionless(1.98e6, 0.3, 22.2)),
    };
    let mut pts = Points::default();
    rect(&mut pts, &spec, [0.2, 0.0], [0.8, depth], 2, rho);
    let k0 = 1.0 - 22.2f64.to_radians().sin();
    for i in 0..pts.len() {
        let syy = -rho * g * theta.cos() * (depth - pts.pos[i][1]);
        pts.stress[i] = [k0 * syy, syy, 0.0, k0 * syy];
        pts.vel[i] = [0.5, 0.0];
    }
    let middle: Vec<bool> = pts.pos.iter().map(|p| (p[0] - 0.5).abs() < 0.03).collect();
    let mut s = setup(
        spec,
        ShapeKind::Gimp,
        Scheme::Usf,
        b,
        [g * theta.sin(), -g * theta.cos()],
        m,
    );
    s.velocity_update = update;
    s.volumetric_averaging = true;
    let mut sys = MpmSystem::new(s, pts, &SingleProcess).expect("system");
    let mean_at = |t: f64, sys: &mut MpmSystem| {
        while sys.time < t - 1e-12 {
            sys.step(&SingleProcess).expect("step");
        }
        let p = &sys.points;
        let sel: Vec<usize> = (0..p.len()).filter(|&i| middle[p.id[i] as usize]).collect();
        sel.iter().map(|&i| p.vel[i][0]).sum::<f64>() / sel.len() as f64
    };
    times.iter().map(|&t| mean_at(t, &mut sys)).collect()
}

/// A Mohr–Coulomb layer sliding on a rough incline below its friction angle stops at the
/// rate of a Coulomb block whose friction is the mobilised ratio τ/σ on horizontal planes:
/// at yield, with σxx = σyy (coaxial flow of ψ = 0), τ/σ = sin φ; at most, for any σxx,
/// tan φ. The layer yields at every depth at once (τ and σ both grow as the depth), so the
/// deceleration g (μ cos θ − sin θ) lies between those of μ = sin φ (1.04 m/s²) and
/// μ = tan φ (1.33 m/s²); 5 % margin. Measured with APIC, which does not damp the layer's
/// (affine) shear. The FLIP/PIC blend brakes far harder: its PIC part drags the layer
/// towards the no-slip nodes every step (a numerical viscosity ~ α c h).
#[test]
fn mohr_coulomb_layer_stops_on_a_rough_incline_at_the_coulomb_rate() {
    let (g, theta, phi) = (9.81f64, 15f64.to_radians(), 22.2f64.to_radians());
    let a_sin = g * (phi.sin() * theta.cos() - theta.sin());
    let a_tan = g * (phi.tan() * theta.cos() - theta.sin());
    let v = layer_velocity(VelocityUpdate::Apic, &[0.1, 0.3]);
    let apic = (v[0] - v[1]) / 0.2;
    println!("APIC: {apic:.3} m/s² (bounds {a_sin:.3}–{a_tan:.3})");
    assert!(
        apic > 0.95 * a_sin && apic < 1.05 * a_tan,
        "APIC: {apic} m/s², expected {a_sin}–{a_tan}"
    );
    // Even from the start at the tan φ rate the layer would still move at 0.37 m/s at 0.1 s.
    let blend = layer_velocity(VelocityUpdate::Flip { pic: 0.05 }, &[0.1])[0];
    println!("FLIP + 5 % PIC: {blend:.3} m/s at 0.1 s");
    assert!(
        blend < 0.5 * (0.5 - 0.1 * a_tan),
        "FLIP + 5 % PIC: {blend} m/s at 0.1 s"
    );
}
