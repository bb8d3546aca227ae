//! Preparing a sample: random sequential addition in a rectangle, settling under gravity, and
//! a loader for CSV files of (x, y, r).

use super::contact::DemError;
use super::grains::Grains;
use super::system::DemSystem;
use std::path::Path;

/// Grain radii to draw (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SizeDistribution {
    /// One radius.
    Mono {
        /// Radius (m).
        r: f64,
    },
    /// Two radii; `fraction_small` of the grains (by number) take `small`.
    Bidisperse {
        /// Small radius (m).
        small: f64,
        /// Large radius (m).
        large: f64,
        /// Number fraction of small grains in [0, 1].
        fraction_small: f64,
    },
    /// Uniform in [min, max].
    Uniform {
        /// Smallest radius (m).
        min: f64,
        /// Largest radius (m).
        max: f64,
    },
    /// Normal with `mean` and `std`, redrawn until inside [min, max].
    Normal {
        /// Mean radius (m).
        mean: f64,
        /// Standard deviation (m).
        std: f64,
        /// Smallest radius (m).
        min: f64,
        /// Largest radius (m).
        max: f64,
    },
}

impl SizeDistribution {
    /// Every radius positive and finite, min ≤ max, mean inside the bounds, fraction in
    /// [0, 1], std ≥ 0.
    pub fn validate(&self) -> Result<(), DemError> {
        let bad = |name, value, why| Err(DemError::Parameter { name, value, why });
        let radius = |name, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                bad(name, v, "a radius must be positive and finite")
            }
        };
        match *self {
            SizeDistribution::Mono { r } => radius("radius_m", r),
            SizeDistribution::Bidisperse {
                small,
                large,
                fraction_small,
            } => {
                radius("small_radius_m", small)?;
                radius("large_radius_m", large)?;
                if !(0.0..=1.0).contains(&fraction_small) {
                    return bad("fraction_small", fraction_small, "must be in [0, 1]");
                }
                Ok(())
            }
            SizeDistribution::Uniform { min, max } => {
                radius("min_radius_m", min)?;
                radius("max_radius_m", max)?;
                if min > max {
                    return bad("min_radius_m", min, "must not exceed max_radius_m");
                }
                Ok(())
            }
            SizeDistribution::Normal {
                mean,
                std,
                min,
                max,
            } => {
                radius("min_radius_m", min)?;
                radius("max_radius_m", max)?;
                if !(min <= mean && mean <= max) {
                    return bad(
                        "mean_radius_m",
                        mean,
                        "must lie in [min_radius_m, max_radius_m]",
                    );
                }
                if !(std >= 0.0 && std.is_finite()) {
                    return bad("std_radius_m", std, "must be ≥ 0");
                }
                Ok(())
            }
        }
    }

    /// The smallest radius it can draw.
    pub fn min_radius(&self) -> f64 {
        match *self {
            SizeDistribution::Mono { r } => r,
            SizeDistribution::Bidisperse { small, large, .. } => small.min(large),
            SizeDistribution::Uniform { min, .. } | SizeDistribution::Normal { min, .. } => min,
        }
    }

    /// The largest radius it can draw.
    pub fn max_radius(&self) -> f64 {
        match *self {
            SizeDistribution::Mono { r } => r,
            SizeDistribution::Bidisperse { small, large, .. } => small.max(large),
            SizeDistribution::Uniform { max, .. } | SizeDistribution::Normal { max, .. } => max,
        }
    }

    fn draw(&self, rng: &mut Rng) -> f64 {
        match *self {
            SizeDistribution::Mono { r } => r,
            SizeDistribution::Bidisperse {
                small,
                large,
                fraction_small,
            } => {
                if rng.uniform() < fraction_small {
                    small
                } else {
                    large
                }
            }
            SizeDistribution::Uniform { min, max } => min + (max - min) * rng.uniform(),
            SizeDistribution::Normal {
                mean,
                std,
                min,
                max,
            } => loop {
                // Box–Muller.
                let (u, v) = (rng.uniform().max(1e-300), rng.uniform());
                let r = mean + std * (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos();
                if (min..=max).contains(&r) {
                    break r;
                }
            },
        }
    }
}

