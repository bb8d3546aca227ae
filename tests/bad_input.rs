//! Bad input gets a clear error naming the key and line, and loses nothing; a run that blows
//! up stops at once with the step and cell, keeps its output and exits non-zero.
mod common;
use common::*;
use std::process::Command;

const GOOD: &str = r#"title = "tiny box"
[domain]
cells = [16, 8]
spacing_m = 0.01

[fluid]
density_kg_m3 = 1000.0
viscosity_m2_s = 1.0e-4
reference_velocity_m_s = 0.01
reference_length_m = 0.08
lattice_velocity = 0.05

[boundaries]
west = { kind = "periodic" }
east = { kind = "periodic" }
south = { kind = "wall" }
north = { kind = "moving-wall", velocity_m_s = [0.01, 0.0] }

[run]
steps = 20
"#;

/// Run the binary on `scene` text; returns (exit code, stdout+stderr, temp dir).
fn grainflow(scene: &str, extra: &[&str]) -> (i32, String, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    let out = dir.path().join("out");
    let mut args = vec![
        "run".to_string(),
        path.display().to_string(),
        "--out".into(),
        out.display().to_string(),
        "--quiet".into(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    let o = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args(&args)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (o.status.code().unwrap_or(-1), text, dir)
}

fn expect_error(scene: &str, needles: &[&str]) {
    let (code, text, _d) = grainflow(scene, &[]);
    assert_eq!(code, 1, "expected failure, got {code}:\n{text}");
    for n in needles {
        assert!(text.contains(n), "message lacks `{n}`:\n{text}");
    }
}

#[test]
fn good_scene_runs() {
    let (code, text, d) = grainflow(GOOD, &[]);
    assert_eq!(code, 0, "{text}");
    for f in [
        "summary.json",
        "fields.h5",
        "fields.xdmf",
        "pictures/speed_00000020.png",
    ] {
        assert!(d.path().join("out").join(f).is_file(), "missing {f}");
    }
}

#[test]
fn unknown_key_names_key_and_line() {
    let s = GOOD.replace("spacing_m = 0.01", "spacing_m = 0.01\nspacing_mm = 10");
    expect_error(
        &s,
        &[
            "scene.toml:5",
            "`domain.spacing_mm`",
            "unknown field `spacing_mm`",
        ],
    );
}

#[test]
fn unknown_variant_is_rejected_at_parse_time() {
    let s = GOOD.replace("steps = 20", "steps = 20\nprecision = \"f16\"");
    expect_error(
        &s,
        &[
            "unknown variant `f16`",
            "expected `f32` or `f64`",
            "scene.toml:21",
            "`run.precision`",
        ],
    );
}

#[test]
fn missing_key_is_named() {
    let s = GOOD.replace("viscosity_m2_s = 1.0e-4\n", "");
    expect_error(&s, &["missing field `viscosity_m2_s`"]);
}

#[test]
fn negative_viscosity_names_key_and_line() {
    let s = GOOD.replace("viscosity_m2_s = 1.0e-4", "viscosity_m2_s = -1.0e-4");
    expect_error(&s, &["scene.toml:8", "`viscosity_m2_s`", "positive"]);
}

#[test]
fn tau_at_or_below_half_is_rejected() {
    let s = GOOD.replace("lattice_velocity = 0.05", "relaxation_time = 0.5");
    expect_error(
        &s,
        &["`relaxation_time`", "τ = 0.500000 ≤ ½", "scene.toml:11"],
    );
}

#[test]
fn high_mach_is_rejected_unless_allowed() {
    let s = GOOD.replace("lattice_velocity = 0.05", "lattice_velocity = 0.2");
    expect_error(&s, &["Mach number 0.346", "allow_high_mach"]);
    let s = s.replace(
        "lattice_velocity = 0.2",
        "lattice_velocity = 0.2\nallow_high_mach = true",
    );
    let (code, text, _d) = grainflow(&s, &[]);
    assert_eq!(code, 0, "{text}");
}

#[test]
fn obstacle_outside_domain_is_rejected() {
    let s = format!("{GOOD}\n[[obstacles]]\nname = \"rock\"\nshape = \"circle\"\ncentre_m = [0.15, 0.04]\nradius_m = 0.02\n");
    expect_error(
        &s,
        &[
            "obstacle `rock` extends outside the domain",
            "`name`",
            "scene.toml:23",
        ],
    );
}

#[test]
fn unpaired_periodic_face_is_rejected() {
    let s = GOOD.replace(
        "east = { kind = \"periodic\" }",
        "east = { kind = \"outflow\" }",
    );
    expect_error(&s, &["periodic boundaries come in pairs", "`west`"]);
}

#[test]
fn unwritable_output_folder_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let blocker = dir.path().join("file");
    std::fs::write(&blocker, b"x").unwrap();
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, GOOD).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args([
            "run",
            path.to_str().unwrap(),
            "--quiet",
            "--out",
            blocker.join("sub").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text.contains("cannot write") && text.contains("file/sub"),
        "{text}"
    );
}

#[test]
fn check_on_unknown_quantity_is_rejected_before_running() {
    let s = format!("{GOOD}\n[[checks]]\nquantity = \"drag.lift\"\nmax = 1.0\n");
    expect_error(&s, &["check on unknown quantity `drag.lift`"]);
}

/// A closed cavity at Re ≈ 16 000 on 16 × 8 cells (τ ≈ 0.5015, lid u_lb = 0.5, BGK, no
/// closure), which cannot stay stable, with a snapshot every `every_steps` steps.
fn blow_up_scene(every_steps: u64) -> String {
    GOOD.replace(
        "lattice_velocity = 0.05",
        "lattice_velocity = 0.5\nallow_high_mach = true",
    )
    .replace("viscosity_m2_s = 1.0e-4", "viscosity_m2_s = 1.0e-7")
    .replace(
        "west = { kind = \"periodic\" }",
        "west = { kind = \"wall\" }",
    )
    .replace(
        "east = { kind = \"periodic\" }",
        "east = { kind = \"wall\" }",
    )
    .replace(
        "steps = 20",
        &format!("steps = 5000\n\n[output]\nevery_steps = {every_steps}"),
    )
}

/// Run the blow-up cavity of [`blow_up_scene`]: it stops at a step with exit 3, names the
/// cell, writes a summary with status "unstable", and keeps every snapshot before the
/// failure and the last good state (each step's once: a snapshot written again would make
/// HDF5 refuse the group and end the run with an output error).
fn blow_up_keeps_output(every_steps: u64) -> String {
    let (code, text, d) = grainflow(&blow_up_scene(every_steps), &[]);
    assert_eq!(code, 3, "{text}");
    assert!(
        text.contains("unstable at step") && text.contains("cell ("),
        "{text}"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.path().join("out/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "unstable");
    let steps = summary["steps"].as_u64().unwrap();
    assert!(steps > 0 && steps < 5000);
    // The error names the step that went bad, counted from 1. A density that goes bad in a
    // sweep is caught there: the run keeps the last good state, whose step count the summary
    // gives. A speed past the lattice's sound is caught in a completed step's snapshot
    // fields: the run keeps that state, as coupled runs keep theirs.
    let bad = common::unstable_step(&text);
    if text.contains("speed of sound") {
        assert_eq!(bad, steps, "{text}");
    } else {
        assert_eq!(bad, steps + 1, "{text}");
    }
    let pics = std::fs::read_dir(d.path().join("out/pictures"))
        .unwrap()
        .count() as u64;
    assert!(
        pics >= 2 * (steps / every_steps + 1),
        "{pics} pictures for {steps} steps"
    );
    text
}

/// With no snapshot before it goes bad, the sweep's density check stops the run.
#[test]
fn blow_up_stops_with_step_and_cell_and_keeps_output() {
    let text = blow_up_keeps_output(1000);
    assert!(text.contains("has density"), "{text}");
}

/// With a snapshot after every step, the snapshot's speed check sees the flow pass the
/// lattice's speed of sound before any density goes bad.
#[test]
fn blow_up_right_after_a_snapshot_keeps_it_and_stops_as_unstable() {
    let text = blow_up_keeps_output(1);
    assert!(text.contains("speed of sound"), "{text}");
}

#[test]
fn check_and_info_commands() {
    let o = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args([
            "check",
            root().join("jobs/cylinder/scene.toml").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    assert!(
        text.contains("relaxation time  τ = 0.600000") && text.contains("memory estimate"),
        "{text}"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .arg("info")
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&o.stdout).contains("threads:"));
    // `info` takes `--threads`, as its own output suggests.
    let o = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args(["info", "--threads", "3"])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("threads: 3 "));
}

#[test]
fn strouhal_transient_longer_than_the_run_is_rejected() {
    let scene = format!(
        "{GOOD}\n[[probes]]\nkind = \"point\"\nname = \"p\"\nposition_m = [0.05, 0.04]\n\n\
         [[analyses]]\nkind = \"strouhal\"\nprobe = \"p\"\nvelocity_m_s = 0.01\n\
         length_m = 0.08\nskip_s = 1.0e6\n"
    );
    expect_error(&scene, &["skip_s", "lengthen the run"]);
}

/// A flow accelerated past the lattice's speed of sound keeps every density positive (the
/// tiny box, periodic all round, under a body force speeds up without bound): the run stops
/// as unstable at the first snapshot that sees it, naming the step and the cell. It used to
/// run to the end and report `ok` with the fluid at 2.5 cells per step.
#[test]
fn a_flow_past_the_speed_of_sound_stops_the_run() {
    let scene = supersonic("every_steps = 10");
    assert!(scene.contains("south = { kind = \"periodic\" }"));
    let (code, text, _d) = grainflow(&scene, &[]);
    assert_eq!(code, 3, "{text}");
    assert!(text.contains("unstable at step 50: cell (0, 0)"), "{text}");
    assert!(text.contains("speed of sound"), "{text}");
}

/// The tiny box, periodic all round, under a body force that speeds it up without bound,
/// for 200 steps with `output` (an `[output]` cadence) and no pictures.
fn supersonic(output: &str) -> String {
    GOOD.replace(
        "lattice_velocity = 0.05",
        "lattice_velocity = 0.05\nbody_acceleration_m_s2 = [0.05, 0.0]",
    )
    .replace("kind = \"wall\" }", "kind = \"periodic\" }")
    .replace(
        "north = { kind = \"moving-wall\", velocity_m_s = [0.01, 0.0] }",
        "north = { kind = \"periodic\" }",
    )
    .replace(
        "steps = 20",
        &format!("steps = 200\n\n[output]\n{output}\npictures = false"),
    )
}

/// The same flow with snapshots only at its ends and a checkpoint every 10 steps: the speeds
/// are checked before every checkpoint too, so the run still stops at step 50, and no
/// checkpoint keeps the state past the speed of sound as if it were good.
#[test]
fn a_checkpoint_never_keeps_a_flow_past_the_speed_of_sound() {
    let scene = supersonic("checkpoint_every_steps = 10");
    let (code, text, _d) = grainflow(&scene, &[]);
    assert_eq!(code, 3, "{text}");
    assert!(text.contains("unstable at step 50: cell (0, 0)"), "{text}");
}

/// An error quotes its cause once: a missing scene file said "No such file or directory"
/// twice (the message quoted its cause, and the cause chain repeated it).
#[test]
fn an_error_names_its_cause_once() {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args(["check", "/nonexistent/scene.toml"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("cannot read scene file /nonexistent/scene.toml"),
        "{err}"
    );
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
}
