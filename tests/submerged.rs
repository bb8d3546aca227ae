//! Submerged granular column collapse against its dry twin (issue 17, validation 5), at the
//! smallest size whose outcome does not hang on the packing's details: the study's a = 1
//! loose pair (`jobs/submerged-collapse/{sub,dry}-a1-loose.toml`, L_i = 36 mm, about 900
//! disks, PSM). At L_i = 12 mm (about 100 disks) eight packing seeds gave run-out ratios
//! (submerged / dry) from 0.37 to 2.3; at 36 mm four seeds gave 1.04–1.18, and the submerged
//! t₉₅ 2.7–3.0 times the dry one. The full study (a = 0.5, 1, 2, loose and dense) is
//! `jobs/submerged-collapse/run.sh`. `cargo test --release --test submerged -- --nocapture`
//! prints the figures.
mod common;
use common::{root, summary};
use std::process::Command;

/// Start a scene with the CLI on one thread (grains-only and coupled alike).
fn start(scene: &str, out: &std::path::Path) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args(["run", scene, "--quiet", "--threads", "1", "--out"])
        .arg(out)
        .current_dir(root())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap()
}

/// Wait for a run started by [`start`]; its summary.json.
fn finish(run: std::process::Child, scene: &str, out: &std::path::Path) -> serde_json::Value {
    let o = run.wait_with_output().unwrap();
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
    // The two runs side by side, a thread each.
    let scenes = [
        "jobs/submerged-collapse/dry-a1-loose.toml",
        "jobs/submerged-collapse/sub-a1-loose.toml",
    ];
    let outs = [tmp.path().join("dry"), tmp.path().join("sub")];
    let [dry, sub] = [start(scenes[0], &outs[0]), start(scenes[1], &outs[1])];
    let dry = finish(dry, scenes[0], &outs[0]);
    let sub = finish(sub, scenes[1], &outs[1]);
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
    // The liquid must be pushed aside: the front needs at least twice as long (2.7-3.0x over
    // four packings; 2-3.5x over the study's columns).
    assert!(t_sub > 2.0 * t_dry, "t95 dry {t_dry}, submerged {t_sub}");
    // A loose column contracts as it fails: the liquid under it carries load (positive excess
    // pore pressure, 3.9-17 Pa over four packings) and it runs further than dry (Rondon et
    // al. 2011; 4-18 % over four packings).
    assert!(p_max > 1.0, "largest excess pore pressure {p_max} Pa");
    assert!(r_sub > r_dry, "run-out dry {r_dry}, submerged {r_sub}");
}
