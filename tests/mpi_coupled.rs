//! Coupled fluid–grain runs with real `mpirun`: the same scene on 1, 2, 3 and 4 ranks, with
//! the in-place or the two-array kernel, gives bit-identical fields and grains (f64) for
//! each interface scheme, with grains
//! crossing rank faces, straddling them, colliding and repelling across them, and next to
//! a periodic seam; a coupled checkpoint restarted on another rank count continues bit for
//! bit. `cargo test --release --test mpi_coupled -- --nocapture` prints the runs.
mod common;
use common::{assert_bit_identical, assert_grains_identical, grainflow, root, run_ok, summary};
use std::path::Path;

/// `scene` with its `[coupling] scheme` replaced, written into `dir`.
fn with_scheme(scene: &str, scheme: &str, dir: &Path) -> String {
    let text = std::fs::read_to_string(common::root().join(scene)).unwrap();
    let text = text
        .replace(
            "scheme = \"bounce-back\"",
            &format!("scheme = \"{scheme}\""),
        )
        .replace("scheme = \"psm\"", &format!("scheme = \"{scheme}\""));
    let path = dir.join(format!("{scheme}.toml"));
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_owned()
}

/// The coupling stage's per-pass seconds are all reported and, on one rank, add up to no
/// more than the stage itself (they are timed inside it); the counts show the map updated
/// in place.
fn assert_passes_inside_the_stage(s: &serde_json::Value, scheme: &str) {
    let passes = &s["coupling_pass_seconds"];
    let mut sum = 0.0;
    for name in grainflow::coupling::PASSES {
        let v = passes[name]
            .as_f64()
            .unwrap_or_else(|| panic!("{scheme}: no coupling pass {name} in {passes}"));
        assert!(v >= 0.0, "{scheme}: pass {name} took {v} s");
        sum += v;
    }
    // Each scheme maps its grains and plans every step.
    assert!(passes["map"].as_f64().unwrap() > 0.0 && passes["plan"].as_f64().unwrap() > 0.0);
    let stage = s["stage_seconds"]["coupling"].as_f64().unwrap();
    assert!(
        sum <= stage * (1.0 + 1e-9) + 1e-6,
        "{scheme}: passes {sum} s > stage {stage} s"
    );
    // On one rank the same grains stay in view: after the first step, the bounce-back
    // schemes update the cover map in place and keep some boundary lists.
    let counts = &s["coupling_counts"];
    let count = |name: &str| {
        counts[name]
            .as_u64()
            .unwrap_or_else(|| panic!("{scheme}: {counts}"))
    };
    if scheme != "psm" {
        assert!(
            count("remaps_in_place") > 10 * count("remaps_afresh"),
            "{scheme}: {counts}"
        );
        assert!(count("lists_kept") > 0, "{scheme}: {counts}");
    }
}

/// The scene on 1 rank and on each of `ranks` with the default (in-place) kernel, and with
/// the two-array kernel on 1 rank and on `two_array_ranks`: identical fields, grains and
/// summaries.
fn rank_invariance(scene: &str, schemes: &[&str], ranks: &[usize], two_array_ranks: usize) {
    let d = tempfile::tempdir().unwrap();
    for scheme in schemes {
        let scene = with_scheme(scene, scheme, d.path());
        let one = d.path().join(format!("{scheme}-np1"));
        run_ok(1, &scene, &one, &[]);
        assert_eq!(summary(&one)["status"], "ok");
        assert_passes_inside_the_stage(&summary(&one), scheme);
        for n in [1, two_array_ranks] {
            let two = d.path().join(format!("{scheme}-two-array-np{n}"));
            run_ok(n, &scene, &two, &["--kernel", "two-array"]);
            assert_bit_identical(&one, &two);
            assert_grains_identical(&one, &two);
            eprintln!("{scheme}: the two-array kernel on {n} ranks matches in place bit for bit");
        }
        for &n in ranks {
            let many = d.path().join(format!("{scheme}-np{n}"));
            run_ok(n, &scene, &many, &[]);
            assert_eq!(summary(&many)["ranks"], n);
            assert_bit_identical(&one, &many);
            assert_grains_identical(&one, &many);
            eprintln!("{scheme}: {n} ranks match 1 rank bit for bit");
        }
    }
}

