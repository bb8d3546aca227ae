//! One scene language for every solver: `[domain]`, `[run]` length and `[output]` cadence
//! keys are the same for fluid, grain and MPM scenes, the keys of the older dialects are
//! refused with their replacement, and one time loop writes snapshots and checkpoints at
//! the same cadence for every kind of run.

mod common;

use common::{grainflow, summary};
use grainflow::scene::{load_any, AnyScene};
use std::path::{Path, PathBuf};

const FLUID: &str = "tests/scenes/mpi_channel.toml";
const GRAINS: &str = "tests/scenes/grains_collapse.toml";
const MPM: &str = "tests/scenes/mpm_collapse.toml";

/// `text` with `insert` added on the line after `[table]` (appended when absent).
fn with_in_table(text: &str, table: &str, insert: &str) -> String {
    let header = format!("[{table}]\n");
    match text.find(&header) {
        Some(i) => {
            let at = i + header.len();
            format!("{}{insert}\n{}", &text[..at], &text[at..])
        }
        None => format!("{text}\n{header}{insert}\n"),
    }
}

/// The error `load_any` gives for `text` written beside the test scenes.
fn load_error(text: &str, dir: &Path) -> String {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    match load_any(&path) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

fn read(p: &str) -> String {
    std::fs::read_to_string(common::root().join(p)).unwrap()
}

#[test]
fn keys_of_the_old_dialects_are_refused_with_their_replacement() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (FLUID, "run", "output_every = 10", "[output] every_steps"),
        (
            FLUID,
            "run",
            "probe_every = 2",
            "[output] probe_every_steps",
        ),
        (
            FLUID,
            "run",
            "checkpoint_minutes = 5.0",
            "checkpoint_every_minutes",
        ),
        (FLUID, "run", "fields = [\"density\"]", "[output] fields"),
        (GRAINS, "run", "output_every_s = 0.1", "[output] every_s"),
        (
            GRAINS,
            "run",
            "checkpoint_every = 10",
            "checkpoint_every_steps",
        ),
        (GRAINS, "region", "min_m = [0.0, 0.0]", "size_m"),
        (MPM, "mpm", "domain_m = [0.2, 0.1]", "cells = [nx, ny]"),
        (MPM, "mpm", "cell_size_m = 0.004", "[domain] spacing_m"),
        (
            MPM,
            "run",
            "picture_field = \"speed\"",
            "[output] picture_field",
        ),
    ];
    for (scene, table, key, replacement) in cases {
        let text = with_in_table(&read(scene), table, key);
        let e = load_error(&text, dir.path());
        let name = match table {
            "region" => "region",
            _ => key.split('=').next().unwrap().trim(),
        };
        assert!(
            e.contains(name) && e.contains(replacement) && e.contains("migrate-scenes.py"),
            "{scene} with [{table}] {key}: {e}"
        );
        // The error points at the line of the old key.
        let line = text.lines().position(|l| l.starts_with(key)).unwrap() + 1;
        assert!(
            table == "region" || e.contains(&format!(":{line}:")),
            "no line {line}: {e}"
        );
    }
    // MPM boundaries inside [mpm], with the old side names.
    let text = with_in_table(
        &read(MPM),
        "mpm",
        "boundaries = { left = { kind = \"roller\" }, right = { kind = \"roller\" }, bottom = { kind = \"fixed\" }, top = { kind = \"open\" } }",
    );
    let e = load_error(&text, dir.path());
    assert!(e.contains("mpm.boundaries") && e.contains("west"), "{e}");
}

#[test]
fn output_keys_of_another_solver_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    // Every kind draws pictures, each its own fields and limits.
    for (scene, key, why) in [
        (
            FLUID,
            "picture_field = \"plastic-strain\"",
            "picture_field \"plastic-strain\" is not drawn in this kind of scene; use one of \"speed\", \"vorticity\", \"pressure\"",
        ),
        (
            GRAINS,
            "picture_limits = { pressure_pa = 5.0 }",
            "picture_limits.pressure_pa: this kind of scene draws no pressure picture",
        ),
        (
            MPM,
            "picture_size_px = 10",
            "picture_size_px must be from 64 to 8192 pixels, got 10",
        ),
    ] {
        let e = load_error(&with_in_table(&read(scene), "output", key), dir.path());
        assert!(e.contains(why), "{scene}, {key}: {e}");
    }
    for (scene, key, owner) in [
        (GRAINS, "fields = [\"density\"]", "fluid"),
        (GRAINS, "probe_every_steps = 2", "fluid"),
        (MPM, "compression = 1", "fluid"),
    ] {
        let text = with_in_table(&read(scene), "output", key);
        let e = load_error(&text, dir.path());
        assert!(
            e.contains(&format!("applies to {owner} scenes only")),
            "{scene}, {key}: {e}"
        );
    }
    for (bad, why) in [
        ("every_steps = 0", "at least 1"),
        ("every_s = -1.0", "positive"),
        ("every_s = nan", "finite"),
        ("checkpoint_every_minutes = inf", "finite"),
    ] {
        let text = read(GRAINS).replace("every_s = 0.04", bad);
        let e = load_error(&text, dir.path());
        assert!(e.contains(why), "{bad}: {e}");
    }
    let text = with_in_table(&read(GRAINS), "output", "every_steps = 5");
    let e = load_error(&text, dir.path());
    assert!(e.contains("not both"), "{e}");
    let text = with_in_table(
        &read(FLUID),
        "output",
        "fields = [\"density\", \"density\"]",
    );
    assert!(load_error(&text, dir.path()).contains("twice"));
}

