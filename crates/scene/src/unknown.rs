//! Keys the strict parse let through: serde rejects unknown keys in every table, except
//! beside the tag of a variant that takes no parameters (`south = { kind = "wall",
//! velocity_m_s = … }`, `collision = { model = "bgk", magic = 0.2 }`), where it ignores
//! them. The parsed scene is written back to TOML and every key of the file that did not
//! survive the round trip is an error with its key path.

use super::SceneError;
use serde::Serialize;
use std::path::Path;

/// The first key of `raw` (the file as a TOML table) that `parsed` (the scene it gave)
/// does not hold, as an error naming its path. Nothing when the scene cannot be written
/// back (then there is nothing to compare).
pub(crate) fn refuse_ignored<T: Serialize>(
    raw_text: &str,
    parsed: &T,
    path: &Path,
) -> Result<(), SceneError> {
    let (Ok(raw), Ok(back)) = (
        toml::from_str::<toml::Value>(raw_text),
        toml::Value::try_from(parsed),
    ) else {
        return Ok(());
    };
    match first_ignored(&raw, &back, "") {
        None => Ok(()),
        Some((key_path, tag)) => Err(SceneError::Invalid {
            path: path.to_owned(),
            line: line_of(raw_text, &key_path),
            message: match tag {
                Some(tag) => format!(
                    "unknown key: `{tag}` takes no parameter here; remove it (or choose a \
                     variant that takes it)"
                ),
                None => "unknown key; remove it or correct its spelling".into(),
            },
            key: key_path,
        }),
    }
}

/// The path of the first key in `raw` missing from `back`, and the variant tag beside it
/// (`kind = "wall"`), if any.
fn first_ignored(
    raw: &toml::Value,
    back: &toml::Value,
    at: &str,
) -> Option<(String, Option<String>)> {
    match (raw, back) {
        (toml::Value::Table(r), toml::Value::Table(b)) => {
            for (key, value) in r {
                let path = if at.is_empty() {
                    key.clone()
                } else {
                    format!("{at}.{key}")
                };
                match b.get(key) {
                    Some(kept) => {
                        if let Some(found) = first_ignored(value, kept, &path) {
                            return Some(found);
                        }
                    }
                    None => {
                        let tag = ["kind", "model", "distribution", "shape"]
                            .iter()
                            .find_map(|t| r.get(*t).and_then(|v| v.as_str()))
                            .map(|v| format!("\"{v}\""));
                        return Some((path, tag));
                    }
                }
            }
            None
        }
        (toml::Value::Array(r), toml::Value::Array(b)) if r.len() == b.len() => r
            .iter()
            .zip(b)
            .enumerate()
            .find_map(|(n, (x, y))| first_ignored(x, y, &format!("{at}[{n}]"))),
        _ => None,
    }
}

/// 1-based line of the last key of `key_path` (`a.b[2].c` → `c = …`) in `text`.
pub(crate) fn line_of(text: &str, key_path: &str) -> Option<usize> {
    let last = key_path.rsplit('.').next().unwrap_or(key_path);
    let key = last.split('[').next().unwrap_or(last);
    super::context::line_of_key(text, key, 0)
}
