// `!(x > 0.0)` is used on purpose throughout: unlike `x <= 0.0` it is true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
//! Domain decomposition for grainflow, with no physics in it.
//!
//! * [`Comm`]: the small communicator interface every solver talks to. [`SingleProcess`]
//!   implements it for one rank (unit tests, serial runs); an MPI implementation follows in
//!   the distributed-runs work and lives only in this crate.
//! * [`SlabPartition`]: splits the global lattice into slabs along x, optionally weighted by
//!   per-column cost, with owner look-ups and global ↔ local index maps.

mod comm;
mod slab;

pub use comm::{Comm, SingleProcess};
pub use slab::{PartitionError, Slab, SlabPartition};
