//! Submerged granular column collapse against its dry twin (issue 17, validation 5), at the
//! smallest size that still shows the fluid's effect: a = 1, L_i = 12 mm, about 100 disks of
//! the DEM study, loose packing, PSM (`tests/scenes/submerged_small.toml` and
//! `dry_small.toml`, written with `jobs/submerged-collapse/make-scenes.py`'s functions).
//! The full study (a = 0.5, 1, 2, loose and dense) is `jobs/submerged-collapse/run.sh`.
//! `cargo test --release --test submerged -- --nocapture` prints the figures.
mod common;
use common::{root, summary};
use std::process::Command;

/// Run a scene with the CLI (grains-only and coupled alike); its summary.json.
fn run(scene: &str, out: &std::path::Path) -> serde_json::Value {
    let o = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args(["run", scene, "--quiet", "--out"])
        .arg(out)
        .current_dir(root())
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{scene}: {:?}\n{}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
    summary(out)
}

#[test]
fn the_liquid_slows_a_loose_column_and_lifts_its_pore_pressure() {
    let tmp = tempfile::tempdir().unwrap();
    let dry = run("tests/scenes/dry_small.toml", &tmp.path().join("dry"));
    let sub = run("tests/scenes/submerged_small.toml", &tmp.path().join("sub"));
    let get = |s: &serde_json::Value, k: &str| {
        s["results"][k]
            .as_f64()
            .unwrap_or_else(|| panic!("no result {k}"))
    };
    let (t_dry, t_sub) = (
        get(&dry, "collapse.front_t95"),
        get(&sub, "collapse.front_t95"),
    );
    let (r_dry, r_sub) = (get(&dry, "collapse.runout"), get(&sub, "collapse.runout"));
    let (p_min, p_max) = (
        get(&sub, "collapse.pore_pressure_min_pa"),
        get(&sub, "collapse.pore_pressure_max_pa"),
    );
    eprintln!("dry: run-out {r_dry:.3}, t95 {t_dry:.2} tau_c");
    eprintln!("submerged: run-out {r_sub:.3}, t95 {t_sub:.2} tau_c, pore pressure {p_min:+.2} / {p_max:+.2} Pa");
    // Both columns collapse (the gate is removed at t = 0).
    assert!(r_dry > 0.2 && r_sub > 0.2, "run-outs {r_dry} {r_sub}");
    // The liquid must be pushed aside: the front needs at least twice as long (the full-size
    // runs measure 2-3.5x; the dry front settles in about 2-5 tau_c).
    assert!(t_sub > 2.0 * t_dry, "t95 dry {t_dry}, submerged {t_sub}");
    // A loose column contracts as it fails: the liquid under it carries load (positive excess
    // pore pressure) and it runs further than dry (Rondon et al. 2011).
    assert!(p_max > 1.0, "largest excess pore pressure {p_max} Pa");
    assert!(r_sub > r_dry, "run-out dry {r_dry}, submerged {r_sub}");
}
