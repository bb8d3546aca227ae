//! The coupled grains of a fluid scene: the DEM system, the coupler, and the unit
//! conversions between them (the DEM works in SI, the coupler in lattice units).

use super::exchange::{Coupler, CouplingError};
use super::map::{GrainView, SlabFrame};
use crate::dem::{DemSystem, Grains, Wall};
use crate::lbm::lattice::{Face, FaceCondition};
use crate::lbm::{Lattice, Real};
use crate::run::RunError;
use crate::scene::coupling::{grain_scene, MIN_CELLS_PER_DIAMETER};
use crate::scene::{Units, ValidScene};
use decomposition::Comm;

/// Grains coupled to this rank's lattice.
pub struct LbmDem {
    /// The grains and their contacts (SI units, N and m per metre of depth).
    pub dem: DemSystem,
    coupler: Coupler,
    substeps: u32,
    units: Units,
    /// Domain size (m).
    domain: [f64; 2],
    /// Grains in lattice units, refreshed after every DEM advance.
    views: Vec<GrainView>,
    /// Force and torque held on each grain during the last advance (SI): hydrodynamic plus
    /// repulsion.
    held: Vec<[f64; 3]>,
    /// Hydrodynamic part of `held` (SI).
    hydro: Vec<[f64; 3]>,
    /// The previous step's hydrodynamic force (SI), for the two-step average.
    prev: Vec<[f64; 3]>,
    /// Hold the average of the last two steps' forces.
    average: bool,
    /// Repulsion (range m, strength in submerged weights), if on.
    repulsion: Option<(f64, f64)>,
    /// Submerged weight per grain (N/m).
    weight: Vec<f64>,
    /// Walls to remove at a time (index, time s).
    removals: Vec<(usize, f64)>,
}

impl LbmDem {
    /// Prepare the grains of `scene` (packing and settling as a grains scene would), add a
    /// DEM wall on every wall face of the fluid, and place the grains on `lat`.
    /// Errors name the key: a grain outside the domain or under three cells across.
    pub fn new<T: Real>(
        scene: &ValidScene,
        lat: &mut Lattice<T>,
        comm: &dyn Comm,
    ) -> Result<Self, RunError> {
        let s = &scene.scene;
        let (spec, coupling) = match (&s.grains, &s.coupling) {
            (Some(g), Some(c)) => (g, c),
            _ => unreachable!("validated: grains and coupling come together"),
        };
        let units = scene.units;
        let invalid = |key: &str, message: String| scene.invalid(key, message);
        let gs = grain_scene(s, spec, &scene.base_dir, &scene.path);
        let (grains, _) = crate::run_grains::sample::prepare(&gs, comm)?;
        let domain = gs.scene.region.max_m;
        for i in 0..grains.len() {
            let (x, y, r) = (grains.x[i], grains.y[i], grains.r[i]);
            if x - r < 0.0 || y - r < 0.0 || x + r > domain[0] || y + r > domain[1] {
                return Err(invalid(
                    "sample",
                    format!(
                        "grain {} at ({x}, {y}) m with radius {r} m is not wholly inside the \
                         fluid domain [0, 0]–{domain:?} m; move it inside",
                        grains.id[i]
                    ),
                )
                .into());
            }
            let cells = 2.0 * r / units.dx_m;
            if cells < MIN_CELLS_PER_DIAMETER {
                return Err(invalid(
                    "sample",
                    format!(
                        "grain {} is {cells:.2} cells across; the coupling needs at least \
                         {MIN_CELLS_PER_DIAMETER}: refine the lattice or use larger grains",
                        grains.id[i]
                    ),
                )
                .into());
            }
        }
        let rho_ratio = s.fluid.density_kg_m3 / spec.density_kg_m3;
        let g = spec.gravity_m_s2;
        // Static buoyancy by reduced gravity (1 − ρ/ρ_s) g (seed §5.4, eq. 5.57).
        let gravity = [g[0] * (1.0 - rho_ratio), g[1] * (1.0 - rho_ratio)];
        let weight: Vec<f64> = grains
            .m
            .iter()
            .map(|m| m * (gravity[0].hypot(gravity[1])))
            .collect();
        let mut walls = gs.walls();
        walls.extend(fluid_walls(lat, domain, spec.contact.friction));
        let dt_d = gs.time_step(&grains);
        let substeps = coupling
            .substeps
            .unwrap_or_else(|| (units.dt_s / dt_d).floor() as u32 + 1);
        let dt_s = units.dt_s / substeps as f64;
        let mut dem = DemSystem::new(
            grains,
            walls,
            gs.contact_model(),
            gravity,
            dt_s,
            gs.lambda(),
            spec.allow_overlap,
        )?;
        dem.global_damping = spec.global_damping_1_s;
        // Grain indices must stay fixed: the coupler's per-grain forces follow them.
        dem.spatial_sort = false;
        let removals = spec
            .walls
            .iter()
            .enumerate()
            .filter_map(|(i, w)| w.remove_at_s.map(|t| (i, t)))
            .collect();
        let frame = frame_of(lat);
        let n = dem.owned();
        let coupler = Coupler::new(coupling.scheme, coupling.refill, frame, n);
        let mut me = Self {
            dem,
            coupler,
            substeps,
            units,
            domain,
            views: Vec::new(),
            held: vec![[0.0; 3]; n],
            hydro: vec![[0.0; 3]; n],
            prev: vec![[0.0; 3]; n],
            average: coupling
                .force_averaging
                .unwrap_or(coupling.scheme == super::Scheme::BounceBack),
            repulsion: coupling.repulsion.as_ref().map(|r| (r.range_m, r.strength)),
            weight,
            removals,
        };
        me.refresh_views();
        me.coupler.start(lat, &me.views);
        Ok(me)
    }

