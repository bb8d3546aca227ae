// `!(x > 0.0)` is used on purpose throughout: unlike `x <= 0.0` it is true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Numerical kernels index several arrays in lock-step; iterator chains would obscure them.
#![allow(clippy::needless_range_loop)]
//! grainflow: fluid–grain flow solver for geomechanics.
//!
//! The fluid core is a 2-D D2Q9 lattice Boltzmann solver ([`lbm`]); scenes are TOML files
//! in SI units ([`scene`]); a [`simulation::Simulation`] runs the stages a scene asks for
//! and writes snapshots, pictures, probe series and a `summary.json` ([`io`]).

pub mod analysis;
pub mod coupling;
pub mod dem;
pub mod gpu;
pub mod io;
pub mod lbm;
pub mod mpm;
pub mod pool;
pub mod progress;
pub mod run;
pub mod run_grains;
pub mod run_mpm;
pub mod scene;
pub mod simulation;
pub mod stability;
#[cfg(test)]
pub(crate) mod test_rng;
