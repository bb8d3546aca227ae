//! Distributed MPM with real `mpirun`: a small column collapse on 1, 2 and 4 ranks. Points
//! migrate across every slab face and the slabs rebalance; no point is lost or duplicated,
//! and every snapshot — points and grid — matches one rank bit for bit once point rows are
//! sorted by id (node sums add the unsummed strips of the cell columns in the same order on
//! any partition, and global sums add per-column partial sums in column order). A
//! checkpoint written on 2 ranks restarts on 3 and ends bit-identical to the uninterrupted
//! run.
mod common;
use common::root;
use std::path::Path;

const BIN: &str = env!("CARGO_BIN_EXE_grainflow");
const SCENE: &str = "tests/scenes/mpm_collapse.toml";

fn run(ranks: usize, scene: &Path, out: &Path, extra: &[&str]) {
    common::run_on_ranks(ranks, BIN, scene, out, extra);
}

/// Every snapshot: group name, sorted ids, point datasets reordered by id, grid datasets.
type Snapshot = (String, Vec<u64>, Vec<(String, Vec<f64>)>);

fn snapshots(dir: &Path) -> Vec<Snapshot> {
    let f = hdf5::File::open(dir.join("mpm.h5")).unwrap();
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
            match name.as_str() {
                "id" => continue,
                "grid" => {
                    for field in ["mass", "velocity"] {
                        let v = grp
                            .dataset(&format!("grid/{field}"))
                            .unwrap()
                            .read_raw::<f64>()
                            .unwrap();
                        sets.push((format!("grid/{field}"), v));
                    }
                    continue;
                }
                _ => {}
            }
            let v = grp.dataset(&name).unwrap().read_raw::<f64>().unwrap();
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

fn assert_same(a: &[Snapshot], b: &[Snapshot], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: snapshot count");
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x.0, y.0, "{what}: groups");
        assert_eq!(x.1, y.1, "{what}: {} ids", x.0);
        for ((n1, v1), (n2, v2)) in x.2.iter().zip(&y.2) {
            assert_eq!(n1, n2);
            let same =
                v1.len() == v2.len() && v1.iter().zip(v2).all(|(p, q)| p.to_bits() == q.to_bits());
            assert!(same, "{what}: {} / {n1} differs", x.0);
        }
    }
}

#[test]
fn mpm_on_1_2_and_4_ranks_match_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = root().join(SCENE);
    let dirs: Vec<_> = [1, 2, 4]
        .iter()
        .map(|r| tmp.path().join(format!("r{r}")))
        .collect();
    for (r, d) in [1, 2, 4].iter().zip(&dirs) {
        run(*r, &scene, d, &[]);
    }
    let one = snapshots(&dirs[0]);
    let n = one[0].1.len();
    assert!(n > 1000, "{n} points");
    for s in &one {
        // Every id exactly once.
        assert_eq!(s.1.len(), n, "{}: point count", s.0);
        assert!(
            s.1.windows(2).all(|w| w[0] < w[1]),
            "{}: duplicated id",
            s.0
        );
    }
    let s1 = summary(&dirs[0]);
    assert!(
        s1["results"]["collapse.thick_front_m"].as_f64().unwrap() > 0.06,
        "thick front: {}",
        s1["results"]
    );
    for (r, d) in [2, 4].iter().zip(&dirs[1..]) {
        assert_same(&one, &snapshots(d), &format!("{r} ranks"));
        let s = summary(d);
        assert_eq!(s["status"], "ok");
        assert!(
            s["migrated"].as_u64().unwrap() > 50,
            "{r} ranks: {} migrations",
            s["migrated"]
        );
        assert_eq!(s["mass_kg_m"], s1["mass_kg_m"], "{r} ranks: mass");
        assert_eq!(
            s["kinetic_energy_j_m"], s1["kinetic_energy_j_m"],
            "{r} ranks: kinetic energy"
        );
        assert_eq!(s["momentum"], s1["momentum"], "{r} ranks: momentum");
        // The deposit analysis gathers its columns from every rank.
        assert_eq!(s["results"], s1["results"], "{r} ranks: collapse results");
        if *r == 4 {
            assert!(
                s["rebalances"].as_u64().unwrap() > 0,
                "4 ranks never rebalanced"
            );
        }
    }
    // Mass is conserved to the bit: the same point masses, summed exactly whatever the
    // order in which the points now lie.
    let m = s1["mass_kg_m"].as_array().unwrap();
    assert_eq!(m[0], m[1], "mass");
}

#[test]
fn mpm_apic_walls_mu_i_checkpoint_on_2_ranks_restarts_on_3_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join(SCENE)).unwrap();
    // With APIC, so that the points' affine moments must survive migration and the
    // checkpoint for the runs to agree, side walls, whose strips cross the slab faces, and
    // μ(I) friction.
    let with_ckpt = text
        .replace(
            "every_s = 0.04",
            "every_s = 0.04\ncheckpoint_every_steps = 1200",
        )
        .replace(
            "separation_volume_ratio = 1.15",
            "separation_volume_ratio = 1.15\ninertial_friction = { limit_friction_deg = 32.76, \
             reference_inertial_number = 0.279, grain_diameter_m = 1.15e-3, \
             grain_density_kg_m3 = 2500.0 }",
        )
        .replace(
            "update = \"usf\"",
            "update = \"usf\"\nvelocity_transfer = \"apic\"\nside_walls = { gap_m = 0.1, friction = 0.46 }",
        );
    assert!(
        with_ckpt.contains("apic")
            && with_ckpt.contains("checkpoint_every_steps")
            && with_ckpt.contains("side_walls")
            && with_ckpt.contains("inertial_friction")
    );
    let scene = tmp.path().join("ckpt.toml");
    std::fs::write(&scene, with_ckpt).unwrap();
    let (full, part, cont) = (
        tmp.path().join("full"),
        tmp.path().join("part"),
        tmp.path().join("cont"),
    );
    run(1, &scene, &full, &[]);
    run(2, &scene, &part, &[]);
    let ckpt = part.join("checkpoint.h5");
    assert!(ckpt.is_file());
    run(3, &scene, &cont, &["--restart", ckpt.to_str().unwrap()]);
    let (a, b) = (snapshots(&full), snapshots(&cont));
    // The restarted run writes the snapshots after the checkpoint: compare its last one.
    assert_same(&a[a.len() - 1..], &b[b.len() - 1..], "restart");
    // It did restart from the last checkpoint (step 2400 of 3193), not from the start.
    let from = summary(&cont)["restarted_from_step"].as_u64().unwrap();
    assert!(
        from > 0 && from.is_multiple_of(1200),
        "restarted from step {from}"
    );
    // The summary's totals, the initial mass among them, are those of the uninterrupted run.
    let (s_full, s_cont) = (summary(&full), summary(&cont));
    for key in [
        "mass_kg_m",
        "kinetic_energy_j_m",
        "momentum",
        "yielding_points",
    ] {
        assert_eq!(s_full[key], s_cont[key], "after the restart: {key}");
    }
}
