//! The `[coupling]` table of a fluid scene with `[grains]` (validated in `coupling_check`).

use serde::{Deserialize, Serialize};

/// How the fluid and the grains exchange momentum.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CouplingSpec {
    /// The interface scheme: `"bounce-back"` (Ladd), `"interpolated"` (Bouzidi) or `"psm"`
    /// (Noble–Torczynski partially saturated cells).
    pub scheme: coupling::Scheme,
    /// How a cell a grain uncovers is refilled (bounce-back schemes): `"equilibrium"`
    /// (default) or `"extrapolation"`.
    #[serde(default)]
    pub refill: coupling::Refill,
    /// DEM sub-steps per fluid step; default ⌊Δt/Δt_D⌋ + 1 (seed eq. 5.61).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub substeps: Option<u32>,
    /// Hold the average of the last two steps' hydrodynamic forces (Ladd 1994) instead of
    /// the last one: damps the oscillation that makes explicit coupling unstable for light
    /// grains. Default: on for `bounce-back`, off for the others.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_averaging: Option<bool>,
    /// Short-range repulsion between grains, and between grains and walls, that stops them
    /// touching where the lattice no longer resolves the gap (Glowinski et al. 2001); off
    /// when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repulsion: Option<RepulsionSpec>,
    /// r_h / r in (0, 1]: the fluid sees each grain with radius r_h = ratio × r while the
    /// contacts use r, so touching disks leave pore throats the fluid can drain through (in
    /// 2-D, disks in contact seal the packing). 1 (the grains as they are) by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hydrodynamic_radius_ratio: Option<f64>,
    /// On more than one rank: every this many steps, move the slab boundaries to follow
    /// the measured work (fluid cells and the coupled grains over them) when the busiest
    /// rank is more than `rebalance_tolerance` above the mean. 0: never. Default
    /// [`DEFAULT_REBALANCE_EVERY_STEPS`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rebalance_every_steps: Option<u64>,
    /// The imbalance tolerated before the slabs move: the busiest rank's measured work
    /// over the mean, minus one (≥ 0; 0 moves them whenever the model finds a better
    /// split). Default [`DEFAULT_REBALANCE_TOLERANCE`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rebalance_tolerance: Option<f64>,
}

/// Steps between load-balance checks of a coupled run on several ranks, by default.
pub const DEFAULT_REBALANCE_EVERY_STEPS: u64 = 1000;
/// Imbalance a coupled run tolerates before its slabs move, by default (10 %).
pub const DEFAULT_REBALANCE_TOLERANCE: f64 = 0.1;

impl CouplingSpec {
    /// Steps between load-balance checks (0: never).
    pub fn rebalance_every_steps(&self) -> u64 {
        self.rebalance_every_steps
            .unwrap_or(DEFAULT_REBALANCE_EVERY_STEPS)
    }

    /// The imbalance tolerated before the slabs move.
    pub fn rebalance_tolerance(&self) -> f64 {
        self.rebalance_tolerance
            .unwrap_or(DEFAULT_REBALANCE_TOLERANCE)
    }

    /// r_h / r (1 unless the scene sets it).
    pub fn hydrodynamic_radius_ratio(&self) -> f64 {
        self.hydrodynamic_radius_ratio.unwrap_or(1.0)
    }
}

/// Glowinski et al. (2001) short-range repulsion: F = s · W · ((r_i + r_j + ζ − d)/ζ)² along
/// the line of centres for gaps below ζ, with W the lighter grain's submerged weight.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RepulsionSpec {
    /// Range ζ (m): the gap below which it acts (typically one or two lattice cells).
    pub range_m: f64,
    /// Strength s: the force at touching, in submerged weights.
    pub strength: f64,
}

pub use coupling::MIN_CELLS_PER_DIAMETER;
/// Cells per diameter below which `check` warns that the drag is under-resolved.
pub const WARN_CELLS_PER_DIAMETER: f64 = 8.0;
