//! The scene file schema (TOML). Every table rejects unknown keys; variants are tagged by
//! `kind`, `shape` or `model`; SI units are in the field names.

pub use super::check::Check;
use lbm::gpu::GpuStorage;
use serde::{Deserialize, Serialize};

/// A whole scene. Only the physics it names is allocated and run.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Free text shown in reports.
    #[serde(default)]
    pub title: String,
    /// The lattice.
    pub domain: Domain,
    /// The fluid and its lattice Boltzmann model.
    pub fluid: Fluid,
    /// Conditions on the four faces.
    pub boundaries: Boundaries,
    /// Solid obstacles (half-way bounce-back).
    #[serde(default)]
    pub obstacles: Vec<Obstacle>,
    /// Run length, precision and backend.
    pub run: Run,
    /// Snapshots, pictures, probes' cadence and checkpoints.
    #[serde(default)]
    pub output: super::output::Output,
    /// Time series recorded during the run.
    #[serde(default)]
    pub probes: Vec<Probe>,
    /// Derived quantities computed at the end of the run.
    #[serde(default)]
    pub analyses: Vec<Analysis>,
    /// Pass/fail checks on probes and derived quantities.
    #[serde(default)]
    pub checks: Vec<Check>,
    /// Grains in the fluid (DEM disks); with `[coupling]` the scene runs LBM–DEM coupled.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grains: Option<super::grains::GrainsSpec>,
    /// How the fluid and the grains exchange momentum.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coupling: Option<super::coupling::CouplingSpec>,
}

/// Lattice size and spacing. The domain spans [0, cells_x·dx] × [0, cells_y·dx]. Either
/// `cells` with `spacing_m`, or `size_m` when `[fluid]` fixes the relaxation time and the
/// lattice velocity together (validation then fills `cells` and `spacing_m`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Domain {
    /// Cells along x and y ([0, 0] in the file when `size_m` is given).
    #[serde(default)]
    pub cells: [usize; 2],
    /// Lattice spacing Δx in metres (0 in the file when `size_m` is given).
    #[serde(default)]
    pub spacing_m: f64,
    /// Width and height of the domain (m), instead of `cells` and `spacing_m`: the spacing
    /// follows from `[fluid] relaxation_time` and `lattice_velocity`
    /// (Δx = ν u_lb / (U (τ − ½)/3)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size_m: Option<[f64; 2]>,
}

/// Fluid properties and model choices.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Fluid {
    /// Reference density ρ₀ (kg/m³); pressures are relative to ρ₀ c_s².
    pub density_kg_m3: f64,
    /// Kinematic viscosity ν (m²/s).
    pub viscosity_m2_s: f64,
    /// Largest velocity expected in the flow (m/s): sets the Mach number.
    pub reference_velocity_m_s: f64,
    /// Length used for the Reynolds number (m).
    pub reference_length_m: f64,
    /// How the time step is chosen: exactly one of these three.
    #[serde(default)]
    pub time_step_s: Option<f64>,
    /// Lattice velocity of `reference_velocity_m_s` (u_lb = U Δt/Δx); sets Δt.
    #[serde(default)]
    pub lattice_velocity: Option<f64>,
    /// Relaxation time τ = 3ν Δt/Δx² + ½; sets Δt.
    #[serde(default)]
    pub relaxation_time: Option<f64>,
    /// Uniform body acceleration (m/s²), Guo forcing.
    #[serde(default)]
    pub body_acceleration_m_s2: [f64; 2],
    /// Collision operator.
    #[serde(default = "default_collision")]
    pub collision: CollisionModel,
    /// Smagorinsky constant C_s (typically 0.1–0.17); absent = no closure.
    #[serde(default)]
    pub smagorinsky_constant: Option<f64>,
    /// Permit Mach ≥ 0.3 (compressibility errors grow as Ma²).
    #[serde(default)]
    pub allow_high_mach: bool,
    /// Initial condition.
    #[serde(default = "default_initial")]
    pub initial: Initial,
}

fn default_collision() -> CollisionModel {
    CollisionModel::Bgk
}
fn default_initial() -> Initial {
    Initial::Rest
}

