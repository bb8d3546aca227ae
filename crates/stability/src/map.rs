//! The measured stability map and the verdict `grainflow check` gives from it.
//!
//! The map (`jobs/stability/lbm-map.csv`, made by `grainflow stability-map`) holds, for each
//! operator, test flow, relaxation time τ and lattice Mach number, whether the run stayed
//! stable. At a measured Mach number the *stable limit* is the smallest measured τ from which
//! every larger measured τ was stable in both flows. A scene between two measured Mach
//! numbers is judged against the larger of their two limits (the conservative side).

use super::lbm::{Flow, Operator, Sample};

/// The map shipped with grainflow.
pub const BUILTIN_CSV: &str = include_str!("../../../jobs/stability/lbm-map.csv");

/// What the map says about a (τ, Mach) point.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// Inside the measured stable region: τ at or above the limit measured at this Mach.
    Stable {
        /// The limit τ it is compared with.
        tau_limit: f64,
        /// The measured Mach numbers it came from.
        machs: (f64, f64),
    },
    /// Below the measured limit, or above every Mach number measured stable.
    LikelyUnstable {
        /// The limit τ at this Mach (None: nothing was stable there).
        tau_limit: Option<f64>,
        /// The measured Mach numbers it came from.
        machs: (f64, f64),
    },
}

impl Verdict {
    /// Whether the point is predicted stable.
    pub fn stable(&self) -> bool {
        matches!(self, Verdict::Stable { .. })
    }

    /// One line for `grainflow check`.
    pub fn describe(&self, op: &Operator, tau: f64, mach: f64) -> String {
        let at = |m: (f64, f64)| {
            if m.0 == m.1 {
                format!("Ma {:.2}", m.0)
            } else {
                format!("Ma {:.2}–{:.2}", m.0, m.1)
            }
        };
        match self {
            Verdict::Stable { tau_limit, machs } => format!(
                "inside the measured stable region ({}: stable for τ ≥ {tau_limit} at {}; here τ = {tau:.4}, Ma = {mach:.3})",
                op.name(),
                at(*machs)
            ),
            Verdict::LikelyUnstable {
                tau_limit: Some(t),
                machs,
            } => format!(
                "likely unstable ({}: measured stable only for τ ≥ {t} at {}; here τ = {tau:.4}, Ma = {mach:.3}): raise τ (coarser lattice or higher viscosity), lower the lattice velocity, or use an operator with a lower limit",
                op.name(),
                at(*machs)
            ),
            Verdict::LikelyUnstable {
                tau_limit: None,
                machs,
            } => format!(
                "likely unstable ({}: no measured τ was stable at {}; here Ma = {mach:.3}): lower the lattice velocity",
                op.name(),
                at(*machs)
            ),
        }
    }
}

/// A stability map: measured samples.
#[derive(Debug, Clone, Default)]
pub struct StabilityMap {
    /// The samples.
    pub samples: Vec<Sample>,
}

/// Header of the map's CSV.
pub const HEADER: &str = "flow,operator,tau,mach,re_cell,stable";

impl StabilityMap {
    /// Parse the CSV written by [`StabilityMap::to_csv`].
    pub fn parse(csv: &str) -> Result<Self, String> {
        let mut samples = Vec::new();
        for (n, line) in csv.lines().enumerate().skip(1) {
            if line.trim().is_empty() {
                continue;
            }
            let f: Vec<&str> = line.split(',').collect();
            if f.len() != 6 {
                return Err(format!(
                    "line {}: expected 6 fields, got {}",
                    n + 1,
                    f.len()
                ));
            }
            let flow = Flow::ALL
                .into_iter()
                .find(|x| x.name() == f[0])
                .ok_or_else(|| format!("line {}: unknown flow `{}`", n + 1, f[0]))?;
            let operator = Operator::ALL
                .into_iter()
                .find(|o| o.name() == f[1])
                .ok_or_else(|| format!("line {}: unknown operator `{}`", n + 1, f[1]))?;
            let num = |s: &str| {
                s.parse::<f64>()
                    .map_err(|e| format!("line {}: `{s}`: {e}", n + 1))
            };
            samples.push(Sample {
                flow,
                operator,
                tau: num(f[2])?,
                mach: num(f[3])?,
                stable: f[5] == "1",
            });
        }
        Ok(Self { samples })
    }

