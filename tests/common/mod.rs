//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod gpu_parity;

use grainflow::run::{run, Overrides, Precision, RunOptions, Status, Summary};
use std::path::{Path, PathBuf};

/// The step an instability error names ("unstable at step S: …").
pub fn unstable_step(error: &str) -> u64 {
    let after = error
        .split("unstable at step ")
        .nth(1)
        .unwrap_or_else(|| panic!("no step in: {error}"));
    after.split(':').next().unwrap().parse().unwrap()
}

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
    let mut scene = scene.clone();
    let overrides = Overrides {
        precision,
        ..Default::default()
    };
    let opts = RunOptions {
        out_dir: out.path().to_path_buf(),
        scene_length: overrides.apply_fluid(&mut scene),
        progress: false,
        restart: None,
        force: false,
    };
    let s = run(&scene, &opts).unwrap_or_else(|e| panic!("{e}"));
    (s, out)
}

/// Assert the run finished and every check of the scene passed, printing them.
pub fn assert_checks_pass(s: &Summary) {
    for c in &s.run.checks {
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
        s.run.status,
        Status::Ok,
        "status {:?}, error {:?}",
        s.run.status,
        s.run.error
    );
    assert!(
        !s.run.checks.is_empty(),
        "a validation scene must declare checks"
    );
}

/// A named result.
pub fn result(s: &Summary, name: &str) -> f64 {
    *s.run
        .results
        .get(name)
        .unwrap_or_else(|| panic!("no result {name}; have {:?}", s.run.results.keys()))
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

// Helpers of the distributed (mpirun) tests.

/// Run `grainflow ARGS` on `ranks` ranks: directly for 1, under mpirun otherwise.
pub fn grainflow(ranks: usize, args: &[&str]) -> std::process::Output {
    let o = on_ranks(ranks, env!("CARGO_BIN_EXE_grainflow"))
        .args(args)
        .args(["--quiet", "--threads", "1"])
        .output()
        .expect("grainflow or mpirun starts (scripts/setup.sh installs Open MPI)");
    eprintln!("$ {ranks} rank(s): grainflow {}", args.join(" "));
    eprintln!("{}", String::from_utf8_lossy(&o.stderr));
    o
}

/// `grainflow run SCENE --out OUT EXTRA…` on `ranks` ranks; panics unless it succeeds.
pub fn run_ok(ranks: usize, scene: &str, out: &Path, extra: &[&str]) {
    let mut args = vec!["run", scene, "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = grainflow(ranks, &args);
    assert!(
        o.status.success(),
        "{ranks} ranks: {scene} failed: {:?}",
        o.status
    );
}

/// Every dataset of every snapshot group, as raw f64 values.
pub fn snapshots(path: &Path) -> Vec<(String, Vec<f64>)> {
    let f = hdf5::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut out = Vec::new();
    for g in f.member_names().unwrap() {
        let group = f.group(&g).unwrap();
        for d in group.member_names().unwrap() {
            let v = group.dataset(&d).unwrap().read_raw::<f64>().unwrap();
            out.push((format!("{g}/{d}"), v));
        }
    }
    assert!(!out.is_empty(), "{} has no snapshots", path.display());
    out
}

pub fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap()
}

/// How many values of `a` and `b` differ in their bits (pairwise).
pub fn bits_differing(a: &[f64], b: &[f64]) -> usize {
    a.iter()
        .zip(b)
        .filter(|(x, y)| x.to_bits() != y.to_bits())
        .count()
}

pub fn assert_bit_identical(a: &Path, b: &Path) {
    let (sa, sb) = (
        snapshots(&a.join("fields.h5")),
        snapshots(&b.join("fields.h5")),
    );
    assert_eq!(
        sa.iter().map(|x| &x.0).collect::<Vec<_>>(),
        sb.iter().map(|x| &x.0).collect::<Vec<_>>()
    );
    for ((name, va), (_, vb)) in sa.iter().zip(&sb) {
        let differ = bits_differing(va, vb);
        assert_eq!(
            differ, 0,
            "{name}: {differ} values differ between {a:?} and {b:?}"
        );
    }
    let (ja, jb) = (summary(a), summary(b));
    for key in [
        "totals_initial",
        "totals_final",
        "probes",
        "results",
        "checks",
        "fluid_cells",
    ] {
        assert_eq!(ja[key], jb[key], "summary `{key}` differs");
    }
}

/// Every grain snapshot of `dir/grains.h5` as (group/dataset, values sorted by grain id).
pub fn grain_snapshots(dir: &Path) -> Vec<(String, Vec<f64>)> {
    let f = hdf5::File::open(dir.join("grains.h5")).expect("grains.h5");
    let mut out = Vec::new();
    for g in f.member_names().unwrap() {
        let group = f.group(&g).unwrap();
        let ids = group.dataset("id").unwrap().read_raw::<u64>().unwrap();
        let mut order: Vec<usize> = (0..ids.len()).collect();
        order.sort_by_key(|&i| ids[i]);
        for d in group.member_names().unwrap() {
            if d == "id" || d == "contacts" {
                continue;
            }
            let ds = group.dataset(&d).unwrap();
            let v = ds.read_raw::<f64>().unwrap();
            let w = v.len() / ids.len().max(1);
            let sorted: Vec<f64> = order
                .iter()
                .flat_map(|&i| v[i * w..(i + 1) * w].to_vec())
                .collect();
            out.push((format!("{g}/{d}"), sorted));
        }
    }
    out
}

/// The grain snapshots of two runs hold the same bits (rows matched by id).
pub fn assert_grains_identical(a: &Path, b: &Path) {
    let (ga, gb) = (grain_snapshots(a), grain_snapshots(b));
    assert_eq!(
        ga.iter().map(|x| &x.0).collect::<Vec<_>>(),
        gb.iter().map(|x| &x.0).collect::<Vec<_>>()
    );
    for ((name, va), (_, vb)) in ga.iter().zip(&gb) {
        let differ = bits_differing(va, vb);
        assert_eq!(
            differ, 0,
            "{name}: {differ} values differ between {a:?} and {b:?}"
        );
    }
}
