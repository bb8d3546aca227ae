//! Scenes of continuum bodies (MPM only): an `[mpm]` table and no `[fluid]` or `[grains]`.
//! Parsed strictly: unknown keys are errors, variants are tagged, SI units in the names.

use super::grains::GrainAnalysis;
use super::schema::Check;
use mpm::{Boundaries, Scheme, ShapeKind, Side, SideWalls};
use serde::{Deserialize, Serialize};

/// An MPM scene.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MpmScene {
    /// Free text shown in reports.
    #[serde(default)]
    pub title: String,
    /// The background grid: `cells` × `spacing_m` from the origin.
    pub domain: super::schema::Domain,
    /// Conditions on the four sides of the domain.
    pub boundaries: MpmBoundaries,
    /// Materials, bodies and the update scheme.
    pub mpm: MpmSpec,
    /// Run length.
    pub run: MpmRun,
    /// Snapshots, pictures and checkpoints.
    #[serde(default)]
    pub output: super::output::Output,
    /// Derived quantities computed at the end (`column-collapse`).
    #[serde(default)]
    pub analyses: Vec<GrainAnalysis>,
    /// Pass/fail checks on derived quantities.
    #[serde(default)]
    pub checks: Vec<Check>,
}

/// The continuum model.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MpmSpec {
    /// `linear`, `gimp` (uGIMP) or `cp-gimp`.
    pub shape_functions: ShapeKind,
    /// `usf`, `usl` or `musl`.
    pub update: Scheme,
    /// Gravity (m/s²).
    #[serde(default = "default_gravity")]
    pub gravity_m_s2: [f64; 2],
    /// Cundall local damping α in [0, 1); 0 (off) by default.
    #[serde(default)]
    pub local_damping: f64,
    /// How point velocities are updated from the grid: `flip` (default; blended with
    /// `pic_fraction` of PIC) or `apic` (affine PIC, Jiang et al. 2015: no knob, no
    /// dissipation of affine motion; needs `pic_fraction` = 0).
    #[serde(default)]
    pub velocity_transfer: VelocityTransfer,
    /// Fraction of PIC in the FLIP velocity update, in [0, 1]; 0 = pure FLIP.
    #[serde(default)]
    pub pic_fraction: f64,
    /// Replace each point's volumetric strain rate by the volume-weighted mean of its
    /// cell's points (cell-averaged volumetric strain against volumetric noise and
    /// locking; Coombs et al. 2018). Off by default.
    #[serde(default)]
    pub volumetric_averaging: bool,
    /// Time step: a Courant number of the CFL limit, or a fixed step checked against it.
    #[serde(default)]
    pub time_step: MpmTimeStep,
    /// Side walls of a quasi-two-dimensional channel, `{ gap_m, friction }`: Coulomb
    /// friction μ_w |σ_zz| on both faces of the simulated plane, W = `gap_m` apart. Absent
    /// (default): plane strain without walls.
    #[serde(default)]
    pub side_walls: Option<SideWalls>,
    /// Materials, referred to by name from the bodies.
    pub materials: Vec<MaterialSpec>,
    /// Bodies of material points.
    pub bodies: Vec<BodySpec>,
}

fn default_gravity() -> [f64; 2] {
    [0.0, -9.81]
}

/// How the MPM time step is chosen.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum MpmTimeStep {
    /// Δt = courant · h / c, c the largest dilatational wave speed.
    Courant {
        /// Courant number in (0, 1].
        courant: f64,
    },
    /// A fixed step; an error when above the CFL limit h / c.
    Fixed {
        /// Δt (s).
        time_step_s: f64,
    },
}

impl Default for MpmTimeStep {
    fn default() -> Self {
        MpmTimeStep::Courant { courant: 0.5 }
    }
}

/// A material, tagged by `model`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "model", rename_all = "kebab-case", deny_unknown_fields)]
pub enum MaterialSpec {
    /// Isotropic linear elasticity.
    LinearElastic {
        /// Name the bodies refer to.
        name: String,
        /// Density (kg/m³).
        density_kg_m3: f64,
        /// Young's modulus (Pa).
        youngs_modulus_pa: f64,
        /// Poisson's ratio in [0, 0.5).
        poisson_ratio: f64,
    },
    /// Mohr–Coulomb elastoplasticity with non-associated flow.
    MohrCoulomb {
        /// Name the bodies refer to.
        name: String,
        /// Density (kg/m³).
        density_kg_m3: f64,
        /// Young's modulus (Pa).
        youngs_modulus_pa: f64,
        /// Poisson's ratio in [0, 0.5).
        poisson_ratio: f64,
        /// Friction angle φ (degrees), in (0, 90).
        friction_deg: f64,
        /// Dilation angle ψ (degrees), in [0, φ].
        #[serde(default)]
        dilation_deg: f64,
        /// Cohesion c (Pa).
        #[serde(default)]
        cohesion_pa: f64,
        /// Tension cutoff σ_t (Pa) on the largest principal stress, in [0, c cot φ];
        /// default: c cot φ (the Mohr–Coulomb apex, no extra cutoff).
        #[serde(default)]
        tension_cutoff_pa: Option<f64>,
        /// Linear softening of φ and c with equivalent plastic strain.
        #[serde(default)]
        softening: Option<SofteningSpec>,
        /// Rate-dependent friction (μ(I) law): `friction_deg` is then the static friction.
        /// Not combined with `softening`.
        #[serde(default)]
        inertial_friction: Option<InertialFrictionSpec>,
        /// Volume ratio V/V₀ (> 1) above which a point has lost contact and carries no
        /// stress until compressed back below it: the loosest packing of a granular
        /// material relative to the initial one (Dunatunga & Kamrin 2015). Absent: never;
        /// a stressed point then stops the run if its expansion breaks the CFL limit.
        #[serde(default)]
        separation_volume_ratio: Option<f64>,
    },
}