    /// The map shipped with grainflow.
    pub fn builtin() -> Self {
        Self::parse(BUILTIN_CSV).expect("the shipped map parses")
    }

    /// The samples as CSV (see [`HEADER`]).
    pub fn to_csv(&self) -> String {
        let mut s = String::from(HEADER);
        s.push('\n');
        for p in &self.samples {
            s += &format!(
                "{},{},{},{},{:.6},{}\n",
                p.flow.name(),
                p.operator.name(),
                p.tau,
                p.mach,
                p.re_cell(),
                p.stable as u8
            );
        }
        s
    }

    /// The measured Mach numbers, increasing.
    fn machs(&self) -> Vec<f64> {
        let mut m: Vec<f64> = self.samples.iter().map(|s| s.mach).collect();
        m.sort_by(f64::total_cmp);
        m.dedup();
        m
    }

    /// The stable limit of `op` at measured Mach `mach`: the smallest measured τ from which
    /// every larger measured τ is stable in every flow (None when the largest is not).
    pub fn tau_limit(&self, op: &Operator, mach: f64) -> Option<f64> {
        let mut taus: Vec<(f64, bool)> = Vec::new();
        for s in self
            .samples
            .iter()
            .filter(|s| s.operator == *op && s.mach == mach)
        {
            match taus.iter_mut().find(|t| t.0 == s.tau) {
                Some(t) => t.1 &= s.stable,
                None => taus.push((s.tau, s.stable)),
            }
        }
        taus.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut limit = None;
        for (tau, stable) in taus.iter().rev() {
            if !stable {
                break;
            }
            limit = Some(*tau);
        }
        limit
    }

    /// The verdict for relaxation time `tau` at lattice Mach number `mach` with `op`.
    pub fn verdict(&self, op: &Operator, tau: f64, mach: f64) -> Verdict {
        let machs = self.machs();
        let (lo, hi) = match machs.iter().position(|&m| m >= mach) {
            Some(0) => (machs[0], machs[0]),
            Some(k) => (machs[k - 1], machs[k]),
            // Beyond the fastest measured: judged by it, and only stable if it was at every τ
            // measured there.
            None => {
                let m = *machs.last().unwrap_or(&0.0);
                return Verdict::LikelyUnstable {
                    tau_limit: None,
                    machs: (m, m),
                };
            }
        };
        let limit = match (self.tau_limit(op, lo), self.tau_limit(op, hi)) {
            (Some(a), Some(b)) => Some(a.max(b)),
            _ => None,
        };
        match limit {
            Some(t) if tau >= t => Verdict::Stable {
                tau_limit: t,
                machs: (lo, hi),
            },
            t => Verdict::LikelyUnstable {
                tau_limit: t,
                machs: (lo, hi),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(op: Operator, tau: f64, mach: f64, stable: bool) -> Sample {
        Sample {
            flow: Flow::Cavity,
            operator: op,
            tau,
            mach,
            stable,
        }
    }

    #[test]
    fn limits_and_verdicts() {
        let op = Operator::ALL[0];
        let map = StabilityMap {
            samples: vec![
                sample(op, 0.51, 0.1, false),
                sample(op, 0.55, 0.1, true),
                sample(op, 0.6, 0.1, true),
                sample(op, 0.51, 0.2, false),
                sample(op, 0.55, 0.2, false),
                sample(op, 0.6, 0.2, true),
            ],
        };
        assert_eq!(map.tau_limit(&op, 0.1), Some(0.55));
        assert_eq!(map.tau_limit(&op, 0.2), Some(0.6));
        assert!(map.verdict(&op, 0.56, 0.1).stable());
        // Between 0.1 and 0.2 the larger limit counts.
        assert!(!map.verdict(&op, 0.56, 0.15).stable());
        assert!(map.verdict(&op, 0.61, 0.15).stable());
        assert!(
            !map.verdict(&op, 0.9, 0.3).stable(),
            "beyond the measured Mach numbers"
        );
        let round = StabilityMap::parse(&map.to_csv()).unwrap();
        assert_eq!(round.samples, map.samples);
    }
}
