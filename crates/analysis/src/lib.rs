//! Derived quantities computed at the end of a run, and pass/fail checks on them.
//!
//! Each [`scene::Analysis`] produces named results (`poiseuille.max_rel_error`,
//! `<probe>.strouhal`, …). [`checks::evaluate`] compares them with the scene's checks.

pub mod checks;
pub mod collapse;
pub mod flows;
pub mod permeability;
pub mod sedimentation;
mod share;
mod signals;
pub mod units;
pub use share::share_from_root;

use io::probes::Series;
use lbm::fields::{Fields, Totals};
use scene::{Analysis, ValidScene};
use std::collections::BTreeMap;
use thiserror::Error;

/// Named results, sorted by name.
pub type Results = BTreeMap<String, f64>;

/// (x, y, r) of every grain (m), by id.
pub type GrainDisks = Vec<[f64; 3]>;

/// Momentum of the fluid and of the grains (kg·m/s per metre of depth).
pub type MomentumPair = [[f64; 2]; 2];

/// An analysis that could not be computed.
#[derive(Debug, Clone, Error)]
#[error("analysis `{analysis}`: {message}")]
pub struct AnalysisError {
    /// Which analysis.
    pub analysis: String,
    /// What went wrong.
    pub message: String,
}

/// What the analyses read: the final state and the recorded series.
pub struct Inputs<'a> {
    /// The scene.
    pub scene: &'a ValidScene,
    /// Final fields of the whole lattice, lattice units: `Some` where the scene's analyses
    /// read them ([`needs_fields`]; the run gathers them on rank 0 only), else `None`.
    pub fields: Option<&'a Fields>,
    /// Steps taken.
    pub steps: u64,
    /// Probe series.
    pub series: &'a [Series],
    /// Totals at step 0 and at the end.
    pub totals: (Totals, Totals),
    /// Momentum (fluid, grains) at the start and the end of a coupled run (kg·m/s per m).
    pub momentum: Option<(MomentumPair, MomentumPair)>,
    /// (id, radius m) of every grain of a coupled run.
    pub grain_radius: Vec<(u64, f64)>,
    /// (x, y, r) of every grain of a coupled run when it started and at the end (m), by id.
    pub grains: Option<(GrainDisks, GrainDisks)>,
}

/// The relative change of the fluid's mass (Σ ρ over the fluid cells) from `initial` to
/// `last` over `steps` steps, per 10⁴ steps: zero to round-off in a closed domain of plain
/// walls; grains that cover and uncover cells, and open faces, change it. 0 before a step.
pub fn mass_drift_per_1e4_steps(initial: f64, last: f64, steps: u64) -> f64 {
    if steps == 0 || initial == 0.0 {
        return 0.0;
    }
    (last - initial) / initial * 1e4 / steps as f64
}