#[test]
fn grains_crossing_rank_faces_are_bit_identical_on_1_to_4_ranks() {
    // Ten grains in a closed tank: crossing and straddling rank faces, colliding and
    // repelling across them, with force averaging (bounce-back) carried through migration.
    rank_invariance(
        "tests/scenes/mpi_grains_box.toml",
        &["bounce-back", "interpolated", "psm"],
        &[2, 3, 4],
        3,
    );
}

#[test]
fn grains_next_to_a_periodic_seam_are_bit_identical_on_1_to_3_ranks() {
    // Two grains whose disks reach across the periodic x faces: on several ranks they are
    // ghosts of the rank at the other end (on two ranks, the same neighbour on both sides).
    rank_invariance(
        "tests/scenes/mpi_grains_periodic.toml",
        &["psm", "bounce-back"],
        &[2, 3],
        2,
    );
}

/// The PNG pictures in `dir/pictures`, as (file name, bytes), by name.
fn pictures(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir.join("pictures"))
        .unwrap()
        .map(|e| {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        // The PNGs (with ffmpeg present, the series' movies lie beside them).
        .filter(|(name, _)| name.ends_with(".png"))
        .collect();
    out.sort();
    out
}

#[test]
fn pictures_on_3_ranks_are_those_of_1_rank() {
    // Speed and vorticity with the grains drawn over them: rank 0 alone gathers the whole
    // lattice and draws it, byte for byte as one rank does.
    let d = tempfile::tempdir().unwrap();
    let text = common::scene_variant(
        "tests/scenes/mpi_grains_box.toml",
        &[("pictures = false", "pictures = true")],
    );
    let scene = d.path().join("pictures.toml");
    std::fs::write(&scene, text).unwrap();
    let [one, three] = [1, 3].map(|n| {
        let out = d.path().join(format!("np{n}"));
        run_ok(n, scene.to_str().unwrap(), &out, &["--steps", "200"]);
        pictures(&out)
    });
    let names = |p: &[(String, Vec<u8>)]| p.iter().map(|x| x.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&one), names(&three));
    // Speed, vorticity and grains at steps 0 and 200.
    assert_eq!(one.len(), 6, "{:?}", names(&one));
    for ((name, a), (_, b)) in one.iter().zip(&three) {
        assert!(a == b, "{name} differs between 1 and 3 ranks");
    }
}

#[test]
fn coupled_restart_on_another_rank_count_continues_bit_identically() {
    let d = tempfile::tempdir().unwrap();
    for scheme in ["bounce-back", "psm"] {
        let scene = with_scheme("tests/scenes/mpi_grains_box.toml", scheme, d.path());
        let full = d.path().join(format!("{scheme}-full"));
        run_ok(1, &scene, &full, &[]);
        // Stop at step 400 with a checkpoint on 2 ranks; continue to 600 on 3 ranks.
        let split = d.path().join(format!("{scheme}-split"));
        run_ok(2, &scene, &split, &["--steps", "400"]);
        let ck = split.join("checkpoint.h5");
        assert!(
            ck.is_file(),
            "checkpoint_every_steps = 200 wrote checkpoint.h5"
        );
        run_ok(3, &scene, &split, &["--restart", ck.to_str().unwrap()]);
        assert_eq!(summary(&split)["restarted_from_step"], 400);
        assert_bit_identical(&full, &split);
        assert_grains_identical(&full, &split);
        eprintln!("{scheme}: 2 ranks to step 400, then 3 ranks, match 1 rank bit for bit");
    }
}

#[test]
fn rebalanced_coupled_runs_are_bit_identical_to_1_rank() {
    // Twelve grains slide from the left of a tank to the right under tilted gravity; 10
    // steps in and every 49 (odd: the in-place kernel's other layout) the slabs follow the
    // measured work (tolerance 0: whenever the model finds a better split), moving
    // populations and grains between ranks.
    let d = tempfile::tempdir().unwrap();
    for scheme in ["bounce-back", "psm"] {
        let scene = with_scheme("tests/scenes/mpi_grains_rebalance.toml", scheme, d.path());
        let one = d.path().join(format!("{scheme}-np1"));
        run_ok(1, &scene, &one, &[]);
        assert_eq!(
            summary(&one)["rebalances"],
            0,
            "one rank has nothing to balance"
        );
        for n in [2, 3] {
            let many = d.path().join(format!("{scheme}-np{n}"));
            run_ok(n, &scene, &many, &[]);
            let s = summary(&many);
            let moved = s["rebalances"].as_u64().unwrap();
            assert!(moved > 0, "{scheme} on {n} ranks never rebalanced");
            assert_bit_identical(&one, &many);
            assert_grains_identical(&one, &many);
            eprintln!("{scheme}: {n} ranks, {moved} rebalances, match 1 rank bit for bit");
        }
        assert_grain_energy_matches_the_snapshot(&one, "step_00000600");
        let two_array = d.path().join(format!("{scheme}-two-array-np2"));
        run_ok(2, &scene, &two_array, &["--kernel", "two-array"]);
        assert!(summary(&two_array)["rebalances"].as_u64().unwrap() > 0);
        assert_bit_identical(&one, &two_array);
        assert_grains_identical(&one, &two_array);
        // A checkpoint of a rebalanced run restarts on another rank count bit for bit.
        let split = d.path().join(format!("{scheme}-split"));
        run_ok(3, &scene, &split, &["--steps", "400"]);
        assert!(summary(&split)["rebalances"].as_u64().unwrap() > 0);
        let ck = split.join("checkpoint.h5");
        run_ok(2, &scene, &split, &["--restart", ck.to_str().unwrap()]);
        assert_eq!(summary(&split)["restarted_from_step"], 400);
        assert_bit_identical(&one, &split);
        assert_grains_identical(&one, &split);
    }
}

