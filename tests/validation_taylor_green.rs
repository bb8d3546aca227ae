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
