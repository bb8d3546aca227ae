//! The measured stability limits (`grainflow stability-map`, jobs/stability/) and the verdicts
//! `grainflow check` gives from them. The fluid's map must predict fresh points it was not
//! built from: 48 points (8 per operator) at τ and Mach numbers off its grid, each run in
//! both test flows; the verdict must be right for at least 90 % of them.
//! `cargo test --release --test stability -- --nocapture` prints every point.
mod common;
use grainflow::stability::lbm::{run_point, Flow, Operator};
use grainflow::stability::{StabilityMap, LBM_SIZE, LBM_STEPS};
use rayon::prelude::*;

/// A small deterministic generator (the points must be the same in every run).
struct Lcg(u64);

impl Lcg {
    fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn the_map_predicts_fresh_points() {
    let map = StabilityMap::builtin();
    assert!(
        !map.samples.is_empty(),
        "jobs/stability/lbm-map.csv holds the measured map"
    );
    let mut rng = Lcg(2026);
    let mut points = Vec::new();
    for op in Operator::ALL {
        for _ in 0..8 {
            // τ − ½ log-uniform over 1e-4 … 1.5, Mach uniform over 0.03 … 0.38.
            let tau = 0.5 + 10f64.powf(-4.0 + 4.18 * rng.uniform());
            let mach = 0.03 + 0.35 * rng.uniform();
            points.push((op, tau, mach));
        }
    }
    let outcomes: Vec<(Operator, f64, f64, bool, bool)> = points
        .into_par_iter()
        .map(|(op, tau, mach)| {
            let truth = Flow::ALL
                .iter()
                .all(|&f| run_point(f, op, tau, mach, LBM_SIZE, LBM_STEPS));
            (op, tau, mach, truth, map.verdict(&op, tau, mach).stable())
        })
        .collect();
    let mut right = 0;
    for (op, tau, mach, truth, predicted) in &outcomes {
        eprintln!(
            "{:9} τ = {tau:.5} Ma = {mach:.3}: {} , predicted {}{}",
            op.name(),
            if *truth { "stable" } else { "blew up" },
            if *predicted {
                "stable"
            } else {
                "likely unstable"
            },
            if truth == predicted { "" } else { "  <- wrong" }
        );
        right += (truth == predicted) as usize;
    }
    let share = right as f64 / outcomes.len() as f64;
    eprintln!(
        "right for {right} of {} fresh points ({:.0} %)",
        outcomes.len(),
        100.0 * share
    );
    assert!(
        share >= 0.9,
        "the map is right for only {:.0} %",
        100.0 * share
    );
}

#[test]
fn the_dem_and_mpm_limits_are_measured_and_used() {
    let l = grainflow::stability::dem::lambda_limit(grainflow::stability::DEM_CSV)
        .expect("jobs/stability/dem-lambda.csv holds a stable λ");
    let c = grainflow::stability::mpm::courant_limit(grainflow::stability::MPM_CSV)
        .expect("jobs/stability/mpm-courant.csv holds a stable Courant number");
    eprintln!("DEM stable up to λ = {l}, MPM up to Courant {c}");
    // The DEM's limit is real: at it the pile keeps its energy, at twice it the energy grows.
    let pile = grainflow::stability::dem::settled_pile();
    let at = grainflow::stability::dem::energy_ratio(&pile, l, 5000);
    let beyond = grainflow::stability::dem::energy_ratio(&pile, 2.0 * l, 5000);
    eprintln!(
        "energy ratio after 5000 steps: {at:.6} at λ = {l}, {beyond:.3e} at λ = {}",
        2.0 * l
    );
    assert!(at <= 1.001 && beyond > 1.001, "{at} {beyond}");
}

/// `grainflow check` prints the verdicts.
#[test]
fn check_reports_the_verdicts() {
    let d = tempfile::tempdir().unwrap();
    let scene = |tau: f64, velocity: f64| {
        format!(
            r#"title = "stability verdict"
[domain]
cells = [64, 64]
spacing_m = 0.001
[fluid]
density_kg_m3 = 1000.0
viscosity_m2_s = 1.0e-4
reference_velocity_m_s = {velocity}
reference_length_m = 0.064
relaxation_time = {tau}
[boundaries]
west = {{ kind = "wall" }}
east = {{ kind = "wall" }}
south = {{ kind = "wall" }}
north = {{ kind = "moving-wall", velocity_m_s = [{velocity}, 0.0] }}
[run]
steps = 10
"#
        )
    };
    for (tau, velocity, needle) in [
        (0.8, 0.01, "inside the measured stable region (bgk"),
        (0.5002, 0.5, "likely unstable (bgk"),
    ] {
        let path = d.path().join("s.toml");
        std::fs::write(&path, scene(tau, velocity)).unwrap();
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_grainflow"))
            .args(["check", path.to_str().unwrap()])
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&o.stdout);
        eprintln!("{text}");
        assert!(text.contains(needle), "expected `{needle}` in {text}");
    }
    for (scene, needle) in [
        (
            "tests/scenes/grains_collapse.toml",
            "time-step factor λ = 0.100: inside",
        ),
        (
            "tests/scenes/mpm_collapse.toml",
            "Courant number 0.500: inside",
        ),
    ] {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_grainflow"))
            .args(["check", scene])
            .current_dir(common::root())
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains(needle), "expected `{needle}` in {text}");
    }
}
