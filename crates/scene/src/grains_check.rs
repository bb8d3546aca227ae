//! Validation of grains-only scenes and their conversion to DEM parameters.

use super::context::{positive, validate_checks, Context};
use super::grains::*;
use super::SceneError;
use dem::{stable_time_step, ContactModel, DemSetup, Grains, SizeDistribution, Wall};
use std::path::{Path, PathBuf};

/// A grains scene that passed validation.
#[derive(Debug, Clone)]
pub struct ValidGrainScene {
    /// The parsed scene.
    pub scene: GrainScene,
    /// Non-fatal findings.
    pub warnings: Vec<String>,
    /// Directory of the scene file.
    pub base_dir: PathBuf,
    /// Path of the scene file.
    pub path: PathBuf,
}

/// Names of the results a grains scene produces (what checks may refer to).
pub fn grain_result_names(s: &GrainScene) -> Vec<String> {
    let mut names = Vec::new();
    for a in &s.analyses {
        match a {
            GrainAnalysis::ColumnCollapse { .. } => {
                for q in crate::collapse_names::QUANTITIES {
                    names.push(format!("collapse.{q}"));
                }
                for q in ["front_t95", "front_t10", "front_speed_m_s"] {
                    names.push(format!("collapse.{q}"));
                }
            }
        }
    }
    names
}

/// Parse and validate a grains scene.
pub fn parse_grains(text: &str, path: &Path) -> Result<ValidGrainScene, SceneError> {
    super::screen_raw(text, path)?;
    let scene: GrainScene = super::locate::strict(text, path)?;
    super::unknown::refuse_ignored(text, &scene, path)?;
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let ctx = Context {
        text,
        path,
        base_dir: &base_dir,
    };
    let mut warnings = validate(&scene, &ctx)?;
    super::gates::validate(&scene.grains, scene.run.end_time_s, &ctx)?;
    warnings.extend(no_floor(&scene.grains));
    Ok(ValidGrainScene {
        scene,
        warnings,
        base_dir,
        path: path.to_owned(),
    })
}

pub(super) fn non_negative(ctx: &Context, key: &str, v: f64) -> Result<(), SceneError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(ctx.err(key, 0, format!("must be a finite number ≥ 0, got {v}")))
    }
}

/// The contact law of `c`.
fn contact_model(c: &ContactSpec) -> ContactModel {
    ContactModel {
        kn: c.normal_stiffness_n_m2,
        kt: c.tangential_stiffness_n_m2,
        restitution: c.restitution,
        friction: c.friction,
        rolling_friction: c.rolling_friction,
        tangential_damping: c.tangential_damping,
    }
}

/// About how many grains `sample` holds: listed ones, or a packed rectangle's share
/// (area × solid fraction over the mean of the extreme disks' areas, before any settling
/// trim); `None` for a CSV file, whose grains are read at run time.
pub fn estimated_grains(sample: &SampleSpec) -> Option<f64> {
    match sample {
        SampleSpec::List { grains } => Some(grains.len() as f64),
        SampleSpec::Pack {
            min_m,
            max_m,
            sizes,
            solid_fraction,
            ..
        } => Some(packed_grains(*min_m, *max_m, sizes, *solid_fraction)),
        SampleSpec::Csv { .. } => None,
    }
}

/// Grains a packed rectangle will hold: its area times the solid fraction over the mean of
/// the smallest and largest disk's area (within a factor of 2 for these distributions).
fn packed_grains(min_m: [f64; 2], max_m: [f64; 2], sizes: &SizeSpec, solid_fraction: f64) -> f64 {
    let d = size_distribution(sizes);
    let (r0, r1) = (d.min_radius(), d.max_radius());
    let area = (max_m[0] - min_m[0]) * (max_m[1] - min_m[1]);
    solid_fraction * area / (std::f64::consts::PI * 0.5 * (r0 * r0 + r1 * r1))
}

/// Every component of `v` finite and at most `max` in magnitude.
pub(super) fn bounded(ctx: &Context, key: &str, v: &[f64], max: f64) -> Result<(), SceneError> {
    if v.iter().all(|x| x.is_finite() && x.abs() <= max) {
        Ok(())
    } else {
        Err(ctx.err(
            key,
            0,
            format!("{v:?} is out of range: each component must lie within ±{max:e}"),
        ))
    }
}

