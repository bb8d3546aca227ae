//! The coupled (LBM–DEM) stability verdict, from the robustness sweep
//! (`jobs/robustness/sweep.py`): a disk settling from rest, for each scheme, at 8–64 cells per
//! diameter, density ratios 1.01–8 and terminal Reynolds numbers 1–500
//! (`jobs/robustness/coupled-map.csv`).
//!
//! The verdict assumes what the sweep shows: a coupled run gets no less stable with more
//! cells per diameter, a heavier grain, a larger relaxation time or a smaller lattice
//! velocity. A scene no better than a measured failure in all four is *likely unstable*; one
//! no worse than a measured stable run in all four is *inside the measured stable region*;
//! any other scene lies outside what was measured.

/// The coupled map shipped with grainflow.
pub const COUPLED_CSV: &str = include_str!("../../../jobs/robustness/coupled-map.csv");

/// One measured (or judged) coupled case.
#[derive(Debug, Clone, PartialEq)]
pub struct CoupledCase {
    /// The coupling scheme, as scenes name it.
    pub scheme: String,
    /// Cells per diameter of the smallest grain.
    pub cells_per_diameter: f64,
    /// Grain density over fluid density.
    pub density_ratio: f64,
    /// Relaxation time τ.
    pub tau: f64,
    /// Lattice velocity of the reference velocity (the grains' speed scale).
    pub lattice_velocity: f64,
}

impl CoupledCase {
    /// Whether this case is at least as stable as `other` in every respect.
    fn no_worse_than(&self, other: &CoupledCase) -> bool {
        self.scheme == other.scheme
            && self.cells_per_diameter >= other.cells_per_diameter
            && self.density_ratio >= other.density_ratio
            && self.tau >= other.tau
            && self.lattice_velocity <= other.lattice_velocity
    }

    fn describe(&self) -> String {
        format!(
            "{} cells per diameter, ρ_s/ρ = {}, τ = {:.4}, u_lb = {}",
            self.cells_per_diameter, self.density_ratio, self.tau, self.lattice_velocity
        )
    }
}

/// What the map says of a coupled case.
#[derive(Debug, Clone, PartialEq)]
pub enum CoupledVerdict {
    /// No worse than this measured stable run.
    Stable(CoupledCase),
    /// No better than this measured failure.
    Unstable(CoupledCase),
    /// No worse than this measured stable run except in τ, which is below the smallest τ
    /// measured stable among such runs: judged likely unstable (the sweep's failures lie
    /// there).
    BelowStableTau(CoupledCase),
    /// Neither.
    Unmeasured,
}

impl CoupledVerdict {
    /// One line for `check`, about the case `c`.
    pub fn describe(&self, c: &CoupledCase) -> String {
        match self {
            CoupledVerdict::Stable(s) => format!(
                "inside the measured stable region ({}: no worse than a stable sweep run at {})",
                c.scheme,
                s.describe()
            ),
            CoupledVerdict::Unstable(u) => format!(
                "likely unstable ({}: no better than a sweep run that blew up at {}): refine the \
                 lattice, raise τ, or use psm",
                c.scheme,
                u.describe()
            ),
            CoupledVerdict::BelowStableTau(s) => format!(
                "likely unstable ({}: τ = {:.4} is below the smallest τ measured stable, {}, \
                 for runs no better than this one ({})): raise τ to at least {}, refine the \
                 lattice, or use psm",
                c.scheme,
                c.tau,
                s.tau,
                s.describe(),
                s.tau
            ),
            CoupledVerdict::Unmeasured => format!(
                "outside the measured region ({}, {}; jobs/robustness/coupled-map.csv)",
                c.scheme,
                c.describe()
            ),
        }
    }
}

