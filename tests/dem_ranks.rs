//! Distributed DEM with real `mpirun`: a small column collapse (settling, gate removal,
//! flow across every slab face, slab boundaries rebalanced) on 1, 2 and 4 ranks. No grain is lost or duplicated, grains
//! do migrate, and every snapshot matches one rank bit for bit once rows are sorted by id
//! (pairs are evaluated by id and summed by partner id, and list rebuilds are global
//! decisions, so the arithmetic per grain does not depend on the partition). Momentum and
//! kinetic energy are sums over ranks, so they agree to round-off.
mod common;
use common::root;
use std::path::Path;

const BIN: &str = env!("CARGO_BIN_EXE_grainflow");
const SCENE: &str = "tests/scenes/grains_collapse.toml";

fn run(ranks: usize, out: &Path) {
    run_scene(ranks, &root().join(SCENE), out, &[]);
}

fn run_scene(ranks: usize, scene: &Path, out: &Path, extra: &[&str]) {
    common::run_on_ranks(ranks, BIN, scene, out, extra);
}

/// One snapshot: group, ids sorted, every dataset's rows reordered by id.
type Snapshot = (String, Vec<u64>, Vec<(String, Vec<f64>)>);

fn snapshots(dir: &Path) -> Vec<Snapshot> {
    let f = hdf5::File::open(dir.join("grains.h5")).unwrap();
    let mut groups = f.member_names().unwrap();
    groups.sort();
    let mut out = Vec::new();
    for g in groups {
        let grp = f.group(&g).unwrap();
        let ids = grp.dataset("id").unwrap().read_raw::<u64>().unwrap();
        let mut order: Vec<usize> = (0..ids.len()).collect();
        order.sort_by_key(|&i| ids[i]);
        let mut sets = Vec::new();
        for name in grp.member_names().unwrap() {
            if name == "id" {
                continue;
            }
            let v = grp.dataset(&name).unwrap().read_raw::<f64>().unwrap();
            if name == "contacts" {
                // The contact network: rows (id a, id b, point, force) in rank order.
                let mut rows: Vec<&[f64]> = v.chunks_exact(6).collect();
                rows.sort_by(|p, q| (p[0], p[1]).partial_cmp(&(q[0], q[1])).unwrap());
                assert!(rows.len() > 100, "{g}: {} contacts", rows.len());
                sets.push((name, rows.concat()));
                continue;
            }
            let w = v.len() / ids.len();
            let sorted: Vec<f64> = order
                .iter()
                .flat_map(|&i| v[i * w..(i + 1) * w].to_vec())
                .collect();
            sets.push((name, sorted));
        }
        sets.sort_by(|a, b| a.0.cmp(&b.0));
        out.push((g, order.iter().map(|&i| ids[i]).collect(), sets));
    }
    out
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn grains_on_1_2_and_4_ranks_match_and_none_is_lost() {
    let tmp = tempfile::tempdir().unwrap();
    let one = tmp.path().join("r1");
    run(1, &one);
    let reference = snapshots(&one);
    let n = summary(&one)["grains"].as_u64().unwrap();
    assert!(n > 300, "{n} grains");
    assert!(reference.len() >= 4, "{} snapshots", reference.len());
    let p1 = summary(&one)["momentum"].clone();
    for ranks in [2, 4] {
        let dir = tmp.path().join(format!("r{ranks}"));
        run(ranks, &dir);
        let s = summary(&dir);
        let migrated = s["migrated"].as_u64().unwrap();
        eprintln!("{ranks} ranks: {migrated} grains migrated");
        assert!(migrated > 20, "{ranks} ranks: only {migrated} migrations");
        // The flow loads the right-hand slabs: boundaries move, grains cross several slabs
        // in rounds, and nothing changes in the results.
        let rebalances = s["rebalances"].as_u64().unwrap();
        eprintln!(
            "{ranks} ranks: {rebalances} rebalances, final slabs {}",
            s["slab_bounds_m"]
        );
        if ranks == 4 {
            assert!(rebalances > 0, "4 ranks never rebalanced");
        }
        let got = snapshots(&dir);
        assert_eq!(got.len(), reference.len());
        for ((g, ids, sets), (g1, ids1, sets1)) in got.iter().zip(&reference) {
            assert_eq!(g, g1);
            // Every grain exactly once: ids 0..N.
            assert_eq!(ids.len() as u64, n, "{ranks} ranks, {g}: grain count");
            assert!(
                ids.iter().enumerate().all(|(k, &id)| id == k as u64),
                "{g}: ids"
            );
            assert_eq!(ids, ids1);
            for ((name, v), (_, v1)) in sets.iter().zip(sets1) {
                let same = v.iter().zip(v1).all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(same, "{ranks} ranks, {g}/{name} differs from 1 rank");
            }
        }
        // Sums over the grains do not depend on how they are spread over the ranks.
        for k in 0..2 {
            assert_eq!(s["momentum"][k], p1[k], "momentum[{k}]");
        }
    }
}

/// A checkpoint written on 2 ranks (grains with their last forces, contact history, walls,
/// counters) and restarted on 4 ranks ends bit-identical to an uninterrupted 1-rank run;
/// restarted in its own folder on 3 ranks, the whole snapshot file matches.
#[test]
fn grains_checkpoint_restarts_on_another_rank_count_bit_identically() {
    let tmp = tempfile::tempdir().unwrap();
    let one = tmp.path().join("r1");
    run(1, &one);
    let text = std::fs::read_to_string(root().join(SCENE)).unwrap();
    let with_checkpoints = text.replace("[output]\n", "[output]\ncheckpoint_every_steps = 3000\n");
    assert_ne!(text, with_checkpoints);
    let scene = tmp.path().join("checkpointed.toml");
    std::fs::write(&scene, with_checkpoints).unwrap();
    let first = tmp.path().join("first");
    run_scene(2, &scene, &first, &[]);
    let ckpt = first.join("checkpoint.h5");
    assert!(ckpt.is_file());
    assert!(!first.join("checkpoint.h5.tmp").exists());
    let second = tmp.path().join("second");
    run_scene(4, &scene, &second, &["--restart", ckpt.to_str().unwrap()]);
    let s = summary(&second);
    assert_eq!(s["restarted_from_step"].as_u64(), Some(6000));
    let (a, b) = (snapshots(&one), snapshots(&second));
    let (last_a, last_b) = (a.last().unwrap(), b.last().unwrap());
    assert_eq!(last_a.0, last_b.0, "same final step");
    assert_eq!(last_a.1, last_b.1);
    for ((name, v), (_, w)) in last_a.2.iter().zip(&last_b.2) {
        let same = v.iter().zip(w).all(|(x, y)| x.to_bits() == y.to_bits());
        assert!(same, "{name} differs after the restart");
    }
    // The analyses see the same initial column, and the sums over the grains do not depend
    // on their storage order (a restart reorders them).
    assert_eq!(summary(&one)["results"], s["results"]);
    for key in ["kinetic_energy_j_m", "momentum"] {
        assert_eq!(summary(&one)[key], s[key], "{key} after the restart");
    }
    // Restarting in the run's own folder keeps the snapshots up to the checkpoint and
    // rewrites the later ones: the file then matches the uninterrupted run's, every group.
    run_scene(3, &scene, &first, &["--restart", ckpt.to_str().unwrap()]);
    let (a, c) = (snapshots(&one), snapshots(&first));
    assert_eq!(
        a.iter().map(|x| &x.0).collect::<Vec<_>>(),
        c.iter().map(|x| &x.0).collect::<Vec<_>>()
    );
    for ((g, ids, sets), (_, ids_c, sets_c)) in a.iter().zip(&c) {
        assert_eq!(ids, ids_c, "{g}");
        for ((name, v), (_, w)) in sets.iter().zip(sets_c) {
            let same = v.iter().zip(w).all(|(x, y)| x.to_bits() == y.to_bits());
            assert!(same, "{g}/{name} differs after restarting in place");
        }
    }
}
