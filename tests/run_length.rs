//! `--steps` and `--end-time` set the length of every kind of run (fluid, grains, MPM), and
//! a command line that does not parse exits with the usage code, not 2 ("a check failed").

mod common;

use common::{grainflow, summary};

/// The steps and simulated time a run's summary.json reports.
fn length(out: &std::path::Path) -> (u64, f64) {
    let s = summary(out);
    (
        s["steps"].as_u64().expect("steps"),
        s["simulated_time_s"].as_f64().expect("simulated_time_s"),
    )
}

#[test]
fn steps_and_end_time_set_the_length_of_every_kind_of_run() {
    let dir = tempfile::tempdir().unwrap();
    for (kind, scene) in [
        ("fluid", "tests/scenes/mpi_channel.toml"),
        ("grains", "tests/scenes/grains_collapse.toml"),
        ("mpm", "tests/scenes/mpm_collapse.toml"),
    ] {
        let by_steps = dir.path().join(format!("{kind}-steps"));
        let o = grainflow(
            1,
            &[
                "run",
                scene,
                "--out",
                by_steps.to_str().unwrap(),
                "--steps",
                "7",
            ],
        );
        assert!(o.status.success(), "{kind}: --steps 7 failed");
        let (steps, t) = length(&by_steps);
        assert_eq!(steps, 7, "{kind}: --steps 7 ran {steps} steps");
        // The time step of the run, from its own report.
        let dt = t / steps as f64;
        let by_time = dir.path().join(format!("{kind}-time"));
        let end = format!("{}", 11.4 * dt);
        let o = grainflow(
            1,
            &[
                "run",
                scene,
                "--out",
                by_time.to_str().unwrap(),
                "--end-time",
                &end,
            ],
        );
        assert!(o.status.success(), "{kind}: --end-time {end} failed");
        let (steps, _) = length(&by_time);
        // Fluid runs round the end time to whole steps (as their scenes' end_time_s); grain
        // and MPM runs take the step that reaches it.
        let expected = if kind == "fluid" { 11 } else { 12 };
        assert_eq!(
            steps, expected,
            "{kind}: --end-time of 11.4 steps ran {steps}"
        );
    }
}

#[test]
fn a_command_line_that_does_not_parse_exits_with_the_usage_code() {
    let scene = "tests/scenes/mpi_channel.toml";
    for args in [
        vec!["run", scene, "--steps", "0"],
        vec!["run", scene, "--steps", "3", "--end-time", "1"],
        vec!["run", scene, "--end-time=-1"],
        vec!["run", scene, "--end-time", "inf"],
        vec!["run", scene, "--no-such-flag"],
    ] {
        let o = grainflow(1, &args);
        assert_eq!(o.status.code(), Some(64), "{args:?}");
    }
    let o = grainflow(1, &["--version"]);
    assert_eq!(o.status.code(), Some(0));
}

/// The keys `driver::RunHeader` gives every summary.json.
const HEADER: [&str; 19] = [
    "version",
    "solver",
    "scene_path",
    "title",
    "status",
    "error",
    "warnings",
    "ranks",
    "threads",
    "idle_workers_active",
    "restarted_from_step",
    "steps",
    "simulated_time_s",
    "wall_time_s",
    "stage_seconds",
    "stages",
    "checkpoints",
    "results",
    "checks",
];

#[test]
fn every_kind_of_run_writes_the_same_summary_header() {
    let dir = tempfile::tempdir().unwrap();
    for (solver, scene) in [
        ("fluid", "tests/scenes/mpi_channel.toml"),
        ("coupled", "tests/scenes/submerged_small.toml"),
        ("grains", "tests/scenes/grains_collapse.toml"),
        ("mpm", "tests/scenes/mpm_collapse.toml"),
    ] {
        let out = dir.path().join(solver);
        let o = grainflow(
            1,
            &["run", scene, "--out", out.to_str().unwrap(), "--steps", "3"],
        );
        assert!(o.status.success(), "{solver}: {scene} failed");
        let s = summary(&out);
        for key in HEADER {
            assert!(s.get(key).is_some(), "{solver}: summary.json has no {key}");
        }
        assert_eq!(s["solver"], solver);
        assert_eq!(s["steps"], 3, "{solver}");
        assert_eq!(
            s["shortened"], true,
            "{solver}: 3 steps cut the scene short"
        );
        assert!(s["stage_seconds"]
            .as_object()
            .is_some_and(|m| !m.is_empty()));
    }
}

/// A run cut short by `--steps` writes its summary and exits 0: the analyses that cannot
/// run on so short a series are skipped with the reason, and the scene's checks are
/// reported but not judged. The same scene at its own (here short) length fails with
/// exit 2 and names the analysis that could not run.
#[test]
fn shortened_runs_skip_what_they_cannot_measure() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("short");
    let o = grainflow(
        1,
        &[
            "run",
            "jobs/karman/re112.toml",
            "--out",
            out.to_str().unwrap(),
            "--steps",
            "40",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "a shortened run exits 0");
    let s = summary(&out);
    assert_eq!(s["status"], "ok");
    assert_eq!(s["shortened"], true);
    let skipped = s["analyses_skipped"].as_array().unwrap();
    assert_eq!(skipped.len(), 2, "{skipped:?}");
    assert!(skipped[0]["analysis"]
        .as_str()
        .unwrap()
        .starts_with("strouhal of probe `wake"));
    assert!(skipped[0]["reason"].as_str().unwrap().contains("skip_s"));
    let checks = s["checks"].as_array().unwrap();
    assert!(!checks.is_empty());
    assert!(
        checks.iter().all(|c| c["skipped"].is_string()),
        "{checks:?}"
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("warning: analysis `strouhal of probe `wake`"),
        "{stderr}"
    );

    // At the scene's own length, an analysis that cannot run fails the run (exit 2): here
    // a Strouhal analysis left with too few samples after its transient.
    let end = s["simulated_time_s"].as_f64().unwrap();
    let text = std::fs::read_to_string(common::root().join("jobs/karman/re112.toml"))
        .unwrap()
        .replace("end_time_s = 600.0", "steps = 40")
        .replace("skip_s = 300.0", &format!("skip_s = {}", 0.9 * end));
    assert!(text.contains(&format!("skip_s = {}", 0.9 * end)));
    let scene = dir.path().join("short_re112.toml");
    std::fs::write(&scene, text).unwrap();
    let full = dir.path().join("full");
    let o = grainflow(
        1,
        &[
            "run",
            scene.to_str().unwrap(),
            "--out",
            full.to_str().unwrap(),
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    let s = summary(&full);
    assert_eq!(s["status"], "checks-failed");
    assert_eq!(s["shortened"], false);
    assert_eq!(s["analyses_skipped"].as_array().unwrap().len(), 2);
    let checks = s["checks"].as_array().unwrap();
    assert!(checks
        .iter()
        .all(|c| c["skipped"].as_str().unwrap().contains("could not run")));
}
