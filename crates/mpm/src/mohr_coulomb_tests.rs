//! Tests of the Mohr–Coulomb return mapping against hand-computed cases.
use super::*;
use Region::*;

/// E = 2.5 MPa, ν = 0.25 → λ = G = 1 MPa exactly: D = 1e6 [[3,1,1],[1,3,1],[1,1,3]].
fn mat(phi: f64, psi: f64, c: f64, st: f64) -> MohrCoulomb {
    MohrCoulomb {
        youngs_modulus_pa: 2.5e6,
        poisson_ratio: 0.25,
        friction_deg: phi,
        dilation_deg: psi,
        cohesion_pa: c,
        tension_cutoff_pa: st,
        softening: None,
        inertial_friction: None,
    }
}

/// c with 2c cos 30° = 10 kPa (c ≈ 5773.5 Pa); the apex c cot 30° is then 10 kPa.
fn c30() -> f64 {
    5e3 / 30f64.to_radians().cos()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1.0)
}

/// Update with a zero increment (the given stress is the trial).
fn ret(m: &MohrCoulomb, trial: [f64; 4], eps_p: f64) -> (Outcome, [f64; 4], f64) {
    let (mut st, mut ep) = (trial, eps_p);
    let o = m.update(&mut st, [0.0; 3], &mut ep);
    (o, st, ep)
}

/// Values of `st` on the principal axes of `ax`, in the sorted slots of `ax`.
fn on_axes(ax: &Principal, st: &[f64; 4]) -> [f64; 3] {
    let (c2, s2) = axes(ax);
    // n·σ·n = m ± ((σxx−σyy)/2 cos 2θ + σxy sin 2θ) on the major/minor in-plane axis.
    let (m, r) = (
        0.5 * (st[0] + st[1]),
        0.5 * (st[0] - st[1]) * c2 + st[2] * s2,
    );
    match ax.zz {
        0 => [st[3], m + r, m - r],
        1 => [m + r, st[3], m - r],
        _ => [m + r, m - r, st[3]],
    }
}

#[test]
fn elastic_increment_is_hooke() {
    // λ = G = 1e6, tr Δε = −1e-5 → λ tr = −10 Pa; Δσxx = −10 + 2e6·1e-5 = 10,
    // Δσyy = −10 − 2e6·2e-5 = −50, Δσxy = 2e6·3e-6 = 6, Δσzz = −10. Far inside the surface.
    let m = mat(30.0, 0.0, 1e6, 1e9);
    let (mut st, mut ep) = ([-1e4, -2e4, 1e3, -1.5e4], 0.25);
    let o = m.update(&mut st, [1e-5, -2e-5, 3e-6], &mut ep);
    assert_eq!((o.yielded, o.iterations, o.region), (false, 0, Elastic));
    let want = [-1e4 + 10.0, -2e4 - 50.0, 1e3 + 6.0, -1.5e4 - 10.0];
    assert!((0..4).all(|i| (st[i] - want[i]).abs() < 1e-9), "{st:?}");
    assert_eq!(ep, 0.25);
}

#[test]
fn plane_return_matches_closed_form() {
    // Trial principal (0, −20e3, −60e3) = (σyy, σzz, σxx); φ = 30°, 2c cos φ = 1e4:
    // f = 60e3 − 30e3 − 1e4 = 20e3, a = (1.5, 0, −0.5).
    // ψ = 30°: b = a, D b = 1e6 (4, 1, 0), a·Db = 6e6, Δλ = 1/300 →
    //   σ = (−40e3/3, −70e3/3, −60e3), Δε_p = Δλ √(2/3 (1.5² + 0.5²)) = √(5/3)/300.
    // ψ = 0: b = (1, 0, −1), D b = 1e6 (2, 0, −2), a·Db = 4e6, Δλ = 5e-3 →
    //   σ = (−10e3, −20e3, −50e3), Δε_p = 5e-3 √(4/3).
    let cases = [
        (
            30.0,
            [-40.0 / 3.0, -70.0 / 3.0, -60.0],
            (5.0f64 / 3.0).sqrt() / 300.0,
        ),
        (0.0, [-10.0, -20.0, -50.0], 5e-3 * (4.0f64 / 3.0).sqrt()),
    ];
    for (psi, want_kpa, dep) in cases {
        let want = want_kpa.map(|v| 1e3 * v);
        let (o, st, ep) = ret(&mat(30.0, psi, c30(), 1e9), [-60e3, 0.0, 0.0, -20e3], 0.0);
        assert_eq!((o.region, o.iterations, o.yielded), (Plane, 1, true));
        let got = [st[1], st[3], st[0]];
        assert!((0..3).all(|i| close(got[i], want[i], 1e-9)), "{got:?}");
        assert!(st[2].abs() < 1e-9 && close(ep, dep, 1e-9), "{ep} vs {dep}");
        assert!(MohrCoulomb::yield_value(&st, 30.0, c30()).abs() < 1e-6 * 6e4);
        // σ_trial − σ is parallel to D ∂g/∂σ: zero cross product.
        let sg = psi.to_radians().sin();
        let b = d_mul([1.0 + sg, 0.0, sg - 1.0], 1e6, 1e6);
        let ds = [-got[0], -20e3 - got[1], -60e3 - got[2]];
        let cr = [
            ds[1] * b[2] - ds[2] * b[1],
            ds[2] * b[0] - ds[0] * b[2],
            ds[0] * b[1] - ds[1] * b[0],
        ];
        assert!(dot(cr, cr).sqrt() <= 1e-9 * (dot(ds, ds) * dot(b, b)).sqrt());
    }
}

