//! Where a scene came from, for errors that name the key and its line; and the checks
//! every kind of scene shares.

use super::check::Check;
use super::SceneError;
use std::path::Path;

/// Where the scene came from, for messages.
pub(crate) struct Context<'a> {
    pub text: &'a str,
    pub path: &'a Path,
    pub base_dir: &'a Path,
}

/// 1-based line of the `nth` occurrence (0-based) of `key = …` in `text`: `key` a whole
/// word, outside comments.
pub(crate) fn line_of_key(text: &str, key: &str, nth: usize) -> Option<usize> {
    let mut seen = 0;
    for (i, line) in text.lines().enumerate() {
        let code = line.split('#').next().unwrap_or("");
        let mut rest = code;
        while let Some(pos) = rest.find(key) {
            let before = rest[..pos].chars().last();
            let after = rest[pos + key.len()..].trim_start();
            let word_start = before.is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
            if word_start && after.starts_with('=') {
                if seen == nth {
                    return Some(i + 1);
                }
                seen += 1;
                break;
            }
            rest = &rest[pos + key.len()..];
        }
    }
    None
}

impl Context<'_> {
    /// 1-based line of the `nth` occurrence (0-based) of `key = …` in the text.
    fn line_of(&self, key: &str, nth: usize) -> Option<usize> {
        line_of_key(self.text, key, nth)
    }

    /// An `Invalid` error for the `nth` occurrence of `key`.
    pub(crate) fn err(&self, key: &str, nth: usize, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            path: self.path.to_owned(),
            line: self.line_of(key, nth),
            key: key.to_owned(),
            message: message.into(),
        }
    }
}

pub(crate) fn positive(ctx: &Context, key: &str, v: f64, what: &str) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(ctx.err(key, 0, format!("{what} must be a positive number, got {v}")))
    }
}

/// Each check gives expected with one tolerance, or max and/or min.
pub(crate) fn validate_checks(checks: &[Check], ctx: &Context) -> Result<(), SceneError> {
    for (n, c) in checks.iter().enumerate() {
        let forms = [c.expected.is_some(), c.max.is_some() || c.min.is_some()];
        let tol = c.tolerance.is_some() as u8 + c.relative_tolerance.is_some() as u8;
        let ok = match forms {
            [true, false] => tol == 1,
            [false, true] => tol == 0,
            _ => false,
        };
        if !ok {
            return Err(ctx.err(
                "quantity",
                n,
                format!(
                    "check on `{}` must give either expected with one of tolerance/relative_tolerance, or max and/or min",
                    c.quantity
                ),
            ));
        }
        for (key, v) in [
            ("tolerance", c.tolerance),
            ("relative_tolerance", c.relative_tolerance),
        ] {
            if v.is_some_and(|t| !(t >= 0.0)) {
                return Err(ctx.err(
                    key,
                    0,
                    format!(
                        "check on `{}`: {key} must be ≥ 0, got {}",
                        c.quantity,
                        v.unwrap_or(0.0)
                    ),
                ));
            }
        }
        if let (Some(lo), Some(hi)) = (c.min, c.max) {
            if lo > hi {
                return Err(ctx.err(
                    "min",
                    0,
                    format!(
                        "check on `{}`: min ({lo}) is above max ({hi}); no value passes",
                        c.quantity
                    ),
                ));
            }
        }
    }
    Ok(())
}