impl MaterialSpec {
    /// The material's name.
    pub fn name(&self) -> &str {
        match self {
            MaterialSpec::LinearElastic { name, .. } | MaterialSpec::MohrCoulomb { name, .. } => {
                name
            }
        }
    }
}

/// Softening of a Mohr–Coulomb material.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SofteningSpec {
    /// Residual friction angle (degrees), ≤ the peak.
    pub residual_friction_deg: f64,
    /// Residual cohesion (Pa), ≤ the peak.
    pub residual_cohesion_pa: f64,
    /// Equivalent plastic strain where softening starts.
    pub plastic_strain_start: f64,
    /// Equivalent plastic strain where the residual values are reached (> start).
    pub plastic_strain_end: f64,
}

/// The μ(I) law of a Mohr–Coulomb material (Jop, Forterre & Pouliquen 2006):
/// sin φ(I) = sin φ_s + (tan φ₂ − sin φ_s) I / (I₀ + I), I = γ̇ d / √(P / ρ_s), P the
/// in-plane mean pressure. μ(I) is the shear-to-normal stress ratio of a steady simple shear,
/// which a ψ = 0 plane-strain Mohr–Coulomb material mobilises as sin φ, so a steady layer
/// flows on a slope θ where tan θ = μ(I) (Bagnold's profile; see `grainflow::mpm::inertial`).
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InertialFrictionSpec {
    /// φ₂ (degrees): the slope angle of the fastest steady flows, μ₂ = tan φ₂, above
    /// `friction_deg` and below 45° (glass beads: 32.76°, Jop et al. 2005).
    pub limit_friction_deg: f64,
    /// I₀ (–): the inertial number at which half of the increase is reached (glass beads:
    /// 0.279).
    pub reference_inertial_number: f64,
    /// Mean grain diameter d (m).
    pub grain_diameter_m: f64,
    /// Density of the grains' solid ρ_s (kg/m³), at least the bulk `density_kg_m3`.
    pub grain_density_kg_m3: f64,
}

/// Point velocity update of an MPM scene.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum VelocityTransfer {
    /// FLIP, blended with `pic_fraction` of PIC.
    #[default]
    Flip,
    /// Affine particle-in-cell.
    Apic,
}

/// A body of material points.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name of its material.
    pub material: String,
    /// n: the body gets n × n points per cell (1 to 6).
    pub points_per_cell: usize,
    /// The region filled.
    pub shape: ShapeSpec,
    /// Initial velocity (m/s).
    #[serde(default)]
    pub velocity_m_s: [f64; 2],
    /// Initial stress; absent: stress-free.
    #[serde(default)]
    pub initial_stress: Option<InitialStress>,
}

/// A region, tagged by `kind`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum ShapeSpec {
    /// Axis-aligned rectangle.
    Rectangle {
        /// Lower-left corner (m).
        min_m: [f64; 2],
        /// Upper-right corner (m).
        max_m: [f64; 2],
    },
    /// Simple polygon (at least 3 vertices, in order).
    Polygon {
        /// Vertices (m).
        vertices_m: Vec<[f64; 2]>,
    },
}

/// An initial stress state, tagged by `kind`.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum InitialStress {
    /// Geostatic: σ_yy = −ρ g (surface − y), σ_xx = σ_zz = k0 σ_yy, σ_xy = 0.
    Geostatic {
        /// Height of the free surface (m).
        surface_y_m: f64,
        /// Lateral earth pressure coefficient K₀ (Jaky: 1 − sin φ).
        k0: f64,
    },
}

/// Run length of an MPM scene.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MpmRun {
    /// Number of steps (exclusive with `end_time_s`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps: Option<u64>,
    /// Simulated time (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end_time_s: Option<f64>,
    /// Stop early once the kinetic energy per unit mass stays below this (J/kg) after
    /// 10 % of the run; 0 = never.
    #[serde(default)]
    pub stop_below_specific_kinetic_energy_j_kg: f64,
}

/// The four sides of an MPM domain, named as in a fluid scene: `west` (x = 0), `east`
/// (x = width), `south` (y = 0), `north` (y = height). Each is `{ kind = "open" }`,
/// `"fixed"`, `"roller"` or `{ kind = "frictional", friction = μ }`.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MpmBoundaries {
    /// x = 0.
    pub west: Side,
    /// x = width.
    pub east: Side,
    /// y = 0.
    pub south: Side,
    /// y = height.
    pub north: Side,
}

impl MpmBoundaries {
    /// The solver's sides.
    pub fn sides(&self) -> Boundaries {
        Boundaries {
            left: self.west,
            right: self.east,
            bottom: self.south,
            top: self.north,
        }
    }
}
