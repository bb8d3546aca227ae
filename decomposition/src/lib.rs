// `!(x > 0.0)` is used on purpose throughout: unlike `x <= 0.0` it is true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
//! Domain decomposition for grainflow, with no physics in it. MPI lives only in this crate.
//!
//! * [`Comm`]: the small communicator interface every solver talks to. [`SingleProcess`]
//!   implements it for one rank (unit tests, serial runs); [`MpiComm`] wraps Open MPI.
//! * [`SlabPartition`]: splits the global lattice into slabs along x, optionally weighted by
//!   per-column cost, with owner look-ups and global ↔ local index maps.
//! * [`SlabHalo`]: the two-face halo exchange of a slab: one contiguous buffer per
//!   neighbour, non-blocking, with work overlapped while the messages travel.
//! * [`swap_neighbours`], [`swap_neighbours_varlen`]: one message per neighbour for
//!   particle solvers (ghosts, migration, MPM grid strips).
//! * [`PackRows`], [`Record`]: how a grain, a material point or a ghost's state becomes
//!   the f64 words of a message (and of a checkpoint row), and back.

mod comm;
mod exact_sum;
mod halo;
mod mpi_comm;
mod neighbours;
mod pack;
mod redistribute;
mod slab;
mod traffic;

pub use comm::{ordered_sum, Comm, Incoming, Outgoing, SingleProcess};
pub use exact_sum::reproducible_sums;
pub use halo::{Side, SlabHalo};
pub use mpi_comm::{launched_by_mpi, MpiComm, RawComm};
pub use neighbours::{swap_neighbours, swap_neighbours_varlen};
pub use pack::{pack_rows, pack_words, unpack_rows, unpack_words, PackRows, Record, Word};
pub use redistribute::move_columns;
pub use slab::{PartitionError, Slab, SlabPartition};
pub use traffic::Traffic;