/// The result names a scene's analyses will produce (to validate checks before running).
pub fn result_names(scene: &ValidScene) -> Vec<String> {
    let mut names = vec![
        "run.mass".to_string(),
        "run.mass_drift_per_1e4_steps".to_string(),
        "run.max_speed_m_s".to_string(),
    ];
    for a in &scene.scene.analyses {
        match a {
            Analysis::Poiseuille => names.extend(
                [
                    "max_rel_error",
                    "l2_rel_error",
                    "peak_rel_error",
                    "centreline_velocity_m_s",
                ]
                .map(|q| format!("poiseuille.{q}")),
            ),
            Analysis::Couette => names.push("couette.l2_rel_error".into()),
            Analysis::TaylorGreen => names.push("taylor_green.l2_rel_error".into()),
            Analysis::Ghia { .. } => {
                names.extend(["ghia.max_u_deviation".into(), "ghia.max_v_deviation".into()])
            }
            Analysis::ForceCoefficients { probe, .. } => {
                names.extend(signals::FORCE_QUANTITIES.map(|q| format!("{probe}.{q}")))
            }
            Analysis::Strouhal { probe, .. } => names.extend([
                format!("{probe}.strouhal"),
                format!("{probe}.relative_oscillation"),
            ]),
            Analysis::PressureDifference { upstream, .. } => {
                names.push(format!("{upstream}.pressure_difference_pa"))
            }
            Analysis::MassDrift => names.push("mass.relative_drift".into()),
            Analysis::Settling { probe, .. } => names.extend(
                [
                    "settling_velocity_m_s",
                    "reynolds",
                    "drag_coefficient",
                    "velocity_drift",
                ]
                .map(|q| format!("{probe}.{q}")),
            ),
            Analysis::DraftKissTumble { .. } => names.extend(
                [
                    "kiss_time",
                    "min_gap",
                    "tumble_time",
                    "separation_time",
                    "draft",
                    "tumbled",
                    "separated",
                    "lower_velocity_m_s",
                    "upper_velocity_m_s",
                    "second_kiss_time",
                    "leader_fall_m_s",
                    "trailer_fall_m_s",
                    "leader_fall_deviation",
                    "trailer_fall_deviation",
                ]
                .map(|q| format!("dkt.{q}")),
            ),
            Analysis::ColumnCollapse { .. } => {
                names.extend(collapse::QUANTITIES.map(|q| format!("collapse.{q}")));
                names.extend(
                    [
                        "front_t95",
                        "front_t10",
                        "front_speed_m_s",
                        "packing_fraction",
                        "pore_pressure_min_pa",
                        "pore_pressure_max_pa",
                    ]
                    .map(|q| format!("collapse.{q}")),
                );
            }
            Analysis::MomentumBalance => names.extend(
                [
                    "relative_drift",
                    "fluid_x_kg_m_s",
                    "fluid_y_kg_m_s",
                    "grains_x_kg_m_s",
                    "grains_y_kg_m_s",
                ]
                .map(|q| format!("momentum.{q}")),
            ),
            Analysis::Permeability => {
                names.extend(permeability::QUANTITIES.map(|q| format!("permeability.{q}")))
            }
        }
    }
    names
}

/// Whether any of the scene's analyses reads the final fields (the reference flows); the
/// others read probes, totals and grains, so a run gathers no lattice for them.
pub fn needs_fields(scene: &ValidScene) -> bool {
    scene.scene.analyses.iter().any(|a| {
        matches!(
            a,
            Analysis::Poiseuille
                | Analysis::Couette
                | Analysis::TaylorGreen
                | Analysis::Ghia { .. }
                | Analysis::Permeability
        )
    })
}

/// What the analyses of a run gave: their results, and the analyses that could not run
/// (a series too short for the averaging window, say), each with the reason.
#[derive(Debug, Clone, Default)]
pub struct Outcome {
    /// Named results.
    pub results: Results,
    /// The analyses that were skipped, with why.
    pub skipped: Vec<AnalysisError>,
}

/// Run every analysis of the scene. An analysis that cannot run is skipped with its
/// reason ([`Outcome::skipped`]) and the others still run.
pub fn run_all(inp: &Inputs) -> Outcome {
    let mut r = Results::new();
    let u = &inp.scene.units;
    r.insert("run.mass".into(), inp.totals.1.mass);
    r.insert(
        "run.mass_drift_per_1e4_steps".into(),
        mass_drift_per_1e4_steps(inp.totals.0.mass, inp.totals.1.mass, inp.steps),
    );
    r.insert(
        "run.max_speed_m_s".into(),
        u.velocity_to_si(inp.totals.1.max_speed),
    );
    let mut skipped = Vec::new();
    for a in &inp.scene.scene.analyses {
        if let Err(mut e) = run_one(inp, a, &mut r) {
            // Name the probe where two analyses of one kind may differ only in it.
            if let Analysis::ForceCoefficients { probe, .. }
            | Analysis::Strouhal { probe, .. }
            | Analysis::Settling { probe, .. } = a
            {
                e.analysis = format!("{} of probe `{probe}`", e.analysis);
            }
            skipped.push(e);
        }
    }
    Outcome {
        results: r,
        skipped,
    }
}

