//! The measured stability map and the verdict `grainflow check` gives from it.
//!
//! The map (`jobs/stability/lbm-map.csv`, made by `grainflow stability-map`) holds, for each
//! operator, test flow, relaxation time τ and lattice Mach number, whether the run stayed
//! stable. At a measured Mach number the *stable limit* of a flow is the smallest measured τ
//! from which every larger measured τ was stable; the true limit lies between it and the
//! measured τ just below it, and the verdict takes their geometric mean in τ − ½ (the
//! measured τ are spaced geometrically in τ − ½). Between two measured Mach numbers the
//! limit is interpolated linearly in Mach, on ln(τ − ½). Each test flow gets its own verdict:
//! the double shear layer stands for free shear, the cavity for wall-driven flow.

use super::lbm::{Flow, Operator, Sample};

/// The map shipped with grainflow.
pub const BUILTIN_CSV: &str = include_str!("../../../jobs/stability/lbm-map.csv");

/// What the map says about a (τ, Mach) point in one test flow.
#[derive(Debug, Clone, PartialEq)]
pub struct FlowVerdict {
    /// The test flow.
    pub flow: Flow,
    /// Predicted stable: τ at or above the estimated limit.
    pub stable: bool,
    /// The estimated limit τ at this Mach number (infinite where nothing was stable).
    pub tau_limit: f64,
    /// The estimated upper end of the stable band (infinite where the largest measured τ was
    /// stable).
    pub tau_ceiling: f64,
}

/// What the map says about a (τ, Mach) point: one verdict per test flow.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// Shear layer, then cavity.
    pub flows: [FlowVerdict; 2],
    /// The measured Mach numbers the limits came from (equal at a measured one).
    pub machs: (f64, f64),
    /// Beyond the fastest measured Mach number: no limit is known.
    pub beyond: bool,
}

impl Verdict {
    /// Whether the point is predicted stable in both test flows.
    pub fn stable(&self) -> bool {
        self.flows.iter().all(|f| f.stable)
    }

    /// The verdict for one flow.
    pub fn flow(&self, flow: Flow) -> &FlowVerdict {
        &self.flows[(flow == Flow::Cavity) as usize]
    }

