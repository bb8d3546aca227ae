//! Pass/fail checks on named results.

use super::Results;
use scene::Check;
use serde::Serialize;

/// The outcome of one check, as written to `summary.json`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct CheckOutcome {
    /// Quantity name.
    pub quantity: String,
    /// Measured value (absent when the quantity was not produced).
    pub value: Option<f64>,
    /// Reference value.
    pub expected: Option<f64>,
    /// Absolute tolerance.
    pub tolerance: Option<f64>,
    /// Relative tolerance.
    pub relative_tolerance: Option<f64>,
    /// Lower bound.
    pub min: Option<f64>,
    /// Upper bound.
    pub max: Option<f64>,
    /// Whether it passed.
    pub passed: bool,
    /// Why it was not judged (a shortened run, or an analysis that could not run); such a
    /// check does not fail the run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skipped: Option<String>,
}

/// Mark checks as not judged, with `why`: every one with `every` (a run cut short by the
/// command line, where the scene's checks do not apply), else those whose quantity was not
/// measured.
pub fn mark_skipped(outcomes: &mut [CheckOutcome], why: &str, every: bool) {
    for c in outcomes.iter_mut() {
        if every || c.value.is_none() {
            c.skipped = Some(why.to_string());
        }
    }
}

/// Whether a check failed the run: one that failed and was judged.
pub fn any_failed(outcomes: &[CheckOutcome]) -> bool {
    outcomes.iter().any(|c| !c.passed && c.skipped.is_none())
}

/// Evaluate every check against the results.
pub fn evaluate(checks: &[Check], results: &Results) -> Vec<CheckOutcome> {
    checks
        .iter()
        .map(|c| {
            let value = results.get(&c.quantity).copied();
            let passed = value.is_some_and(|v| {
                v.is_finite()
                    && c.min.is_none_or(|m| v >= m)
                    && c.max.is_none_or(|m| v <= m)
                    && match c.expected {
                        None => true,
                        Some(e) => {
                            let d = (v - e).abs();
                            c.tolerance.is_none_or(|t| d <= t)
                                && c.relative_tolerance.is_none_or(|t| d <= t * e.abs())
                        }
                    }
            });
            CheckOutcome {
                quantity: c.quantity.clone(),
                value,
                expected: c.expected,
                tolerance: c.tolerance,
                relative_tolerance: c.relative_tolerance,
                min: c.min,
                max: c.max,
                passed,
                skipped: None,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(q: &str) -> Check {
        Check {
            quantity: q.into(),
            expected: None,
            tolerance: None,
            relative_tolerance: None,
            max: None,
            min: None,
        }
    }

    #[test]
    fn forms_pass_and_fail() {
        let mut r = Results::new();
        r.insert("a".into(), 0.14);
        let mut c1 = check("a");
        c1.expected = Some(0.141);
        c1.tolerance = Some(0.002);
        let mut c2 = check("a");
        c2.expected = Some(0.145); // |0.14 − 0.145| = 0.005 ≤ 5 % of 0.145
        c2.relative_tolerance = Some(0.05);
        let mut c3 = check("a");
        c3.max = Some(0.1);
        let c4 = check("missing");
        let o = evaluate(&[c1, c2, c3, c4], &r);
        assert_eq!(
            o.iter().map(|c| c.passed).collect::<Vec<_>>(),
            [true, true, false, false]
        );
    }

    #[test]
    fn nan_never_passes() {
        let mut r = Results::new();
        r.insert("a".into(), f64::NAN);
        let mut c = check("a");
        c.max = Some(1.0);
        assert!(!evaluate(&[c], &r)[0].passed);
    }
}
