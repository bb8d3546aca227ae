//! Distributed runs with real `mpirun`: the same scene on 1, 2, 3 and 4 ranks gives
//! bit-identical HDF5 fields (f64) and identical totals, probes, results and checks;
//! a checkpoint restarted on another rank count continues bit-identically; a truncated or
//! mismatched checkpoint is refused with a clear message; SIGTERM checkpoints and stops.
mod common;
use common::root;
use std::path::Path;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_grainflow");

use common::{assert_bit_identical, grainflow, run_ok, snapshots, summary};

fn rank_invariance(scene: &str) {
    let d = tempfile::tempdir().unwrap();
    let one = d.path().join("np1");
    run_ok(1, scene, &one, &[]);
    for n in [2, 3, 4] {
        let many = d.path().join(format!("np{n}"));
        run_ok(n, scene, &many, &[]);
        let j = summary(&many);
        assert_eq!(j["ranks"], n);
        assert_eq!(j["partition"].as_array().unwrap().len(), n);
        assert!(j["halo_bytes_per_step"].as_u64().unwrap() > 0);
        assert_bit_identical(&one, &many);
        // The file written through MPI-IO opens with the stock HDF5 tools too.
        let dump = Command::new("h5dump")
            .args(["-H"])
            .arg(many.join("fields.h5"))
            .output()
            .expect("h5dump (hdf5-tools, installed by scripts/setup.sh)");
        assert!(dump.status.success());
        assert!(String::from_utf8_lossy(&dump.stdout).contains("DATASET \"velocity\""));
    }
}

#[test]
fn channel_with_cylinder_across_ranks_is_bit_identical_on_1_to_4_ranks() {
    // Zou–He inlet, pressure outlet, wall and moving lid, MRT + Smagorinsky, a cylinder
    // cut by the rank faces, force and point probes.
    rank_invariance("tests/scenes/mpi_channel.toml");
}

#[test]
fn periodic_wrap_across_ranks_is_bit_identical_on_1_to_4_ranks() {
    // Periodic x with obstacles on the seam, body force, free-slip floor, moving lid.
    rank_invariance("tests/scenes/mpi_periodic.toml");
}

#[test]
fn sliced_velocity_face_and_outflow_are_bit_identical_on_1_to_4_ranks() {
    // Zou–He velocity profile on the south face (each rank holds its part), pressure
    // north, zero-gradient outflow east, corners.
    rank_invariance("tests/scenes/mpi_faces.toml");
}

#[test]
fn restart_on_another_rank_count_continues_bit_identically() {
    let d = tempfile::tempdir().unwrap();
    let scene = "tests/scenes/mpi_channel.toml";
    let full = d.path().join("full");
    run_ok(1, scene, &full, &[]);
    // Stop at step 200 with a checkpoint, on 2 ranks; continue to 300 on 3 ranks.
    let split = d.path().join("split");
    run_ok(2, scene, &split, &["--steps", "200"]);
    let ck = split.join("checkpoint.h5");
    assert!(
        ck.is_file(),
        "checkpoint_every_steps = 100 wrote checkpoint.h5"
    );
    assert!(
        !split.join("checkpoint.h5.tmp").exists(),
        "no temporary file left"
    );
    run_ok(3, scene, &split, &["--restart", ck.to_str().unwrap()]);
    assert_eq!(summary(&split)["restarted_from_step"], 200);
    assert_bit_identical(&full, &split);
}

#[test]
fn truncated_or_mismatched_checkpoint_is_refused_clearly() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    run_ok(
        1,
        "tests/scenes/mpi_channel.toml",
        &run,
        &["--steps", "100"],
    );
    let ck = run.join("checkpoint.h5");
    let bytes = std::fs::read(&ck).unwrap();
    let cut = d.path().join("cut.h5");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    // 4 KiB of flipped bytes in the middle: the digest no longer matches.
    let flipped = d.path().join("flipped.h5");
    let mut bad = bytes.clone();
    let mid = bad.len() / 2;
    for b in &mut bad[mid..mid + 4096] {
        *b ^= 0xa5;
    }
    std::fs::write(&flipped, &bad).unwrap();
    for (scene, file, needle) in [
        ("tests/scenes/mpi_channel.toml", &cut, "truncated"),
        (
            "tests/scenes/mpi_channel.toml",
            &flipped,
            "contents changed",
        ),
        (
            "tests/scenes/mpi_periodic.toml",
            &ck,
            "lattice is 120 × 42, but the scene's is 96 × 40",
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
                file.to_str().unwrap(),
            ],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains(needle), "expected `{needle}` in: {err}");
    }
    let o = grainflow(
        1,
        &[
            "run",
            "tests/scenes/mpi_channel.toml",
            "--precision",
            "f32",
            "--out",
            d.path().join("p").to_str().unwrap(),
            "--restart",
            ck.to_str().unwrap(),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("restart with --precision f64"), "{err}");
}

