//! `check`'s memory estimate is what `run` uses: for a fluid, a coupled, a grains and an
//! MPM run, each large enough that its own data outweighs the program's, the estimate
//! `check` prints equals the one `summary.json` records, and it lies within 10 % of the
//! peak resident memory the run's processes reached (their high-water marks, summed over
//! the ranks).

mod common;
use common::*;

/// `grainflow check SCENE --ranks N`'s memory line, in MiB.
fn check_estimate_mib(scene: &str, ranks: usize) -> f64 {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args([
            "check",
            scene,
            "--ranks",
            &ranks.to_string(),
            "--threads",
            "1",
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("memory: about"))
        .unwrap_or_else(|| panic!("no memory line:\n{text}"));
    line.split_whitespace().nth(2).unwrap().parse().unwrap()
}

/// Run `scene` for two steps on `ranks` ranks; (estimate, peak) in MiB from its summary,
/// after checking that the estimate is `check`'s.
fn estimate_and_peak(scene: &str, ranks: usize) -> (f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    let path = root().join(scene);
    let p = path.to_str().unwrap();
    let o = grainflow(
        ranks,
        &[
            "run",
            p,
            "--steps",
            "2",
            "--out",
            dir.path().to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{scene} on {ranks} rank(s) failed");
    let s = summary(dir.path());
    let mib = |k: &str| s[k].as_f64().unwrap_or_else(|| panic!("no {k}")) / 1048576.0;
    let (estimate, peak) = (mib("memory_estimate_bytes"), mib("peak_memory_bytes"));
    let printed = check_estimate_mib(p, ranks);
    assert!(
        (printed - estimate).abs() <= 0.05,
        "{scene}: check prints {printed} MiB, the run estimated {estimate:.2} MiB"
    );
    eprintln!("{scene} on {ranks} rank(s): estimate {estimate:.1} MiB, peak {peak:.1} MiB");
    (estimate, peak)
}

fn assert_within_tenth(scene: &str, ranks: usize) {
    let (estimate, peak) = estimate_and_peak(scene, ranks);
    let ratio = estimate / peak;
    assert!(
        (0.9..=1.1).contains(&ratio),
        "{scene} on {ranks} rank(s): estimate {estimate:.1} MiB against a peak of {peak:.1} \
         MiB (ratio {ratio:.3})"
    );
}

#[test]
fn the_fluid_estimate_is_within_a_tenth_of_the_peak() {
    assert_within_tenth("tests/scenes/memory/fluid.toml", 1);
}

#[test]
fn the_fluid_estimate_on_two_ranks_is_within_a_tenth_of_their_summed_peaks() {
    assert_within_tenth("tests/scenes/memory/fluid.toml", 2);
}

#[test]
fn the_coupled_estimate_is_within_a_tenth_of_the_peak() {
    // 7.2 million cells and 2500 grains in f32 with partially saturated cells.
    assert_within_tenth("jobs/seed-table-5-3/scene.toml", 1);
}

#[test]
fn the_grains_estimate_is_within_a_tenth_of_the_peak() {
    assert_within_tenth("tests/scenes/memory/grains.toml", 1);
}

#[test]
fn the_mpm_estimate_is_within_a_tenth_of_the_peak() {
    assert_within_tenth("tests/scenes/memory/mpm.toml", 1);
}