#[test]
fn rebalanced_grains_next_to_a_periodic_seam_are_bit_identical() {
    // Grains reaching across the periodic x faces, their images on the ranks at both ends,
    // while the slabs move every 25 steps.
    let d = tempfile::tempdir().unwrap();
    let text = common::scene_variant(
        "tests/scenes/mpi_grains_periodic.toml",
        &[(
            "scheme = \"psm\"",
            "scheme = \"psm\"\nrebalance_every_steps = 25\nrebalance_tolerance = 0.0",
        )],
    );
    let scene = d.path().join("periodic.toml");
    std::fs::write(&scene, text).unwrap();
    let scene = scene.to_str().unwrap();
    let one = d.path().join("np1");
    run_ok(1, scene, &one, &[]);
    for n in [2, 3] {
        let many = d.path().join(format!("np{n}"));
        run_ok(n, scene, &many, &[]);
        // Two grains on each of 2 ranks are balanced already; 3 ranks hold 1, 2 and 1.
        if n == 3 {
            assert!(summary(&many)["rebalances"].as_u64().unwrap() > 0);
        }
        assert_bit_identical(&one, &many);
        assert_grains_identical(&one, &many);
    }
}

#[test]
fn coupled_checkpoints_are_refused_by_the_wrong_scene() {
    let d = tempfile::tempdir().unwrap();
    let coupled = d.path().join("coupled");
    run_ok(
        1,
        "tests/scenes/mpi_grains_box.toml",
        &coupled,
        &["--steps", "200"],
    );
    let fluid = d.path().join("fluid");
    run_ok(
        1,
        "tests/scenes/mpi_channel.toml",
        &fluid,
        &["--steps", "100"],
    );
    for (scene, ck, needle) in [
        (
            "tests/scenes/mpi_grains_box.toml",
            fluid.join("checkpoint.h5"),
            "holds no grains",
        ),
        (
            "tests/scenes/mpi_channel.toml",
            coupled.join("checkpoint.h5"),
            "lattice is 160 × 80",
        ),
    ] {
        let out = d.path().join("again");
        let o = grainflow(
            1,
            &[
                "run",
                scene,
                "--out",
                out.to_str().unwrap(),
                "--restart",
                ck.to_str().unwrap(),
            ],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains(needle), "expected `{needle}` in: {err}");
    }
}

/// The device backend on 2 ranks gives the bits of 1 device rank (coupled, f32; the
/// device sums each grain's loads per column, so they must not depend on where a slab
/// starts): in the closed tank, and with grains reaching across the periodic x faces.
#[test]
fn coupled_gpu_runs_on_2_ranks_match_1_gpu_rank() {
    if grainflow::lbm::gpu::list_adapters().is_empty() {
        eprintln!("SKIPPED: no GPU adapter (scripts/setup.sh installs Mesa lavapipe)");
        return;
    }
    let d = tempfile::tempdir().unwrap();
    let gpu = ["--backend", "gpu", "--precision", "f32"];
    for (scene, scheme) in [
        ("mpi_grains_box", "bounce-back"),
        ("mpi_grains_box", "psm"),
        ("mpi_grains_periodic", "interpolated"),
        // Slabs that move: each rebalance builds the device lattice on the new slab.
        ("mpi_grains_rebalance", "psm"),
    ] {
        let name = scene;
        let scene = with_scheme(&format!("tests/scenes/{scene}.toml"), scheme, d.path());
        let one = d.path().join(format!("{name}-{scheme}-gpu1"));
        run_ok(1, &scene, &one, &gpu);
        let two = d.path().join(format!("{name}-{scheme}-gpu2"));
        run_ok(2, &scene, &two, &gpu);
        assert!(summary(&two)["device"].as_str().unwrap().starts_with("gpu"));
        if name == "mpi_grains_rebalance" {
            assert!(summary(&two)["rebalances"].as_u64().unwrap() > 0);
        }
        assert_bit_identical(&one, &two);
        assert_grains_identical(&one, &two);
        eprintln!("{scheme}: 2 GPU ranks match 1 GPU rank bit for bit");
    }
}

