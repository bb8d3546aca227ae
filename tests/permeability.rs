//! Permeability of square arrays of fixed disks against Sangani & Acrivos (1982, Table 1),
//! for every coupling scheme; what the hydrodynamic radius does to it; and grains held in
//! place (`fixed = true`). The full sweep (c = 0.05–0.5, 8–64 cells per diameter) is
//! `jobs/permeability/sweep.py`; its table is in docs/validation.md.
mod common;
use common::*;
use grainflow::run::Status;

const SCENE: &str = "jobs/permeability/square-array.toml";

/// The canonical scene (c = 0.2, 16 cells per diameter) with `scheme`, and the disk's
/// hydrodynamic radius ratio.
fn array(scheme: &str, ratio: f64) -> String {
    scene_variant(
        SCENE,
        &[(
            "scheme = \"interpolated\"",
            &format!("scheme = \"{scheme}\"\nhydrodynamic_radius_ratio = {ratio}"),
        )],
    )
}

/// Every scheme's drag on the disks at c = 0.2, 16 cells per diameter and τ = 0.6 lies within
/// 5 % of Sangani & Acrivos' K = 51.53 (measured: bounce-back +2.4 %, interpolated −0.1 %,
/// partially saturated −3.0 %), in Stokes flow.
#[test]
fn square_array_drag_matches_sangani_acrivos() {
    for scheme in ["bounce-back", "interpolated", "psm"] {
        let (s, _out) = run_text(&array(scheme, 1.0), &root().join("jobs/permeability"), None);
        let k = result(&s, "permeability.drag_factor");
        let c = result(&s, "permeability.solid_fraction");
        eprintln!("{scheme}: c = {c:.4}, K = {k:.2} (Sangani & Acrivos 51.53)");
        assert!((c - 0.2).abs() < 1e-3, "{scheme}: solid fraction {c}");
        assert_checks_pass(&s);
        assert!(s.run.checks.iter().all(|c| c.passed), "{scheme}");
    }
}

/// A hydrodynamic radius below the contact radius opens the pores: at the same disks
/// (contact fraction 0.2), r_h / r = 0.8 leaves the fluid a solid fraction of 0.128, and
/// Darcy's k = π r_h² / (c K) rises by the table's factor
/// (0.64 × 0.2 × 51.53) / (0.128 × 30.45) = 1.69 (K(0.128) = 30.45 interpolated in ln K).
#[test]
fn a_smaller_hydrodynamic_radius_raises_the_permeability() {
    let run = |ratio: f64| {
        let (s, _out) = run_text(
            &array("interpolated", ratio),
            &root().join("jobs/permeability"),
            None,
        );
        assert_eq!(s.run.status, Status::Ok, "{:?}", s.run.error);
        (
            result(&s, "permeability.permeability_m2"),
            result(&s, "permeability.solid_fraction"),
            result(&s, "permeability.sangani_acrivos_ratio"),
        )
    };
    let (k1, c1, _) = run(1.0);
    let (k08, c08, dev08) = run(0.8);
    eprintln!("r_h/r = 1: k = {k1:.4e} m² at c = {c1:.3}; 0.8: k = {k08:.4e} m² at c = {c08:.3}");
    assert!(
        (c08 / c1 - 0.64).abs() < 1e-9,
        "c scales with r_h²: {c08} vs {c1}"
    );
    assert!(
        (k08 / k1 / 1.69 - 1.0).abs() < 0.05,
        "k rises by {} at r_h/r = 0.8, the table by 1.69",
        k08 / k1
    );
    // At 12.8 cells per hydrodynamic diameter the drag is still within 5 % of the table.
    assert!((dev08 - 1.0).abs() < 0.05, "K / K_SA = {dev08}");
}

