//! A pass/fail check on a named result, the same in every kind of scene.

use serde::{Deserialize, Serialize};

/// A pass/fail check on a named quantity. Give `max`, `min`, or `expected` with
/// `tolerance` (absolute) or `relative_tolerance`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Check {
    /// Quantity name, e.g. `poiseuille.max_rel_error`.
    pub quantity: String,
    /// Reference value.
    #[serde(default)]
    pub expected: Option<f64>,
    /// Allowed absolute deviation from `expected`.
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// Allowed relative deviation from `expected`.
    #[serde(default)]
    pub relative_tolerance: Option<f64>,
    /// Upper bound.
    #[serde(default)]
    pub max: Option<f64>,
    /// Lower bound.
    #[serde(default)]
    pub min: Option<f64>,
}