/// A run reports what its ranks sent each step, the inputs of `scripts/scaling-model`: one
/// process sends nothing; on two ranks the messages carry the fluid's halo faces and the
/// ghost grains (more bytes than the faces alone), and the ranks agree through collectives.
#[test]
fn runs_report_their_communication_per_step() {
    let dir = tempfile::tempdir().unwrap();
    let scene = root().join("tests/scenes/mpi_grains_box.toml");
    let scene = scene.to_str().unwrap();
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    run_ok(1, scene, &one, &["--steps", "100"]);
    run_ok(2, scene, &two, &["--steps", "100"]);
    let (a, b) = (summary(&one), summary(&two));
    let f = |s: &serde_json::Value, k: &str| s[k].as_f64().unwrap_or_else(|| panic!("no {k}"));
    for k in [
        "message_bytes_per_step",
        "messages_per_step",
        "collectives_per_step",
    ] {
        assert_eq!(f(&a, k), 0.0, "one process: {k}");
    }
    let (bytes, halo) = (
        f(&b, "message_bytes_per_step"),
        f(&b, "halo_bytes_per_step"),
    );
    assert!(
        halo > 0.0 && bytes > halo,
        "{bytes} B per step, {halo} of them halo"
    );
    assert!(f(&b, "messages_per_step") >= 2.0);
    assert!(f(&b, "collectives_per_step") >= 1.0);
    // Time in communication: none on one process; on two, some, and no more than the loop.
    let wait =
        |s: &serde_json::Value| [0, 1].map(|k| s["communication_wait_s"][k].as_f64().unwrap());
    assert_eq!(wait(&a), [0.0, 0.0]);
    let [least, most] = wait(&b);
    assert!(
        least > 0.0 && least <= most && most < f(&b, "wall_time_s"),
        "{least} .. {most} s of {} s",
        f(&b, "wall_time_s")
    );
    // Per stage: none on one process; on two, within each rank's stage time, some, and no
    // more than the ranks spent in communication over the steps (the least of those bounds
    // the sum of each stage's least). Snapshots, checkpoints and moves are not a step's,
    // and the probes stage also holds the probes recorded before the first step.
    let stage_waits = |s: &serde_json::Value| -> Vec<(String, [f64; 2], f64)> {
        s["stages"]
            .as_object()
            .unwrap()
            .iter()
            .map(|(k, v)| {
                let w = &v["wait_s"];
                let w = [0, 1].map(|i| w[i].as_f64().unwrap_or_else(|| panic!("{k}: {v}")));
                (k.clone(), w, v["max_s"].as_f64().unwrap())
            })
            .collect()
    };
    for (k, w, _) in stage_waits(&a) {
        assert_eq!(w, [0.0, 0.0], "{k} on one process");
    }
    let waits = stage_waits(&b);
    for (k, [lo, hi], max) in &waits {
        assert!(
            0.0 <= *lo && lo <= hi && hi <= max,
            "{k}: {lo} .. {hi} of {max} s"
        );
    }
    let in_steps = waits
        .iter()
        .filter(|w| !["output", "checkpoint", "rebalance", "probes"].contains(&w.0.as_str()));
    let (lows, highs): (f64, f64) = in_steps.fold((0.0, 0.0), |s, w| (s.0 + w.1[0], s.1 + w.1[1]));
    assert!(
        highs > 0.0 && lows <= least * (1.0 + 1e-9) + 1e-6,
        "the stages' least waits sum to {lows} s, the most to {highs}; the steps {least} s"
    );
    let out = std::process::Command::new("python3")
        .arg(root().join("scripts/scaling-model"))
        .args([&one, &two])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && text.contains("1024"), "{text}");
}

