//! Why an MPM step could not be completed.

use thiserror::Error;

/// Why a step could not be completed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MpmError {
    /// A point reached the edge of the grid through an open side.
    #[error("step {step}: material point {id} left the grid at ({x:.6}, {y:.6}) m; enlarge the domain or close that side")]
    LeftDomain {
        /// Step number.
        step: u64,
        /// Point id.
        id: u64,
        /// Position x (m).
        x: f64,
        /// Position y (m).
        y: f64,
    },
    /// Another rank stopped this step (its error names the point).
    #[error("step {step}: stopped because another rank failed (see its message)")]
    Elsewhere {
        /// Step number.
        step: u64,
    },
    /// A stress-carrying point expanded so far that its wave speed breaks the CFL limit.
    #[error("step {step}: material point {id} at ({x:.6}, {y:.6}) m carries stress at {ratio:.1} times its initial volume, so its wave speed breaks the CFL limit (Courant {courant:.2} > 1); set separation_volume_ratio on its material (about 1.1–1.5 for a cohesionless granular material) or lower the Courant number")]
    CflExceeded {
        /// Step number.
        step: u64,
        /// Point id.
        id: u64,
        /// Position x (m).
        x: f64,
        /// Position y (m).
        y: f64,
        /// Its volume ratio J.
        ratio: f64,
        /// Its effective Courant number.
        courant: f64,
    },
    /// The grid has fewer cell columns than the ranks need.
    #[error("{ranks} ranks need at least {} cell columns (3 per slab), the grid has {columns}; use fewer ranks or smaller cells", 3 * ranks)]
    TooManyRanks {
        /// Ranks.
        ranks: usize,
        /// Cell columns of the grid.
        columns: usize,
    },
    /// A point's position became non-finite.
    #[error("step {step}: the run went unstable: material point {id} has a non-finite position; reduce the time step (courant) or check the material")]
    Unstable {
        /// Step number.
        step: u64,
        /// Point id.
        id: u64,
    },
}
