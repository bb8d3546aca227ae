//! Velocity transfers of the MPM: APIC (Jiang et al. 2015) carries an affine velocity field
//! through particle-to-grid and grid-to-particle exactly and keeps a spinning body spinning;
//! PIC smears both. Run with `cargo test --release`.

use decomposition::SingleProcess;
use grainflow::mpm::*;
use grainflow::mpm::{shape, transfer};

fn setup(shape: ShapeKind, update: VelocityUpdate, spec: GridSpec, e: f64) -> MpmSetup {
    let open = Boundaries::floor(Side::Open);
    let m = Material::linear_elastic(e, 0.3, 1000.0);
    MpmSetup {
        velocity_update: update,
        ..MpmSetup::plain(spec, shape, open, [0.0; 2], m)
    }
}

/// A disk of radius `r` (m) centred at `c` with 2×2 points per cell.
fn disk(spec: &GridSpec, c: [f64; 2], r: f64) -> Points {
    let mut pts = Points::default();
    let mut id = 0;
    let n = 48;
    let vertices = (0..n)
        .map(|k| {
            let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            [c[0] + r * t.cos(), c[1] + r * t.sin()]
        })
        .collect();
    fill(
        &mut pts,
        &Shape::Polygon(vertices),
        spec,
        2,
        1000.0,
        0,
        &mut id,
    );
    pts
}

/// APIC moment B = A D_p (m²/s) of point `i` for the velocity gradient `a` (1/s), D_p the
/// diagonal of Σ S (x_I − x_p)(x_I − x_p)ᵀ at its position.
fn moment(p: &Points, i: usize, kind: ShapeKind, h: f64, a: [f64; 4]) -> [f64; 4] {
    let half = shape::half_lengths(kind, p.half0[i], &p.defgrad[i], h);
    let d: Vec<f64> = (0..2)
        .map(|k| {
            let x = p.pos[i][k];
            let cell = (x / h).floor();
            let w = shape::weights_1d(kind, x, cell as i64, h, half[k]);
            transfer::inertia_1d(&w, cell as u32, h, x)
        })
        .collect();
    [a[0] * d[0], a[1] * d[1], a[2] * d[0], a[3] * d[1]]
}

/// Largest |v_p − (A x_p + b)| (m/s) and |B_p − A D_p| (m²/s) over the points after one step
/// from the affine field v = A x + b (A a rigid rotation, so no stress arises), matched by
/// id to the starting positions.
fn one_step_error(shape: ShapeKind, update: VelocityUpdate) -> (f64, f64) {
    let spec = GridSpec {
        nx: 20,
        ny: 20,
        h: 0.1,
    };
    let a = [0.0, -2.0, 2.0, 0.0];
    let b = [0.3, -0.1];
    let mut pts = disk(&spec, [1.0, 1.0], 0.55);
    let start: Vec<[f64; 2]> = pts.pos.clone();
    let want_b: Vec<[f64; 4]> = (0..pts.len())
        .map(|i| moment(&pts, i, shape, spec.h, a))
        .collect();
    for (i, moment) in want_b.iter().enumerate() {
        let [x, y] = pts.pos[i];
        pts.vel[i] = [a[0] * x + a[1] * y + b[0], a[2] * x + a[3] * y + b[1]];
        if update == VelocityUpdate::Apic {
            pts.affine[i] = *moment;
        }
    }
    let mut sys =
        MpmSystem::new(setup(shape, update, spec, 1e6), pts, &SingleProcess).expect("system");
    sys.step(&SingleProcess).expect("step");
    let p = &sys.points;
    let (mut ev, mut ec) = (0.0f64, 0.0f64);
    for i in 0..p.len() {
        let [x, y] = start[p.id[i] as usize];
        let want = [a[0] * x + a[1] * y + b[0], a[2] * x + a[3] * y + b[1]];
        ev = ev.max((p.vel[i][0] - want[0]).hypot(p.vel[i][1] - want[1]));
        if update == VelocityUpdate::Apic {
            // B is taken at the start position (before the move): A D_p there.
            let want = want_b[p.id[i] as usize];
            for (got, want) in p.affine[i].iter().zip(want) {
                ec = ec.max((got - want).abs());
            }
        }
    }
    (ev, ec)
}

#[test]
fn apic_carries_an_affine_velocity_field_exactly() {
    // Transfers exact for affine fields (Jiang et al. 2015, §5): round-off only. Speeds are
    // about 1 m/s and B about 1e-3 m²/s. cpGIMP's domain follows F, which the stress update
    // stretches by O((ω Δt)²) before the grid-to-particle pass: a point on the edge of a
    // node's support then reaches a node without mass (velocity 0) with a weight of
    // O((ω Δt)⁴) ~ 1e-11, hence its own bound.
    for (shape, tol) in [
        (ShapeKind::Linear, 1e-12),
        (ShapeKind::Gimp, 1e-12),
        (ShapeKind::CpGimp, 1e-10),
    ] {
        let (ev, eb) = one_step_error(shape, VelocityUpdate::Apic);
        eprintln!("{shape:?}: |Δv| {ev:e}, |ΔB| {eb:e}");
        assert!(
            ev < tol && eb < 1e-2 * tol,
            "{shape:?}: |Δv| {ev:e}, |ΔB| {eb:e}"
        );
        // PIC averages the field over each node's support: wrong at the disk's edge.
        let (ev_pic, _) = one_step_error(shape, VelocityUpdate::Flip { pic: 1.0 });
        assert!(ev_pic > 1e-2, "{shape:?}: PIC error {ev_pic:e}");
    }
}

