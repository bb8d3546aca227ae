//! Helpers shared by the integration tests.
#![allow(dead_code)]

use grainflow::run::{run, Precision, RunOptions, Status, Summary};
use std::path::{Path, PathBuf};

/// Repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Run a scene file through the library; output goes to a fresh temporary folder.
pub fn run_scene(path: &Path, precision: Option<Precision>) -> (Summary, tempfile::TempDir) {
    let scene = grainflow::scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    run_valid(&scene, precision)
}

/// Run scene text as if it were a file in `dir` (relative paths in it resolve there).
pub fn run_text(
    text: &str,
    dir: &Path,
    precision: Option<Precision>,
) -> (Summary, tempfile::TempDir) {
    let path = dir.join("__test_scene.toml");
    let scene = grainflow::scene::parse(text, &path).unwrap_or_else(|e| panic!("{e}"));
    run_valid(&scene, precision)
}

fn run_valid(
    scene: &grainflow::scene::ValidScene,
    precision: Option<Precision>,
) -> (Summary, tempfile::TempDir) {
    let out = tempfile::tempdir().expect("temp dir");
    let opts = RunOptions {
        out_dir: out.path().to_path_buf(),
        precision,
        steps: None,
        progress: false,
        restart: None,
        backend: None,
        gpu_storage: None,
    };
    let s = run(scene, &opts).unwrap_or_else(|e| panic!("{e}"));
    (s, out)
}

/// Assert the run finished and every check of the scene passed, printing them.
pub fn assert_checks_pass(s: &Summary) {
    for c in &s.checks {
        eprintln!(
            "  {} = {:?} (expected {:?} ±{:?}/{:?}, min {:?}, max {:?}) passed={}",
            c.quantity,
            c.value,
            c.expected,
            c.tolerance,
            c.relative_tolerance,
            c.min,
            c.max,
            c.passed
        );
    }
    assert_eq!(
        s.status,
        Status::Ok,
        "status {:?}, error {:?}",
        s.status,
        s.error
    );
    assert!(
        !s.checks.is_empty(),
        "a validation scene must declare checks"
    );
}

/// A named result.
pub fn result(s: &Summary, name: &str) -> f64 {
    *s.results
        .get(name)
        .unwrap_or_else(|| panic!("no result {name}; have {:?}", s.results.keys()))
}

/// A scene from `jobs/` with some text replacements applied.
pub fn scene_variant(rel: &str, replacements: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(root().join(rel)).expect("scene");
    for (a, b) in replacements {
        assert!(text.contains(a), "{rel} does not contain `{a}`");
        text = text.replace(a, b);
    }
    text
}

/// A command running `bin` on `ranks` ranks: directly for 1, under `mpirun` otherwise
/// (oversubscribed and unbound so rayon keeps its threads; allowed as root for CI
/// containers), from the repository root.
pub fn on_ranks(ranks: usize, bin: &str) -> std::process::Command {
    let mut cmd = if ranks == 1 {
        std::process::Command::new(bin)
    } else {
        let mut c = std::process::Command::new("mpirun");
        c.args(["--oversubscribe", "--bind-to", "none", "-np"])
            .arg(ranks.to_string())
            .arg(bin);
        c
    };
    cmd.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .current_dir(root());
    cmd
}

/// `grainflow run SCENE --out OUT --quiet --threads 1 EXTRA…` on `ranks` ranks; panics
/// (printing stderr) unless it succeeds.
pub fn run_on_ranks(ranks: usize, bin: &str, scene: &Path, out: &Path, extra: &[&str]) {
    let o = on_ranks(ranks, bin)
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--quiet", "--threads", "1"])
        .args(extra)
        .output()
        .expect("grainflow or mpirun starts");
    eprintln!("{}", String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{ranks} ranks failed: {:?}", o.status);
}