pub(super) fn rectangle(
    ctx: &Context,
    key: &str,
    lo: [f64; 2],
    hi: [f64; 2],
) -> Result<(), SceneError> {
    if lo.iter().chain(&hi).all(|v| v.is_finite()) && lo[0] < hi[0] && lo[1] < hi[1] {
        Ok(())
    } else {
        Err(ctx.err(
            key,
            0,
            format!("the rectangle {lo:?}–{hi:?} is empty: min_m must be below and left of max_m"),
        ))
    }
}

/// Validate a grains scene section by section; returns its warnings.
pub(super) fn validate(s: &GrainScene, ctx: &Context) -> Result<Vec<String>, SceneError> {
    super::output::validate_grain_domain(&s.domain, ctx)?;
    let g = &s.grains;
    validate_material(g, ctx)?;
    validate_time_step(g, ctx)?;
    validate_sample(g, s.domain.size(), ctx)?;
    validate_walls(g, ctx)?;
    validate_run_and_checks(s, ctx)?;
    Ok(Vec::new())
}

/// A warning when gravity pulls the sample (its packing rectangle, or its listed grains)
/// towards no wall and no fixed grain: every grain would fall out of the domain. Nothing
/// for a CSV sample (its extent is known only once read) or without gravity.
pub(super) fn no_floor(g: &GrainsSpec) -> Option<String> {
    let grav = g.gravity_m_s2;
    let norm = grav[0].hypot(grav[1]);
    if norm == 0.0 {
        return None;
    }
    let down = [grav[0] / norm, grav[1] / norm];
    let across = [-down[1], down[0]];
    let (points, fixed): (Vec<[f64; 2]>, Vec<[f64; 3]>) = match &g.sample {
        SampleSpec::Pack { min_m, max_m, .. } => (
            vec![*min_m, *max_m, [min_m[0], max_m[1]], [max_m[0], min_m[1]]],
            Vec::new(),
        ),
        SampleSpec::List { grains } => (
            grains
                .iter()
                .filter(|l| !l.fixed)
                .flat_map(|l| {
                    let (p, r) = (l.position_m, l.radius_m);
                    [[p[0] - r, p[1] - r], [p[0] + r, p[1] + r]]
                })
                .collect(),
            grains
                .iter()
                .filter(|l| l.fixed)
                .map(|l| [l.position_m[0], l.position_m[1], l.radius_m])
                .collect(),
        ),
        SampleSpec::Csv { .. } => return None,
    };
    let dot = |p: [f64; 2], a: [f64; 2]| p[0] * a[0] + p[1] * a[1];
    let range = |ps: &mut dyn Iterator<Item = f64>| {
        ps.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        })
    };
    let (lo, hi) = range(&mut points.iter().map(|&p| dot(p, across)));
    let (_, deepest) = range(&mut points.iter().map(|&p| dot(p, down)));
    if !lo.is_finite() {
        return None;
    }
    // Something below the sample (further along gravity) that overlaps it across gravity.
    let walls = g.walls.iter().any(|w| {
        let (a, b) = (dot(w.from_m, across), dot(w.to_m, across));
        let below = dot(w.from_m, down).max(dot(w.to_m, down)) >= deepest;
        below && a.min(b) < hi && a.max(b) > lo
    });
    let grains = fixed.iter().any(|f| {
        let (c, r) = ([f[0], f[1]], f[2]);
        dot(c, down) + r >= deepest && dot(c, across) + r >= lo && dot(c, across) - r <= hi
    });
    (!walls && !grains).then(|| {
        format!(
            "gravity [{}, {}] m/s² pulls the grains towards no wall and no fixed grain: they \
             will fall out of the domain. Add a floor under the sample to `[[grains.walls]]`",
            grav[0], grav[1]
        )
    })
}

/// The grains' density, damping, gravity and `[grains.contact]`.
fn validate_material(g: &GrainsSpec, ctx: &Context) -> Result<(), SceneError> {
    positive(ctx, "density_kg_m3", g.density_kg_m3, "the grain density")?;
    non_negative(ctx, "global_damping_1_s", g.global_damping_1_s)?;
    bounded(
        ctx,
        "gravity_m_s2",
        &g.gravity_m_s2,
        super::limits::MAX_GRAVITY_M_S2,
    )?;
    let c = &g.contact;
    positive(ctx, "normal_stiffness_n_m2", c.normal_stiffness_n_m2, "k_n")?;
    non_negative(
        ctx,
        "tangential_stiffness_n_m2",
        c.tangential_stiffness_n_m2,
    )?;
    if !(c.restitution > 0.0 && c.restitution <= 1.0) {
        return Err(ctx.err(
            "restitution",
            0,
            format!("must be in (0, 1], got {}", c.restitution),
        ));
    }
    non_negative(ctx, "friction", c.friction)?;
    non_negative(ctx, "rolling_friction", c.rolling_friction)?;
    if !(0.0..=1.0).contains(&c.tangential_damping) {
        return Err(ctx.err(
            "tangential_damping",
            0,
            format!(
                "must be in [0, 1] (a fraction of the normal dashpot), got {}",
                c.tangential_damping
            ),
        ));
    }
    Ok(())
}

