//! The wgpu backend: device discovery ([`context`]), the WGSL kernels (`shaders/*.wgsl`) and the
//! GPU fluid solver ([`fluid::GpuFluid`]), which implements
//! [`crate::FluidBackend`] on one rank's slab.

mod body_columns;
pub mod buffers;
mod cells;
pub mod context;
pub mod fluid;

use serde::{Deserialize, Serialize};

pub use context::{list_adapters, AdapterSummary, GpuContext, GpuError};
pub use fluid::GpuFluid;

/// Storage of the populations on the GPU.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum GpuStorage {
    /// The run's precision.
    #[default]
    Native,
    /// IEEE binary16 storage with f32 arithmetic (Lehmann et al. 2022, "FP16S"): half the
    /// memory and memory traffic of f32.
    F16,
}