/// Collision operator choice.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "model", rename_all = "kebab-case", deny_unknown_fields)]
pub enum CollisionModel {
    /// BGK.
    Bgk,
    /// TRT with Λ (default 3/16).
    Trt {
        /// Magic parameter Λ.
        #[serde(default = "magic_default")]
        magic: f64,
    },
    /// MRT (Lallemand & Luo 2000).
    Mrt {
        /// s_e (default 1.4).
        #[serde(default = "mrt_default")]
        s_e: f64,
        /// s_ε (default 1.4).
        #[serde(default = "mrt_default")]
        s_eps: f64,
        /// s_q; absent = derived for Λ = 3/16.
        #[serde(default)]
        s_q: Option<f64>,
    },
}

fn magic_default() -> f64 {
    3.0 / 16.0
}
fn mrt_default() -> f64 {
    1.4
}

/// Initial condition of the fluid.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Initial {
    /// ρ = ρ₀, u = 0.
    Rest,
    /// Uniform velocity (m/s).
    Uniform {
        /// Velocity.
        velocity_m_s: [f64; 2],
    },
    /// Taylor–Green vortex u = U(−cos kx sin ky, sin kx cos ky) with one period across the
    /// domain in each direction (Taylor & Green 1937); pressure set consistently.
    TaylorGreen {
        /// Amplitude U (m/s).
        amplitude_m_s: f64,
    },
}

/// Conditions on west (x = 0), east, south (y = 0) and north.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Boundaries {
    /// x = 0.
    pub west: BoundarySpec,
    /// x = L_x.
    pub east: BoundarySpec,
    /// y = 0.
    pub south: BoundarySpec,
    /// y = L_y.
    pub north: BoundarySpec,
}

/// One face's condition.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum BoundarySpec {
    /// Wraps to the opposite face.
    Periodic,
    /// No-slip wall (half-way bounce-back).
    Wall,
    /// Wall moving tangentially (Ladd bounce-back).
    MovingWall {
        /// Wall velocity (m/s).
        velocity_m_s: [f64; 2],
    },
    /// Free-slip (specular) wall.
    FreeSlip,
    /// Zero-gradient outflow.
    Outflow,
    /// Zou–He velocity inlet/outlet.
    Velocity {
        /// Velocity (m/s); for `parabolic`, the peak velocity.
        velocity_m_s: [f64; 2],
        /// Profile along the face.
        #[serde(default)]
        profile: Profile,
        /// Ramp the velocity up as sin²(πt / 2T) over this time (s); 0 = impulsive start.
        /// A ramp avoids the pressure waves an impulsive start sends between open faces.
        #[serde(default)]
        ramp_time_s: f64,
    },
    /// Zou–He pressure inlet/outlet.
    Pressure {
        /// Pressure relative to ρ₀ c_s² (Pa).
        pressure_pa: f64,
    },
}

/// Velocity profile along an inlet.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize, PartialEq)]
#[serde(rename_all = "kebab-case")]
pub enum Profile {
    /// Same velocity everywhere.
    #[default]
    Uniform,
    /// u(s) = 4 U s (L − s)/L², zero at the face's ends.
    Parabolic,
}

/// A named solid obstacle (geometry in metres), tagged by `shape`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "shape", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Obstacle {
    /// Axis-aligned rectangle.
    Rectangle {
        /// Name (unique); force probes refer to it.
        name: String,
        /// Lower-left corner (m).
        min_m: [f64; 2],
        /// Upper-right corner (m).
        max_m: [f64; 2],
    },
    /// Disk.
    Circle {
        /// Name (unique).
        name: String,
        /// Centre (m).
        centre_m: [f64; 2],
        /// Radius (m).
        radius_m: f64,
        /// How the fluid meets the wall: `"interpolated"` (the exact circle, Bouzidi et al.
        /// 2001; the default in a scene without grains) or `"staircase"` (half-way bounce-back
        /// on the cells whose centres lie inside; the default, and the only choice, in a
        /// scene with grains).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        wall: Option<CircleWall>,
    },
    /// Polygon, vertices in order (m).
    Polygon {
        /// Name (unique).
        name: String,
        /// Vertices.
        vertices_m: Vec<[f64; 2]>,
    },
    /// A PNG mask the size of the lattice (dark pixels are solid; top row is north).
    Mask {
        /// Name (unique).
        name: String,
        /// Path relative to the scene file.
        image: String,
    },
}

