//! A coupled scene's grains, set up from the scene: the sample prepared (or restored), the
//! DEM's sub-steps and walls, and the coupling's choices, handed to
//! [`coupling::LbmDem::new`] as plain numbers; and what `check` reports of them.

pub mod plan;

use crate::error::RunError;
use crate::run_grains::sample;
use coupling::{
    check_grains, fluid_walls, LbmDem, LbmDemSetup, RestoredCoupling, Scheme, SetupError,
};
use decomposition::{Comm, SlabPartition};
use dem::{DemSetup, Grains};
use lbm::lattice::FaceCondition;
use lbm::{FluidBackend, Real};
use scene::coupling::CouplingSpec;
use scene::coupling_check::grain_scene;
use scene::{ValidGrainScene, ValidScene};

pub use plan::{plan, CouplingPlan};

/// The grains of a coupled `scene` on this rank's `fluid`: packed and settled as a grains
/// scene would be, or the state of a checkpoint (`restored`), with a DEM wall on every wall
/// face of the fluid (`faces`: the whole lattice's), spread over the slabs of `partition`.
/// Errors name the key: a grain outside the domain or under three cells across, a slab too
/// narrow for the grains. Collective.
pub fn lbm_dem<T: Real>(
    scene: &ValidScene,
    fluid: &mut dyn FluidBackend<T>,
    faces: &[FaceCondition; 4],
    partition: &SlabPartition,
    comm: &dyn Comm,
    restored: Option<RestoredCoupling>,
) -> Result<LbmDem, RunError> {
    let s = &scene.scene;
    let (spec, c) = match (&s.grains, &s.coupling) {
        (Some(g), Some(c)) => (g, c),
        _ => unreachable!("validated: grains and coupling come together"),
    };
    let units = scene.units;
    let gs = grain_scene(s, spec, &scene.base_dir, &scene.path);
    let domain = gs.scene.domain.size();
    let rho_ratio = s.fluid.density_kg_m3 / spec.density_kg_m3;
    let g = spec.gravity_m_s2;
    // Static buoyancy by reduced gravity (1 − ρ/ρ_s) g (seed §5.4, eq. 5.57).
    let gravity = [g[0] * (1.0 - rho_ratio), g[1] * (1.0 - rho_ratio)];
    // A settled sample's grains press into each other by their contact overlaps.
    let (grains, restored, settled) = match restored {
        Some(mut r) => (std::mem::take(&mut r.grains), Some(r), true),
        None => {
            let (g, settle_steps) = sample::prepare(&gs, comm)?;
            (g, None, settle_steps > 0)
        }
    };
    check_grains(&grains, domain, units.dx_m, settled).map_err(|(k, m)| scene.invalid(k, m))?;
    let substeps = substeps_for(c, &gs, &grains, units.dt_s);
    let setup = LbmDemSetup {
        scheme: c.scheme,
        refill: c.refill,
        units,
        domain_m: domain,
        dem: DemSetup {
            walls: gs.walls(),
            model: gs.contact_model(),
            gravity,
            dt: units.dt_s / substeps as f64,
            lambda: gs.lambda(),
            fixed: gs.fixed_ids(),
        },
        face_wall_friction: spec.contact.friction,
        substeps,
        allow_overlap: spec.allow_overlap || settled,
        global_damping_1_s: spec.global_damping_1_s,
        average_forces: c.force_averaging.unwrap_or(c.scheme == Scheme::BounceBack),
        hydrodynamic_radius_ratio: c.hydrodynamic_radius_ratio(),
        repulsion: c.repulsion.as_ref().map(|r| (r.range_m, r.strength)),
        removals: spec
            .walls
            .iter()
            .enumerate()
            .filter_map(|(i, w)| w.remove_at_s.map(|t| (i, t)))
            .collect(),
    };
    LbmDem::new(setup, grains, restored, fluid, faces, partition, comm).map_err(|e| match e {
        SetupError::Invalid { key, message } => scene.invalid(key, message).into(),
        SetupError::Dem(e) => e.into(),
    })
}

/// How many DEM walls a coupled scene has: its own, then one per wall face of the fluid
/// (what a checkpoint of it holds).
pub fn wall_count(scene: &ValidScene) -> Result<usize, RunError> {
    let built = scene::build_lattice(scene)?;
    let own = match (&scene.scene.grains, &scene.scene.coupling) {
        (Some(spec), Some(_)) => {
            let gs = grain_scene(&scene.scene, spec, &scene.base_dir, &scene.path);
            gs.walls()
        }
        _ => Vec::new(),
    };
    let d = &scene.scene.domain;
    let domain = [
        d.cells[0] as f64 * d.spacing_m,
        d.cells[1] as f64 * d.spacing_m,
    ];
    let faces = fluid_walls(&built.setup.faces, domain, 0.0, &own).len();
    Ok(own.len() + faces)
}

/// DEM sub-steps per fluid step: the scene's, or n_s = ⌊Δt/Δt_D⌋ + 1 (seed eq. 5.61).
fn substeps_for(c: &CouplingSpec, gs: &ValidGrainScene, grains: &Grains, dt: f64) -> u32 {
    c.substeps
        .unwrap_or_else(|| (dt / gs.time_step(grains)).floor() as u32 + 1)
}