/// A small deterministic generator (SplitMix64), so a seed always gives the same sample.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// Seeded generator.
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) as f64 / 18_446_744_073_709_551_616.0
    }
}

/// Fill the rectangle `[lo, hi]` (m) with non-overlapping disks of density `rho` by random
/// sequential addition until the solid fraction reaches `solid_fraction` or `attempts`
/// consecutive positions fail for the next radius (radii are placed in the order drawn, so
/// the sample follows `sizes`). Grains lie wholly inside the rectangle. Deterministic in `seed`.
/// The grains are numbered in space, not in the order placed: band by band (bands two radii
/// high), along x in a band.
pub fn random_sequential_addition(
    lo: [f64; 2],
    hi: [f64; 2],
    sizes: SizeDistribution,
    rho: f64,
    solid_fraction: f64,
    seed: u64,
    attempts: usize,
) -> Grains {
    let mut rng = Rng::new(seed);
    let cell = 2.0 * sizes.max_radius();
    let nx = ((hi[0] - lo[0]) / cell).ceil().max(1.0) as usize;
    let ny = ((hi[1] - lo[1]) / cell).ceil().max(1.0) as usize;
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
    let mut g = Grains::default();
    let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
    let mut filled = 0.0;
    let mut failures = 0;
    // A radius is kept until it is placed: redrawing after a failed try would favour small
    // grains as the box fills, and the sample would no longer follow `sizes`.
    let mut r = sizes.draw(&mut rng);
    while filled < solid_fraction * area && failures < attempts {
        let x = lo[0] + r + (hi[0] - lo[0] - 2.0 * r) * rng.uniform();
        let y = lo[1] + r + (hi[1] - lo[1] - 2.0 * r) * rng.uniform();
        let cx = (((x - lo[0]) / cell) as usize).min(nx - 1);
        let cy = (((y - lo[1]) / cell) as usize).min(ny - 1);
        let mut free = true;
        'search: for yy in cy.saturating_sub(1)..(cy + 2).min(ny) {
            for xx in cx.saturating_sub(1)..(cx + 2).min(nx) {
                for &j in &grid[yy * nx + xx] {
                    let j = j as usize;
                    let reach = r + g.r[j];
                    if (g.x[j] - x).powi(2) + (g.y[j] - y).powi(2) < reach * reach {
                        free = false;
                        break 'search;
                    }
                }
            }
        }
        if free {
            let i = g.push([x, y], r, rho, false);
            grid[cy * nx + cx].push(i as u32);
            filled += std::f64::consts::PI * r * r;
            failures = 0;
            r = sizes.draw(&mut rng);
        } else {
            failures += 1;
        }
    }
    in_bands(&g, cell)
}

/// `g` renumbered band by band: bands of height `band` (m, > 0) from the lowest grain up,
/// and along x within a band. Grains near each other in space are then near each other in
/// number, so the passes that walk grains in id order (the coupling's map, its sums, a
/// DEM without re-sorting) read their neighbours from nearby memory. Each grain keeps its
/// state (position, velocity, angle, radius, mass); forces are not carried, and ids are
/// the new numbers.
fn in_bands(g: &Grains, band: f64) -> Grains {
    debug_assert!(band > 0.0, "band height {band}");
    let y0 = g.y.iter().cloned().fold(f64::INFINITY, f64::min);
    let key = |i: usize| (((g.y[i] - y0) / band).floor() as u64, g.x[i]);
    let mut order: Vec<usize> = (0..g.len()).collect();
    order.sort_by(|&a, &b| {
        let (ka, kb) = (key(a), key(b));
        ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1)).then(a.cmp(&b))
    });
    let mut out = Grains::default();
    for i in order {
        let n = out.push([g.x[i], g.y[i]], g.r[i], 1.0, false);
        (out.m[n], out.inv_inertia[n]) = (g.m[i], g.inv_inertia[i]);
        (out.vx[n], out.vy[n]) = (g.vx[i], g.vy[i]);
        (out.theta[n], out.omega[n]) = (g.theta[i], g.omega[i]);
    }
    out
}

