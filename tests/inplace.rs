//! The in-place CPU kernel (AA pattern) against the two-array kernel: the same scenes give
//! bit-identical fields (f64), probes, forces and totals at every snapshot, odd and even
//! steps alike, on 1–4 ranks, for every boundary the fluid core has (Zou–He velocity and
//! pressure faces and the corners between two of them, walls, moving walls, free slip, outflow, periodic faces
//! and the periodic seam across ranks, obstacles, body force, BGK/TRT/MRT, Smagorinsky); a
//! checkpoint written by one kernel continues bit-identically in the other; in-place storage
//! is half the two-array storage.
mod common;
use common::{assert_bit_identical, grainflow, run_ok, summary};
use std::path::Path;

/// The scene with a snapshot every 7 steps (odd and even steps), written into `dir`.
fn every_7(scene: &str, dir: &Path) -> String {
    let text = std::fs::read_to_string(common::root().join(scene)).unwrap();
    let text = regex_free_replace(&text, "every_steps", "every_steps = 7");
    let path = dir.join(Path::new(scene).file_name().unwrap());
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_owned()
}

/// Replace the line that starts with `key` by `line`.
fn regex_free_replace(text: &str, key: &str, line: &str) -> String {
    text.lines()
        .map(|l| if l.starts_with(key) { line } else { l })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

#[test]
fn in_place_is_bit_identical_to_two_arrays_on_1_to_4_ranks() {
    let d = tempfile::tempdir().unwrap();
    for scene in [
        "tests/scenes/mpi_channel.toml",
        "tests/scenes/mpi_periodic.toml",
        "tests/scenes/mpi_faces.toml",
        "tests/scenes/mpi_corners.toml",
    ] {
        let scene = every_7(scene, d.path());
        let two = d.path().join("two-array");
        run_ok(1, &scene, &two, &["--kernel", "two-array"]);
        for n in [1, 2, 3, 4] {
            let one = d.path().join(format!("in-place-{n}"));
            run_ok(n, &scene, &one, &["--kernel", "in-place"]);
            assert_bit_identical(&two, &one);
            let (a, b) = (summary(&two), summary(&one));
            if n == 1 {
                assert_eq!(
                    b["memory_bytes"].as_u64().unwrap() * 2,
                    a["memory_bytes"].as_u64().unwrap(),
                    "in place holds one buffer"
                );
            }
            eprintln!("{scene}: in place on {n} rank(s) matches two arrays bit for bit");
        }
    }
}

#[test]
fn checkpoints_move_between_the_kernels() {
    let d = tempfile::tempdir().unwrap();
    let text =
        std::fs::read_to_string(common::root().join("tests/scenes/mpi_channel.toml")).unwrap();
    let text = regex_free_replace(
        &text,
        "checkpoint_every_steps",
        "checkpoint_every_steps = 67",
    );
    let path = d.path().join("channel.toml");
    std::fs::write(&path, text).unwrap();
    let scene = path.to_str().unwrap();
    let full = d.path().join("full");
    run_ok(1, scene, &full, &["--kernel", "two-array"]);
    // Stop in place after an odd number of steps (the pushed layout), continue with two
    // arrays on 2 ranks; and the other way round.
    for (first, then, stop) in [
        ("in-place", "two-array", "201"),
        ("two-array", "in-place", "134"),
    ] {
        let split = d.path().join(format!("{first}-then-{then}"));
        let o = grainflow(
            1,
            &[
                "run",
                scene,
                "--out",
                split.to_str().unwrap(),
                "--kernel",
                first,
                "--steps",
                stop,
            ],
        );
        assert!(o.status.success());
        let ck = split.join("checkpoint.h5");
        run_ok(
            2,
            scene,
            &split,
            &["--kernel", then, "--restart", ck.to_str().unwrap()],
        );
        let s = summary(&split);
        assert_eq!(s["restarted_from_step"].as_u64().unwrap().to_string(), stop);
        let (a, b) = (summary(&full), s);
        for key in ["totals_final", "probes", "results"] {
            assert_eq!(
                a[key], b[key],
                "{first} then {then}: summary `{key}` differs"
            );
        }
        eprintln!("{first} to step {stop}, then {then} on 2 ranks: the same final state");
    }
}

#[test]
fn in_place_is_refused_on_the_gpu() {
    let d = tempfile::tempdir().unwrap();
    let o = grainflow(
        1,
        &[
            "run",
            "tests/scenes/mpi_grains_box.toml",
            "--out",
            d.path().join("g").to_str().unwrap(),
            "--kernel",
            "in-place",
            "--backend",
            "gpu",
            "--steps",
            "1",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("`kernel`") && err.contains("CPU backend"),
        "{err}"
    );
}