    /// DEM sub-steps per fluid step.
    pub fn substeps(&self) -> u32 {
        self.substeps
    }

    /// The coupler (maps, forces).
    pub fn coupler(&self) -> &Coupler {
        &self.coupler
    }

    /// Hydrodynamic force and torque on each grain held during the last advance
    /// (N/m, N·m/m), by grain index.
    pub fn hydrodynamic(&self) -> &[[f64; 3]] {
        &self.hydro
    }

    /// Grains in lattice units.
    pub fn views(&self) -> &[GrainView] {
        &self.views
    }

    fn refresh_views(&mut self) {
        let (dx, dt) = (self.units.dx_m, self.units.dt_s);
        let g = &self.dem.grains;
        self.views.clear();
        self.views.extend((0..self.dem.owned()).map(|i| GrainView {
            centre: [g.x[i] / dx, g.y[i] / dx],
            radius: g.r[i] / dx,
            velocity: [g.vx[i] * dt / dx, g.vy[i] * dt / dx],
            omega: g.omega[i] * dt,
        }));
    }

    /// Stage "coupling" (fluid side): see [`Coupler::exchange`].
    pub fn exchange<T: Real>(&mut self, lat: &mut Lattice<T>) -> Result<(), CouplingError> {
        let ids = &self.dem.grains.id;
        self.coupler.exchange(lat, &self.views, ids)
    }

    /// Stage "dem": hold the hydrodynamic force (and the repulsion) and take the DEM
    /// sub-steps of one fluid step. Errors when a grain leaves the fluid domain.
    pub fn advance(&mut self) -> Result<(), CouplingError> {
        let u = self.units;
        for (k, f) in self.coupler.forces().enumerate() {
            // Lattice momentum per step → N/m; the torque's arm is in cells (× Δx).
            self.hydro[k] = [
                u.force_to_si(f[0]),
                u.force_to_si(f[1]),
                u.force_to_si(f[2]) * u.dx_m,
            ];
        }
        if self.average {
            // Ladd 1994 (part I, §4): the force of two successive steps, averaged, damps the
            // step-to-step oscillation that makes explicit bounce-back coupling unstable for
            // light grains (their rotation first).
            for (h, (a, b)) in self.held.iter_mut().zip(self.hydro.iter().zip(&self.prev)) {
                *h = [
                    0.5 * (a[0] + b[0]),
                    0.5 * (a[1] + b[1]),
                    0.5 * (a[2] + b[2]),
                ];
            }
            self.prev.copy_from_slice(&self.hydro);
        } else {
            self.held.copy_from_slice(&self.hydro);
        }
        if let Some((range, strength)) = self.repulsion {
            self.add_repulsion(range, strength);
        }
        self.dem.set_external(&self.held);
        let t_end = self.dem.time + u.dt_s;
        for (w, t) in &self.removals {
            if *t <= t_end && !self.dem.walls[*w].removed {
                self.dem.remove_wall(*w);
            }
        }
        for _ in 0..self.substeps {
            self.dem.step();
        }
        let g = &self.dem.grains;
        for i in 0..self.dem.owned() {
            let (x, y) = (g.x[i], g.y[i]);
            if !(x >= 0.0 && y >= 0.0 && x <= self.domain[0] && y <= self.domain[1]) {
                return Err(CouplingError::Left {
                    step: (self.dem.time / u.dt_s).round() as u64,
                    grain: g.id[i],
                    position: [x, y],
                });
            }
        }
        self.refresh_views();
        Ok(())
    }

