//! `check` tells the truth: over a corpus of scenes (every shipped scene in `jobs/`,
//! `templates/` and `tests/scenes/`, and seeded numeric variants of them), whenever
//! `grainflow check` passes, `grainflow run` of the same scene does not fail its
//! validation or set-up: it runs its first step (or is interrupted by the time limit while
//! setting up a large sample, which is reported).

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Every shipped scene file.
fn corpus() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "toml") {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    for d in ["jobs", "templates", "tests/scenes"] {
        walk(&root().join(d), &mut out);
    }
    out.sort();
    out
}

/// A small deterministic generator (SplitMix64).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// `text` with its `nth` float literal (a `key = number` line) scaled by `factor`; `None`
/// when it has fewer.
fn scaled(text: &str, nth: usize, factor: f64) -> Option<(String, String)> {
    let mut seen = 0;
    let mut out = String::with_capacity(text.len());
    let mut what = None;
    for line in text.lines() {
        let mut l = line.to_string();
        if let Some((key, value)) = line.split_once(" = ") {
            let key = key.trim();
            if !key.starts_with('#') && !key.contains(' ') {
                if let Ok(v) = value.trim().parse::<f64>() {
                    if value.contains('.') || value.contains('e') {
                        if seen == nth {
                            l = format!("{key} = {:e}", v * factor);
                            what = Some(format!("{key} × {factor}"));
                        }
                        seen += 1;
                    }
                }
            }
        }
        out.push_str(&l);
        out.push('\n');
    }
    what.map(|w| (out, w))
}

/// The exit status of `grainflow ARGS` within `limit` (`None`: still running, killed), and
/// its output.
fn grainflow_within(args: &[&str], limit: Duration) -> (Option<i32>, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if t.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let o = child.wait_with_output().unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (status.map(|s| s.code().unwrap_or(-1)), text)
}

/// Seconds a run may take to set up and take its step (large packed samples settle first).
const LIMIT_S: u64 = 15;

