//! `grainflow template KIND` writes a complete, commented scene of each kind that passes
//! `check` and runs to its end with every check passing.

mod common;

use common::grainflow;
use std::process::{Command, Output};

/// `grainflow ARGS` as a user types it (no extra flags).
fn plain(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn every_template_passes_check_and_runs_with_its_checks_passing() {
    let dir = tempfile::tempdir().unwrap();
    for kind in ["fluid", "coupled", "grains", "mpm"] {
        let scene = dir.path().join(format!("{kind}.toml"));
        let o = plain(&["template", kind, "--out", scene.to_str().unwrap()]);
        assert!(o.status.success(), "template {kind}");
        let written = std::fs::read_to_string(&scene).unwrap();
        let shipped =
            std::fs::read_to_string(common::root().join(format!("templates/{kind}.toml"))).unwrap();
        assert_eq!(
            written, shipped,
            "{kind}: the binary's template is the shipped file"
        );
        // Every table is explained: a comment on most lines that set a key.
        let keys = written
            .lines()
            .filter(|l| l.contains(" = ") && !l.trim_start().starts_with('#'));
        assert!(keys.count() >= 10, "{kind}: too small to be a template");
        // An existing file is not overwritten.
        let again = plain(&["template", kind, "--out", scene.to_str().unwrap()]);
        assert_eq!(
            again.status.code(),
            Some(1),
            "{kind}: overwrote an existing file"
        );
        let o = plain(&["check", scene.to_str().unwrap()]);
        assert!(o.status.success(), "{kind}: check failed");
        let out = dir.path().join(format!("{kind}-out"));
        let o = grainflow(
            1,
            &[
                "run",
                scene.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
        );
        assert_eq!(
            o.status.code(),
            Some(0),
            "{kind}: the run or a check failed"
        );
        let s = common::summary(&out);
        assert_eq!(s["status"], "ok", "{kind}");
        assert!(
            !s["checks"].as_array().unwrap().is_empty(),
            "{kind}: no checks"
        );
    }
}