#[test]
fn edges_and_apex() {
    // φ = 30°, 2c cos φ = 1e4, apex 1e4 Pa. Hand solutions of [a_i·D b_j] Δλ = f_i:
    // compression, trial (0, −1e3, −60e3), ψ = 30°: A = [[6, 1.5], [1.5, 6]]e6,
    //   f = (20e3, 18.5e3), Δλ = (2.7333e-3, 2.4e-3) → σ1 = σ2 = −40e3/3, σ3 = −60e3;
    //   ψ = 0: A = [[4, 1], [1, 4]]e6, Δλ = (4.1e-3, 3.6e-3) → (−8200, −8200, −44600).
    // extension, trial (0, −59e3, −60e3), ψ = 30°: A = [[6, 5.5], [5.5, 6]]e6,
    //   f = (20e3, 19.5e3), Δλ = (12.75, 7)/5.75 e-3 → σ1 = −316e3/23, σ2 = σ3 = −1408e3/23;
    //   ψ = 0: A = [[4, 3], [3, 4]]e6, Δλ = (21.5, 18)/7 e-3 → (−79e3/7, −377e3/7, −377e3/7).
    // apex: trial (50e3, 49e3, 48e3) fails both edges (σ3 > σ1, resp. σ2 > σ1) → 1e4;
    //   with c = 0 the trial (1e3, 900, 800) goes to 0.
    // Stresses below in kPa.
    let (c, e, x) = (c30(), -377.0 / 7.0, -1408.0 / 23.0);
    let (ec, ee) = (EdgeCompression, EdgeExtension);
    let cases = [
        (
            30.0,
            c,
            [0.0, -1.0, -60.0],
            ec,
            [-40.0 / 3.0, -40.0 / 3.0, -60.0],
        ),
        (0.0, c, [0.0, -1.0, -60.0], ec, [-8.2, -8.2, -44.6]),
        (30.0, c, [0.0, -59.0, -60.0], ee, [-316.0 / 23.0, x, x]),
        (0.0, c, [0.0, -59.0, -60.0], ee, [-79.0 / 7.0, e, e]),
        (30.0, c, [50.0, 49.0, 48.0], Apex, [10.0; 3]),
        (0.0, c, [50.0, 49.0, 48.0], Apex, [10.0; 3]),
        (10.0, c, [50.0, 49.0, 48.0], Apex, [10.0; 3]),
        (30.0, 0.0, [1.0, 0.9, 0.8], Apex, [0.0; 3]),
        (0.0, 0.0, [1.0, 0.9, 0.8], Apex, [0.0; 3]),
    ];
    for (psi, c, t, region, want) in cases {
        let (t, want) = (t.map(|v| 1e3 * v), want.map(|v| 1e3 * v));
        // σxx = σ1, σyy = σ3, σzz = σ2: zz in the middle slot.
        let (o, st, ep) = ret(&mat(30.0, psi, c, 1e9), [t[0], t[2], 0.0, t[1]], 0.0);
        let s = principal(&st).s;
        assert_eq!(o.region, region, "ψ = {psi}, {t:?} → {s:?}");
        assert!(
            (0..3).all(|i| close(s[i], want[i], 1e-9)),
            "{s:?} vs {want:?}"
        );
        assert!(MohrCoulomb::yield_value(&st, 30.0, c) <= 1e-9 * 6e4);
        assert!(s[0] >= s[1] && s[1] >= s[2] && ep > 0.0);
    }
}

