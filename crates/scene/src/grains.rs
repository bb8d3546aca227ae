//! Scenes of dry grains (DEM only): a `[grains]` table and no `[fluid]`. Parsed with the
//! same strictness as fluid scenes: unknown keys are errors, variants are tagged, SI units
//! are in the names.

use super::check::Check;
use serde::{Deserialize, Serialize};

/// A grains-only scene.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GrainScene {
    /// Free text shown in reports.
    #[serde(default)]
    pub title: String,
    /// The region the grains live in, from the origin: it is split into slabs over the
    /// ranks and framed in pictures. Grains may leave it (walls keep them in).
    pub domain: super::output::GrainDomain,
    /// Grains, contacts and walls.
    pub grains: GrainsSpec,
    /// Run length.
    pub run: GrainRun,
    /// Snapshots, pictures and checkpoints.
    #[serde(default)]
    pub output: super::output::Output,
    /// Derived quantities computed at the end.
    #[serde(default)]
    pub analyses: Vec<GrainAnalysis>,
    /// Pass/fail checks on derived quantities.
    #[serde(default)]
    pub checks: Vec<Check>,
}

/// The grains and everything that acts on them.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GrainsSpec {
    /// Solid density (kg/m³); disks have unit depth.
    pub density_kg_m3: f64,
    /// Gravity (m/s²).
    #[serde(default = "default_gravity")]
    pub gravity_m_s2: [f64; 2],
    /// Global viscous damping α (1/s), seed eq. 5.57; 0 (off) by default.
    #[serde(default)]
    pub global_damping_1_s: f64,
    /// Accept grains that overlap in the input (they push apart at the first step).
    #[serde(default)]
    pub allow_overlap: bool,
    /// Contact law between grains.
    pub contact: ContactSpec,
    /// Time step: a fraction λ of the critical step (eq. 5.59–5.60), or a fixed step.
    #[serde(default)]
    pub time_step: TimeStepSpec,
    /// Where the grains come from.
    pub sample: SampleSpec,
    /// Straight walls.
    #[serde(default)]
    pub walls: Vec<WallSpec>,
}

fn default_gravity() -> [f64; 2] {
    [0.0, -9.81]
}

/// Linear spring–dashpot contacts with Coulomb friction.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Normal stiffness k_n (N/m per metre of depth, i.e. N/m²).
    pub normal_stiffness_n_m2: f64,
    /// Tangential stiffness k_t (N/m²).
    pub tangential_stiffness_n_m2: f64,
    /// Coefficient of restitution e in (0, 1]; sets the normal dashpot.
    pub restitution: f64,
    /// Friction coefficient μ between grains.
    pub friction: f64,
    /// Rolling-resistance coefficient μ_r (dimensionless); 0 = off.
    #[serde(default)]
    pub rolling_friction: f64,
    /// Tangential dashpot as a fraction β of the normal one, c_t = β c_n, in [0, 1];
    /// 0 (none) by default.
    #[serde(default)]
    pub tangential_damping: f64,
}

/// How the DEM time step is chosen.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum TimeStepSpec {
    /// Δt = λ Δt_cr of the lightest grain.
    Critical {
        /// λ in (0, 1]; 0.1 by default.
        #[serde(default = "default_lambda")]
        lambda: f64,
    },
    /// A fixed step; an error when above λ Δt_cr.
    Fixed {
        /// Δt (s).
        time_step_s: f64,
        /// The stability fraction it is checked against (default 0.1).
        #[serde(default = "default_lambda")]
        lambda: f64,
    },
}

fn default_lambda() -> f64 {
    0.1
}

impl Default for TimeStepSpec {
    fn default() -> Self {
        TimeStepSpec::Critical { lambda: 0.1 }
    }
}

/// Grain radius distribution, tagged by `distribution`.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(tag = "distribution", rename_all = "kebab-case", deny_unknown_fields)]
pub enum SizeSpec {
    /// One radius.
    Mono {
        /// Radius (m).
        radius_m: f64,
    },
    /// Two radii by number fraction.
    Bidisperse {
        /// Small radius (m).
        small_radius_m: f64,
        /// Large radius (m).
        large_radius_m: f64,
        /// Number fraction of small grains in [0, 1].
        fraction_small: f64,
    },
    /// Uniform in [min, max].
    Uniform {
        /// Smallest radius (m).
        min_radius_m: f64,
        /// Largest radius (m).
        max_radius_m: f64,
    },
    /// Normal, truncated to [min, max].
    Normal {
        /// Mean (m).
        mean_radius_m: f64,
        /// Standard deviation (m).
        std_radius_m: f64,
        /// Smallest radius (m).
        min_radius_m: f64,
        /// Largest radius (m).
        max_radius_m: f64,
    },
}

