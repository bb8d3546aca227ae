//! What every kind of scene shares about its run: the length (`[run] steps` or
//! `end_time_s`), the `[output]` table (snapshot and checkpoint cadence), and the
//! `[domain]` of a grains scene. One set of keys for fluid, coupled, grain and MPM scenes.

use super::context::Context;
use super::schema::FieldName;
use super::SceneError;
use serde::{Deserialize, Serialize};

/// Which solver a scene runs, for the keys that apply to one kind only.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneKind {
    /// Lattice Boltzmann fluid, with or without grains.
    Fluid,
    /// Dry grains (DEM).
    Grains,
    /// Material points (MPM).
    Mpm,
}

impl SceneKind {
    fn name(self) -> &'static str {
        match self {
            SceneKind::Fluid => "fluid",
            SceneKind::Grains => "grains",
            SceneKind::Mpm => "MPM",
        }
    }
}

/// Snapshots, pictures and checkpoints. Every key is optional; without the table a run
/// writes a snapshot at its start and its end and no checkpoint.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Snapshot (HDF5 + PNG) every this many steps (≥ 1). Exclusive with `every_s`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every_steps: Option<u64>,
    /// Snapshot every this much simulated time (s, > 0). Exclusive with `every_steps`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every_s: Option<f64>,
    /// Write PNG pictures with each snapshot (default true).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pictures: Option<bool>,
    /// Fluid scenes: fields in snapshots, any of "density", "velocity", "vorticity",
    /// "pressure" (default all four).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fields: Option<Vec<FieldName>>,
    /// Fluid scenes: deflate level of snapshot datasets, 0 (off, the default: lattice
    /// doubles compress by only ~10 % and deflate cuts write bandwidth ~6×) to 9.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compression: Option<u8>,
    /// Fluid scenes: record probes every this many steps (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub probe_every_steps: Option<u64>,
    /// What the pictures show: fluid scenes "speed", "vorticity" or "pressure" (default:
    /// speed and vorticity); MPM scenes "speed" (default) or "plastic-strain"; grains
    /// scenes "speed".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub picture_field: Option<super::pictures::PictureField>,
    /// The longer side of a picture's panel (pixels, 64–8192; default 1024).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub picture_size_px: Option<u32>,
    /// The top of each picture's colour scale, fixed for the whole run (signed fields run
    /// from minus to plus the limit); a field not given takes a limit from the scene's
    /// scales (docs/outputs.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub picture_limits: Option<super::pictures::PictureLimits>,
    /// Write `checkpoint.h5` every this many steps; absent or 0: never (a checkpoint is
    /// still written on SIGTERM and SIGUSR1, and at the end with `checkpoint_at_end`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkpoint_every_steps: Option<u64>,
    /// Also write a checkpoint every this many minutes of wall-clock time; absent or 0:
    /// never.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkpoint_every_minutes: Option<f64>,
    /// Write a checkpoint after the last step (default false).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkpoint_at_end: Option<bool>,
}

/// When snapshots are written between the first and the last one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cadence {
    /// Only at the start and the end.
    Ends,
    /// Every this many steps.
    Steps(u64),
    /// Every this much simulated time (s).
    Seconds(f64),
}

impl Output {
    /// The snapshot cadence.
    pub fn cadence(&self) -> Cadence {
        match (self.every_steps, self.every_s) {
            (Some(n), _) if n > 0 => Cadence::Steps(n),
            (_, Some(t)) if t > 0.0 => Cadence::Seconds(t),
            _ => Cadence::Ends,
        }
    }
    /// Whether snapshots carry pictures.
    pub fn pictures(&self) -> bool {
        self.pictures.unwrap_or(true)
    }
    /// The fields of fluid snapshots.
    pub fn fields(&self) -> Vec<FieldName> {
        self.fields.clone().unwrap_or_else(|| {
            vec![
                FieldName::Density,
                FieldName::Velocity,
                FieldName::Vorticity,
                FieldName::Pressure,
            ]
        })
    }
    /// Deflate level of fluid snapshots.
    pub fn compression(&self) -> u8 {
        self.compression.unwrap_or(0)
    }
    /// Probe cadence of fluid runs (steps).
    pub fn probe_every_steps(&self) -> u64 {
        self.probe_every_steps.unwrap_or(1)
    }
    /// What MPM pictures colour.
    pub fn picture_field(&self) -> super::pictures::PictureField {
        self.picture_field.unwrap_or_default()
    }
    /// The longer side of a picture's panel (pixels).
    pub fn picture_size_px(&self) -> usize {
        self.picture_size_px.map_or(1024, |p| p as usize)
    }
    /// The scene's colour limits (none set: all `None`).
    pub fn picture_limits(&self) -> super::pictures::PictureLimits {
        self.picture_limits.clone().unwrap_or_default()
    }
    /// Checkpoint cadence in steps (0: never).
    pub fn checkpoint_every_steps(&self) -> u64 {
        self.checkpoint_every_steps.unwrap_or(0)
    }
    /// Checkpoint cadence in wall-clock minutes (0: never).
    pub fn checkpoint_every_minutes(&self) -> f64 {
        self.checkpoint_every_minutes.unwrap_or(0.0)
    }
    /// Whether a checkpoint follows the last step.
    pub fn checkpoint_at_end(&self) -> bool {
        self.checkpoint_at_end.unwrap_or(false)
    }
}