#[test]
fn coupled_checkpoint_after_an_odd_step_restarts_bit_identically() {
    // After an odd step the in-place kernel holds its populations streamed to the
    // neighbours; a checkpoint taken then (an odd cadence, a signal, a wall-clock cadence)
    // must restart into the steps the run would have taken, at the links of bounce-back
    // grains crossing a rank face too. Twelve grains slide across the faces of 3 slabs.
    // Fields written after odd steps (every 3) match 1 rank's on 3 ranks too.
    let d = tempfile::tempdir().unwrap();
    for scheme in ["bounce-back", "psm"] {
        let text = common::scene_variant(
            "tests/scenes/mpi_grains_rebalance.toml",
            &[
                (
                    "scheme = \"bounce-back\"",
                    &format!("scheme = \"{scheme}\""),
                ),
                ("rebalance_every_steps = 49", "rebalance_every_steps = 0"),
                (
                    "checkpoint_every_steps = 200",
                    "checkpoint_every_steps = 201",
                ),
                ("every_steps = 200", "every_steps = 3"),
            ],
        );
        let scene = d.path().join(format!("{scheme}-odd.toml"));
        std::fs::write(&scene, text).unwrap();
        let scene = scene.to_str().unwrap();
        let full = d.path().join(format!("{scheme}-odd-full"));
        run_ok(1, scene, &full, &[]);
        let three = d.path().join(format!("{scheme}-odd-np3"));
        run_ok(3, scene, &three, &[]);
        assert_bit_identical(&full, &three);
        let all = common::snapshots(&full.join("fields.h5"));
        for (n, m) in [(1, 1), (1, 3), (2, 3)] {
            let split = d.path().join(format!("{scheme}-odd-split-{n}-{m}"));
            run_ok(n, scene, &split, &["--steps", "201"]);
            let ck = split.join("checkpoint.h5");
            run_ok(m, scene, &split, &["--restart", ck.to_str().unwrap()]);
            assert_eq!(summary(&split)["restarted_from_step"], 201);
            let after: Vec<_> = common::snapshots(&split.join("fields.h5"))
                .into_iter()
                .filter(|(name, _)| name.as_str() >= "step_00000202")
                .collect();
            assert_eq!(after.len(), 4 * 133, "{scheme}: snapshots 204..=600");
            for (name, values) in &after {
                let (_, expected) = all.iter().find(|(a, _)| a == name).unwrap();
                assert_eq!(
                    common::bits_differing(expected, values),
                    0,
                    "{scheme}, {name}: checkpoint at step 201 on {n} rank(s), restarted on {m}"
                );
            }
            let grains = common::grain_snapshots(&full);
            for (name, values) in common::grain_snapshots(&split) {
                if name.as_str() >= "step_00000202" {
                    let (_, expected) = grains.iter().find(|(a, _)| *a == name).unwrap();
                    assert_eq!(
                        common::bits_differing(expected, &values),
                        0,
                        "{scheme}, grains {name}: {n} then {m}"
                    );
                }
            }
            let (a, b) = (summary(&full), summary(&split));
            assert_eq!(a["totals_final"], b["totals_final"], "{scheme}");
        }
    }
}

/// The kinetic-energy probe's grain column at `step` is Σ ½m|v|² + ½Iω² of the written
/// grains (disks of 2500 kg/m³: m = ρπr², I = ½mr²) to 1e-12, and its fluid column is
/// positive and finite.
fn assert_grain_energy_matches_the_snapshot(dir: &Path, step: &str) {
    let f = hdf5::File::open(dir.join("grains.h5")).unwrap();
    let read = |d: &str| {
        f.dataset(&format!("{step}/{d}"))
            .unwrap()
            .read_raw::<f64>()
            .unwrap()
    };
    let (r, v, w) = (read("radius"), read("velocity"), read("angular_velocity"));
    let expected: f64 = (0..r.len())
        .map(|i| {
            let m = 2500.0 * std::f64::consts::PI * r[i] * r[i];
            0.5 * m * (v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1])
                + 0.25 * m * r[i] * r[i] * w[i] * w[i]
        })
        .sum();
    let s = summary(dir);
    let e = &s["probes"]["energy"];
    let grains = e["grains_j_m"].as_f64().unwrap();
    assert!(
        (grains - expected).abs() <= 1e-12 * expected,
        "{grains} J/m against {expected}"
    );
    let fluid = e["fluid_j_m"].as_f64().unwrap();
    assert!(fluid.is_finite() && fluid > 0.0, "{e}");
}