/// Angular velocity Σ m (x − x̄) × v / Σ m |x − x̄|² (rad/s) and kinetic energy of the points.
fn spin(p: &Points) -> (f64, f64) {
    let m: f64 = p.mass.iter().sum();
    let c = (0..p.len()).fold([0.0; 2], |c, i| {
        [
            c[0] + p.mass[i] * p.pos[i][0] / m,
            c[1] + p.mass[i] * p.pos[i][1] / m,
        ]
    });
    let (mut l, mut j, mut ke) = (0.0, 0.0, 0.0);
    for i in 0..p.len() {
        let (x, y) = (p.pos[i][0] - c[0], p.pos[i][1] - c[1]);
        let [u, v] = p.vel[i];
        l += p.mass[i] * (x * v - y * u);
        j += p.mass[i] * (x * x + y * y);
        ke += 0.5 * p.mass[i] * (u * u + v * v);
    }
    (l / j, ke)
}

/// Angular momentum Σ_I m_I x_I × v_I (kg m²/s per metre) of the grid after the last step.
fn grid_angular_momentum(sys: &MpmSystem) -> f64 {
    let spec = &sys.setup.spec;
    let n = &sys.nodes;
    let mut l = 0.0;
    for i in -1..=spec.nx as i64 + 1 {
        let (r0, r1) = n.active[(i + 1) as usize];
        for r in r0 as usize..r1 as usize {
            let k = (i + 1) as usize * spec.rows() + r;
            let (x, y) = (i as f64 * spec.h, (r as i64 - 1) as f64 * spec.h);
            l += n.mass[k] * (x * n.v_new[k][1] - y * n.v_new[k][0]);
        }
    }
    l
}

/// A free elastic disk spinning at ω = 1 rad/s for a quarter turn: ω_end/ω₀, KE_end/KE₀ of
/// the points and the relative drift of the grid's angular momentum.
fn spinning_disk(shape: ShapeKind, update: VelocityUpdate) -> (f64, f64, f64) {
    let spec = GridSpec {
        nx: 60,
        ny: 60,
        h: 0.05,
    };
    let c = [1.5, 1.5];
    let mut pts = disk(&spec, c, 0.5);
    for i in 0..pts.len() {
        let (x, y) = (pts.pos[i][0] - c[0], pts.pos[i][1] - c[1]);
        pts.vel[i] = [-y, x];
        if update == VelocityUpdate::Apic {
            pts.affine[i] = moment(&pts, i, shape, spec.h, [0.0, -1.0, 1.0, 0.0]);
        }
    }
    let (w0, ke0) = spin(&pts);
    let s = setup(shape, update, spec, 1e5);
    let steps = (std::f64::consts::FRAC_PI_2 / s.dt).ceil() as usize;
    let mut sys = MpmSystem::new(s, pts, &SingleProcess).expect("system");
    sys.step(&SingleProcess).expect("step");
    let l0 = grid_angular_momentum(&sys);
    for _ in 1..steps {
        sys.step(&SingleProcess).expect("step");
    }
    let (w, ke) = spin(&sys.points);
    eprintln!(
        "{update:?}: ω {w} KE {ke} L {}",
        grid_angular_momentum(&sys) / l0 - 1.0
    );
    (w / w0, ke / ke0, grid_angular_momentum(&sys) / l0 - 1.0)
}

#[test]
fn apic_keeps_a_free_disk_spinning() {
    // A quarter turn (730 steps) of a free elastic disk, uGIMP. APIC conserves the grid's
    // angular momentum to round-off (Jiang et al. 2015, §5.2: the transfers and a symmetric
    // stress do) and keeps the spin: the disk's own ω changes by the explicit time
    // integration only (+0.23 % here, halving with Δt). PIC stops it (Jiang et al. 2015,
    // fig. 1), and pure FLIP loses angular momentum to its noise.
    let (w, ke, l) = spinning_disk(ShapeKind::Gimp, VelocityUpdate::Apic);
    // Round-off accumulated over 730 steps of sums over ~10⁴ node slots.
    assert!(l.abs() < 1e-9, "APIC: grid angular momentum drift {l:e}");
    assert!(
        (w - 1.0).abs() < 0.005 && (ke - 1.0).abs() < 0.005,
        "APIC: ω {w}, KE {ke}"
    );
    let (w, ke, l) = spinning_disk(ShapeKind::Gimp, VelocityUpdate::Flip { pic: 1.0 });
    assert!(
        w < 0.01 && ke < 0.01 && l < -0.99,
        "PIC: ω {w}, KE {ke}, L drift {l}"
    );
    let (_, _, l) = spinning_disk(ShapeKind::Gimp, VelocityUpdate::Flip { pic: 0.0 });
    assert!(l < -1e-3, "FLIP: L drift {l}");
}