/// The initial grains, tagged by `kind`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum SampleSpec {
    /// Random sequential addition in a rectangle, then (optionally) settling under gravity
    /// inside the scene's walls until the mean kinetic energy per grain is below a
    /// threshold.
    Pack {
        /// Lower-left corner (m).
        min_m: [f64; 2],
        /// Upper-right corner (m).
        max_m: [f64; 2],
        /// Radii.
        sizes: SizeSpec,
        /// Target area fraction of the rectangle (RSA jams near 0.55).
        solid_fraction: f64,
        /// Random seed.
        #[serde(default)]
        seed: u64,
        /// Settling before the run (absent: no settling).
        #[serde(default)]
        settle: Option<SettleSpec>,
    },
    /// Grains listed in the scene (for a few grains: settling, draft–kiss–tumble).
    List {
        /// The grains.
        grains: Vec<ListedGrain>,
    },
    /// Rows of `x, y, r` (m) from a CSV file, relative to the scene.
    Csv {
        /// Path.
        file: String,
    },
}

/// Settling of a packed sample.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SettleSpec {
    /// Global damping during settling (1/s).
    pub damping_1_s: f64,
    /// Stop when the mean kinetic energy per grain is below this (J/m).
    pub kinetic_energy_per_grain_j_m: f64,
    /// Give up after this many steps (an error names the energy reached).
    pub max_steps: u64,
    /// Keep only grains whose centre ends below this height (m): trims the loose top of a
    /// settled column to a flat surface.
    #[serde(default)]
    pub trim_above_m: Option<f64>,
    /// Friction of every contact (grain–grain and grain–wall) while settling, with no
    /// rolling resistance: 0 settles the densest packing, the sample's own friction (the
    /// default) a looser one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
}

/// A straight wall segment.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// Name (unique), used in messages.
    pub name: String,
    /// One end (m).
    pub from_m: [f64; 2],
    /// Other end (m).
    pub to_m: [f64; 2],
    /// Grain–wall friction coefficient.
    pub friction: f64,
    /// Translation velocity (m/s).
    #[serde(default)]
    pub velocity_m_s: [f64; 2],
    /// Remove the wall at this time (s), e.g. the gate of a column collapse.
    #[serde(default)]
    pub remove_at_s: Option<f64>,
}

/// Run length of a grains scene.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GrainRun {
    /// Number of steps after the sample is ready (exclusive with `end_time_s`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps: Option<u64>,
    /// Simulated time to reach after the sample is ready (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end_time_s: Option<f64>,
    /// Stop early once the mean kinetic energy per grain stays below this (J/m) after the
    /// last wall removal; 0 = never.
    #[serde(default)]
    pub stop_below_kinetic_energy_j_m: f64,
}

/// A derived quantity of a grains run.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum GrainAnalysis {
    /// Granular column collapse against a wall at x = `wall_x_m` (Lajeunesse et al. 2005):
    /// `collapse.runout` = (L_f − L_i)/L_i, `collapse.final_height` = H_f/L_i,
    /// `collapse.aspect_ratio` = H_i/L_i, `collapse.front_m`, `collapse.height_m`,
    /// `collapse.stop_time` (t/τ_c with τ_c = √(H_i/g), when motion stopped),
    /// `collapse.front_t10` and `collapse.front_t95` (t/τ_c when the front first passed
    /// 10 % and 95 % of its run-out, sampled every 200 steps), `collapse.front_speed_m_s`
    /// (its mean speed between the two),
    /// `collapse.dem_law_ratio` and `collapse.experiment_ratio` (run-out over the published
    /// 2-D DEM law and over the experiments' law at the measured a).
    ColumnCollapse {
        /// The fixed wall behind the column (m).
        wall_x_m: f64,
        /// The floor (m).
        floor_y_m: f64,
        /// MPM scenes only: also measure the front where the deposit is still this thick
        /// (m, > 0; a few grain diameters): the farthest cell column, contiguous from the
        /// wall, whose highest point centre stands at least this high above the floor.
        /// Gives `collapse.thick_front_m`, `collapse.thick_runout` and
        /// `collapse.thick_experiment_ratio`. Unlike the front, it does not follow a tail
        /// one or two points thick, so it converges with the cells.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        front_min_height_m: Option<f64>,
    },
}

/// One grain of a `kind = "list"` sample.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ListedGrain {
    /// Centre (m).
    pub position_m: [f64; 2],
    /// Radius (m).
    pub radius_m: f64,
    /// Initial velocity (m/s).
    #[serde(default)]
    pub velocity_m_s: [f64; 2],
    /// Initial angular velocity (rad/s, counter-clockwise).
    #[serde(default)]
    pub angular_velocity_rad_s: f64,
    /// Held in place for the whole run: it neither moves nor turns, and the forces on it
    /// (contacts, the fluid) are still computed and reported. For fixed obstacles made of
    /// grains (a rough bed, an array of cylinders). Contacts with it are damped with the
    /// pair's reduced mass, as between two free grains.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub fixed: bool,
}