#[test]
fn a_grains_domain_is_a_size_or_the_fluid_scenes_cells() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("twin.toml");
    let text = read(GRAINS).replace(
        "size_m = [0.12, 0.04]",
        "cells = [120, 40]\nspacing_m = 0.001",
    );
    std::fs::write(&path, &text).unwrap();
    match load_any(&path).unwrap_or_else(|e| panic!("{e}")) {
        AnyScene::Grains(g) => {
            let s = g.scene.domain.size();
            assert!(
                (s[0] - 0.12).abs() < 1e-12 && (s[1] - 0.04).abs() < 1e-12,
                "{s:?}"
            );
        }
        _ => panic!("not a grains scene"),
    }
    let both = read(GRAINS).replace(
        "size_m = [0.12, 0.04]",
        "size_m = [0.12, 0.04]\ncells = [1, 1]",
    );
    assert!(load_error(&both, dir.path()).contains("size_m = [width, height]"));
}

/// Run `text` (a scene beside the test scenes) with `args`; the output folder.
fn run(text: &str, dir: &Path, name: &str, args: &[&str]) -> PathBuf {
    let scene = common::root()
        .join("tests/scenes")
        .join(format!("__dialect_{name}.toml"));
    std::fs::write(&scene, text).unwrap();
    let out = dir.join(name);
    let mut all = vec![
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    all.extend_from_slice(args);
    let o = grainflow(1, &all);
    std::fs::remove_file(&scene).ok();
    assert!(
        o.status.code().is_some_and(|c| c == 0 || c == 2),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

/// The steps of the snapshots a run wrote, from its pictures' names (`…00000005.png`).
fn snapshot_steps(out: &Path) -> Vec<u64> {
    let mut steps: Vec<u64> = std::fs::read_dir(out.join("pictures"))
        .unwrap()
        .filter_map(|e| {
            let name = e.ok()?.file_name().into_string().ok()?;
            let stem = name.strip_suffix(".png")?;
            stem.get(stem.len().checked_sub(8)?..)?.parse().ok()
        })
        .collect();
    steps.sort_unstable();
    steps.dedup();
    steps
}

#[test]
fn every_kind_of_run_takes_the_same_length_and_cadence_keys() {
    let dir = tempfile::tempdir().unwrap();
    for (kind, scene) in [("fluid", FLUID), ("grains", GRAINS), ("mpm", MPM)] {
        // `[run] steps` and `[output] every_steps` with checkpoints every 4 steps.
        let mut text = read(scene);
        for old in ["end_time_s = ", "steps = "] {
            if let Some(i) = text.find(&format!("\n{old}")) {
                let j = text[i + 1..].find('\n').unwrap() + i + 1;
                text.replace_range(i + 1..j, "steps = 11");
                break;
            }
        }
        let start = text.find("[output]").unwrap();
        let stop = text[start..]
            .find("\n[")
            .map_or(text.len(), |k| start + k + 1);
        let mut output = String::from("[output]\nevery_steps = 5\ncheckpoint_every_steps = 4\n");
        if kind == "mpm" {
            output.push_str("picture_field = \"plastic-strain\"\n");
        }
        text.replace_range(start..stop, &output);
        let out = run(&text, dir.path(), kind, &[]);
        let s = summary(&out);
        assert_eq!(s["steps"].as_u64(), Some(11), "{kind}: {s}");
        // A snapshot at the start, every 5 steps and at the end, each once.
        assert_eq!(snapshot_steps(&out), vec![0, 5, 10, 11], "{kind}");
        // Checkpoints at steps 4 and 8.
        assert_eq!(s["checkpoints"].as_array().map(Vec::len), Some(2), "{kind}");
        let stages = s["stages"].as_object().unwrap();
        assert!(
            stages.contains_key("output") && stages.contains_key("checkpoint"),
            "{kind}"
        );
        // The same run to a simulated time, with snapshots every 4 steps' time.
        let dt = s["simulated_time_s"].as_f64().unwrap() / 11.0;
        let every = format!("every_s = {}", 4.0 * dt * (1.0 + 1e-9));
        let text = text.replace("every_steps = 5", &every);
        let out = run(&text, dir.path(), &format!("{kind}-s"), &[]);
        let steps = snapshot_steps(&out);
        assert_eq!(steps.first(), Some(&0), "{kind}");
        assert_eq!(steps.last(), Some(&11), "{kind}");
        assert!(steps.len() >= 4, "{kind}: snapshots at {steps:?}");
    }
}

#[test]
fn a_restart_keeps_the_time_cadence_of_an_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = read(FLUID);
    let start = text.find("[output]").unwrap();
    let stop = text[start..]
        .find("\n[")
        .map_or(text.len(), |k| start + k + 1);
    // Δt = 6 ms in this scene: a snapshot every 10 steps' time, a checkpoint at the end.
    text.replace_range(
        start..stop,
        "[output]\nevery_s = 0.0599999999\ncheckpoint_at_end = true\n",
    );
    let full = run(&text, dir.path(), "full", &["--steps", "40"]);
    let cut = run(&text, dir.path(), "cut", &["--steps", "20"]);
    let ck = cut.join("checkpoint.h5");
    let scene = common::root().join("tests/scenes/__dialect_restart.toml");
    std::fs::write(&scene, &text).unwrap();
    let o = grainflow(
        1,
        &[
            "run",
            scene.to_str().unwrap(),
            "--out",
            cut.to_str().unwrap(),
            "--steps",
            "40",
            "--restart",
            ck.to_str().unwrap(),
        ],
    );
    std::fs::remove_file(&scene).ok();
    assert!(o.status.code().is_some_and(|c| c == 0 || c == 2));
    assert_eq!(snapshot_steps(&full), vec![0, 10, 20, 30, 40]);
    assert_eq!(snapshot_steps(&cut), snapshot_steps(&full));
}