/// The measured cases of a coupled map (`scheme,cells_per_diameter,density_ratio,tau,
/// lattice_velocity,stable` per line, after a header), each with whether it was stable.
pub fn parse(csv: &str) -> Vec<(CoupledCase, bool)> {
    csv.lines()
        .skip(1)
        .filter_map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            if f.len() != 6 {
                return None;
            }
            let num = |i: usize| f[i].trim().parse::<f64>().ok();
            Some((
                CoupledCase {
                    scheme: f[0].trim().to_string(),
                    cells_per_diameter: num(1)?,
                    density_ratio: num(2)?,
                    tau: num(3)?,
                    lattice_velocity: num(4)?,
                },
                f[5].trim() == "1",
            ))
        })
        .collect()
}

/// The verdict on `case` from the measured cases `map`. A measured failure it does not
/// beat wins over a stable run it matches (the map is then not monotone there, and the
/// failure is the safer guide).
pub fn verdict(map: &[(CoupledCase, bool)], case: &CoupledCase) -> CoupledVerdict {
    if let Some((u, _)) = map
        .iter()
        .find(|(m, stable)| !stable && m.no_worse_than(case))
    {
        return CoupledVerdict::Unstable(u.clone());
    }
    if let Some((s, _)) = map
        .iter()
        .find(|(m, stable)| *stable && case.no_worse_than(m))
    {
        return CoupledVerdict::Stable(s.clone());
    }
    // Stable runs it matches in all but τ: it lies below every such run's τ (else it would
    // be no worse than one), where the sweep found its failures.
    let below = CoupledCase {
        tau: f64::INFINITY,
        ..case.clone()
    };
    map.iter()
        .filter(|(m, stable)| *stable && below.no_worse_than(m))
        .map(|(m, _)| m)
        .min_by(|a, b| a.tau.total_cmp(&b.tau))
        .map_or(CoupledVerdict::Unmeasured, |m| {
            CoupledVerdict::BelowStableTau(m.clone())
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case(scheme: &str, cells: f64, ratio: f64, tau: f64) -> CoupledCase {
        CoupledCase {
            scheme: scheme.into(),
            cells_per_diameter: cells,
            density_ratio: ratio,
            tau,
            lattice_velocity: 0.05,
        }
    }

    #[test]
    fn the_shipped_map_judges_by_dominance() {
        let map = parse(COUPLED_CSV);
        assert!(map.len() >= 150, "{} cases", map.len());
        // Measured: bounce-back at 8 cells per diameter, τ = 0.5024, blew up; at 64 cells,
        // τ = 0.5192, ran.
        let bad = case("bounce-back", 8.0, 1.5, 0.5024);
        assert!(matches!(verdict(&map, &bad), CoupledVerdict::Unstable(_)));
        // Coarser and lighter than a failure: still unstable.
        let worse = case("bounce-back", 6.0, 1.2, 0.5010);
        assert!(matches!(verdict(&map, &worse), CoupledVerdict::Unstable(_)));
        let good = case("bounce-back", 64.0, 1.5, 0.52);
        assert!(matches!(verdict(&map, &good), CoupledVerdict::Stable(_)));
        // PSM ran everywhere in the sweep.
        let psm = case("psm", 8.0, 1.01, 0.5024);
        assert!(matches!(verdict(&map, &psm), CoupledVerdict::Stable(_)));
        // Faster than anything measured: no claim.
        let fast = CoupledCase {
            lattice_velocity: 0.2,
            ..good.clone()
        };
        assert_eq!(verdict(&map, &fast), CoupledVerdict::Unmeasured);
        assert!(verdict(&map, &bad)
            .describe(&bad)
            .contains("likely unstable"));
        // Between a measured failure (τ = 0.5024) and the smallest τ measured stable
        // (0.512) at 8 cells per diameter: a user's settling disk at τ = 0.510 blew up
        // there, and is judged likely unstable.
        let gap = case("bounce-back", 8.0, 1.2, 0.510);
        match verdict(&map, &gap) {
            CoupledVerdict::BelowStableTau(m) => assert_eq!(m.tau, 0.512),
            v => panic!("{v:?}"),
        }
    }
}
