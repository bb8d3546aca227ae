//! Key paths for the strict parse's errors. serde reads a tagged table (`west = { kind =
//! "velocity", … }`, `[[obstacles]]`) whole before it knows its variant, so toml can only
//! point at the table when a value inside it has the wrong type or a key is missing. The
//! file is parsed again with its spans, the error's position is mapped to the innermost key
//! around it, and a wrong type or an unknown variant is traced to the value inside that
//! table that has it.

use super::SceneError;
use serde::de::DeserializeOwned;
use std::ops::Range;
use std::path::Path;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// Deserialize `text` strictly; an error names the key path and its line where it can be
/// found, otherwise it is toml's own message.
pub(crate) fn strict<T: DeserializeOwned>(text: &str, path: &Path) -> Result<T, SceneError> {
    toml::from_str(text).map_err(|e| locate(text, path, &e))
}

/// `e` as an error naming its key path, when its position lies inside a key or value.
fn locate(text: &str, path: &Path, e: &toml::de::Error) -> SceneError {
    let fallback = || SceneError::Parse {
        path: path.to_owned(),
        message: e.to_string().trim_end().to_string(),
    };
    let (Some(span), Ok(doc)) = (e.span(), DeTable::parse(text)) else {
        return fallback();
    };
    let message = e.message().trim_end().to_string();
    // On an array of tables' `[[name]]` header: the name.
    let header = text[span.start.min(text.len())..]
        .strip_prefix("[[")
        .and_then(|h| h.split("]]").next())
        .map(|h| h.split('.').map(str::trim).collect::<Vec<_>>().join("."));
    let Some(found) = innermost(doc.get_ref(), span.start, header.as_deref(), "") else {
        return fallback();
    };
    let (key, at, hint) = refine(text, &found, &message);
    SceneError::Invalid {
        path: path.to_owned(),
        line: Some(text[..at.min(text.len())].matches('\n').count() + 1),
        key,
        message: format!("{message}{hint}"),
    }
}

/// A key path and its value's span and node.
struct Found<'a, 'i> {
    path: String,
    span: Range<usize>,
    value: &'a DeValue<'i>,
}

fn join(at: &str, key: &str) -> String {
    if at.is_empty() {
        key.to_string()
    } else {
        format!("{at}.{key}")
    }
}

/// The innermost entry of `table` (key path prefix `at`) whose key or value spans `pos`;
/// when `pos` is on the `[[header]]` of an array of tables, the element that follows it.
fn innermost<'a, 'i>(
    table: &'a DeTable<'i>,
    pos: usize,
    header: Option<&str>,
    at: &str,
) -> Option<Found<'a, 'i>> {
    for (k, v) in table {
        let path = join(at, k.get_ref());
        // A `[table]`'s span need not cover its body: look inside every table.
        if header == Some(path.as_str()) {
            // toml puts every element's error on the array's first header: the whole array,
            // for `refine` to search.
            return Some(Found {
                path,
                span: v.span(),
                value: v.get_ref(),
            });
        }
        let deeper = match v.get_ref() {
            DeValue::Array(items) => in_array(items, pos, header, &path),
            DeValue::Table(t) => innermost(t, pos, header, &path),
            _ => None,
        };
        if deeper.is_some() {
            return deeper;
        }
        if k.span().contains(&pos) || v.span().contains(&pos) {
            return Some(Found {
                path,
                span: v.span(),
                value: v.get_ref(),
            });
        }
    }
    None
}

/// The innermost entry under the element of `items` (key path `path`) that spans `pos`.
fn in_array<'a, 'i>(
    items: &'a [Spanned<DeValue<'i>>],
    pos: usize,
    header: Option<&str>,
    path: &str,
) -> Option<Found<'a, 'i>> {
    // An array of tables' element spans need not cover their bodies: look inside each.
    for (n, item) in items.iter().enumerate() {
        let path = format!("{path}[{n}]");
        let deeper = match item.get_ref() {
            DeValue::Table(t) => innermost(t, pos, header, &path),
            DeValue::Array(inner) => in_array(inner, pos, header, &path),
            _ => None,
        };
        if deeper.is_some() {
            return deeper;
        }
    }
    let hit = items.iter().position(|x| x.span().contains(&pos))?;
    let item = &items[hit];
    Some(Found {
        path: format!("{path}[{hit}]"),
        span: item.span(),
        value: item.get_ref(),
    })
}

