//! `grainflow run --wait-policy`: whether the idle workers look for work through the time
//! loop (`active`) or sleep until woken (`passive`), a coupled run gives the same bits
//! (every parallel pass is deterministic on any schedule).
mod common;
use common::{assert_bit_identical, assert_grains_identical, root, summary};

#[test]
fn active_and_passive_waiting_give_the_same_bits() {
    let tmp = tempfile::tempdir().unwrap();
    let run = |policy: &str| {
        let out = tmp.path().join(policy);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_grainflow"))
            .args(["run", "tests/scenes/submerged_small.toml", "--out"])
            .arg(&out)
            .args(["--steps", "1600", "--threads", "2", "--quiet"])
            .args(["--wait-policy", policy])
            .current_dir(root())
            .output()
            .expect("grainflow starts");
        assert!(
            o.status.success(),
            "{policy}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        out
    };
    let (active, passive) = (run("active"), run("passive"));
    // Each run did what it was asked (the comparison below would pass with neither spinning).
    assert_eq!(summary(&active)["idle_workers_active"], true);
    assert_eq!(summary(&passive)["idle_workers_active"], false);
    assert_bit_identical(&active, &passive);
    assert_grains_identical(&active, &passive);
}