#[test]
fn associated_return_is_the_closest_point() {
    // With ψ = φ the return is the projection onto the convex elastic domain in the energy
    // norm ⟨a, b⟩ = a : D⁻¹ : b, so ⟨σ_tr − σ, σ* − σ⟩ ≤ 0 for every admissible σ*; the other
    // results serve as σ*. This checks the whole region logic (plane, both edges, apex).
    let m = mat(35.0, 35.0, 2e4, 1e9);
    let mut seed = 7u64;
    let mut rnd = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let pairs: Vec<_> = (0..300)
        .map(|_| {
            let t = [3e4, 3e4, 0.0, 3e4].map(|v| v + 1e5 * rnd());
            (t, ret(&m, t, 0.0).1)
        })
        .collect();
    let inner = |a: [f64; 4], b: [f64; 4]| {
        dot(d_inv_mul([a[0], a[1], a[3]], 1e6, 1e6), [b[0], b[1], b[3]]) + a[2] * b[2] / 1e6
    };
    for (t, s) in &pairs {
        let r = [0, 1, 2, 3].map(|i| t[i] - s[i]);
        for (_, q) in &pairs {
            let v = inner(r, [0, 1, 2, 3].map(|i| q[i] - s[i]));
            assert!(v <= 1e-9 * 1e-2 * 1e5, "{t:?} → {s:?}: {v}");
        }
    }
}

#[test]
fn rotation_invariance() {
    // The return changes principal values only, so rotating the trial by α and the result
    // back by −α reproduces the unrotated result (to round-off).
    fn rot(s: [f64; 4], a: f64) -> [f64; 4] {
        let (sn, cs) = a.sin_cos();
        let (c2, s2, sc) = (cs * cs, sn * sn, sn * cs);
        [
            c2 * s[0] + s2 * s[1] + 2.0 * sc * s[2],
            s2 * s[0] + c2 * s[1] - 2.0 * sc * s[2],
            sc * (s[1] - s[0]) + (c2 - s2) * s[2],
            s[3],
        ]
    }
    let m = mat(30.0, 5.0, c30(), 5e3);
    for tr in [
        [-60e3, 0.0, 0.0, -20e3],
        [-30e3, -10e3, 25e3, -20e3],
        [-60e3, 0.0, 0.0, -1e3],
        [20e3, -3e3, 4e3, 1e3],
        [50e3, 48e3, 0.0, 49e3],
    ] {
        for a in [0.3, 1.1, -2.0] {
            let ((o0, s0, e0), (o1, s1, e1)) = (ret(&m, tr, 0.0), ret(&m, rot(tr, a), 0.0));
            let back = rot(s1, -a);
            assert!(o0.region == o1.region && close(e0, e1, 1e-9));
            assert!(
                (0..4).all(|i| (back[i] - s0[i]).abs() < 6e-5),
                "{back:?} {s0:?}"
            );
        }
    }
}

#[test]
fn tension_cutoff_caps_principal_stresses() {
    // 2c cos 30° = 1e6 (apex 1e6 Pa), σt = 1e4. Uniaxial σxx = 5e4: f = 7.5e4 − 1e6 < 0,
    // only the cutoff acts: Δλ = 4e4/(λ+2G) = 4e4/3e6, σxx = 1e4, σyy = σzz = −λΔλ = −4e4/3.
    let m = mat(30.0, 0.0, 100.0 * c30(), 1e4);
    let (o, st, _) = ret(&m, [5e4, 0.0, 0.0, 0.0], 0.0);
    assert_eq!(o.region, TensionCutoff);
    let want = [1e4, -4e4 / 3.0, 0.0, -4e4 / 3.0];
    assert!((0..4).all(|i| close(st[i], want[i], 1e-12)), "{st:?}");
    // Hydrostatic 5e4 (MC-admissible): all three exceed σt and all come back to σt.
    let (_, st, _) = ret(&m, [5e4, 5e4, 0.0, 5e4], 0.0);
    assert!([0, 1, 3].iter().all(|&i| close(st[i], 1e4, 1e-12)) && st[2] == 0.0);
    // (5e4, 2e4, 0): after the σ1 return σzz = 2e4 − 4e4/3 < σt, so σ1 alone is active.
    let (_, st, _) = ret(&m, [5e4, 0.0, 0.0, 2e4], 0.0);
    assert!(close(st[0], 1e4, 1e-12) && close(st[3], 2e4 - 4e4 / 3.0, 1e-12));
}

fn soft_mat() -> MohrCoulomb {
    let mut m = mat(30.0, 0.0, c30(), 1e9);
    m.softening = Some(Softening {
        residual_friction_deg: 20.0,
        residual_cohesion_pa: 0.2 * c30(),
        plastic_strain_start: 0.002,
        plastic_strain_end: 0.01,
    });
    m
}

#[test]
fn softening_interpolates_linearly() {
    // ε_p = 0.004 is a quarter of the way from 0.002 to 0.01: φ = 27.5°, c = 0.8 c0.
    let m = soft_mat();
    assert_eq!(m.strength_at(0.001), (30.0, c30()));
    assert_eq!(m.strength_at(0.02), (20.0, 0.2 * c30()));
    let (phi, c) = m.strength_at(0.004);
    assert!(close(phi, 27.5, 1e-12) && close(c, 0.8 * c30(), 1e-12));
}

