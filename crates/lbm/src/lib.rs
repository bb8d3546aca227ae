//! 2-D lattice Boltzmann (D2Q9) fluid solver.
//!
//! Storage is structure-of-arrays of the *shifted* distributions `h_i = f_i - w_i`
//! (so f32 keeps its digits for the small deviations from rest), padded by one halo
//! cell on every side. A step is one fused pull stream–collide sweep from one buffer into
//! the other; the buffers hold post-collision values, which is what half-way bounce-back
//! needs. Bulk cells run a vectorised row kernel; cells touching solids or open boundaries
//! run a scalar path that reconstructs their links first.

pub mod aligned;
pub mod backend;
pub mod boundary;
mod bulk_aa;
mod cells;
pub mod collision;
pub mod curved;
pub mod d2q9;
mod external;
pub mod fields;
mod forces;
pub mod geometry;
mod inplace;
pub mod kernel;
pub mod lanes;
pub mod lattice;
pub mod moving;
mod partial;
mod plans;
pub mod population_bgk;
pub mod real;
mod rows;
pub mod units;
mod wall_runs;
mod whole_cells;

pub mod gpu;
#[doc(hidden)]
pub mod test_rng;

pub use backend::FluidBackend;
pub use collision::{Collision, CollisionParams};
pub use lattice::{Lattice, LatticeSetup, Layout, StepError};
pub use real::Real;
