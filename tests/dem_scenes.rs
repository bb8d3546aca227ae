//! Grains scenes end to end: the shortest column of the sweep (a = 0.5) runs out within 20 %
//! of the published 2-D DEM law, and bad grains scenes are refused with the field named.
mod common;
use common::root;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_grainflow");

/// a = 0.5 column (about 2350 grains, settled, gate removed): run-out within 20 % of the
/// published 2-D DEM law 1.67 a (the scene's own check says the same), H_f/L_i ≈ a as in
/// the experiments (Lajeunesse et al. 2005: the top of a short column does not move).
#[test]
fn short_column_collapse_matches_the_2d_dem_law() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("a0.5");
    let o = Command::new(BIN)
        .args(["run", "jobs/column-collapse/a0.5.toml", "--quiet", "--out"])
        .arg(&out)
        .current_dir(root())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        o.status.success(),
        "checks failed or the run broke: {:?}",
        o.status
    );
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let r = &s["results"];
    let runout = r["collapse.runout"].as_f64().unwrap();
    let a = r["collapse.aspect_ratio"].as_f64().unwrap();
    assert!((a - 0.5).abs() < 0.03, "aspect ratio {a}");
    let law = 1.67 * a;
    assert!(
        (runout / law - 1.0).abs() < 0.2,
        "run-out {runout} vs 1.67 a = {law}"
    );
    let h = r["collapse.final_height"].as_f64().unwrap();
    assert!((h / a - 1.0).abs() < 0.05, "H_f/L_i = {h} vs a = {a}");
    assert!(out.join("grains.xdmf").is_file());
    assert!(out.join("pictures").read_dir().unwrap().count() >= 2);
}

fn refused(scene: &str, expect: &[&str]) {
    refused_by("check", scene, expect)
}

/// `grainflow <cmd> scene` fails and its message names every string of `expect`.
fn refused_by(cmd: &str, scene: &str, expect: &[&str]) {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("bad.toml");
    std::fs::write(&path, scene).unwrap();
    let mut c = Command::new(BIN);
    c.arg(cmd).arg(&path);
    if cmd == "run" {
        c.args(["--quiet", "--out"]).arg(tmp.path().join("out"));
    }
    let o = c.output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "accepted: {scene}");
    for e in expect {
        assert!(err.contains(e), "message lacks `{e}`: {err}");
    }
}

const GOOD: &str = r#"
[domain]
size_m = [0.1, 0.1]
[grains]
density_kg_m3 = 2500.0
[grains.contact]
normal_stiffness_n_m2 = 1e5
tangential_stiffness_n_m2 = 5e4
restitution = 0.7
friction = 0.5
[grains.sample]
kind = "pack"
min_m = [0.0, 0.0]
max_m = [0.02, 0.02]
sizes = { distribution = "mono", radius_m = 5e-4 }
solid_fraction = 0.4
[run]
end_time_s = 0.01
"#;

/// `check` warns when gravity pulls the grains towards no wall (they would all fall out of
/// the domain), and not once a floor is under them.
#[test]
fn check_warns_of_grains_with_no_floor() {
    let check = |scene: &str| {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("s.toml");
        std::fs::write(&path, scene).unwrap();
        let o = Command::new(BIN).arg("check").arg(&path).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        )
    };
    let open = check(GOOD);
    assert!(open.contains("towards no wall"), "{open}");
    let floor = GOOD.replace(
        "[run]",
        "[[grains.walls]]\nname = \"floor\"\nfrom_m = [-0.01, 0.0]\nto_m = [0.11, 0.0]\n\
         friction = 0.5\n\n[run]",
    );
    let closed = check(&floor);
    assert!(!closed.contains("towards no wall"), "{closed}");
    // In a coupled scene the fluid's wall faces hold the grains.
    let settling = std::fs::read_to_string(root().join("jobs/settling/disk-16.toml")).unwrap();
    let coupled = check(&settling);
    assert!(!coupled.contains("towards no wall"), "{coupled}");
}

/// `run` warns, on stderr and in `summary.json`, when grains ended outside the domain (they
/// fell out of a scene with no floor), and not once a floor holds them.
#[test]
fn run_warns_of_grains_that_left_the_domain() {
    let run = |scene: &str| {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("s.toml");
        std::fs::write(&path, scene).unwrap();
        let out = tmp.path().join("out");
        let o = Command::new(BIN)
            .args(["run", "--quiet", "--out"])
            .arg(&out)
            .arg(&path)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        (
            String::from_utf8_lossy(&o.stderr).into_owned(),
            s["warnings"].clone(),
        )
    };
    // 0.05 s of free fall: 12 mm, below the floor line for the lower grains (the pack
    // centred, so that the floor's pile stays inside).
    let falling = GOOD
        .replace("end_time_s = 0.01", "end_time_s = 0.05")
        .replace("min_m = [0.0, 0.0]", "min_m = [0.04, 0.0]")
        .replace("max_m = [0.02, 0.02]", "max_m = [0.06, 0.02]");
    let (err, warnings) = run(&falling);
    assert!(err.contains("ended outside the domain"), "{err}");
    assert!(
        warnings.to_string().contains("ended outside the domain"),
        "{warnings}"
    );
    let floor = falling.replace(
        "[run]",
        "[[grains.walls]]\nname = \"floor\"\nfrom_m = [-0.01, 0.0]\nto_m = [0.11, 0.0]\n\
         friction = 0.5\n\n[run]",
    );
    let (err, warnings) = run(&floor);
    assert!(!err.contains("outside the domain"), "{err}");
    assert!(!warnings.to_string().contains("outside the domain"));
}

#[test]
fn bad_grains_scenes_name_the_field() {
    let o = Command::new(BIN)
        .arg("check")
        .arg("jobs/column-collapse/a8.toml")
        .current_dir(root())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    refused(
        &GOOD.replace("friction = 0.5", "friction = 0.5\nfrictoin = 1"),
        &["frictoin"],
    );
    refused(
        &GOOD.replace("restitution = 0.7", "restitution = 1.5"),
        &["restitution", "(0, 1]"],
    );
    refused(
        &GOOD.replace("radius_m = 5e-4", "radius_m = -1"),
        &["radius"],
    );
    refused(
        &GOOD.replace("solid_fraction = 0.4", "solid_fraction = 0.95"),
        &["solid_fraction"],
    );
    refused(
        &GOOD.replace("[grains]\n", "[grains]\nallow_overlap = 3\n"),
        &["allow_overlap"],
    );
    // A step above λ Δt_cr is known once the grains exist: `run` refuses it.
    refused_by(
        "run",
        &format!("{GOOD}[grains.time_step]\nkind = \"fixed\"\ntime_step_s = 1.0\n"),
        &["time step", "exceeds"],
    );
    // With [fluid] it is a coupled scene, which needs the fluid's tables and [coupling]
    // (its [domain] may keep size_m: a fluid domain takes it too).
    refused(
        &format!("{GOOD}[fluid]\n"),
        &["`fluid.density_kg_m3`", "runs coupled", "[coupling]"],
    );
    refused(
        &format!("{GOOD}[[analyses]]\nkind = \"column-collapse\"\nwall_x_m = 0.0\nfloor_y_m = 0.0\nfront_min_height_m = 0.005\n"),
        &["front_min_height_m", "MPM"],
    );
}
