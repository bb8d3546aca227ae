//! Material point method: explicit 2-D MPM on a regular background grid (plane strain).
//!
//! - [`points`]: material points, structure of arrays.
//! - [`shape`]: linear, uGIMP and cpGIMP shape functions.
//! - [`grid`]: grid geometry, node fields, boundary conditions.
//! - [`order`], [`transfer`]: canonical point order and the particle-to-grid sums whose
//!   order does not depend on threads or ranks.
//! - [`sweeps`]: node update, stress update, grid-to-particle.
//! - [`material`], [`mohr_coulomb`], [`inertial`]: constitutive models (Mohr–Coulomb,
//!   optionally with μ(I) rate-dependent friction).
//! - [`system`]: the time step (USF, USL, MUSL) as timed stages.
//! - [`generate`]: filling rectangles and polygons with n × n points per cell.

pub mod balance;
pub mod error;
pub mod generate;
pub mod grid;
pub mod inertial;
pub mod material;
pub mod mohr_coulomb;
pub mod order;
pub mod points;
pub mod shape;
pub mod slab;
pub mod sweeps;
pub mod system;
pub mod transfer;

pub use generate::{fill, Shape};
pub use grid::{Boundaries, GridSpec, NodeFields, Side, SideWalls};
pub use inertial::InertialFriction;
pub use material::{Material, Model};
pub use mohr_coulomb::MohrCoulomb;
pub use points::Points;
pub use shape::ShapeKind;
pub use slab::Totals;
pub use sweeps::VelocityUpdate;
pub use system::{critical_dt, MpmError, MpmSetup, MpmSystem, Scheme, MPM_STAGES};
