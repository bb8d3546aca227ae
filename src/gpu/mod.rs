//! The wgpu backend: device discovery ([`context`]), the WGSL kernels (`shaders/*.wgsl`) and the
//! GPU fluid solver ([`fluid::GpuFluid`]), which implements
//! [`crate::lbm::FluidBackend`] on one rank's slab.

mod body_columns;
pub mod buffers;
mod cells;
pub mod context;
pub mod fluid;
mod moving;

pub use context::{list_adapters, AdapterSummary, GpuContext, GpuError};
pub use fluid::GpuFluid;