/// `[grains.time_step]`: λ in (0, 1], and a fixed step within λ Δt_cr of the smallest grain.
fn validate_time_step(g: &GrainsSpec, ctx: &Context) -> Result<(), SceneError> {
    let c = &g.contact;
    match g.time_step {
        TimeStepSpec::Critical { lambda } | TimeStepSpec::Fixed { lambda, .. } => {
            if !(lambda > 0.0 && lambda <= 1.0) {
                return Err(ctx.err(
                    "lambda",
                    0,
                    format!("λ must be in (0, 1] (about 0.1, seed eq. 5.60), got {lambda}"),
                ));
            }
        }
    }
    if let TimeStepSpec::Fixed {
        time_step_s,
        lambda,
    } = g.time_step
    {
        positive(ctx, "time_step_s", time_step_s, "the time step")?;
        // What `run` refuses once the grains exist, refused here when the scene alone
        // gives the lightest grain (seed eq. 5.59–5.60).
        if let Some((r, _)) = super::coupling_check::radius_range(&g.sample) {
            let m = g.density_kg_m3 * std::f64::consts::PI * r * r;
            let limit = lambda * contact_model(c).critical_time_step(m);
            if time_step_s > limit {
                return Err(ctx.err(
                    "time_step_s",
                    0,
                    format!(
                        "the DEM time step {time_step_s:e} s exceeds λ·Δt_cr = {limit:e} s of the \
                         smallest grain (λ = {lambda}); use a time step ≤ {limit:e} s, softer \
                         contacts or kind = \"critical\""
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// `[grains.sample]`, inside the region of `size` (m).
fn validate_sample(g: &GrainsSpec, size: [f64; 2], ctx: &Context) -> Result<(), SceneError> {
    match &g.sample {
        SampleSpec::Pack {
            min_m,
            max_m,
            sizes,
            solid_fraction,
            settle,
            ..
        } => {
            rectangle(ctx, "min_m", *min_m, *max_m)?;
            let dist = size_distribution(sizes);
            if let Err(e) = dist.validate() {
                return Err(ctx.err("distribution", 0, e.to_string()));
            }
            if !(*solid_fraction > 0.0 && *solid_fraction <= 0.9) {
                return Err(ctx.err(
                    "solid_fraction",
                    0,
                    format!("must be in (0, 0.9] (random addition jams near 0.55), got {solid_fraction}"),
                ));
            }
            let inside = (0..2).all(|a| min_m[a] >= 0.0 && max_m[a] <= size[a]);
            if !inside {
                return Err(ctx.err(
                    "max_m",
                    0,
                    format!(
                        "the packing rectangle {min_m:?}–{max_m:?} m reaches outside the domain \
                         [0, 0]–{size:?} m; move it inside or enlarge [domain]"
                    ),
                ));
            }
            let grains = packed_grains(*min_m, *max_m, sizes, *solid_fraction);
            if !(grains <= super::limits::MAX_GRAINS) {
                return Err(ctx.err(
                    "sizes",
                    0,
                    format!(
                        "this rectangle holds about {grains:.3e} grains of these radii, more \
                         than grainflow packs ({:.0e}); use larger grains or a smaller rectangle",
                        super::limits::MAX_GRAINS
                    ),
                ));
            }
            if let Some(st) = settle {
                positive(ctx, "damping_1_s", st.damping_1_s, "the settling damping")?;
                positive(
                    ctx,
                    "kinetic_energy_per_grain_j_m",
                    st.kinetic_energy_per_grain_j_m,
                    "the settling threshold",
                )?;
                if st.max_steps == 0 || st.max_steps > 1_000_000_000 {
                    return Err(ctx.err(
                        "max_steps",
                        0,
                        format!("must be 1 to 10⁹ steps, got {}", st.max_steps),
                    ));
                }
                if let Some(h) = st.trim_above_m {
                    if h <= min_m[1] + dist.min_radius() {
                        return Err(ctx.err(
                            "trim_above_m",
                            0,
                            format!(
                                "trimming above {h} m keeps no grain of a sample packed from \
                                 y = {} m; set it above the settled layer's bottom",
                                min_m[1]
                            ),
                        ));
                    }
                }
                if let Some(f) = st.friction {
                    if !(f >= 0.0 && f.is_finite()) {
                        return Err(ctx.err(
                            "friction",
                            0,
                            format!("the settling friction must be 0 or positive, got {f}"),
                        ));
                    }
                }
            }
        }
        SampleSpec::List { grains } => {
            if grains.is_empty() {
                return Err(ctx.err("grains", 0, "the list holds no grains: add at least one"));
            }
            for (n, l) in grains.iter().enumerate() {
                positive(ctx, "radius_m", l.radius_m, "a grain radius")?;
                bounded(
                    ctx,
                    "velocity_m_s",
                    &l.velocity_m_s,
                    super::limits::MAX_SPEED_M_S,
                )?;
                let inside = |a: usize| {
                    l.position_m[a] - l.radius_m >= 0.0 && l.position_m[a] + l.radius_m <= size[a]
                };
                let finite = l
                    .position_m
                    .iter()
                    .chain(&l.velocity_m_s)
                    .all(|v| v.is_finite());
                if !(finite && inside(0) && inside(1)) {
                    return Err(ctx.err(
                        "position_m",
                        n,
                        format!(
                            "grain {n} at {:?} with radius {} m is not wholly inside the domain \
                             [0, 0]–{size:?} m; move it inside",
                            l.position_m, l.radius_m
                        ),
                    ));
                }
                let moving = l.velocity_m_s != [0.0, 0.0] || l.angular_velocity_rad_s != 0.0;
                if l.fixed && moving {
                    return Err(ctx.err(
                        "fixed",
                        n,
                        format!(
                            "grain {n} is held in place (`fixed = true`) but is given a \
                             velocity: drop `velocity_m_s` and `angular_velocity_rad_s`, or \
                             `fixed`"
                        ),
                    ));
                }
            }
        }
        SampleSpec::Csv { file } => {
            let p = ctx.base_dir.join(file);
            if !p.is_file() {
                return Err(ctx.err(
                    "file",
                    0,
                    format!(
                        "grain file {} not found (paths are relative to the scene)",
                        p.display()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// `[[grains.walls]]`: unique names, a length, finite velocities.
fn validate_walls(g: &GrainsSpec, ctx: &Context) -> Result<(), SceneError> {
    for (n, w) in g.walls.iter().enumerate() {
        if g.walls[..n].iter().any(|o| o.name == w.name) {
            return Err(ctx.err("name", n, format!("wall name `{}` is used twice", w.name)));
        }
        if w.from_m == w.to_m || !w.from_m.iter().chain(&w.to_m).all(|v| v.is_finite()) {
            return Err(ctx.err("from_m", n, format!("wall `{}` has no length", w.name)));
        }
        bounded(
            ctx,
            "velocity_m_s",
            &w.velocity_m_s,
            super::limits::MAX_SPEED_M_S,
        )?;
        non_negative(ctx, "friction", w.friction)?;
        if let Some(t) = w.remove_at_s {
            non_negative(ctx, "remove_at_s", t)?;
        }
    }
    Ok(())
}

/// `[run]`, `[output]`, the analysis and the checks.
fn validate_run_and_checks(s: &GrainScene, ctx: &Context) -> Result<(), SceneError> {
    super::output::validate_length(s.run.steps, s.run.end_time_s, ctx)?;
    super::output::validate_output(&s.output, super::output::SceneKind::Grains, ctx)?;
    non_negative(
        ctx,
        "stop_below_kinetic_energy_j_m",
        s.run.stop_below_kinetic_energy_j_m,
    )?;
    if s.analyses.len() > 1 {
        return Err(ctx.err("kind", 0, "at most one column-collapse analysis per scene"));
    }
    if let Some(GrainAnalysis::ColumnCollapse {
        front_min_height_m: Some(_),
        ..
    }) = s.analyses.first()
    {
        return Err(ctx.err(
            "front_min_height_m",
            0,
            "the thick front is measured on MPM deposits only (a grain deposit's front is \
             already grain by grain); remove front_min_height_m",
        ));
    }
    validate_checks(&s.checks, ctx)?;
    let names = grain_result_names(s);
    for (n, c) in s.checks.iter().enumerate() {
        if !names.contains(&c.quantity) {
            return Err(ctx.err(
                "quantity",
                n,
                format!(
                    "check on unknown quantity `{}`; this scene produces: {}",
                    c.quantity,
                    if names.is_empty() {
                        "nothing".to_string()
                    } else {
                        names.join(", ")
                    }
                ),
            ));
        }
    }
    Ok(())
}

/// The radius distribution of a size spec.
pub fn size_distribution(s: &SizeSpec) -> SizeDistribution {
    match *s {
        SizeSpec::Mono { radius_m } => SizeDistribution::Mono { r: radius_m },
        SizeSpec::Bidisperse {
            small_radius_m,
            large_radius_m,
            fraction_small,
        } => SizeDistribution::Bidisperse {
            small: small_radius_m,
            large: large_radius_m,
            fraction_small,
        },
        SizeSpec::Uniform {
            min_radius_m,
            max_radius_m,
        } => SizeDistribution::Uniform {
            min: min_radius_m,
            max: max_radius_m,
        },
        SizeSpec::Normal {
            mean_radius_m,
            std_radius_m,
            min_radius_m,
            max_radius_m,
        } => SizeDistribution::Normal {
            mean: mean_radius_m,
            std: std_radius_m,
            min: min_radius_m,
            max: max_radius_m,
        },
    }
}

impl ValidGrainScene {
    /// An error about `key` of this scene that only shows once the scene is being built
    /// (no line: the key may stand for a sample file).
    pub fn invalid(&self, key: &str, message: String) -> SceneError {
        SceneError::unlocated(&self.path, key, message)
    }

    /// The contact law of the scene.
    pub fn contact_model(&self) -> ContactModel {
        contact_model(&self.scene.grains.contact)
    }

    /// λ of the time-step choice: the fraction of Δt_cr the step must respect.
    pub fn lambda(&self) -> f64 {
        match self.scene.grains.time_step {
            TimeStepSpec::Critical { lambda } | TimeStepSpec::Fixed { lambda, .. } => lambda,
        }
    }

    /// The time step (s) a run of this scene takes, when the scene alone decides it: the
    /// fixed one, or λ Δt_cr of its smallest packed or listed grain (the lightest; a CSV
    /// sample's grains decide theirs: `None`).
    pub fn planned_time_step(&self) -> Option<f64> {
        if let TimeStepSpec::Fixed { time_step_s, .. } = self.scene.grains.time_step {
            return Some(time_step_s);
        }
        let (r, _) = super::coupling_check::radius_range(&self.scene.grains.sample)?;
        let m = self.scene.grains.density_kg_m3 * std::f64::consts::PI * r * r;
        Some(self.lambda() * self.contact_model().critical_time_step(m))
    }

    /// About how many grains the sample holds: listed ones, or a packed rectangle's share
    /// (area × solid fraction over the mean of the extreme disks' areas); `None` for a CSV
    /// file.
    pub fn estimated_grains(&self) -> Option<f64> {
        estimated_grains(&self.scene.grains.sample)
    }

    /// The time step for `grains` (s): the fixed one, or λ Δt_cr of the lightest grain.
    pub fn time_step(&self, grains: &Grains) -> f64 {
        match self.scene.grains.time_step {
            TimeStepSpec::Fixed { time_step_s, .. } => time_step_s,
            TimeStepSpec::Critical { lambda } => {
                stable_time_step(grains, &self.contact_model(), lambda)
            }
        }
    }

    /// Walls (at t = 0), contacts, gravity, time step and λ of the scene for `grains`.
    pub fn dem_setup(&self, grains: &Grains) -> DemSetup {
        DemSetup {
            walls: self.walls(),
            model: self.contact_model(),
            gravity: self.scene.grains.gravity_m_s2,
            dt: self.time_step(grains),
            lambda: self.lambda(),
            fixed: self.fixed_ids(),
        }
    }

    /// Ids of the grains held in place: listed grains with `fixed = true` (ids are the
    /// sample's order).
    pub fn fixed_ids(&self) -> Vec<u64> {
        match &self.scene.grains.sample {
            SampleSpec::List { grains } => (0..grains.len() as u64)
                .filter(|&i| grains[i as usize].fixed)
                .collect(),
            _ => Vec::new(),
        }
    }

    /// The walls at t = 0, in scene order.
    pub fn walls(&self) -> Vec<Wall> {
        self.scene
            .grains
            .walls
            .iter()
            .map(|w| Wall {
                velocity: w.velocity_m_s,
                ..Wall::fixed(w.from_m, w.to_m, w.friction)
            })
            .collect()
    }
}
