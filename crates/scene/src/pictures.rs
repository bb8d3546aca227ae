//! What the pictures of a run show (`[output] picture_field`), their size and their colour
//! limits, for every kind of scene.

use super::context::Context;
use super::output::{Output, SceneKind};
use super::SceneError;
use serde::{Deserialize, Serialize};

/// What the PNG pictures colour.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum PictureField {
    /// Speed |u| (m/s): the fluid's, the grains' or the points'.
    #[default]
    Speed,
    /// The fluid's vorticity (1/s).
    Vorticity,
    /// The fluid's pressure relative to the reference density's (Pa).
    Pressure,
    /// The points' equivalent plastic strain (MPM).
    PlasticStrain,
}

impl PictureField {
    /// The name in scenes and picture file names.
    pub fn as_str(self) -> &'static str {
        match self {
            PictureField::Speed => "speed",
            PictureField::Vorticity => "vorticity",
            PictureField::Pressure => "pressure",
            PictureField::PlasticStrain => "plastic-strain",
        }
    }

    /// The fields a kind of scene can draw.
    pub fn allowed(kind: SceneKind) -> &'static [PictureField] {
        match kind {
            SceneKind::Fluid => &[
                PictureField::Speed,
                PictureField::Vorticity,
                PictureField::Pressure,
            ],
            SceneKind::Grains => &[PictureField::Speed],
            SceneKind::Mpm => &[PictureField::Speed, PictureField::PlasticStrain],
        }
    }
}

/// Colour limits of the pictures, fixed for the whole run; each field's is optional.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PictureLimits {
    /// Top of the speed scale (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed_m_s: Option<f64>,
    /// Limit of the vorticity scale, ± (1/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vorticity_1_s: Option<f64>,
    /// Limit of the pressure scale, ± (Pa).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure_pa: Option<f64>,
    /// Top of the plastic-strain scale.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plastic_strain: Option<f64>,
}

impl PictureLimits {
    /// (key, value, the field it limits).
    fn entries(&self) -> [(&'static str, Option<f64>, PictureField); 4] {
        [
            ("speed_m_s", self.speed_m_s, PictureField::Speed),
            ("vorticity_1_s", self.vorticity_1_s, PictureField::Vorticity),
            ("pressure_pa", self.pressure_pa, PictureField::Pressure),
            (
                "plastic_strain",
                self.plastic_strain,
                PictureField::PlasticStrain,
            ),
        ]
    }
}

/// Validate the picture keys of `[output]` for a scene of `kind`.
pub(crate) fn validate(o: &Output, kind: SceneKind, ctx: &Context) -> Result<(), SceneError> {
    let allowed = PictureField::allowed(kind);
    let names = || {
        allowed
            .iter()
            .map(|f| format!("\"{}\"", f.as_str()))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Some(f) = o.picture_field {
        if !allowed.contains(&f) {
            return Err(ctx.err(
                "picture_field",
                0,
                format!(
                    "picture_field \"{}\" is not drawn in this kind of scene; use one of {}",
                    f.as_str(),
                    names()
                ),
            ));
        }
    }
    if let Some(px) = o.picture_size_px {
        if !(64..=8192).contains(&px) {
            return Err(ctx.err(
                "picture_size_px",
                0,
                format!("picture_size_px must be from 64 to 8192 pixels, got {px}"),
            ));
        }
    }
    for (key, value, field) in o.picture_limits().entries() {
        let Some(v) = value else { continue };
        if !allowed.contains(&field) {
            return Err(ctx.err(
                key,
                0,
                format!(
                    "picture_limits.{key}: this kind of scene draws no {} picture; remove it \
                     (pictures here: {})",
                    field.as_str(),
                    names()
                ),
            ));
        }
        if !(v.is_finite() && v > 0.0) {
            return Err(ctx.err(
                key,
                0,
                format!("picture_limits.{key} must be a positive finite number, got {v}"),
            ));
        }
    }
    Ok(())
}