    /// One line for `grainflow check`.
    pub fn describe(&self, op: &Operator, tau: f64, mach: f64) -> String {
        let here = format!("here τ = {tau:.4}, Ma = {mach:.3}");
        if self.beyond {
            return format!(
                "likely unstable ({}: nothing measured above Ma {:.2}; {here}): lower the lattice velocity",
                op.name(),
                self.machs.1
            );
        }
        let limit = |f: &FlowVerdict| match (f.tau_limit.is_finite(), f.tau_ceiling.is_finite()) {
            (false, _) => format!("{}: no stable τ", f.flow.name()),
            (true, false) => format!("{} τ ≥ {:.4}", f.flow.name(), f.tau_limit),
            (true, true) => format!(
                "{} {:.4} ≤ τ < {:.3} (more viscous runs overshoot)",
                f.flow.name(),
                f.tau_limit,
                f.tau_ceiling
            ),
        };
        let limits = format!(
            "{}: stable for {}, {}",
            op.name(),
            limit(&self.flows[0]),
            limit(&self.flows[1])
        );
        let fix = "raise τ (coarser lattice or higher viscosity), lower the lattice velocity, or use an operator with a lower limit";
        match (self.flows[0].stable, self.flows[1].stable) {
            (true, true) => format!("inside the measured stable region ({limits}; {here})"),
            (false, false) => format!(
                "likely unstable: blows up or overshoots 1.5 × its driving speed ({limits}; {here}): {fix}"
            ),
            (shear, _) => format!(
                "stable in {} flow, likely unstable (blows up or overshoots 1.5 × its driving speed) in {} ({limits}; {here}): which one this scene resembles decides; to be safe, {fix}",
                if shear { "free-shear" } else { "wall-driven (cavity)" },
                if shear { "wall-driven (cavity) flow" } else { "free shear layers" },
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

    /// The stable limit of `op` at measured Mach `mach` in both flows: the smallest measured
    /// τ from which every larger measured τ, up to the largest stable one, is stable in every
    /// flow (None when no τ is). `stability-map` prints it; `check` estimates each flow's
    /// limit between measured τ instead ([`StabilityMap::verdict`]).
    pub fn tau_limit(&self, op: &Operator, mach: f64) -> Option<f64> {
        self.bracket(op, None, mach).1
    }

    /// At measured Mach `mach`, for `op` in `flow` (`None`: every flow at once): the largest
    /// measured τ that failed below the stable limit, and the stable limit. Failures above
    /// every stable τ (at the map's highest Mach numbers the most viscous cavity overshoots)
    /// bound the stable band from above instead ([`StabilityMap::ceiling`]).
    fn bracket(&self, op: &Operator, flow: Option<Flow>, mach: f64) -> (Option<f64>, Option<f64>) {
        let taus = self.column(op, flow, mach);
        let top = taus.iter().rposition(|t| t.1);
        let mut limit = None;
        for (tau, stable) in taus[..top.map_or(0, |k| k + 1)].iter().rev() {
            if !stable {
                return (Some(*tau), limit);
            }
            limit = Some(*tau);
        }
        (None, limit)
    }

    /// The measured (τ, stable in every asked flow) of `op` at Mach `mach`, τ increasing.
    fn column(&self, op: &Operator, flow: Option<Flow>, mach: f64) -> Vec<(f64, bool)> {
        let mut taus: Vec<(f64, bool)> = Vec::new();
        for s in self
            .samples
            .iter()
            .filter(|s| s.operator == *op && s.mach == mach && flow.is_none_or(|f| f == s.flow))
        {
            match taus.iter_mut().find(|t| t.0 == s.tau) {
                Some(t) => t.1 &= s.stable,
                None => taus.push((s.tau, s.stable)),
            }
        }
        taus.sort_by(|a, b| a.0.total_cmp(&b.0));
        taus
    }

    /// The estimated upper end τ − ½ of the stable band of `op` in `flow` at measured Mach
    /// `mach`: the geometric mean of the largest stable τ − ½ and the failed one above it,
    /// infinity when the largest measured τ was stable.
    fn ceiling(&self, op: &Operator, flow: Flow, mach: f64) -> f64 {
        let taus = self.column(op, Some(flow), mach);
        match taus.iter().rposition(|t| t.1) {
            Some(k) if k + 1 < taus.len() => ((taus[k].0 - 0.5) * (taus[k + 1].0 - 0.5)).sqrt(),
            Some(_) => f64::INFINITY,
            None => 0.0,
        }
    }

    /// The estimated limit τ − ½ of `op` in `flow` at measured Mach `mach`: the geometric
    /// mean of the bracket's τ − ½, the smallest measured τ − ½ when every τ was stable, and
    /// infinity when none was.
    fn limit_above_half(&self, op: &Operator, flow: Flow, mach: f64) -> f64 {
        match self.bracket(op, Some(flow), mach) {
            (_, None) => f64::INFINITY,
            (None, Some(t)) => t - 0.5,
            (Some(lo), Some(hi)) => ((lo - 0.5) * (hi - 0.5)).sqrt(),
        }
    }

    /// The verdict for relaxation time `tau` at lattice Mach number `mach` with `op` (a NaN
    /// `mach` is judged as beyond the map).
    pub fn verdict(&self, op: &Operator, tau: f64, mach: f64) -> Verdict {
        let machs = self.machs();
        let (lo, hi) = match machs.iter().position(|&m| m >= mach) {
            Some(k) if k == 0 || machs[k] == mach => (machs[k], machs[k]),
            Some(k) => (machs[k - 1], machs[k]),
            None => {
                let m = machs.last().copied().unwrap_or(0.0);
                let none = |flow| FlowVerdict {
                    flow,
                    stable: false,
                    tau_limit: f64::INFINITY,
                    tau_ceiling: f64::INFINITY,
                };
                return Verdict {
                    flows: [none(Flow::ShearLayer), none(Flow::Cavity)],
                    machs: (m, m),
                    beyond: true,
                };
            }
        };
        let judge = |flow: Flow| {
            let (a, b) = (
                self.limit_above_half(op, flow, lo),
                self.limit_above_half(op, flow, hi),
            );
            let limit = if lo == hi {
                a
            } else if a.is_finite() && b.is_finite() {
                // Linear in Mach on ln(τ − ½).
                let w = (mach - lo) / (hi - lo);
                (a.ln() * (1.0 - w) + b.ln() * w).exp()
            } else {
                f64::INFINITY
            };
            // Above the band's measured ceiling (the lower of the two Mach numbers').
            let ceiling = self.ceiling(op, flow, lo).min(self.ceiling(op, flow, hi));
            FlowVerdict {
                flow,
                stable: tau - 0.5 >= limit && tau - 0.5 < ceiling,
                tau_limit: 0.5 + limit,
                tau_ceiling: 0.5 + ceiling,
            }
        };
        Verdict {
            flows: [judge(Flow::ShearLayer), judge(Flow::Cavity)],
            machs: (lo, hi),
            beyond: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(flow: Flow, op: Operator, tau: f64, mach: f64, stable: bool) -> Sample {
        Sample {
            flow,
            operator: op,
            tau,
            mach,
            stable,
        }
    }

    #[test]
    fn limits_and_verdicts() {
        let op = Operator::ALL[0];
        let mut samples = Vec::new();
        for (flow, mach, row) in [
            (Flow::Cavity, 0.1, [false, true, true]),
            (Flow::Cavity, 0.2, [false, false, true]),
            (Flow::ShearLayer, 0.1, [true, true, true]),
            (Flow::ShearLayer, 0.2, [true, true, true]),
        ] {
            for (tau, stable) in [0.51, 0.55, 0.6].into_iter().zip(row) {
                samples.push(sample(flow, op, tau, mach, stable));
            }
        }
        let map = StabilityMap { samples };
        // The table's limit: every larger τ stable in both flows.
        assert_eq!(map.tau_limit(&op, 0.1), Some(0.55));
        assert_eq!(map.tau_limit(&op, 0.2), Some(0.6));
        // At Ma 0.1 the cavity's limit lies between 0.51 and 0.55: ½ + √(0.01 · 0.05).
        let v = map.verdict(&op, 0.53, 0.1);
        let cavity = v.flow(Flow::Cavity);
        assert!((cavity.tau_limit - (0.5 + (0.01f64 * 0.05).sqrt())).abs() < 1e-12);
        assert!(cavity.stable && v.stable());
        assert!(!map.verdict(&op, 0.52, 0.1).stable());
        // The shear layer was stable at every τ: from the smallest measured on.
        assert_eq!(v.flow(Flow::ShearLayer).tau_limit, 0.51);
        // Halfway between Ma 0.1 and 0.2, ln(τ − ½) halfway between the two limits: no
        // longer the larger one.
        let mid = (0.01f64 * 0.05).sqrt().ln() * 0.5 + (0.05f64 * 0.1).sqrt().ln() * 0.5;
        let v = map.verdict(&op, 0.56, 0.15);
        assert!((v.flow(Flow::Cavity).tau_limit - 0.5 - mid.exp()).abs() < 1e-12);
        assert!(v.stable(), "0.56 is above the interpolated 0.540");
        assert!(!map.verdict(&op, 0.535, 0.15).stable());
        // One flow stable and the other not is said so.
        let split = map.verdict(&op, 0.52, 0.1);
        assert!(split.flow(Flow::ShearLayer).stable && !split.flow(Flow::Cavity).stable);
        assert!(split
            .describe(&op, 0.52, 0.1)
            .contains("stable in free-shear flow"));
        assert!(
            !map.verdict(&op, 0.9, 0.3).stable(),
            "beyond the measured Mach numbers"
        );
        // A failure above every stable τ caps the band instead of emptying it.
        let mut capped = map.clone();
        capped
            .samples
            .push(sample(Flow::Cavity, op, 2.0, 0.1, false));
        capped
            .samples
            .push(sample(Flow::ShearLayer, op, 2.0, 0.1, true));
        let v = capped.verdict(&op, 0.6, 0.1);
        assert!(v.stable() && v.flow(Flow::Cavity).tau_limit < 0.53);
        let above = capped.verdict(&op, 1.9, 0.1);
        assert!(!above.flow(Flow::Cavity).stable);
        assert!(
            above.describe(&op, 1.9, 0.1).contains("≤ τ < 0.887"),
            "{above:?}"
        );
        // A measured Mach number other than the first is judged by its own column alone.
        let v = map.verdict(&op, 0.56, 0.2);
        assert_eq!(v.machs, (0.2, 0.2));
        assert!((v.flow(Flow::Cavity).tau_limit - 0.5 - (0.05f64 * 0.1).sqrt()).abs() < 1e-12);
        let round = StabilityMap::parse(&map.to_csv()).unwrap();
        assert_eq!(round.samples, map.samples);
    }
}