/// The wall model of a circular obstacle.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum CircleWall {
    /// Linear interpolated bounce-back at the exact link fraction (Bouzidi, Firdaouss &
    /// Lallemand 2001).
    Interpolated,
    /// Half-way bounce-back on the cells whose centres lie inside (Ladd 1994).
    Staircase,
}

impl Obstacle {
    /// The wall model this obstacle gets in a scene with (`grains = true`) or without
    /// grains: `None` for shapes other than circles, which are always staircased.
    pub fn circle_wall(&self, grains: bool) -> Option<CircleWall> {
        match self {
            Obstacle::Circle { wall, .. } => Some(wall.unwrap_or(if grains {
                CircleWall::Staircase
            } else {
                CircleWall::Interpolated
            })),
            _ => None,
        }
    }

    /// The obstacle's name.
    pub fn name(&self) -> &str {
        match self {
            Obstacle::Rectangle { name, .. }
            | Obstacle::Circle { name, .. }
            | Obstacle::Polygon { name, .. }
            | Obstacle::Mask { name, .. } => name,
        }
    }
}

/// Run length, precision and backend.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Run {
    /// Number of steps (exclusive with `end_time_s`).
    #[serde(default)]
    pub steps: Option<u64>,
    /// Simulated time to reach (s).
    #[serde(default)]
    pub end_time_s: Option<f64>,
    /// "f32" or "f64" (default f64); the CLI may override.
    #[serde(default)]
    pub precision: Precision,
    /// Device of the fluid solver: "cpu" (rayon, the default) or "gpu" (wgpu); the CLI's
    /// `--backend` overrides.
    #[serde(default)]
    pub backend: Backend,
    /// How the GPU stores populations: "native" (the run's precision, the default) or
    /// "f16" (IEEE half, arithmetic in f32; needs `backend = "gpu"` and `precision = "f32"`).
    #[serde(default)]
    pub gpu_storage: GpuStorage,
    /// The CPU kernel: "two-array", "in-place" (the AA pattern: half the memory), or
    /// "auto" (the default: in place where it measured faster, see the README); the CLI's
    /// `--kernel` overrides.
    #[serde(default)]
    pub kernel: Kernel,
}

/// Floating-point precision of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// Single (half the memory traffic).
    F32,
    /// Double.
    #[default]
    F64,
}

/// The device that runs the fluid solver.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// rayon threads on the CPU.
    #[default]
    Cpu,
    /// wgpu compute kernels (Vulkan; Mesa lavapipe where there is no GPU).
    Gpu,
}

/// The CPU kernel's storage scheme.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kernel {
    /// In place for every CPU run, with grains or without (it measured faster everywhere);
    /// two arrays on the GPU backend.
    #[default]
    Auto,
    /// Two buffers, fused pull stream–collide.
    TwoArray,
    /// One buffer (the AA pattern): half the memory. Not on the GPU backend.
    InPlace,
}

/// A field written to snapshots.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FieldName {
    /// Density (kg/m³).
    Density,
    /// Velocity (m/s), three components (u_x, u_y, 0), as ParaView reads vectors.
    Velocity,
    /// Vorticity (1/s).
    Vorticity,
    /// Pressure relative to the reference density's (Pa): p = c_s² (ρ − ρ₀).
    Pressure,
}

impl FieldName {
    /// Dataset name in the HDF5 file.
    pub fn as_str(self) -> &'static str {
        match self {
            FieldName::Density => "density",
            FieldName::Velocity => "velocity",
            FieldName::Vorticity => "vorticity",
            FieldName::Pressure => "pressure",
        }
    }
}

/// Which probe signal a Strouhal analysis transforms.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Signal {
    /// Pressure (as the seed study).
    #[default]
    Pressure,
    /// Transverse velocity: on the wake axis it oscillates only when vortices shed.
    Uy,
}