/// Validate `[output]` for a scene of `kind`: the cadence and the keys that apply to it.
pub(crate) fn validate_output(
    o: &Output,
    kind: SceneKind,
    ctx: &Context,
) -> Result<(), SceneError> {
    if o.every_steps.is_some() && o.every_s.is_some() {
        return Err(ctx.err(
            "every_steps",
            0,
            "[output] takes one snapshot cadence: every_steps or every_s, not both",
        ));
    }
    if o.every_steps == Some(0) {
        return Err(ctx.err(
            "every_steps",
            0,
            "every_steps must be at least 1; remove it for snapshots at the start and the end only",
        ));
    }
    if let Some(t) = o.every_s {
        if !(t.is_finite() && t > 0.0) {
            return Err(ctx.err(
                "every_s",
                0,
                format!("every_s must be a positive number of seconds, got {t}; remove it for snapshots at the start and the end only"),
            ));
        }
    }
    let only = |key: &str, set: bool, for_kind: SceneKind| {
        if set && kind != for_kind {
            Err(ctx.err(
                key,
                0,
                format!(
                    "`output.{key}` applies to {} scenes only; remove it from this {} scene",
                    for_kind.name(),
                    kind.name()
                ),
            ))
        } else {
            Ok(())
        }
    };
    only("fields", o.fields.is_some(), SceneKind::Fluid)?;
    only("compression", o.compression.is_some(), SceneKind::Fluid)?;
    only(
        "probe_every_steps",
        o.probe_every_steps.is_some(),
        SceneKind::Fluid,
    )?;
    super::pictures::validate(o, kind, ctx)?;
    if o.probe_every_steps == Some(0) {
        return Err(ctx.err(
            "probe_every_steps",
            0,
            "probe_every_steps must be at least 1",
        ));
    }
    if o.compression.is_some_and(|c| c > 9) {
        return Err(ctx.err(
            "compression",
            0,
            "compression is a deflate level from 0 (off) to 9; use 1 for a good speed/size balance",
        ));
    }
    if let Some(fields) = &o.fields {
        for (n, f) in fields.iter().enumerate() {
            if fields[..n].contains(f) {
                return Err(ctx.err(
                    "fields",
                    0,
                    format!("field \"{}\" is listed twice", f.as_str()),
                ));
            }
        }
    }
    let m = o.checkpoint_every_minutes();
    if !(m >= 0.0 && m.is_finite()) {
        return Err(ctx.err(
            "checkpoint_every_minutes",
            0,
            "checkpoint_every_minutes must be a finite number ≥ 0 (0 turns wall-clock checkpoints off)",
        ));
    }
    Ok(())
}

/// `[run] steps` or `end_time_s` of a grains or MPM scene, checked: exactly one, a
/// positive step count or a positive finite time.
pub(crate) fn validate_length(
    steps: Option<u64>,
    end_time_s: Option<f64>,
    ctx: &Context,
) -> Result<(), SceneError> {
    match (steps, end_time_s) {
        (Some(0), None) => Err(ctx.err("steps", 0, "steps must be at least 1")),
        (Some(_), None) => Ok(()),
        (None, Some(t)) if t.is_finite() && t > 0.0 => Ok(()),
        (None, Some(t)) => Err(ctx.err(
            "end_time_s",
            0,
            format!("the run's end time must be a positive number, got {t}"),
        )),
        _ => Err(ctx.err("run", 0, "set exactly one of steps or end_time_s in [run]")),
    }
}

/// The region of a grains scene, `[domain]`: its lower-left corner is the origin, its size
/// is `size_m`, or `cells` × `spacing_m` as in a fluid scene (so the dry twin of a coupled
/// scene keeps the same table). It is split into slabs over the ranks and framed in
/// pictures; grains may leave it (walls keep them in).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GrainDomain {
    /// Width and height (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size_m: Option<[f64; 2]>,
    /// Cells along x and y (with `spacing_m`), as in a fluid scene.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cells: Option<[usize; 2]>,
    /// Cell size (m), with `cells`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing_m: Option<f64>,
}

impl GrainDomain {
    /// Width and height (m); valid after validation.
    pub fn size(&self) -> [f64; 2] {
        match (self.size_m, self.cells, self.spacing_m) {
            (Some(s), _, _) => s,
            (None, Some(c), Some(h)) => [c[0] as f64 * h, c[1] as f64 * h],
            _ => [f64::NAN; 2],
        }
    }
}

/// Validate a grains `[domain]`: `size_m`, or `cells` with `spacing_m`.
pub(crate) fn validate_grain_domain(d: &GrainDomain, ctx: &Context) -> Result<(), SceneError> {
    match (d.size_m, d.cells, d.spacing_m) {
        (Some(_), None, None) | (None, Some(_), Some(_)) => {}
        _ => {
            return Err(ctx.err(
                "domain",
                0,
                "[domain] of a grains scene takes size_m = [width, height] (m), or cells = \
                 [nx, ny] with spacing_m as in a fluid scene",
            ))
        }
    }
    let s = d.size();
    if !(s.iter().all(|v| v.is_finite() && *v > 0.0)) {
        let key = if d.size_m.is_some() {
            "size_m"
        } else {
            "cells"
        };
        return Err(ctx.err(
            key,
            0,
            format!("the domain's width and height must be positive numbers of metres, got {s:?}"),
        ));
    }
    Ok(())
}