/// Run `system` with global damping `alpha` (1/s) until the mean kinetic energy per grain
/// falls below `ke_per_grain` (J/m) or `max_steps` pass; the damping is switched off
/// afterwards. Returns the steps taken.
pub fn settle(system: &mut DemSystem, alpha: f64, ke_per_grain: f64, max_steps: u64) -> u64 {
    let before = system.global_damping;
    system.global_damping = alpha;
    let n = system.grains.len().max(1) as f64;
    let mut steps = 0;
    while steps < max_steps {
        for _ in 0..100 {
            system.step();
        }
        steps += 100;
        if system.grains.kinetic_energy() / n < ke_per_grain {
            break;
        }
    }
    system.global_damping = before;
    steps
}

/// Grains from a CSV file of `x, y, r` rows (m), density `rho`. A first line that does not
/// parse as numbers is taken as a header; `#` starts a comment.
pub fn load_csv(path: &Path, rho: f64) -> Result<Grains, DemError> {
    let text = std::fs::read_to_string(path).map_err(|e| DemError::Input {
        path: path.display().to_string(),
        line: 0,
        message: e.to_string(),
    })?;
    let mut g = Grains::default();
    for (k, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let values: Result<Vec<f64>, _> = fields.iter().map(|f| f.parse::<f64>()).collect();
        match values {
            Ok(v) if v.len() == 3 && v[2] > 0.0 && v.iter().all(|x| x.is_finite()) => {
                g.push([v[0], v[1]], v[2], rho, false);
            }
            Err(_) if k == 0 => continue,
            _ => {
                return Err(DemError::Input {
                    path: path.display().to_string(),
                    line: k + 1,
                    message: format!(
                        "expected `x, y, r` with finite numbers and r > 0, found `{raw}`"
                    ),
                })
            }
        }
    }
    Ok(g)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A packing is numbered band by band and along x in a band, and holds the grains it
    /// placed, each with its own radius and mass.
    #[test]
    fn a_packing_is_numbered_in_space() {
        let sizes = SizeDistribution::Uniform {
            min: 0.8e-3,
            max: 1.2e-3,
        };
        let band = 2.0 * sizes.max_radius();
        let g = random_sequential_addition([0.0, 0.0], [0.05, 0.03], sizes, 2500.0, 0.5, 3, 2000);
        assert!(g.len() > 100, "{} grains", g.len());
        let y0 = g.y.iter().cloned().fold(f64::INFINITY, f64::min);
        let bands: Vec<u64> =
            g.y.iter()
                .map(|y| ((y - y0) / band).floor() as u64)
                .collect();
        for i in 0..g.len() {
            assert_eq!(g.id[i], i as u64);
            let m = 2500.0 * std::f64::consts::PI * g.r[i] * g.r[i];
            assert_eq!(g.m[i], m);
            assert_eq!(g.inv_inertia[i], 1.0 / (0.5 * m * g.r[i] * g.r[i]));
            if i == 0 {
                continue;
            }
            let later_band = bands[i] > bands[i - 1];
            assert!(
                later_band || (bands[i] == bands[i - 1] && g.x[i] >= g.x[i - 1]),
                "grain {i} at ({}, {}) after ({}, {})",
                g.x[i],
                g.y[i],
                g.x[i - 1],
                g.y[i - 1]
            );
        }
        // Renumbering moves grains, never changes them: the same disks as a second ordering.
        let again = in_bands(&g, 0.5 * band);
        let mut a: Vec<[u64; 3]> = (0..g.len())
            .map(|i| [g.x[i].to_bits(), g.y[i].to_bits(), g.r[i].to_bits()])
            .collect();
        let mut b: Vec<[u64; 3]> = (0..again.len())
            .map(|i| {
                [
                    again.x[i].to_bits(),
                    again.y[i].to_bits(),
                    again.r[i].to_bits(),
                ]
            })
            .collect();
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b);
    }
}
