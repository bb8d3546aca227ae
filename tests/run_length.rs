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
        assert!(s["stage_seconds"]
            .as_object()
            .is_some_and(|m| !m.is_empty()));
    }
}
