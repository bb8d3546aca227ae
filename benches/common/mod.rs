//! Shared set-up of the LBM benchmarks: the periodic box `check`'s speed measurement runs
//! too.
pub use grainflow::budget::walltime::periodic_box;