/// A time series recorded during the run.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Probe {
    /// Velocity and pressure at a point: bilinear interpolation between the centres of the
    /// four cells around it, over those that are fluid (weights renormalised), so a point
    /// on an obstacle's surface reads the fluid beside it.
    Point {
        /// Name (unique).
        name: String,
        /// Position (m).
        position_m: [f64; 2],
    },
    /// Hydrodynamic force on an obstacle (momentum exchange), N per metre of depth.
    Force {
        /// Name (unique).
        name: String,
        /// Obstacle name.
        obstacle: String,
    },
    /// State of one grain of a coupled scene: position (m), velocity (m/s), angular
    /// velocity (rad/s) and the hydrodynamic force on it (N/m).
    Grain {
        /// Name (unique).
        name: String,
        /// Grain id (the sample's order, from 0).
        id: u64,
    },
    /// The deposit of the grains of a coupled scene against a wall (as the column-collapse
    /// analysis measures it): its front, the farthest edge from the wall (m), and its
    /// height above the floor (m).
    Deposit {
        /// Name (unique).
        name: String,
        /// The wall behind the grains (m).
        wall_x_m: f64,
        /// The floor (m).
        floor_y_m: f64,
    },
    /// Kinetic energy per metre of depth (J/m): of the grains (translation and rotation,
    /// zero without grains) and of the fluid outside them (Σ (1 − ε) ½ρ|u|² Δx² over the
    /// fluid cells, ε a cell's solid fraction).
    KineticEnergy {
        /// Name (unique).
        name: String,
    },
}

impl Probe {
    /// The probe's name.
    pub fn name(&self) -> &str {
        match self {
            Probe::Point { name, .. }
            | Probe::Force { name, .. }
            | Probe::Grain { name, .. }
            | Probe::Deposit { name, .. }
            | Probe::KineticEnergy { name } => name,
        }
    }
}

