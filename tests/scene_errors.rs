//! A mutation corpus over every shipped scene (`jobs/` and `tests/scenes/`): each value in
//! turn is given a value of the wrong type (a number becomes a string, a string a number, a
//! boolean a string), and the scene is parsed. Every mutant must be refused, and the error
//! must name the value's key path (`boundaries.west.velocity_m_s[1]`), also inside tagged
//! tables, whose values serde reads before it knows their variant.
mod common;
use common::root;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::de::{DeTable, DeValue};

/// Every `.toml` scene under `dir`, recursively, sorted.
fn scenes(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            scenes(&p, out);
        } else if p.extension().is_some_and(|e| e == "toml") {
            out.push(p);
        }
    }
}

/// Every scalar value under `v` (key path `path`) with its span.
fn leaves(v: &DeValue, span: Range<usize>, path: &str, out: &mut Vec<(String, Range<usize>)>) {
    let join = |k: &str| {
        if path.is_empty() {
            k.to_string()
        } else {
            format!("{path}.{k}")
        }
    };
    match v {
        DeValue::Table(t) => {
            for (k, x) in t {
                leaves(x.get_ref(), x.span(), &join(k.get_ref()), out);
            }
        }
        DeValue::Array(items) => {
            for (n, x) in items.iter().enumerate() {
                leaves(x.get_ref(), x.span(), &format!("{path}[{n}]"), out);
            }
        }
        _ => out.push((path.to_string(), span)),
    }
}

/// Parse `text` as the scene at `path` would be (by its tables, as `load_any` does).
fn parse(text: &str, path: &Path) -> Result<(), String> {
    use grainflow::scene::{parse, parse_grains, parse_mpm};
    let table: toml::Table = toml::from_str(text).map_err(|e| e.to_string())?;
    let r = if table.contains_key("mpm") {
        parse_mpm(text, path).map(|_| ())
    } else if table.contains_key("grains") && !table.contains_key("fluid") {
        parse_grains(text, path).map(|_| ())
    } else {
        parse(text, path).map(|_| ())
    };
    r.map_err(|e| e.to_string())
}

#[test]
fn a_value_of_the_wrong_type_is_refused_naming_its_key_path() {
    let mut files = Vec::new();
    scenes(&root().join("jobs"), &mut files);
    scenes(&root().join("tests/scenes"), &mut files);
    let (mut total, mut named) = (0, 0);
    let mut unnamed = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        let Ok(doc) = DeTable::parse(&text) else {
            continue;
        };
        // Only scenes that parse as they are (the corpus mutates good scenes).
        if parse(&text, file).is_err() {
            continue;
        }
        let mut found = Vec::new();
        leaves(&DeValue::Table(doc.get_ref().clone()), 0..0, "", &mut found);
        for (key, span) in found {
            let old = &text[span.clone()];
            let new = if old.starts_with(['"', '\'']) {
                "7"
            } else {
                "\"x\""
            };
            let mutant = format!("{}{new}{}", &text[..span.start], &text[span.end..]);
            total += 1;
            match parse(&mutant, file) {
                Ok(()) => unnamed.push(format!("{}: `{key}` = {new} accepted", file.display())),
                Err(e) if e.contains(&format!("`{key}`")) => named += 1,
                Err(e) => unnamed.push(format!(
                    "{}: `{key}` = {new}: {}",
                    file.display(),
                    e.lines().next().unwrap_or("")
                )),
            }
        }
    }
    let share = named as f64 / total as f64;
    eprintln!(
        "{named} of {total} mutants ({:.1} %) in {} scenes name their key path",
        100.0 * share,
        files.len()
    );
    for u in unnamed.iter().take(40) {
        eprintln!("  {u}");
    }
    assert!(total > 1000, "{total} mutants");
    assert!(
        share >= 0.95,
        "{} mutants do not name their key",
        unnamed.len()
    );
}

/// The errors inside tagged tables name the key and its line: a wrong type in an inline
/// table, a misspelled tag (with the near miss named), a missing key in the second element
/// of an array of tables, an unknown value of an enum inside an array of tables and of a
/// tag.
#[test]
fn errors_inside_tagged_tables_name_the_key_and_line() {
    let path = root().join("jobs/cylinder/scene.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let cases = [
        (
            text.replace("velocity_m_s = [0.3, 0.0]", "velocity_m_s = [0.3, \"x\"]"),
            ":17: `boundaries.west.velocity_m_s[1]`: invalid type: string \"x\"",
        ),
        (
            text.replace("south = { kind = \"wall\" }", "south = { knd = \"wall\" }"),
            ":19: `boundaries.south.kind`: missing field `kind` in `boundaries.south` (it has \
             `knd`: a misspelling of `kind`?)",
        ),
        (
            text.replace("name = \"back\"\n", ""),
            "`probes[2].name`: missing field `name`",
        ),
        (
            text.replace("wall = \"interpolated\"", "wall = \"bogus\""),
            ":28: `obstacles[0].wall`: unknown variant `bogus`",
        ),
        (
            text.replace("north = { kind = \"wall\" }", "north = { kind = \"wal\" }"),
            ":20: `boundaries.north.kind`: unknown variant `wal`",
        ),
    ];
    for (mutant, want) in cases {
        let e = grainflow::scene::parse(&mutant, &path)
            .unwrap_err()
            .to_string();
        assert!(e.contains(want), "{e}\nlacks {want}");
    }
}
