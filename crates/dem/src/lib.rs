//! Discrete element method for 2-D disks (seed study, chapters 4–5): linear spring–dashpot
//! normal contacts with damping from a coefficient of restitution, Cundall–Strack tangential
//! springs with Coulomb friction, optional rolling resistance, straight walls (which may
//! move), gravity, velocity-Verlet integration, and a Verlet neighbour list built by a
//! deterministic O(N) cell list.
//!
//! Units are SI. Disks have unit depth: mass m = ρ π r² (kg per metre of depth), moment of
//! inertia I = ½ m r².
//!
//! This is the serial/rayon core of the DEM issue. Scenes, output, checkpoints, ghost
//! grains and migration over ranks, and the column-collapse validation build on it.

pub mod cells;
pub mod contact;
mod forces;
pub mod grains;
mod neighbours;
pub mod parallel;
pub mod sample;
pub mod system;
pub mod walls;

pub use contact::{ContactModel, DemError};
pub use grains::Grains;
pub use parallel::SlabDem;
pub use sample::{load_csv, random_sequential_addition, settle, SizeDistribution};
pub use system::{stable_time_step, DemSetup, DemSystem};
pub use walls::{closed_box, Wall};
