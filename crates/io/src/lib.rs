//! Output: HDF5 snapshots with an XDMF sidecar, PNG pictures, probe CSVs, `summary.json`.
//! Every file except the growing HDF5 series is written atomically (temporary file, then
//! rename), so a crash never leaves half a file.

pub mod atomic;
pub mod checkpoint;
pub mod colormap;
pub mod coupled_checkpoint;
pub mod digest;
pub mod figure;
pub mod font;
pub mod grains_checkpoint;
pub mod grains_out;
pub mod grains_picture;
pub mod h5par;
pub mod hdf5_out;
pub mod mpm_checkpoint;
pub mod mpm_out;
pub mod picture;
pub mod probes;
pub mod xdmf;

use thiserror::Error;

/// Output failures.
#[derive(Debug, Error)]
pub enum OutputError {
    /// Filesystem error on a path.
    #[error("cannot write {path}: {source}")]
    Io {
        /// Path.
        path: std::path::PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// HDF5 library error.
    #[error("HDF5 error on {path}: {source}")]
    Hdf5 {
        /// File.
        path: std::path::PathBuf,
        /// Cause.
        source: hdf5::Error,
    },
    /// A checkpoint that cannot be used for this run.
    #[error("checkpoint {path}: {message}")]
    Checkpoint {
        /// File.
        path: std::path::PathBuf,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// PNG encoder error.
    #[error("PNG error on {path}: {message}")]
    Png {
        /// File.
        path: std::path::PathBuf,
        /// Cause.
        message: String,
    },
}
