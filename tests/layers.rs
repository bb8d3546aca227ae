//! The crate graph is the architecture (ARCHITECTURE.md): each workspace crate may depend
//! only on the crates of lower layers, the physics crates not on each other, and only
//! `decomposition` on MPI. Read from `cargo metadata`, so a new dependency that breaks a
//! rule fails here, in every kind (normal, dev and build).

use std::collections::BTreeMap;
use std::process::Command;

/// Each workspace crate and its layer; a crate may depend on crates of lower layers only.
const LAYERS: [(&str, u32); 10] = [
    ("decomposition", 0),
    ("grainflow-lbm", 1),
    ("grainflow-dem", 1),
    ("grainflow-mpm", 1),
    ("grainflow-coupling", 2),
    ("grainflow-scene", 3),
    ("grainflow-io", 4),
    ("grainflow-analysis", 5),
    ("grainflow-stability", 6),
    ("grainflow", 7),
];

/// External crates only one workspace crate may use: MPI lives in `decomposition`.
const ONLY_IN: [(&str, &str); 1] = [("mpi", "decomposition")];

/// Every workspace crate with the names of its dependencies (all kinds).
fn workspace() -> BTreeMap<String, Vec<String>> {
    let out = Command::new(env!("CARGO"))
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    meta["packages"]
        .as_array()
        .expect("packages")
        .iter()
        .map(|p| {
            let deps = p["dependencies"]
                .as_array()
                .expect("dependencies")
                .iter()
                .map(|d| d["name"].as_str().expect("name").to_string())
                .collect();
            (p["name"].as_str().expect("name").to_string(), deps)
        })
        .collect()
}

/// The broken rules of a workspace, one line each.
fn violations(ws: &BTreeMap<String, Vec<String>>) -> Vec<String> {
    let layer: BTreeMap<&str, u32> = LAYERS.into_iter().collect();
    let mut broken = Vec::new();
    for (name, deps) in ws {
        let Some(&own) = layer.get(name.as_str()) else {
            broken.push(format!(
                "{name} has no layer: add it to LAYERS and ARCHITECTURE.md"
            ));
            continue;
        };
        for d in deps {
            if let Some(&theirs) = layer.get(d.as_str()) {
                if theirs >= own {
                    broken.push(format!(
                        "{name} (layer {own}) depends on {d} (layer {theirs}): only lower \
                         layers may be used"
                    ));
                }
            }
            for (external, owner) in ONLY_IN {
                if d == external && name != owner {
                    broken.push(format!("{name} depends on {d}, which only {owner} may use"));
                }
            }
        }
    }
    broken
}

#[test]
fn every_crate_depends_only_on_lower_layers() {
    let ws = workspace();
    for (name, _) in LAYERS {
        assert!(ws.contains_key(name), "{name} is not in the workspace");
    }
    let broken = violations(&ws);
    assert!(
        broken.is_empty(),
        "the crate graph breaks the layers:\n{}",
        broken.join("\n")
    );
}

#[test]
fn an_upward_or_sideways_dependency_is_caught() {
    let mut ws = workspace();
    ws.get_mut("grainflow-lbm")
        .unwrap()
        .push("grainflow-scene".into());
    ws.get_mut("grainflow-dem")
        .unwrap()
        .push("grainflow-mpm".into());
    ws.get_mut("grainflow-io").unwrap().push("mpi".into());
    let broken = violations(&ws);
    assert_eq!(broken.len(), 3, "{broken:?}");
}