/// A grain resting on a fixed one: the fixed grain's position keeps its bits through the
/// run, and the free grain comes to rest on top of it, pressed in by its weight over the
/// normal stiffness (δ = m g / k_n).
#[test]
fn a_fixed_grain_holds_a_free_one() {
    let scene = r#"title = "a grain resting on a fixed one"
[domain]
size_m = [0.02, 0.02]
[grains]
density_kg_m3 = 2500.0
[grains.contact]
normal_stiffness_n_m2 = 1e5
tangential_stiffness_n_m2 = 5e4
restitution = 0.5
friction = 0.5
rolling_friction = 0.1
[grains.sample]
kind = "list"
grains = [
  { position_m = [0.01, 0.005], radius_m = 0.001, fixed = true },
  { position_m = [0.01, 0.009], radius_m = 0.001 },
]
[run]
end_time_s = 0.5
[output]
every_steps = 1000
"#;
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("fixed.toml");
    std::fs::write(&path, scene).unwrap();
    let out = tmp.path().join("out");
    run_ok(1, path.to_str().unwrap(), &out, &[]);
    let snaps = grain_snapshots(&out);
    let positions: Vec<&Vec<f64>> = snaps
        .iter()
        .filter(|(n, _)| n.ends_with("/position"))
        .map(|(_, v)| v)
        .collect();
    assert!(positions.len() > 5);
    for p in &positions {
        assert_eq!(p[0].to_bits(), 0.01f64.to_bits());
        assert_eq!(p[1].to_bits(), 0.005f64.to_bits());
    }
    let last = positions.last().unwrap();
    let weight = 2500.0 * std::f64::consts::PI * 1e-6 * 9.81;
    let overlap = 0.002 - (last[4] - 0.005);
    eprintln!(
        "overlap {overlap:.4e} m, m g / k_n = {:.4e} m",
        weight / 1e5
    );
    assert!(
        (last[3] - 0.01).abs() < 1e-9,
        "slid off sideways: x = {}",
        last[3]
    );
    assert!((overlap / (weight / 1e5) - 1.0).abs() < 0.01);
}

/// A fixed grain given a velocity, and a permeability analysis of free grains, are refused
/// with the key named.
#[test]
fn fixed_grains_are_validated() {
    let moving = scene_variant(
        SCENE,
        &[(
            "radius_m = 8.074e-4, fixed = true",
            "radius_m = 8.074e-4, fixed = true, velocity_m_s = [0.1, 0.0]",
        )],
    );
    let e = grainflow::scene::parse(&moving, &root().join(SCENE)).unwrap_err();
    assert!(e.to_string().contains("fixed"), "{e}");
    let free = scene_variant(SCENE, &[(", fixed = true", "")]);
    let e = grainflow::scene::parse(&free, &root().join(SCENE)).unwrap_err();
    assert!(e.to_string().contains("held in place"), "{e}");
    let walled = scene_variant(
        SCENE,
        &[
            (
                "south = { kind = \"periodic\" }",
                "south = { kind = \"wall\" }",
            ),
            (
                "north = { kind = \"periodic\" }",
                "north = { kind = \"wall\" }",
            ),
        ],
    );
    let e = grainflow::scene::parse(&walled, &root().join(SCENE)).unwrap_err();
    assert!(e.to_string().contains("periodic"), "{e}");
}

/// The sweep script runs (a CI-sized subset: every scheme at c = 0.2 and 8 cells per
/// diameter, and r_h / r = 0.8) and tabulates each run against the table.
#[test]
fn sweep_subset_runs() {
    let out = tempfile::tempdir().unwrap();
    let o = std::process::Command::new("python3")
        .arg(root().join("jobs/permeability/sweep.py"))
        .args(["--out", out.path().to_str().unwrap()])
        .args(["--bin", env!("CARGO_BIN_EXE_grainflow")])
        .args(["--threads", "1", "--fractions", "0.2", "--cells", "8"])
        .args([
            "--ratios",
            "1,0.8",
            "--contact-fraction",
            "0.2",
            "--ratio-cells",
            "8",
        ])
        .output()
        .expect("python3 runs");
    println!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success());
    let rows = std::fs::read_to_string(out.path().join("results.csv")).unwrap();
    // Three schemes at c = 0.2, three at r_h / r = 0.8 (c = 0.128); every one finished.
    assert_eq!(
        rows.lines().filter(|l| l.contains(",finished,")).count(),
        6,
        "{rows}"
    );
    let table = std::fs::read_to_string(out.path().join("results.md")).unwrap();
    assert!(
        table.contains("| interpolated | 0.128 | 8 | 0.8 |"),
        "{table}"
    );
}
