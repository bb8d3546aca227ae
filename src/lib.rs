//! grainflow: fluid–grain flow solver for geomechanics.
//!
//! The fluid core is a 2-D D2Q9 lattice Boltzmann solver ([`lbm`]); scenes are TOML files
//! in SI units ([`scene`]); a [`simulation::Simulation`] runs the stages a scene asks for
//! and writes snapshots, pictures, probe series and a `summary.json` ([`io`]).

pub mod analysis;
pub mod io;
pub mod lbm;
pub mod progress;
pub mod run;
pub mod scene;
pub mod simulation;
