//! The sizes a scene may ask for, checked before anything is allocated: every number in the
//! file finite, the lattice, grain and point counts within what a process can address.
//! What depends on the machine and the launch (memory per rank, run length) is the
//! driver's to judge, with `--force` to override.

use super::SceneError;
use std::path::Path;

/// Most lattice or grid cells a scene may have (2⁴⁰ ≈ 1.1·10¹²: beyond any machine's
/// memory; a cell of the lattice takes 38–146 bytes).
pub const MAX_CELLS: u64 = 1 << 40;
/// Most grains a packed sample may hold (its count is estimated from the rectangle, the
/// solid fraction and the mean radius before packing).
pub const MAX_GRAINS: f64 = 1e8;
/// Most material points a scene may fill (each takes about 200 bytes).
pub const MAX_POINTS: f64 = 1e9;
/// Largest gravity component (m/s²): 10⁵ g is beyond any centrifuge.
pub const MAX_GRAVITY_M_S2: f64 = 1e6;
/// Largest initial or wall speed (m/s).
pub const MAX_SPEED_M_S: f64 = 1e4;
/// Most DEM sub-steps per fluid step.
pub const MAX_SUBSTEPS: u32 = 100_000;

/// The first number in the file that is NaN or infinite, as an error with its key path.
pub(crate) fn refuse_non_finite(text: &str, path: &Path) -> Result<(), SceneError> {
    let Ok(raw) = toml::from_str::<toml::Value>(text) else {
        return Ok(());
    };
    match first_non_finite(&raw, "") {
        None => Ok(()),
        Some((key, v)) => Err(SceneError::Invalid {
            path: path.to_owned(),
            line: super::unknown::line_of(text, &key),
            message: format!("must be a finite number, got {v}"),
            key,
        }),
    }
}

fn first_non_finite(v: &toml::Value, at: &str) -> Option<(String, f64)> {
    match v {
        toml::Value::Float(x) if !x.is_finite() => Some((at.to_string(), *x)),
        toml::Value::Table(t) => t.iter().find_map(|(k, v)| {
            let p = if at.is_empty() {
                k.clone()
            } else {
                format!("{at}.{k}")
            };
            first_non_finite(v, &p)
        }),
        toml::Value::Array(a) => a
            .iter()
            .enumerate()
            .find_map(|(n, v)| first_non_finite(v, &format!("{at}[{n}]"))),
        _ => None,
    }
}

/// `cells` = nx × ny within [`MAX_CELLS`] (no overflow on the way).
pub(crate) fn cell_count(cells: [usize; 2]) -> Option<u64> {
    (cells[0] as u64)
        .checked_mul(cells[1] as u64)
        .filter(|&n| n <= MAX_CELLS)
}