/// Analysis `a`, its results into `r`.
fn run_one(inp: &Inputs, a: &Analysis, r: &mut Results) -> Result<(), AnalysisError> {
    match a {
        Analysis::Poiseuille => flows::poiseuille(inp, r)?,
        Analysis::Couette => flows::couette(inp, r)?,
        Analysis::TaylorGreen => flows::taylor_green(inp, r)?,
        Analysis::Ghia {
            u_reference,
            v_reference,
            column,
        } => flows::ghia(inp, u_reference, v_reference, column, r)?,
        Analysis::ForceCoefficients {
            probe,
            velocity_m_s,
            length_m,
            average_last_s,
        } => signals::force_coefficients(inp, probe, *velocity_m_s, *length_m, *average_last_s, r)?,
        Analysis::Strouhal {
            probe,
            signal,
            velocity_m_s,
            length_m,
            skip_s,
        } => signals::strouhal(inp, probe, *signal, *velocity_m_s, *length_m, *skip_s, r)?,
        Analysis::PressureDifference {
            upstream,
            downstream,
            average_last_s,
        } => signals::pressure_difference(inp, upstream, downstream, *average_last_s, r)?,
        Analysis::MassDrift => {
            let (a, b) = (inp.totals.0.mass, inp.totals.1.mass);
            r.insert("mass.relative_drift".into(), (b - a) / a);
        }
        Analysis::Settling {
            probe,
            average_last_s,
        } => sedimentation::settling(inp, probe, *average_last_s, r)?,
        Analysis::DraftKissTumble {
            lower,
            upper,
            contact_gap_m,
            average_last_s,
            fall_window_s,
            terminal_velocity_m_s,
        } => sedimentation::draft_kiss_tumble(
            inp,
            &sedimentation::DktSetup {
                lower,
                upper,
                contact_gap_m: *contact_gap_m,
                window_s: *average_last_s,
                fall_window_s: *fall_window_s,
                terminal_velocity_m_s: *terminal_velocity_m_s,
            },
            r,
        )?,
        Analysis::ColumnCollapse {
            wall_x_m,
            floor_y_m,
            deposit,
            pore_pressure,
        } => collapse::submerged(
            inp,
            (*wall_x_m, *floor_y_m),
            deposit,
            pore_pressure.as_deref(),
            r,
        )?,
        Analysis::Permeability => permeability::permeability(inp, r)?,
        Analysis::MomentumBalance => {
            let Some((p0, p1)) = inp.momentum else {
                return Err(err("momentum-balance", "the run has no grains"));
            };
            let total = |p: &[[f64; 2]; 2]| [p[0][0] + p[1][0], p[0][1] + p[1][1]];
            let (a, b) = (total(&p0), total(&p1));
            let norm = a[0].hypot(a[1]);
            if norm == 0.0 {
                return Err(err(
                    "momentum-balance",
                    "the initial momentum is zero: give a grain or the fluid a velocity",
                ));
            }
            r.insert(
                "momentum.relative_drift".into(),
                (b[0] - a[0]).hypot(b[1] - a[1]) / norm,
            );
            r.insert("momentum.fluid_x_kg_m_s".into(), p1[0][0]);
            r.insert("momentum.fluid_y_kg_m_s".into(), p1[0][1]);
            r.insert("momentum.grains_x_kg_m_s".into(), p1[1][0]);
            r.insert("momentum.grains_y_kg_m_s".into(), p1[1][1]);
        }
    }
    Ok(())
}

/// The error an analysis that panicked becomes (the panic's message went to stderr), so that
/// every rank of a distributed run stops with it.
pub fn panicked() -> AnalysisError {
    err(
        "(all)",
        "an analysis panicked (a bug: please report it with the scene); its message is above",
    )
}

pub(crate) fn err(analysis: &str, message: impl Into<String>) -> AnalysisError {
    AnalysisError {
        analysis: analysis.into(),
        message: message.into(),
    }
}