#[test]
fn sigterm_writes_a_checkpoint_and_the_restart_matches_an_uninterrupted_run() {
    let d = tempfile::tempdir().unwrap();
    let scene = "tests/scenes/signal.toml";
    let steps = "40000";
    let full = d.path().join("full");
    run_ok(1, scene, &full, &["--steps", steps]);
    let cut = d.path().join("cut");
    let child = Command::new(BIN)
        .args([
            "run",
            scene,
            "--out",
            cut.to_str().unwrap(),
            "--steps",
            steps,
            "--quiet",
            "--threads",
            "1",
        ])
        .current_dir(root())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(400));
    let pid = child.id() as i32;
    let _ = Command::new("kill")
        .args(["-TERM", &pid.to_string()])
        .status();
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(4), "SIGTERM exits with status 4");
    let ck = cut.join("checkpoint.h5");
    let j = summary(&cut);
    assert_eq!(j["status"], "interrupted");
    let stopped = j["steps"].as_u64().unwrap();
    assert!(stopped > 0 && stopped < 40000, "stopped at step {stopped}");
    run_ok(
        2,
        scene,
        &cut,
        &["--steps", steps, "--restart", ck.to_str().unwrap()],
    );
    // The snapshot series differ (the interrupted run kept its last state); the final
    // step must match exactly.
    let last = format!("step_{:08}", 40000);
    let pick = |p: &Path| -> Vec<(String, Vec<f64>)> {
        snapshots(&p.join("fields.h5"))
            .into_iter()
            .filter(|(n, _)| n.starts_with(&last))
            .collect()
    };
    let (a, b) = (pick(&full), pick(&cut));
    assert!(!a.is_empty());
    assert_eq!(a.len(), b.len());
    for ((n, x), (_, y)) in a.iter().zip(&b) {
        assert!(
            x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits()),
            "{n} differs"
        );
    }
}

/// GPU slabs exchange their halos through the host (pack kernel, MPI, unpack kernel) while
/// the inner cells run; 2 and 3 GPU ranks give the same bits as 1 GPU rank, and so does a
/// GPU checkpoint restarted on another rank count.
#[test]
fn gpu_backend_on_2_and_3_ranks_matches_1_gpu_rank() {
    if grainflow::lbm::gpu::list_adapters().is_empty() {
        eprintln!("SKIPPED: no GPU adapter (scripts/setup.sh installs Mesa lavapipe)");
        return;
    }
    for scene in [
        "tests/scenes/mpi_channel.toml",
        "tests/scenes/mpi_periodic.toml",
    ] {
        let d = tempfile::tempdir().unwrap();
        let one = d.path().join("np1");
        let gpu = ["--backend", "gpu", "--precision", "f32"];
        run_ok(1, scene, &one, &gpu);
        for n in [2, 3] {
            let many = d.path().join(format!("np{n}"));
            run_ok(n, scene, &many, &gpu);
            let j = summary(&many);
            assert!(j["device"].as_str().unwrap().starts_with("gpu"));
            assert_eq!(j["ranks"], n);
            assert_bit_identical(&one, &many);
        }
        // A GPU checkpoint (read back from the device) restarts on other ranks: stop at
        // step 200 on 2 GPU ranks, continue on 3.
        if scene.ends_with("mpi_channel.toml") {
            let split = d.path().join("split");
            let mut args = gpu.to_vec();
            args.extend(["--steps", "200"]);
            run_ok(2, scene, &split, &args);
            let ck = split.join("checkpoint.h5");
            let mut args = gpu.to_vec();
            args.extend(["--restart", ck.to_str().unwrap()]);
            run_ok(3, scene, &split, &args);
            assert_eq!(summary(&split)["restarted_from_step"], 200);
            assert_bit_identical(&one, &split);
        }
    }
}

