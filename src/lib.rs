//! grainflow: fluid–grain flow solver for geomechanics.
//!
//! The solvers are crates of their own, layered as the architecture is
//! (`ARCHITECTURE.md`): [`decomposition`] under the physics ([`lbm`], [`dem`], [`mpm`]),
//! [`coupling`] over the fluid and the grains, then the scene language ([`scene`]), output
//! ([`io`]), analyses ([`analysis`]) and the measured stability limits ([`stability`]).
//! This crate is the driver: a [`simulation::Simulation`] runs the stages a scene asks
//! for, and [`run`], [`run_grains`] and [`run_mpm`] run the time loops and write
//! snapshots, pictures, probe series and a `summary.json`. The crates are re-exported
//! here under their own names.

pub use ::analysis;
pub use ::coupling;
pub use ::decomposition;
pub use ::dem;
pub use ::io;
pub use ::lbm;
pub use ::mpm;
pub use ::scene;
pub use ::stability;

pub mod budget;
pub mod check;
pub mod coupled;
pub mod driver;
pub mod error;
pub mod pool;
pub mod progress;
pub mod run;
pub mod run_grains;
pub mod run_mpm;
pub mod simulation;
pub mod summary_units;
pub mod time_loop;
