//! Scenes: TOML files in SI units, parsed strictly and validated before anything is
//! allocated. [`load`] returns a [`ValidScene`]: the parsed scene, its derived lattice
//! [`Units`] and any warnings.

mod build;
mod check;
pub mod collapse_names;
mod context;
pub mod coupling;
pub mod coupling_check;
mod domain;
mod gates;
mod grains;
mod grains_check;
mod legacy;
pub mod limits;
mod locate;
mod mpm;
mod mpm_check;
mod mpm_material_check;
mod output;
mod pictures;
mod probes_check;
mod schema;
mod unknown;
mod validate;

pub use build::{build_lattice, lattice_collision, solid_id_of, BuiltGeometry};
pub use grains::*;
pub use grains_check::{
    estimated_grains, grain_result_names, parse_grains, size_distribution, ValidGrainScene,
};
pub use lbm::gpu::GpuStorage;
pub use lbm::units::{derive, TimeStepChoice, Units};
pub use mpm::*;
pub use mpm_check::{body_shape, mpm_result_names, parse_mpm, ValidMpmScene};
pub use output::{Cadence, GrainDomain, Output, SceneKind};
pub use pictures::{PictureField, PictureLimits};
pub use schema::*;

use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why a scene was rejected.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read scene file {path}: {source}")]
    Io {
        /// Scene path.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// TOML syntax, an unknown key, a missing key or a wrong type (toml's message names the
    /// key, line and column).
    #[error("{path}: {message}")]
    Parse {
        /// Scene path.
        path: PathBuf,
        /// toml's message.
        message: String,
    },
    /// A value that parses but is impossible.
    #[error("{path}{}: `{key}`: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Invalid {
        /// Scene path.
        path: PathBuf,
        /// 1-based line of the key, when it can be located.
        line: Option<usize>,
        /// The offending key.
        key: String,
        /// What is wrong and how to fix it.
        message: String,
    },
}

impl SceneError {
    /// An `Invalid` error about `key` of the scene at `path`, with no line (the key may
    /// stand for a sample or a file, known only once the scene is being built).
    pub fn unlocated(path: &Path, key: &str, message: String) -> Self {
        SceneError::Invalid {
            path: path.to_owned(),
            line: None,
            key: key.into(),
            message,
        }
    }
}

/// A scene that passed validation.
#[derive(Debug, Clone)]
pub struct ValidScene {
    /// The parsed scene.
    pub scene: Scene,
    /// Derived lattice parameters.
    pub units: Units,
    /// Non-fatal findings (e.g. Mach > 0.1).
    pub warnings: Vec<String>,
    /// Directory of the scene file (relative paths in the scene resolve against it).
    pub base_dir: PathBuf,
    /// Path of the scene file.
    pub path: PathBuf,
}

impl ValidScene {
    /// An error about `key` of this scene that only shows once the scene is being built
    /// (no line: the key may stand for a sample or a file).
    pub fn invalid(&self, key: &str, message: String) -> SceneError {
        SceneError::unlocated(&self.path, key, message)
    }
}

/// Read, parse and validate a scene file.
pub fn load(path: &Path) -> Result<ValidScene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse(&text, path)
}

/// A validated scene of either kind.
#[derive(Debug, Clone)]
pub enum AnyScene {
    /// Lattice Boltzmann fluid (with obstacles).
    Fluid(Box<ValidScene>),
    /// Dry grains (DEM only).
    Grains(Box<ValidGrainScene>),
    /// Continuum bodies (MPM only).
    Mpm(Box<ValidMpmScene>),
}

/// Read, parse and validate a scene of any kind: a `[grains]` table without `[fluid]` is a
/// grains scene, an `[mpm]` table alone an MPM scene, `[fluid]` with `[grains]` a coupled
/// fluid scene, anything else a fluid scene.
pub fn load_any(path: &Path) -> Result<AnyScene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_any(&text, path)
}

/// Parse and validate scene text of any kind (as [`load_any`] does a file); `path` is used
/// in messages and to resolve relative files.
pub fn parse_any(text: &str, path: &Path) -> Result<AnyScene, SceneError> {
    let table: toml::Table = toml::from_str(text).map_err(|e| SceneError::Parse {
        path: path.to_owned(),
        message: e.to_string().trim_end().to_string(),
    })?;
    legacy::check(&table, text, path)?;
    if table.contains_key("mpm") {
        if let Some(other) = ["fluid", "grains"]
            .into_iter()
            .find(|k| table.contains_key(*k))
        {
            return Err(SceneError::Invalid {
                path: path.to_owned(),
                line: None,
                key: "mpm".into(),
                message: format!(
                    "a scene with both [mpm] and [{other}] needs coupling between them, which \
                     grainflow does not run yet; split it into separate scenes"
                ),
            });
        }
        return Ok(AnyScene::Mpm(Box::new(parse_mpm(text, path)?)));
    }
    match (table.contains_key("grains"), table.contains_key("fluid")) {
        (true, false) => Ok(AnyScene::Grains(Box::new(parse_grains(text, path)?))),
        (true, true) => parse(text, path)
            .map(|s| AnyScene::Fluid(Box::new(s)))
            .map_err(|e| {
                const HINT: &str = "\n(a scene with [fluid] and [grains] runs coupled: it \
                                    needs [domain], [fluid], [boundaries], [run], [grains] and \
                                    [coupling])";
                match e {
                    SceneError::Parse { path, message } => SceneError::Parse {
                        path,
                        message: format!("{message}{HINT}"),
                    },
                    // The strict parse's errors (the structure), not validation's.
                    SceneError::Invalid {
                        path,
                        line,
                        key,
                        message,
                    } if [
                        "unknown field",
                        "missing field",
                        "invalid type",
                        "unknown variant",
                    ]
                    .iter()
                    .any(|p| message.starts_with(p)) =>
                    {
                        SceneError::Invalid {
                            path,
                            line,
                            key,
                            message: format!("{message}{HINT}"),
                        }
                    }
                    other => other,
                }
            }),
        _ => Ok(AnyScene::Fluid(Box::new(parse(text, path)?))),
    }
}

/// Parse and validate scene text; `path` is used in messages and to resolve relative files.
pub fn parse(text: &str, path: &Path) -> Result<ValidScene, SceneError> {
    screen_raw(text, path)?;
    let mut scene: Scene = locate::strict(text, path)?;
    unknown::refuse_ignored(text, &scene, path)?;
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let ctx = context::Context {
        text,
        path,
        base_dir: &base_dir,
    };
    let mut warnings = domain::resolve(&mut scene, &ctx)?;
    let (units, more) = validate::validate(&scene, &ctx)?;
    warnings.extend(more);
    Ok(ValidScene {
        scene,
        units,
        warnings,
        base_dir,
        path: path.to_owned(),
    })
}

/// Checks on the file as plain TOML, before the strict parse: a key of an older scene
/// dialect (an error naming its replacement) and a NaN or infinite number (an error naming
/// its key path). Nothing when the text is not TOML: the strict parse reports that.
pub(crate) fn screen_raw(text: &str, path: &Path) -> Result<(), SceneError> {
    match toml::from_str::<toml::Table>(text) {
        Ok(table) => {
            legacy::check(&table, text, path)?;
            limits::refuse_non_finite(text, path)
        }
        Err(_) => Ok(()),
    }
}
