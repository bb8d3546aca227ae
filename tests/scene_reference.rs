//! Every key of the scene language has an entry in `docs/scene-reference.md`: the keys are
//! read from the schema's source (the fields of every serde struct and struct variant), so a
//! key added without documentation fails here.

mod common;

use std::collections::BTreeSet;

/// The files that define the scene language's tables.
const SCHEMA: [&str; 10] = [
    "crates/scene/src/schema.rs",
    "crates/scene/src/pictures.rs",
    "crates/scene/src/grains.rs",
    "crates/scene/src/mpm.rs",
    "crates/scene/src/output.rs",
    "crates/scene/src/coupling.rs",
    "crates/scene/src/check.rs",
    "crates/mpm/src/grid.rs",
    "crates/mpm/src/shape.rs",
    "crates/mpm/src/system.rs",
];

/// The field names of every item deriving `Deserialize` in `source`: struct fields and the
/// fields of struct variants.
fn keys(source: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let lines: Vec<&str> = source.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        let derives =
            lines[i].trim_start().starts_with("#[derive(") && lines[i].contains("Deserialize");
        i += 1;
        if !derives {
            continue;
        }
        // The item the derive is attached to: past its other attributes and docs.
        while i < lines.len()
            && (lines[i].trim_start().starts_with("#[") || lines[i].trim_start().starts_with("///"))
        {
            i += 1;
        }
        let Some(head) = lines.get(i) else { break };
        if !(head.starts_with("pub struct ") || head.starts_with("pub enum "))
            || !head.ends_with('{')
        {
            continue;
        }
        let mut depth = 0i32;
        while i < lines.len() {
            let line = lines[i];
            let code = line.trim();
            if depth >= 1 && !code.starts_with("//") && !code.starts_with('#') {
                let code = code.strip_prefix("pub ").unwrap_or(code);
                if let Some((name, _)) = code.split_once(':') {
                    let name = name.trim();
                    let plain = name
                        .chars()
                        .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
                    if !name.is_empty() && plain {
                        out.insert(name.to_string());
                    }
                }
            }
            depth += line.matches('{').count() as i32 - line.matches('}').count() as i32;
            i += 1;
            if depth <= 0 {
                break;
            }
        }
    }
    out
}

#[test]
fn every_scene_key_is_in_the_reference() {
    let root = common::root();
    let reference = std::fs::read_to_string(root.join("docs/scene-reference.md")).unwrap();
    let mut all = BTreeSet::new();
    for file in SCHEMA {
        let Ok(source) = std::fs::read_to_string(root.join(file)) else {
            continue;
        };
        all.extend(keys(&source));
    }
    assert!(all.len() > 80, "found only {} keys: {all:?}", all.len());
    for must in [
        "cells",
        "every_steps",
        "stop_below_kinetic_energy_j_m",
        "west",
        "friction",
    ] {
        assert!(all.contains(must), "the scan misses `{must}`");
    }
    let missing: Vec<&String> = all
        .iter()
        .filter(|k| !reference.contains(&format!("`{k}`")))
        .collect();
    assert!(
        missing.is_empty(),
        "keys without an entry in docs/scene-reference.md: {missing:?}"
    );
}

#[test]
fn the_scan_finds_struct_and_variant_fields() {
    let src = "#[derive(Deserialize)]\npub struct A {\n    /// doc: not a key\n    pub alpha_m: f64,\n}\n#[derive(Deserialize)]\npub enum B {\n    V {\n        beta: u32,\n    },\n    W,\n}\n";
    let k = keys(src);
    assert_eq!(
        k.into_iter().collect::<Vec<_>>(),
        vec!["alpha_m".to_string(), "beta".to_string()]
    );
}
