//! Channel flows against analytic solutions: Poiseuille, Couette, and f32 against f64.
mod common;
use common::*;
use grainflow::run::Precision;

/// Body-force Poiseuille (analytic: u = g y (H − y) / 2ν). BGK at τ = ½ + √3/4 puts
/// half-way walls exactly half-way (Ginzburg & d'Humières 2003): the scene demands a peak
/// error ≤ 0.01 % (seed study: 0.009 %) and an L2 profile error ≤ 1e-4.
#[test]
fn poiseuille_f64_and_f32() {
    let path = root().join("jobs/poiseuille/scene.toml");
    let (s64, _d) = run_scene(&path, Some(Precision::F64));
    assert_checks_pass(&s64);
    let (s32, _d) = run_scene(&path, Some(Precision::F32));
    let (e64, e32) = (
        result(&s64, "poiseuille.l2_rel_error"),
        result(&s32, "poiseuille.l2_rel_error"),
    );
    eprintln!(
        "Poiseuille L2 error: f64 {e64:.3e}, f32 {e32:.3e} ({:.0}x)",
        e32 / e64
    );
    // f32 round-off of the small per-step force increments dominates; it must still be
    // well inside 0.1 % and must not be better than f64 (that would mean f64 is broken).
    assert!(e32 < 1e-3 && e32 > e64, "f32 {e32} f64 {e64}");
}

/// TRT with Λ = 3/16 is exact for Poiseuille at any τ (Ginzburg & d'Humières 2003).
#[test]
fn poiseuille_trt_is_exact_at_any_tau() {
    let text = scene_variant(
        "jobs/poiseuille/scene.toml",
        &[
            (
                "relaxation_time = 0.9330127018922193",
                "relaxation_time = 0.62",
            ),
            (
                "collision = { model = \"bgk\" }",
                "collision = { model = \"trt\" }",
            ),
            ("end_time_s = 240.0", "end_time_s = 900.0"),
        ],
    );
    let (s, _d) = run_text(&text, &root().join("jobs/poiseuille"), None);
    assert_checks_pass(&s);
    assert!(result(&s, "poiseuille.max_rel_error") < 1e-5);
}

/// Couette with a Ladd moving wall: linear profile, L2 error ≤ 1e-3. A point probe between
/// cell centres interpolates them: on the linear profile it reads u = U y / H (to 1e-6 of U;
/// the nearest cell centre, 0.2 mm away, would read 0.6 % of U off), and one on the north
/// wall reads the cells inside the domain.
#[test]
fn couette() {
    let text = scene_variant(
        "jobs/couette/scene.toml",
        &[(
            "[run]",
            "[[probes]]\nkind = \"point\"\nname = \"between\"\nposition_m = [0.002, 0.0137]\n\n\
             [[probes]]\nkind = \"point\"\nname = \"lid\"\nposition_m = [0.002, 0.0319]\n\n[run]",
        )],
    );
    let (s, d) = run_text(&text, &root().join("jobs/couette"), None);
    assert_checks_pass(&s);
    let last_ux = |probe: &str| {
        let rows = std::fs::read_to_string(d.path().join(format!("probe_{probe}.csv"))).unwrap();
        let last = rows.lines().last().unwrap().to_string();
        last.split(',').nth(2).unwrap().parse::<f64>().unwrap()
    };
    let (u, h) = (0.01, 0.032);
    let between = last_ux("between");
    eprintln!(
        "u(13.7 mm) = {between:.6e} m/s, U y / H = {:.6e}",
        u * 0.0137 / h
    );
    assert!((between - u * 0.0137 / h).abs() < 1e-6 * u);
    // Within half a cell of the lid: the row of centres below it (31.5 mm).
    assert!((last_ux("lid") - u * 0.0315 / h).abs() < 1e-6 * u);
}

/// Mass in a closed periodic box is constant to 1e-12 (relative) over 10⁴ steps in f64.
#[test]
fn mass_conservation() {
    let (s, _d) = run_scene(
        &root().join("jobs/conservation/scene.toml"),
        Some(Precision::F64),
    );
    assert_checks_pass(&s);
    assert_eq!(s.run.steps, 10_000);
    // Every run reports its drift per 10⁴ steps; here that is the whole run's.
    let drift = result(&s, "run.mass_drift_per_1e4_steps");
    assert!(drift.abs() <= 1e-12, "{drift}");
    assert!((drift - result(&s, "mass.relative_drift")).abs() < 1e-15);
}