/// The key path, the byte offset to name the line of, and a hint: for a wrong type inside a
/// table, the value in it that has that type; for an unknown variant, the first string in
/// it with that value; for a missing key, the table's keys that look like it.
fn refine(text: &str, found: &Found, message: &str) -> (String, usize, String) {
    let whole = (found.path.clone(), found.span.start, String::new());
    if let Some(rest) = message.strip_prefix("unknown variant `") {
        // serde names the value, not its key: the string inside the table that has it.
        let got = format!("string {:?}", rest.split('`').next().unwrap_or(""));
        let mut leaves = Vec::new();
        leaves_of(found.value, found.span.clone(), &found.path, &mut leaves);
        return leaves
            .into_iter()
            .find(|(_, s)| matches(&text[s.clone()], &got))
            .map_or(whole, |(p, s)| (p, s.start, String::new()));
    }
    if let Some(rest) = message.strip_prefix("invalid type: ") {
        let got = rest.split(", expected").next().unwrap_or("");
        let mut leaves = Vec::new();
        leaves_of(found.value, found.span.clone(), &found.path, &mut leaves);
        if let Some((p, s)) = leaves
            .into_iter()
            .find(|(_, s)| matches(&text[s.clone()], got))
        {
            return (p, s.start, String::new());
        }
        return whole;
    }
    if let (Some(field), DeValue::Array(items)) = (missing_field(message), found.value) {
        // The first element of an array of tables that lacks the field.
        if let Some((n, item)) = items.iter().enumerate().find(|(_, x)| match x.get_ref() {
            DeValue::Table(t) => !t.keys().any(|k| k.get_ref() == field),
            _ => false,
        }) {
            let inner = Found {
                path: format!("{}[{n}]", found.path),
                span: item.span(),
                value: item.get_ref(),
            };
            return refine(text, &inner, message);
        }
    }
    if let (Some(field), DeValue::Table(t)) = (missing_field(message), found.value) {
        let near: Vec<String> = t
            .keys()
            .map(|k| k.get_ref().to_string())
            .filter(|k| edit_distance(k, field) <= 2)
            .collect();
        let hint = if near.is_empty() {
            format!(" in `{}`", found.path)
        } else {
            format!(
                " in `{}` (it has `{}`: a misspelling of `{field}`?)",
                found.path,
                near.join("`, `")
            )
        };
        return (format!("{}.{field}", found.path), found.span.start, hint);
    }
    whole
}

/// The field of a "missing field `x`" message.
fn missing_field(message: &str) -> Option<&str> {
    message.strip_prefix("missing field `")?.split('`').next()
}

/// Every value under `v` (key path `path`, span `span`), scalars and arrays alike, in the
/// file's order, with its key path.
fn leaves_of(v: &DeValue, span: Range<usize>, path: &str, out: &mut Vec<(String, Range<usize>)>) {
    match v {
        DeValue::Table(t) => {
            let mut entries: Vec<_> = t.iter().collect();
            entries.sort_by_key(|(k, _)| k.span().start);
            for (k, x) in entries {
                leaves_of(x.get_ref(), x.span(), &join(path, k.get_ref()), out);
            }
        }
        DeValue::Array(items) => {
            out.push((path.to_string(), span));
            for (n, x) in items.iter().enumerate() {
                leaves_of(x.get_ref(), x.span(), &format!("{path}[{n}]"), out);
            }
        }
        _ => out.push((path.to_string(), span)),
    }
}

/// Whether the source text of a value matches serde's description of what it got
/// (`string "x"`, `integer `7``, `floating point `1.5``, `boolean `true``, `sequence`,
/// `map`).
fn matches(source: &str, got: &str) -> bool {
    let quoted = |s: &str| s.split('`').nth(1).map(str::to_string);
    if let Some(s) = got.strip_prefix("string ") {
        let inner = source.trim_matches(|c| c == '"' || c == '\'');
        return source.starts_with(['"', '\'']) && format!("{inner:?}") == s;
    }
    if got.starts_with("integer") || got.starts_with("floating point") {
        let (Some(want), Ok(have)) = (quoted(got), source.replace('_', "").parse::<f64>()) else {
            return false;
        };
        return want.parse::<f64>().is_ok_and(|w| w == have);
    }
    if got.starts_with("boolean") {
        return quoted(got).is_some_and(|b| b == source);
    }
    match got {
        "sequence" => source.starts_with('['),
        "map" => source.starts_with('{'),
        _ => false,
    }
}

/// Levenshtein distance between two short keys.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + (ca != *cb) as usize).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::edit_distance;

    #[test]
    fn edit_distance_counts_single_edits() {
        assert_eq!(edit_distance("knd", "kind"), 1);
        assert_eq!(edit_distance("kind", "kind"), 0);
        assert_eq!(edit_distance("shape", "kind"), 5);
    }
}
