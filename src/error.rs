//! Why a run could not start or finish: the one error type of the driver, over every
//! solver's.

use io::OutputError;
use scene::SceneError;
use thiserror::Error;

/// Why a run could not start or finish writing.
#[derive(Debug, Error)]
pub enum RunError {
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Output could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// An analysis failed.
    #[error(transparent)]
    Analysis(#[from] analysis::AnalysisError),
    /// The GPU backend could not start.
    #[error(transparent)]
    Gpu(#[from] lbm::gpu::GpuError),
    /// The grains could not be set up.
    #[error(transparent)]
    Dem(#[from] dem::DemError),
    /// The material points could not be set up.
    #[error(transparent)]
    Mpm(#[from] mpm::MpmError),
    /// The run would take too many steps or too much memory (`--force` overrides).
    #[error("{0}")]
    TooLarge(String),
    /// A command-line override does not apply to this kind of scene.
    #[error("{0}")]
    Override(String),
    /// SIGTERM arrived before the first step (while the sample settled).
    #[error("{0}")]
    Interrupted(String),
    /// A check of the solver's own bookkeeping failed (a bug, not the scene's fault).
    #[error("{0}")]
    Internal(String),
}