    /// Glowinski et al. (2001) short-range repulsion between grains closer than `range`
    /// and between grains and walls closer than `range` (walls count as a mirror grain).
    fn add_repulsion(&mut self, range: f64, strength: f64) {
        let g = &self.dem.grains;
        let n = self.dem.owned();
        for i in 0..n {
            for j in i + 1..n {
                let (dx, dy) = (g.x[j] - g.x[i], g.y[j] - g.y[i]);
                let d = dx.hypot(dy);
                let gap = d - g.r[i] - g.r[j];
                if gap < range && d > 0.0 {
                    let w = self.weight[i].min(self.weight[j]);
                    let f = strength * w * ((range - gap) / range).powi(2);
                    self.held[j][0] += f * dx / d;
                    self.held[j][1] += f * dy / d;
                    self.held[i][0] -= f * dx / d;
                    self.held[i][1] -= f * dy / d;
                }
            }
            for w in self.dem.walls.iter().filter(|w| !w.removed) {
                let c = w.closest_point([g.x[i], g.y[i]]);
                let (dx, dy) = (g.x[i] - c[0], g.y[i] - c[1]);
                let d = dx.hypot(dy);
                let gap = d - g.r[i];
                if gap < range && d > 0.0 {
                    let f = strength * self.weight[i] * ((range - gap) / range).powi(2);
                    self.held[i][0] += f * dx / d;
                    self.held[i][1] += f * dy / d;
                }
            }
        }
    }

    /// Stage "coupling" after the grains moved: see [`Coupler::remap`].
    pub fn remap<T: Real>(&mut self, lat: &mut Lattice<T>) {
        self.coupler.remap(lat, &self.views);
    }

    /// Momentum (kg·m/s per metre of depth) of the fluid outside the grains and of the
    /// grains (with force averaging, including the half step of force still in transit):
    /// the two halves of the momentum balance.
    pub fn momentum<T: Real>(&self, lat: &Lattice<T>) -> ([f64; 2], [f64; 2]) {
        let u = self.units;
        let j = self.coupler.fluid_momentum(lat);
        // Lattice momentum of a cell → ρ Δx² (mass per depth) × Δx/Δt.
        let scale = u.density_kg_m3 * u.dx_m.powi(3) / u.dt_s;
        let mut p = self.dem.grains.momentum();
        if self.average {
            // Half of the last step's force is still to be handed to the grains.
            for f in &self.prev {
                p[0] += 0.5 * f[0] * u.dt_s;
                p[1] += 0.5 * f[1] * u.dt_s;
            }
        }
        ([j[0] * scale, j[1] * scale], p)
    }

    /// The grains (owned).
    pub fn grains(&self) -> &Grains {
        &self.dem.grains
    }
}

/// The slab frame of `lat`.
pub fn frame_of<T: Real>(lat: &Lattice<T>) -> SlabFrame {
    let faces = lat.faces();
    SlabFrame {
        nx: lat.nx(),
        ny: lat.ny(),
        x0: lat.x_offset(),
        global_nx: lat.global_nx(),
        stride: lat.stride(),
        // Coupled runs are single-rank, so a periodic x face is still `Periodic` here.
        periodic_x: faces[Face::West as usize] == FaceCondition::Periodic,
        periodic_y: faces[Face::South as usize] == FaceCondition::Periodic,
    }
}

/// A DEM wall along every wall face (bounce-back, moving or free-slip) of the fluid, so
/// grains cannot leave through them; friction `mu`.
fn fluid_walls<T: Real>(lat: &Lattice<T>, domain: [f64; 2], mu: f64) -> Vec<Wall> {
    let [lx, ly] = domain;
    let ends = [
        (Face::West, [0.0, 0.0], [0.0, ly]),
        (Face::East, [lx, 0.0], [lx, ly]),
        (Face::South, [0.0, 0.0], [lx, 0.0]),
        (Face::North, [0.0, ly], [lx, ly]),
    ];
    ends.iter()
        .filter(|(f, _, _)| {
            matches!(
                lat.faces()[*f as usize],
                FaceCondition::Wall { .. } | FaceCondition::FreeSlip
            )
        })
        .map(|&(_, a, b)| Wall::fixed(a, b, mu))
        .collect()
}
