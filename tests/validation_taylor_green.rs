//! Taylor–Green vortex decay: second-order convergence for BGK, TRT and MRT in f64, and the
//! f32 error alongside.
mod common;
use common::*;
use grainflow::run::Precision;

fn error_at(n: usize, model: &str, precision: Precision) -> f64 {
    let text = scene_variant(
        "jobs/taylor-green/scene.toml",
        &[
            ("cells = [64, 64]", &format!("cells = [{n}, {n}]")),
            (
                "spacing_m = 0.015625",
                &format!("spacing_m = {}", 1.0 / n as f64),
            ),
            ("model = \"bgk\"", &format!("model = \"{model}\"")),
        ],
    );
    let (s, _d) = run_text(&text, &root().join("jobs/taylor-green"), Some(precision));
    result(&s, "taylor_green.l2_rel_error")
}

/// Diffusive scaling (fixed τ, Δt ∝ Δx²) at N = 32, 64, 128: the observed order of the
/// velocity error must lie in [1.8, 2.2] for every operator.
#[test]
fn second_order_convergence_all_operators() {
    for model in ["bgk", "trt", "mrt"] {
        let e: Vec<f64> = [32, 64, 128]
            .iter()
            .map(|&n| error_at(n, model, Precision::F64))
            .collect();
        let orders = [(e[0] / e[1]).log2(), (e[1] / e[2]).log2()];
        let e32 = error_at(128, model, Precision::F32);
        eprintln!(
            "{model}: errors {e:?}, orders {orders:.3?}; f32 at N=128: {e32:.3e} (f64 {:.3e})",
            e[2]
        );
        for p in orders {
            assert!((1.8..=2.2).contains(&p), "{model}: order {p}");
        }
        // u_lb is only 8e-4 at N = 128, so f32 round-off visibly shifts the error (a few %);
        // with shifted storage it must stay at the truncation-error level.
        let ratio = e32 / e[2];
        eprintln!("{model}: f32/f64 error ratio at N=128: {ratio:.3}");
        assert!(
            (0.5..2.0).contains(&ratio),
            "{model}: f32 {e32} vs f64 {}",
            e[2]
        );
    }
}

/// The scene as shipped passes its own check.
#[test]
fn scene_check_passes() {
    let (s, _d) = run_scene(&root().join("jobs/taylor-green/scene.toml"), None);
    assert_checks_pass(&s);
}

/// The kinetic-energy probe at N = 32: the fluid's energy decays as exp(−4νk²t) (Taylor &
/// Green 1937: the velocity decays at ν|k|² = 2νk², k = 2π/L) within 0.5 % at every record
/// (measured 0.11 %), and at step 0 it is ½ Σ ρ|u|² Δx² of the written fields to the CSV's 10 digits.
#[test]
fn kinetic_energy_probe_decays_as_taylor_green() {
    let mut text = scene_variant(
        "jobs/taylor-green/scene.toml",
        &[
            ("cells = [64, 64]", "cells = [32, 32]"),
            ("spacing_m = 0.015625", "spacing_m = 0.03125"),
        ],
    );
    text.push_str(
        "\n[output]\nprobe_every_steps = 50\n\n[[probes]]\nkind = \"kinetic-energy\"\nname = \"energy\"\n",
    );
    // In a process of its own: the other tests of this file write HDF5 files in this one
    // at the same time.
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("tg.toml");
    std::fs::write(&scene, &text).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args(["run", "--quiet", "--out"])
        .arg(dir.path())
        .arg(&scene)
        .output()
        .unwrap();
    // Exit 2: the scene's L2 check is set for N = 64, not judged here.
    assert!(
        matches!(o.status.code(), Some(0 | 2)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let csv = std::fs::read_to_string(dir.path().join("probe_energy.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert!(rows.len() >= 3, "{csv}");
    assert!(rows.iter().all(|r| r[2] == 0.0), "no grains: {csv}");
    let (nu, k) = (0.01, 2.0 * std::f64::consts::PI);
    let e0 = rows[0][3];
    for r in &rows {
        let expected = e0 * (-4.0 * nu * k * k * r[1]).exp();
        let rel = (r[3] - expected).abs() / e0;
        assert!(
            rel < 5e-3,
            "t = {} s: {} J/m against {expected} ({rel:.2e})",
            r[1],
            r[3]
        );
    }
    let f = hdf5::File::open(dir.path().join("fields.h5")).unwrap();
    let read = |d: &str| {
        f.dataset(&format!("step_00000000/{d}"))
            .unwrap()
            .read_raw::<f64>()
            .unwrap()
    };
    let (rho, u) = (read("density"), read("velocity"));
    let dx2 = 0.03125f64 * 0.03125;
    let fields: f64 = rho
        .iter()
        .zip(u.chunks_exact(3))
        .map(|(r, v)| 0.5 * r * (v[0] * v[0] + v[1] * v[1]) * dx2)
        .sum();
    assert!((fields - e0).abs() <= 1e-9 * e0, "{fields} against {e0}");
}
