//! Keys of the dialects grainflow read before its scene language was unified: each is an
//! error that names its replacement (and `scripts/migrate-scenes.py`, which rewrites a
//! file), found before the strict parse so the message is not serde's "unknown field".

use super::SceneError;
use std::path::Path;

/// (table, key, replacement) for every key that moved.
const MOVED: &[(&str, &str, &str)] = &[
    ("", "region", "`[domain]` with `size_m = [width, height]` (the old `max_m`; the origin is the lower-left corner)"),
    ("mpm", "domain_m", "`[domain] cells = [nx, ny]` (the old `domain_m` divided by the cell size)"),
    ("mpm", "cell_size_m", "`[domain] spacing_m`"),
    ("mpm", "boundaries", "a top-level `[boundaries]` table with west, east, south, north (left, right, bottom, top before)"),
    ("run", "output_every", "`[output] every_steps`"),
    ("run", "output_every_s", "`[output] every_s`"),
    ("run", "fields", "`[output] fields`"),
    ("run", "pictures", "`[output] pictures`"),
    ("run", "compression", "`[output] compression`"),
    ("run", "picture_field", "`[output] picture_field`"),
    ("run", "probe_every", "`[output] probe_every_steps`"),
    ("run", "checkpoint_every", "`[output] checkpoint_every_steps`"),
    ("run", "checkpoint_minutes", "`[output] checkpoint_every_minutes`"),
    ("run", "checkpoint_at_end", "`[output] checkpoint_at_end`"),
];

/// The first key of an old dialect in `table`, as an error naming its replacement.
pub(crate) fn check(table: &toml::Table, text: &str, path: &Path) -> Result<(), SceneError> {
    for (parent, key, replacement) in MOVED {
        let holder = if parent.is_empty() {
            Some(table)
        } else {
            table.get(*parent).and_then(|v| v.as_table())
        };
        if holder.is_some_and(|t| t.contains_key(*key)) {
            let name = if parent.is_empty() {
                key.to_string()
            } else {
                format!("{parent}.{key}")
            };
            return Err(SceneError::Invalid {
                path: path.to_owned(),
                line: line_of(text, key),
                key: name,
                message: format!(
                    "this key is from an older scene dialect; it is now {replacement}. \
                     `python3 scripts/migrate-scenes.py FILE` rewrites a scene"
                ),
            });
        }
    }
    Ok(())
}

/// 1-based line of the first `[key]` header or `key =` in `text`.
fn line_of(text: &str, key: &str) -> Option<usize> {
    let header = format!("[{key}]");
    text.lines()
        .position(|l| l.split('#').next().unwrap_or("").trim() == header)
        .map(|i| i + 1)
        .or_else(|| super::context::line_of_key(text, key, 0))
}
