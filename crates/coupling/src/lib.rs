//! LBM–DEM coupling (seed study §5.4): the only code that reads both the fluid's and the
//! grains' state. The fluid core and the DEM never import each other.
//!
//! A coupled fluid step, in order (each a timed stage of `Simulation::step`):
//! 1. `coupling`: [`Coupler::plan`] plans the cells at the grains' surfaces from the last
//!    remap's maps (links for the bounce-back schemes, solid shares for PSM), plain data the
//!    fluid core executes;
//! 2. `collide-stream`: the fluid sweep recomputes the planned cells with the chosen scheme
//!    right after their row, one momentum per link or share (PSM in place on a slab with no
//!    exchanged face: most loads summed per grain and column as the cells are blended);
//! 3. `coupling`: [`driver::LbmDem::exchange`] sums each grain's hydrodynamic force and
//!    torque per lattice column; the owners add the columns in order (`sums.rs`,
//!    `ghosts.rs`);
//! 4. `dem`: n_s DEM sub-steps with that force held (seed eq. 5.61), plus the optional
//!    short-range repulsion, then the ghost grains are exchanged; then `coupling` again:
//!    [`Coupler::remap`] maps the grains where they moved and hands over the cells they
//!    covered or uncovered;
//! 5. `boundaries`: the fluid's halo refill.

mod body_sums;
mod boundary_lists;
mod cover_update;
pub mod driver;
pub mod exchange;
mod gather;
pub mod geometry;
pub mod ghosts;
mod grain_neighbours;
mod handover;
mod interface;
mod link_cells;
mod links;
pub mod map;
mod partial_cells;
mod psm;
mod row_walk;
pub mod sums;
#[cfg(test)]
mod test_slabs;

pub use driver::{
    check_grains, fluid_walls, CouplingCounters, LbmDem, LbmDemSetup, RestoredCoupling, SetupError,
    MIN_CELLS_PER_DIAMETER,
};

/// The passes of the "coupling" stage, as [`LbmDem::pass_seconds`] times them: planning the
/// cells at the grains' surfaces, collecting their loads, reducing the loads on the
/// grains' owners, mapping the grains onto the cells, handing over covered and uncovered
/// cells (bounce-back schemes), and rebuilding the boundary lists.
pub const PASSES: [&str; 6] = ["plan", "collect", "reduce", "map", "handover", "lists"];

/// What the coupling counts over a run (summed over ranks in `summary.json`): remaps of
/// the cover map done in place and afresh, grains whose cells those in place decided and
/// skipped (`cover_update.rs`), and grains whose boundary lists were kept and rescanned
/// (`boundary_lists.rs`). Bounce-back schemes only.
pub const COUNTS: [&str; 6] = [
    "remaps_in_place",
    "remaps_afresh",
    "grains_decided",
    "grains_skipped",
    "lists_kept",
    "lists_rescanned",
];

/// Index of each pass in [`PASSES`].
pub(crate) mod pass {
    pub const PLAN: usize = 0;
    pub const COLLECT: usize = 1;
    pub const REDUCE: usize = 2;
    pub const MAP: usize = 3;
    pub const HANDOVER: usize = 4;
    pub const LISTS: usize = 5;
}
pub use exchange::{Coupler, CouplingError};

use serde::{Deserialize, Serialize};

/// The fluid–grain interface scheme.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scheme {
    /// Ladd's (1994) moving half-way bounce-back with momentum exchange (seed eqs. 5.45–5.49):
    /// a cell is solid when its centre is inside a grain.
    BounceBack,
    /// Bouzidi, Firdaouss & Lallemand (2001) linear interpolated bounce-back at the link
    /// fraction δ of the curved surface (seed eqs. 5.50–5.52), with Ladd's moving-wall term.
    Interpolated,
    /// Noble & Torczynski's (1998) partially saturated cells, weighted by each grain's exact
    /// area fraction of the cell (seed eqs. 5.53–5.54).
    Psm,
}

impl Scheme {
    /// Name as in scenes.
    pub fn name(&self) -> &'static str {
        match self {
            Scheme::BounceBack => "bounce-back",
            Scheme::Interpolated => "interpolated",
            Scheme::Psm => "psm",
        }
    }
}

/// How a cell that a grain uncovers gets its populations (bounce-back schemes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Refill {
    /// Equilibrium at the grain's surface velocity and the mean density of the fluid
    /// neighbours.
    #[default]
    Equilibrium,
    /// That equilibrium plus the non-equilibrium part of the fluid neighbour along the
    /// surface normal (Caiazzo 2005).
    Extrapolation,
}