#[test]
fn softening_return_is_consistent() {
    // The plane trial of the closed-form test (Δε_p ≈ 5.8e-3 at peak strength), a larger one
    // that passes the end of softening, and an edge trial: the iteration converges, f = 0 at
    // strength_at(ε_p), and ε_p − ε_p,n = √(2/3 |D⁻¹(σ_tr − σ)|²) of the returned stress.
    let m = soft_mat();
    for trial in [
        [-60e3, 0.0, 0.0, -20e3],
        [-200e3, 0.0, 0.0, -50e3],
        [-60e3, -1e3, 0.0, 0.0],
    ] {
        let (o, st, ep) = ret(&m, trial, 0.001);
        assert!(o.yielded && (2..MAX_ITER).contains(&o.iterations), "{o:?}");
        let (phi, c) = m.strength_at(ep);
        assert!(phi < 30.0 && MohrCoulomb::yield_value(&st, phi, c).abs() < 1e-6 * 6e4);
        let (pt, ps) = (principal(&trial).s, principal(&st).s);
        let e = d_inv_mul([0, 1, 2].map(|i| pt[i] - ps[i]), 1e6, 1e6);
        assert!(
            close(ep - 0.001, (2.0 / 3.0 * dot(e, e)).sqrt(), 1e-8),
            "{ep}"
        );
    }
}

#[test]
fn randomized_consistency() {
    // Random materials (φ ≤ 45°, ψ ≤ φ, c ≥ 0, σt below or above the apex, some softening),
    // stresses and increments: every result is finite and admissible (MC and cutoff), ε_p
    // does not decrease, the principal values keep the trial's order on the trial's axes,
    // and every region occurs.
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut regions = [0usize; 6];
    for _ in 0..20000 {
        let (phi, c) = (45.0 * rnd(), if rnd() < 0.3 { 0.0 } else { 1e5 * rnd() });
        // σt below the apex c cot φ (acts) or above it (never acts).
        let apex = c / phi.to_radians().tan().max(1e-7);
        let cut = apex * if rnd() < 0.5 { rnd() } else { 2.0 };
        let mut m = mat(phi, phi * rnd(), c, cut);
        (m.youngs_modulus_pa, m.poisson_ratio) = (10f64.powf(6.0 + 3.0 * rnd()), 0.45 * rnd());
        if rnd() < 0.3 {
            m.softening = Some(Softening {
                residual_friction_deg: phi * rnd(),
                residual_cohesion_pa: c * rnd(),
                plastic_strain_start: 0.01 * rnd(),
                plastic_strain_end: 0.01 + 0.05 * rnd(),
            });
        }
        let s = 10f64.powf(3.0 + 3.0 * rnd());
        let mut st = [0.0; 4].map(|_: f64| s * (2.0 * rnd() - 1.5));
        let de = s / m.youngs_modulus_pa;
        let d = [0.0; 3].map(|_: f64| de * (2.0 * rnd() - 1.0));
        let mut ep = 0.02 * rnd() * rnd().round();
        let ep0 = ep;
        // The trial, for its principal axes and the scale.
        let (lam, g) = lame(m.youngs_modulus_pa, m.poisson_ratio);
        let tr = d[0] + d[1];
        let trial = [
            st[0] + lam * tr + 2.0 * g * d[0],
            st[1] + lam * tr + 2.0 * g * d[1],
            st[2] + 2.0 * g * d[2],
            st[3] + lam * tr,
        ];
        let pt = principal(&trial);
        let scale = pt.s[0].abs() + pt.s[2].abs() + c + 1.0;
        let o = m.update(&mut st, d, &mut ep);
        regions[o.region as usize] += 1;
        let (phi_n, c_n) = m.strength_at(ep);
        assert!(st.iter().all(|v| v.is_finite()), "{m:?} {trial:?} → {st:?}");
        let f = MohrCoulomb::yield_value(&st, phi_n, c_n);
        assert!(f <= 1e-9 * scale, "{m:?} {trial:?}");
        assert!(principal(&st).s[0] <= m.tension_cutoff_pa + 1e-9 * scale);
        assert!(ep >= ep0 && ep.is_finite() && o.iterations <= MAX_ITER);
        let v = on_axes(&pt, &st);
        let tol = 1e-9 * scale;
        assert!(v[0] >= v[1] - tol && v[1] >= v[2] - tol, "{v:?}");
    }
    assert!(regions.iter().all(|&n| n > 0), "{regions:?}");
}