#[test]
fn whenever_check_passes_run_gets_past_validation() {
    let all = corpus();
    assert!(all.len() > 50, "{} scenes", all.len());
    let full = std::env::var("GRAINFLOW_FULL_CORPUS").is_ok_and(|v| v == "1");
    let mut rng = Rng(0x5EED_C0DE);
    let jobs = root().join("jobs");
    let scenes: Vec<PathBuf> = all
        .into_iter()
        .filter(|p| full || !p.starts_with(&jobs) || rng.below(4) == 0)
        .collect();
    let variants = if full { 40 } else { 16 };
    // Each scene as shipped, then seeded variants with one number scaled.
    let mut cases: Vec<(PathBuf, String, String)> = Vec::new();
    for p in &scenes {
        let text = std::fs::read_to_string(p).unwrap();
        cases.push((p.clone(), text, "as shipped".into()));
    }
    while cases.len() < scenes.len() + variants {
        let p = &scenes[rng.below(scenes.len())];
        let text = std::fs::read_to_string(p).unwrap();
        let factor = [0.1, 0.5, 2.0, 10.0][rng.below(4)];
        if let Some((t, what)) = scaled(&text, rng.below(12), factor) {
            cases.push((p.clone(), t, what));
        }
    }
    let tmp = tempfile::tempdir().unwrap();
    let (mut passed, mut ran, mut slow) = (0, 0, Vec::new());
    for (n, (path, text, what)) in cases.iter().enumerate() {
        // In a folder of its own with the files it names (a grain list, a mask, reference
        // curves), so that its relative paths resolve.
        let dir = tmp.path().join(format!("case{n}"));
        std::fs::create_dir_all(&dir).unwrap();
        for name in text
            .split('"')
            .filter(|w| w.ends_with(".csv") || w.ends_with(".png"))
        {
            let from = path.parent().unwrap().join(name);
            if from.is_file() && !name.contains('/') {
                std::fs::copy(&from, dir.join(name)).unwrap();
            }
        }
        let scene = dir.join("scene.toml");
        std::fs::write(&scene, text).unwrap();
        let s = scene.to_str().unwrap();
        let (check, check_out) = grainflow_within(&["check", s], Duration::from_secs(60));
        let label = format!("{} ({what})", path.strip_prefix(root()).unwrap().display());
        assert!(
            check.is_some() && !check_out.contains("panicked"),
            "{label}: check hung or panicked:\n{check_out}"
        );
        if check == Some(0) {
            passed += 1;
            let out = dir.join("out");
            let mut args = vec!["run", s, "--steps", "1", "--quiet", "--threads", "1"];
            args.extend(["--out", out.to_str().unwrap()]);
            let (code, run_out) = grainflow_within(&args, Duration::from_secs(LIMIT_S));
            match code {
                // Ran, or ran with a check that failed or went unstable: past validation.
                Some(0 | 2 | 3) => ran += 1,
                None => slow.push(label.clone()),
                Some(c) => {
                    panic!("{label}: check passed, run exited {c}:\n{check_out}\n---\n{run_out}")
                }
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    eprintln!(
        "{} cases, check passed {passed}, run got past validation in {ran}, still setting up \
         after {LIMIT_S} s: {slow:?}",
        cases.len()
    );
    assert!(passed >= scenes.len() / 2, "only {passed} passed check");
    assert!(
        ran >= passed / 2,
        "only {ran} of {passed} runs got past set-up in {LIMIT_S} s"
    );
}

/// `check` takes the options of `run` that change the run (precision, backend, kernel,
/// length) and judges the run they make: f32 populations need less memory than f64 (the
/// scene's own), the two-array kernel more than the in-place one, `--steps` and `--end-time` set the steps;
/// a fluid option on a grains scene is refused by `check` and `run` alike, before `run`
/// writes anything.
#[test]
fn check_judges_the_run_the_command_line_makes() {
    let scene = root().join("jobs/cylinder/scene.toml");
    let scene = scene.to_str().unwrap();
    let check = |extra: &[&str]| {
        let args: Vec<&str> = ["check", scene].iter().chain(extra).copied().collect();
        let (code, text) = grainflow_within(&args, Duration::from_secs(120));
        assert_eq!(code, Some(0), "check {extra:?}:\n{text}");
        let figure = |key: &str| -> f64 {
            let line = text
                .lines()
                .find_map(|l| l.trim().strip_prefix(key))
                .unwrap_or_else(|| panic!("no `{key}` in\n{text}"));
            line.split_whitespace()
                .find_map(|w| w.parse().ok())
                .unwrap_or_else(|| panic!("no number in `{line}`"))
        };
        (figure("memory: about"), figure("steps:"))
    };
    let (f64_mib, steps) = check(&["--precision", "f64"]);
    let (f32_mib, _) = check(&["--precision", "f32"]);
    assert!(f32_mib < f64_mib, "f32 {f32_mib} MiB, f64 {f64_mib} MiB");
    let (in_place, _) = check(&["--precision", "f64", "--kernel", "in-place"]);
    let (two_array, _) = check(&["--precision", "f64", "--kernel", "two-array"]);
    assert!(
        two_array > in_place,
        "two arrays {two_array} MiB, in place {in_place} MiB"
    );
    assert_eq!(check(&["--steps", "123"]).1, 123.0);
    let half = check(&["--end-time", "12.5"]).1;
    assert!(
        (half - steps / 2.0).abs() <= 1.0,
        "{half} steps for half of {steps}"
    );
    // One rule refuses a fluid option on a grains scene, in the same words for both.
    let grains = root().join("jobs/column-collapse/a4.toml");
    let grains = grains.to_str().unwrap();
    let out = std::env::temp_dir().join(format!("gf-refused-{}", std::process::id()));
    let out = out.to_str().unwrap();
    for (command, option) in [
        ("check", "--precision"),
        ("run", "--precision"),
        ("run", "--kernel"),
    ] {
        let value = if option == "--kernel" {
            "in-place"
        } else {
            "f32"
        };
        let mut args = vec![command, grains, option, value];
        if command == "run" {
            args.extend(["--out", out, "--quiet"]);
        }
        let (code, text) = grainflow_within(&args, Duration::from_secs(60));
        let said = format!("{option} applies to the fluid; {grains} is a grains scene");
        assert!(
            code == Some(1) && text.contains(&said),
            "{command} {option}: {code:?}: {text}"
        );
        assert!(
            !std::path::Path::new(out).exists(),
            "{command} {option}: the refused run wrote {out}"
        );
    }
}