/// A derived quantity computed at the end of the run; its results are named
/// `<kind-prefix>.<quantity>` (see each variant) and can be checked.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Analysis {
    /// Body-force channel between walls on south and north:
    /// `poiseuille.max_rel_error`, `poiseuille.l2_rel_error`, `poiseuille.centreline_velocity_m_s`.
    Poiseuille,
    /// Shear flow between a fixed south wall and a moving north wall: `couette.l2_rel_error`.
    Couette,
    /// Decay of the Taylor–Green vortex: `taylor_green.l2_rel_error`.
    TaylorGreen,
    /// Lid-driven cavity centrelines against tabulated data (Ghia et al. 1982):
    /// `ghia.max_u_deviation`, `ghia.max_v_deviation` (fractions of the lid speed).
    Ghia {
        /// CSV of (y, u…) along the vertical centreline, relative to the scene file.
        u_reference: String,
        /// CSV of (x, v…) along the horizontal centreline.
        v_reference: String,
        /// Column of the CSVs to compare with.
        column: String,
    },
    /// Drag and lift coefficients c = 2F/(ρ U² D) from a force or grain probe over the last
    /// `average_last_s` (as the Schäfer & Turek benchmarks define them): the means
    /// `<probe>.drag_coefficient` and `<probe>.lift_coefficient`, their extremes
    /// (`..._min`, `..._max`), `<probe>.lift_amplitude` (half the peak-to-peak of c_L) and
    /// `<probe>.lift_strouhal` (f D / U of the lift's dominant frequency; 0 when it does not
    /// oscillate).
    ForceCoefficients {
        /// Force probe (an obstacle's) or grain probe.
        probe: String,
        /// U in c = 2F/(ρ U² D) (m/s).
        velocity_m_s: f64,
        /// D (m).
        length_m: f64,
        /// Window at the end of the run (s); 0 (the default): the last sample only.
        #[serde(default)]
        average_last_s: f64,
    },
    /// Dominant frequency of a point probe's signal after `skip_s` (FFT):
    /// `<probe>.strouhal` = f D / U and `<probe>.relative_oscillation` (peak-to-peak of the
    /// signal over ½ρU² for pressure, over U for velocity: a shedding indicator).
    Strouhal {
        /// Point probe.
        probe: String,
        /// Signal: "pressure" (default, as the seed study) or "uy" (transverse velocity;
        /// on the wake axis it oscillates only when vortices shed, never from acoustics).
        #[serde(default)]
        signal: Signal,
        /// U (m/s).
        velocity_m_s: f64,
        /// D (m).
        length_m: f64,
        /// Transient to discard (s).
        skip_s: f64,
    },
    /// Mean pressure difference between two point probes over the last `average_last_s`:
    /// `<upstream>.pressure_difference_pa` = p(upstream) − p(downstream) (Schäfer & Turek's
    /// ΔP, with probes on the obstacle's surface: a point probe interpolates the fluid cells
    /// around it).
    PressureDifference {
        /// Point probe whose pressure is taken first.
        upstream: String,
        /// Point probe whose pressure is subtracted.
        downstream: String,
        /// Window at the end of the run (s); 0 (the default): the last sample only.
        #[serde(default)]
        average_last_s: f64,
    },
    /// Relative change of the total fluid mass over the run: `mass.relative_drift`.
    MassDrift,
    /// Terminal settling of a grain from its probe, averaged over the last
    /// `average_last_s`: `<probe>.settling_velocity_m_s` (speed), `<probe>.reynolds`
    /// (U d / ν) and `<probe>.drag_coefficient` (2 W / (ρ U² d), W the submerged weight per
    /// metre of depth), plus `<probe>.velocity_drift` (relative change of the speed over the
    /// window's second half: small once terminal).
    Settling {
        /// Grain probe.
        probe: String,
        /// Averaging window at the end of the run (s).
        average_last_s: f64,
    },
    /// Draft, kiss and tumble of two grains from their probes (`dkt.kiss_time`, … in units
    /// of √(D/g); see `analysis::sedimentation::draft_kiss_tumble`).
    DraftKissTumble {
        /// Grain probe of the grain that starts below.
        lower: String,
        /// Grain probe of the grain that starts above.
        upper: String,
        /// Gap between the surfaces (m) that counts as touching (about a lattice cell).
        contact_gap_m: f64,
        /// Window for the final speeds (s).
        average_last_s: f64,
        /// Time window [from, to] (s) over which to average each grain's fall speed (its
        /// velocity along gravity) after the pair has separated: `dkt.leader_fall_m_s` and
        /// `dkt.trailer_fall_m_s`, the leader being the grain further along gravity at `to`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        fall_window_s: Option<[f64; 2]>,
        /// Terminal velocity (m/s) of one grain alone in the same channel (measure it with a
        /// `settling` analysis); with `fall_window_s`, gives `dkt.leader_fall_deviation` and
        /// `dkt.trailer_fall_deviation` = fall speed / this − 1.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        terminal_velocity_m_s: Option<f64>,
    },
    /// Momentum of fluid plus grains: `momentum.relative_drift` = |p_end − p_0| / |p_0|
    /// (needs non-zero initial momentum), and `momentum.grains_x_kg_m_s` etc.
    MomentumBalance,
    /// Stokes flow through a periodic array of fixed grains driven by the fluid's body
    /// acceleration, against the drag on square arrays of cylinders of Sangani & Acrivos
    /// (1982), from the final fields: `permeability.superficial_velocity_m_s`,
    /// `permeability.permeability_m2` (Darcy's k = ν U / |G|), `permeability.solid_fraction`
    /// (with the hydrodynamic radius), `permeability.drag_factor` (K = F / (μ U) per grain),
    /// `permeability.sangani_acrivos_ratio` and `permeability.reynolds`.
    Permeability,
    /// Collapse of a column of grains in the fluid (Lajeunesse et al. 2005 geometry; Rondon
    /// et al. 2011 submerged): the `collapse.*` results of a grains run (run-out, heights,
    /// a, the laws' ratios), `collapse.packing_fraction` of the column (disk area over
    /// L_i H_i), `collapse.stop_time` = t₉₅/τ_c from a deposit probe (when the front reached
    /// 95 % of its final run-out; τ_c = √(H_i/g)), and `collapse.pore_pressure_min_pa` /
    /// `_max_pa` from a point probe (the fluid carries no hydrostatic pressure: grains feel
    /// reduced gravity, so a probe's pressure is the excess pore pressure).
    ColumnCollapse {
        /// The wall behind the column (m).
        wall_x_m: f64,
        /// The floor (m).
        floor_y_m: f64,
        /// Deposit probe that times the collapse.
        deposit: String,
        /// Point probe for the pore pressure (e.g. at the floor under the column).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        pore_pressure: Option<String>,
    },
}