/// Point probes on the columns either side of every rank face: a probe there reads the
/// exchanged halo, which must be current when probes are sampled. The probe series on 2
/// and 3 ranks are the same bytes as on 1 rank.
#[test]
fn probes_next_to_rank_faces_match_one_rank() {
    let d = tempfile::tempdir().unwrap();
    let base = std::fs::read_to_string(root().join("tests/scenes/mpi_channel.toml")).unwrap();
    // The partitions of 2 and 3 ranks (fluid-weighted), from one-step runs.
    let mut columns = Vec::new();
    for n in [2, 3] {
        let out = d.path().join(format!("part{n}"));
        run_ok(n, "tests/scenes/mpi_channel.toml", &out, &["--steps", "1"]);
        for slab in summary(&out)["partition"]
            .as_array()
            .unwrap()
            .iter()
            .skip(1)
        {
            let x0 = slab[0].as_u64().unwrap() as usize;
            columns.extend([x0 - 1, x0]);
        }
    }
    let mut text = base.replace("\nevery_steps = 100\n", "\n");
    for x in &columns {
        // Cell centres at y = 0.35 m (fluid, between the cylinder and the lid).
        text += &format!(
            "\n[[probes]]\nkind = \"point\"\nname = \"edge{x}\"\nposition_m = [{}, 0.35]\n",
            (*x as f64 + 0.5) * 0.01
        );
    }
    let scene = d.path().join("edge_probes.toml");
    std::fs::write(&scene, text).unwrap();
    let scene = scene.to_str().unwrap();
    let one = d.path().join("np1");
    run_ok(1, scene, &one, &["--steps", "60"]);
    for n in [2, 3] {
        let many = d.path().join(format!("np{n}"));
        run_ok(n, scene, &many, &["--steps", "60"]);
        for x in &columns {
            let name = format!("probe_edge{x}.csv");
            let (a, b) = (
                std::fs::read(one.join(&name)).unwrap(),
                std::fs::read(many.join(&name)).unwrap(),
            );
            assert!(a == b, "{name} differs between 1 and {n} ranks");
        }
    }
}

/// An analysis that reads the whole lattice (Taylor–Green) runs on rank 0, which alone
/// gathers the fields; every rank gets its results: on 3 ranks they equal 1 rank's.
#[test]
fn field_analysis_on_3_ranks_equals_1_rank() {
    let d = tempfile::tempdir().unwrap();
    let scene = "jobs/taylor-green/scene.toml";
    let (one, three) = (d.path().join("np1"), d.path().join("np3"));
    run_ok(1, scene, &one, &[]);
    run_ok(3, scene, &three, &[]);
    let (a, b) = (summary(&one), summary(&three));
    assert_eq!(b["ranks"], 3);
    let l2 = &a["results"]["taylor_green.l2_rel_error"];
    assert!(l2.as_f64().is_some_and(|v| v > 0.0 && v < 4e-3), "{l2}");
    assert_eq!(a["results"], b["results"]);
    assert_eq!(a["checks"], b["checks"]);
}

/// An analysis that cannot run on rank 0 is skipped on every rank with rank 0's reason (no
/// rank waits for results that never come), and at the scene's own length that fails the
/// run (exit 2, "checks-failed").
#[test]
fn failing_analysis_on_2_ranks_stops_every_rank_with_its_message() {
    let d = tempfile::tempdir().unwrap();
    // Couette needs walls on south and north; this periodic box has none.
    let text = std::fs::read_to_string(root().join("jobs/taylor-green/scene.toml"))
        .unwrap()
        .replace("kind = \"taylor-green\"\n", "kind = \"couette\"\n")
        .replace(
            "quantity = \"taylor_green.l2_rel_error\"",
            "quantity = \"couette.l2_rel_error\"",
        );
    let scene = d.path().join("couette-in-a-box.toml");
    std::fs::write(&scene, text).unwrap();
    let out = d.path().join("np2");
    let o = grainflow(
        2,
        &[
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("error: analysis `couette` skipped: needs walls"),
        "{err}"
    );
    let s = summary(&out);
    assert_eq!(s["status"], "checks-failed");
    assert_eq!(s["ranks"], 2);
    assert_eq!(s["analyses_skipped"][0]["analysis"], "couette");
    assert!(s["analyses_skipped"][0]["reason"]
        .as_str()
        .unwrap()
        .starts_with("needs walls"));
}
