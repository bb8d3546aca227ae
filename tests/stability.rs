//! The measured stability limits (`grainflow stability-map`, jobs/stability/) and the verdicts
//! `grainflow check` gives from them. The fluid's map must predict fresh points it was not
//! built from: 120 seeded points, 10 per operator and test flow at Mach numbers off the map's
//! grid, half with τ − ½ spread from 10⁻⁴ to 0.3 and half within a factor of 3 of the limit
//! the map estimates there; the verdict for the point's flow must be right for at least 90 %
//! of them.
//! `cargo test --release --test stability -- --nocapture` prints every point and the
//! confusion table.
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
    let mut rng = Lcg(49);
    let mut points = Vec::new();
    for op in Operator::ALL {
        for flow in Flow::ALL {
            for _ in 0..5 {
                // τ − ½ log-uniform over 1e-4 … 0.3 (where the limits lie), Mach uniform
                // over 0.03 … 0.38.
                let tau = 0.5 + 10f64.powf(-4.0 + 3.48 * rng.uniform());
                let mach = 0.03 + 0.35 * rng.uniform();
                points.push((op, flow, tau, mach, false));
                // And one near the limit the map estimates there: τ − ½ within a factor
                // of 3 of it (not below the smallest τ the map measured).
                let mach = 0.03 + 0.35 * rng.uniform();
                let limit = map.verdict(&op, 0.5, mach).flow(flow).tau_limit - 0.5;
                let low = (limit / 3.0).max(1e-4);
                let tau = 0.5 + low * (3.0 * limit / low).powf(rng.uniform());
                points.push((op, flow, tau, mach, true));
            }
        }
    }
    let outcomes: Vec<(Operator, Flow, f64, f64, bool, bool, bool)> = points
        .into_par_iter()
        .map(|(op, flow, tau, mach, near)| {
            let truth = run_point(flow, op, tau, mach, LBM_SIZE, LBM_STEPS);
            let predicted = map.verdict(&op, tau, mach).flow(flow).stable;
            (op, flow, tau, mach, truth, predicted, near)
        })
        .collect();
    // [ran stable, blew up] × [predicted stable, predicted unstable]
    let mut table = [[0usize; 2]; 2];
    let mut near_right = 0;
    for (op, flow, tau, mach, truth, predicted, near) in &outcomes {
        near_right += (*near && truth == predicted) as usize;
        let v = map.verdict(op, *tau, *mach);
        eprintln!(
            "{:9} {:11} τ = {tau:.5} Ma = {mach:.3}: {:7}, predicted {} (limit τ {:.4}){}",
            op.name(),
            flow.name(),
            if *truth { "stable" } else { "blew up" },
            if *predicted {
                "stable"
            } else {
                "likely unstable"
            },
            v.flow(*flow).tau_limit,
            if truth == predicted { "" } else { "  <- wrong" }
        );
        table[!truth as usize][!predicted as usize] += 1;
    }
    let right = table[0][0] + table[1][1];
    let share = right as f64 / outcomes.len() as f64;
    eprintln!("| | predicted stable | predicted unstable |");
    eprintln!("|---|---|---|");
    eprintln!("| ran stable | {} | {} |", table[0][0], table[0][1]);
    eprintln!("| blew up | {} | {} |", table[1][0], table[1][1]);
    eprintln!(
        "right for {right} of {} fresh points ({:.0} %); of the {} near a limit, {near_right}",
        outcomes.len(),
        100.0 * share,
        outcomes.len() / 2
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
    let scene = |tau: f64, velocity: f64, extra: &str| {
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
{extra}
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
    // (ν = 10⁻⁴ m²/s and Δx = 1 mm: τ sets Δt, the lid speed the lattice velocity; 50 m/s at
    // τ 0.5006 and 1 m/s at τ 0.53 are u_lb = 0.1.) The BGK cavity at Ma 0.17 and τ 0.5006
    // with C_s = 0.17 (not the map's 0.1) is run on
    // the spot: finite, but it overshoots the lid speed next to the lid. MRT with its
    // default rates is judged by the map; with s_e = s_ε = 1.1 it is run on the spot.
    let les = "smagorinsky_constant = 0.17";
    for (tau, velocity, extra, needle) in [
        (0.8, 0.01, "", "inside the measured stable region (bgk"),
        (0.5002, 0.5, "", "likely unstable: blows up"),
        (
            0.5006,
            50.0,
            les,
            "likely unstable, measured now with this scene's rates (BGK, Smagorinsky C_s = 0.17)",
        ),
        (
            0.53,
            1.0,
            "collision = { model = \"mrt\" }",
            "(mrt: stable for",
        ),
        (
            0.53,
            1.0,
            "collision = { model = \"mrt\", s_e = 1.1, s_eps = 1.1 }",
            "measured now with this scene's rates (MRT s_e = 1.1, s_ε = 1.1, s_q = from Λ = 3/16)",
        ),
    ] {
        let path = d.path().join("s.toml");
        std::fs::write(&path, scene(tau, velocity, extra)).unwrap();
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
