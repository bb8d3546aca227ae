//! The probes of a simulation: where each samples (a point's surrounding fluid cells with
//! their bilinear weights, an obstacle, a grain, a deposit), and the stage that records
//! them, the same bits on any rank count.

use super::{stage, Simulation};
use crate::driver::Lap;
use crate::error::RunError;
use coupling::LbmDem;
use decomposition::Comm;
use io::probes::Series;
use lbm::curved::CurvedWalls;
use lbm::Real;
use rayon::prelude::*;
use scene::{solid_id_of, BuiltGeometry, Probe, ValidScene};
use std::collections::{HashMap, HashSet};

/// Where a probe samples.
pub(super) enum ProbeTarget {
    /// A point: the global fluid cells (x, y) around it, with their bilinear weights.
    Point(Vec<(usize, usize, f64)>),
    Solid(u16),
    /// A grain of a coupled run, by id.
    Grain(u64),
    /// The deposit of a coupled run's grains against a wall (x) on a floor (y), m.
    Deposit(f64, f64),
    /// The kinetic energy of the grains and of the fluid.
    KineticEnergy,
}

/// The cells whose centres surround `p` (m) on a lattice of spacing `dx` (m) and size `n`,
/// with their bilinear weights, keeping the cells where `fluid(x, y)` and renormalising the
/// weights over them (a point on an obstacle's surface reads the fluid beside it; a point
/// within half a cell of the domain's edge, the cells inside). `None` when no fluid cell
/// surrounds the point.
fn bilinear_corners(
    p: [f64; 2],
    dx: f64,
    n: [usize; 2],
    fluid: impl Fn(usize, usize) -> bool,
) -> Option<Vec<(usize, usize, f64)>> {
    // Cell (i, j)'s centre is at ((i + ½) dx, (j + ½) dx).
    let g = [p[0] / dx - 0.5, p[1] / dx - 0.5];
    let base = g.map(|v| v.floor());
    let frac = [g[0] - base[0], g[1] - base[1]];
    let mut corners = Vec::with_capacity(4);
    for (dy, wy) in [(0, 1.0 - frac[1]), (1, frac[1])] {
        for (dx_, wx) in [(0, 1.0 - frac[0]), (1, frac[0])] {
            let (x, y) = (base[0] as i64 + dx_, base[1] as i64 + dy);
            let inside = x >= 0 && y >= 0 && (x as usize) < n[0] && (y as usize) < n[1];
            let w = wx * wy;
            if inside && w > 0.0 && fluid(x as usize, y as usize) {
                corners.push((x as usize, y as usize, w));
            }
        }
    }
    let total: f64 = corners.iter().map(|c| c.2).sum();
    if corners.is_empty() || total <= 0.0 {
        return None;
    }
    for c in &mut corners {
        c.2 /= total;
    }
    Some(corners)
}

/// Where a surface probe samples the fluid along a curved wall's outward normal: at d₀,
/// d₀ + 1 and d₀ + 2 cells, for the first d₀ here whose three bilinear stencils lie wholly
/// in the fluid (from 1.5 cells on, a stencil never reaches into the circle: a corner is at
/// most √2 cells from its point).
const SURFACE_OFFSETS: [f64; 5] = [0.5, 0.75, 1.0, 1.25, 1.5];

/// For a point `p` (m) within half a cell of the surface of a curved-wall circle: the
/// cells and weights that give the value on the surface at the point's projection,
/// extrapolated quadratically from three bilinear samples along the outward normal
/// (the Lagrange polynomial through d₀, d₀ + 1, d₀ + 2, evaluated at 0; see
/// [`SURFACE_OFFSETS`]). `None` when the point is not on such a surface, or no offset
/// keeps the samples in the fluid (the caller then reads the fluid beside the wall).
fn on_curved_surface(
    p: [f64; 2],
    dx: f64,
    built: &BuiltGeometry,
) -> Option<Vec<(usize, usize, f64)>> {
    let at = [p[0] / dx, p[1] / dx];
    let c = built.curved.iter().find(|c| {
        let d = (at[0] - c.centre[0]).hypot(at[1] - c.centre[1]);
        (d - c.radius).abs() <= 0.5
    })?;
    let d = (at[0] - c.centre[0]).hypot(at[1] - c.centre[1]);
    if d == 0.0 {
        return None;
    }
    let normal = [(at[0] - c.centre[0]) / d, (at[1] - c.centre[1]) / d];
    let (n, fluid) = ([built.setup.nx, built.setup.ny], |x: usize, y: usize| {
        built.is_fluid(x, y)
    });
    let samples = |d0: f64| -> Option<Vec<(usize, usize, f64)>> {
        let weights = [
            (d0 + 1.0) * (d0 + 2.0) / 2.0,
            -d0 * (d0 + 2.0),
            d0 * (d0 + 1.0) / 2.0,
        ];
        let mut out = Vec::with_capacity(12);
        for (k, weight) in weights.into_iter().enumerate() {
            let s = c.radius + d0 + k as f64;
            let q = [
                (c.centre[0] + s * normal[0]) * dx,
                (c.centre[1] + s * normal[1]) * dx,
            ];
            if !stencil_in_fluid(q, dx, n, fluid) {
                return None;
            }
            let corners = bilinear_corners(q, dx, n, fluid)?;
            out.extend(corners.into_iter().map(|(x, y, w)| (x, y, w * weight)));
        }
        Some(out)
    };
    SURFACE_OFFSETS.into_iter().find_map(samples)
}

/// Whether every corner of the bilinear stencil of `q` (m) that carries a weight above
/// 10⁻⁹ lies in the lattice (`n` cells) and in the fluid: a point on a row of cell centres
/// needs only that row, even where rounding gives the next row a weight of 10⁻¹⁶.
fn stencil_in_fluid(
    q: [f64; 2],
    dx: f64,
    n: [usize; 2],
    fluid: impl Fn(usize, usize) -> bool,
) -> bool {
    let g = [q[0] / dx - 0.5, q[1] / dx - 0.5];
    let base = g.map(f64::floor);
    let frac = [g[0] - base[0], g[1] - base[1]];
    let tiny = 1e-9;
    (0..4).all(|c| {
        let (ix, iy) = (c & 1, c >> 1);
        let wx = if ix == 0 { 1.0 - frac[0] } else { frac[0] };
        let wy = if iy == 0 { 1.0 - frac[1] } else { frac[1] };
        let (x, y) = (base[0] as i64 + ix as i64, base[1] as i64 + iy as i64);
        wx * wy <= tiny
            || (x >= 0
                && y >= 0
                && (x as usize) < n[0]
                && (y as usize) < n[1]
                && fluid(x as usize, y as usize))
    })
}

/// The probes' targets on the global lattice and their (empty) series, in scene order.
#[allow(clippy::type_complexity)]
pub(super) fn probe_targets(
    scene: &ValidScene,
    built: &BuiltGeometry,
) -> Result<(Vec<ProbeTarget>, Vec<Series>), RunError> {
    let units = scene.units;
    let mut targets = Vec::new();
    let mut series = Vec::new();
    for p in &scene.scene.probes {
        match p {
            Probe::Point { name, position_m } => {
                let setup = &built.setup;
                let fluid = |x: usize, y: usize| built.is_fluid(x, y);
                let n = [setup.nx, setup.ny];
                let corners = on_curved_surface(*position_m, units.dx_m, built)
                    .or_else(|| bilinear_corners(*position_m, units.dx_m, n, fluid))
                    .ok_or_else(|| {
                        scene.invalid(
                            "position_m",
                            format!(
                                "probe `{name}` lies inside an obstacle (no fluid cell \
                                     centre around it); move it into the fluid or onto the \
                                     obstacle's surface"
                            ),
                        )
                    })?;
                targets.push(ProbeTarget::Point(corners));
                series.push(Series::new(name, vec!["ux_m_s", "uy_m_s", "pressure_pa"]));
            }
            Probe::Force { name, obstacle } => {
                let id = solid_id_of(&built.setup, obstacle).expect("validated");
                targets.push(ProbeTarget::Solid(id));
                series.push(Series::new(name, vec!["fx_n_per_m", "fy_n_per_m"]));
            }
            Probe::Deposit {
                name,
                wall_x_m,
                floor_y_m,
            } => {
                targets.push(ProbeTarget::Deposit(*wall_x_m, *floor_y_m));
                series.push(Series::new(name, vec!["front_m", "height_m"]));
            }
            Probe::KineticEnergy { name } => {
                targets.push(ProbeTarget::KineticEnergy);
                series.push(Series::new(name, vec!["grains_j_m", "fluid_j_m"]));
            }
            Probe::Grain { name, id } => {
                targets.push(ProbeTarget::Grain(*id));
                let columns = vec![
                    "x_m",
                    "y_m",
                    "vx_m_s",
                    "vy_m_s",
                    "omega_rad_s",
                    "fx_n_per_m",
                    "fy_n_per_m",
                ];
                series.push(Series::new(name, columns));
            }
        }
    }
    Ok((targets, series))
}

/// Every grain probe names a grain of the sample. Collective.
pub(super) fn check_grain_probes(
    scene: &ValidScene,
    targets: &[ProbeTarget],
    c: &LbmDem,
    comm: &dyn Comm,
) -> Result<(), RunError> {
    let probed: Vec<u64> = targets
        .iter()
        .filter_map(|t| match t {
            ProbeTarget::Grain(id) => Some(*id),
            _ => None,
        })
        .collect();
    if probed.is_empty() {
        return Ok(());
    }
    let ids: Vec<u64> = c.radii(comm).iter().map(|p| p.0).collect();
    match probed.iter().find(|id| ids.binary_search(id).is_err()) {
        Some(id) => Err(scene
            .invalid(
                "id",
                format!(
                    "grain probe names grain {id}, but the sample has grains 0..{}",
                    ids.len()
                ),
            )
            .into()),
        None => Ok(()),
    }
}

impl<T: Real> Simulation<T> {
    /// Stage "probes": record every probe at the current step. Point probes are sampled
    /// by the rank that owns their cell, forces are reduced in global column order; every
    /// rank ends up with the same series. Collective.
    pub fn record_probes(&mut self, comm: &dyn Comm) {
        if self.targets.is_empty() {
            return;
        }
        let t0 = Lap::start();
        let step = self.fluid.lattice().steps_done();
        let t = self.units.time_si(step);
        let forces = if self
            .targets
            .iter()
            .any(|p| matches!(p, ProbeTarget::Solid(_)))
        {
            self.solid_forces(comm)
        } else {
            Vec::new()
        };
        let points = self
            .targets
            .iter()
            .any(|p| matches!(p, ProbeTarget::Point(..)));
        if points {
            self.show_grains();
        }
        if self.probe_on_rank_face || (points && self.grains.is_some() && comm.size() > 1) {
            self.fluid.refresh_halos(comm);
        }
        let point = self.sample_points(comm);
        let energy = if self
            .targets
            .iter()
            .any(|p| matches!(p, ProbeTarget::KineticEnergy))
        {
            let grains = self.grains.as_ref().map_or(0.0, |c| c.kinetic_energy(comm));
            [grains, self.fluid_kinetic_energy(comm)]
        } else {
            [0.0; 2]
        };
        for (k, (s, target)) in self.series.iter_mut().zip(&self.targets).enumerate() {
            match *target {
                ProbeTarget::Point(..) => s.push(step, t, &point[k]),
                ProbeTarget::Grain(id) => {
                    let c = self
                        .grains
                        .as_ref()
                        .expect("validated: grain probes need grains");
                    let row = c.probe(id, comm).expect("validated id");
                    s.push(step, t, &row);
                }
                ProbeTarget::Deposit(wall, floor) => {
                    let c = self
                        .grains
                        .as_ref()
                        .expect("validated: deposit probes need grains");
                    let g = c.positions(comm);
                    let col = |k: usize| g.iter().map(|p| p[k]).collect::<Vec<f64>>();
                    let shape =
                        analysis::collapse::pile_shape(&col(0), &col(1), &col(2), wall, floor);
                    s.push(step, t, &[shape.length_m, shape.height_m]);
                }
                ProbeTarget::KineticEnergy => s.push(step, t, &energy),
                ProbeTarget::Solid(id) => {
                    let f = forces[id as usize - 1];
                    s.push(
                        step,
                        t,
                        &[self.units.force_to_si(f[0]), self.units.force_to_si(f[1])],
                    );
                }
            }
        }
        self.times.add(stage::PROBES, t0);
    }

    /// Kinetic energy of the fluid outside the grains, J per metre of depth: Σ (1 − ε) ½ρ|u|²
    /// Δx² over the fluid cells (ε: the cell's solid fraction, 1 under bounce-back grains),
    /// summed per column and then exactly over the columns, the same bits on any rank
    /// count. Collective.
    fn fluid_kinetic_energy(&mut self, comm: &dyn Comm) -> f64 {
        let f = self.fields(comm);
        let stride = self.fluid.lattice().stride();
        let mut solid = Vec::new();
        if let Some(c) = &self.grains {
            solid.resize(stride * (f.ny + 2), 0.0);
            c.coupler().solid_fraction(&mut solid);
        }
        // Each column's sum runs south to north; bands of columns in parallel, each walking
        // its rows in order (the arrays are row-major), so every column adds the same
        // terms in the same order whatever the band width.
        let mut columns = vec![0.0; f.nx];
        let band = f.nx.div_ceil(4 * rayon::current_num_threads()).max(64);
        columns
            .par_chunks_mut(band)
            .enumerate()
            .for_each(|(b, sums)| {
                let x0 = b * band;
                for y in 0..f.ny {
                    for (j, sum) in sums.iter_mut().enumerate() {
                        let (x, k) = (x0 + j, y * f.nx + x0 + j);
                        if f.fluid[k] {
                            let open = solid.get((y + 1) * stride + x + 1).map_or(1.0, |e| 1.0 - e);
                            let (u, v) = (f.ux[k], f.uy[k]);
                            *sum += open * 0.5 * f.rho[k] * (u * u + v * v);
                        }
                    }
                }
            });
        let lattice = decomposition::reproducible_sums(&[&columns], comm)[0];
        // Lattice energy per cell (ρ in ρ₀, u in Δx/Δt) to J/m: ρ₀ (Δx/Δt)² Δx².
        let u = &self.units;
        lattice * u.density_kg_m3 * (u.dx_m / u.dt_s).powi(2) * u.dx_m * u.dx_m
    }

    /// Momentum-exchange force (lattice units) on every solid in the last step, indexed by
    /// solid id − 1: the lattice's staircased solids and the curved walls; the same bits on
    /// any number of ranks. Collective.
    fn solid_forces(&mut self, comm: &dyn Comm) -> Vec<[f64; 2]> {
        let mut forces = self.fluid.forces(comm);
        if let Some(w) = &self.curved {
            let all = comm.all_gather_f64(&w.column_forces());
            let widths: Vec<usize> = (0..comm.size())
                .map(|r| self.partition.slab(r).width())
                .collect();
            let totals = CurvedWalls::reduce(&all, &widths, w.circles().len());
            for (c, f) in w.circles().iter().zip(totals) {
                forces[c.solid as usize - 1] = f;
            }
        }
        forces
    }

    /// Velocity (m/s) and pressure (Pa) at every point probe (by target index; zero for
    /// other targets): each rank samples the corner cells it owns, and every rank sums each
    /// probe's corners in their fixed order, so the values have the same bits on any rank
    /// count. In a coupled run, corners whose centre lies inside a grain (as the fluid sees
    /// it) are left out and the weights renormalised over the others, unless every corner is
    /// covered. Collective.
    fn sample_points(&mut self, comm: &dyn Comm) -> Vec<[f64; 3]> {
        let (x0, nx) = (self.fluid.lattice().x_offset(), self.fluid.lattice().nx());
        let mut tags = Vec::new();
        let mut cells = Vec::new();
        for (k, target) in self.targets.iter().enumerate() {
            if let ProbeTarget::Point(corners) = target {
                for (j, &(x, y, _)) in corners.iter().enumerate() {
                    if (x0..x0 + nx).contains(&x) {
                        tags.push((k, j));
                        cells.push((x - x0, y));
                    }
                }
            }
        }
        let dx = self.units.dx_m;
        let covered = match &self.grains {
            Some(c) => {
                let centres: Vec<[f64; 2]> = cells
                    .iter()
                    .map(|&(x, y)| [((x + x0) as f64 + 0.5) * dx, (y as f64 + 0.5) * dx])
                    .collect();
                c.covers(&centres)
            }
            None => vec![false; cells.len()],
        };
        let mut mine = Vec::with_capacity(6 * cells.len());
        let mut sampled = self.fluid.sample(&cells);
        let corners: HashSet<(usize, usize)> = cells.iter().copied().collect();
        let links: HashMap<(usize, usize), (f64, [f64; 2])> = self
            .link_cell_moments(Some(&corners))
            .into_iter()
            .map(|(x, y, rho, u)| ((x, y), (rho, u)))
            .collect();
        for (cell, value) in cells.iter().zip(sampled.iter_mut()) {
            if let Some(v) = links.get(cell) {
                *value = *v;
            }
        }
        for (((k, j), (rho, u)), cov) in tags.into_iter().zip(sampled).zip(covered) {
            mine.extend([
                k as f64,
                j as f64,
                cov as u8 as f64,
                self.units.velocity_to_si(u[0]),
                self.units.velocity_to_si(u[1]),
                self.units.drho_to_pressure(rho - 1.0),
            ]);
        }
        let all = comm.all_gather_f64(&mine);
        let mut values = vec![Vec::new(); self.targets.len()];
        for r in all.chunks_exact(6) {
            values[r[0] as usize].push((r[1] as usize, r[2] != 0.0, [r[3], r[4], r[5]]));
        }
        let mut point = vec![[0.0; 3]; self.targets.len()];
        for (k, target) in self.targets.iter().enumerate() {
            if let ProbeTarget::Point(corners) = target {
                values[k].sort_by_key(|v| v.0);
                let open = values[k].iter().any(|v| !v.1);
                let used: Vec<_> = values[k].iter().filter(|v| !open || !v.1).collect();
                let total: f64 = used.iter().map(|v| corners[v.0].2).sum();
                for v in used {
                    for c in 0..3 {
                        point[k][c] += corners[v.0].2 / total * v.2[c];
                    }
                }
            }
        }
        point
    }

    /// Density and velocity (lattice units) of the fluid cells next to bounce-back grains
    /// or curved walls, by local cell (x, y), from their own values: a plain read of such a
    /// cell pulls the values under the grain or wall instead of the bounce-back populations
    /// the sweep gives it.
    /// The collision keeps ρ and adds F to the momentum (Guo forcing), so from the
    /// post-collision values ρ = 1 + Σ h_i and u = (Σ h_i c_i − F/2) / ρ (Guo, Zheng & Shi
    /// 2002, eq. 10). Only the cells `wanted` keeps (all when `None`); empty for a fluid run
    /// or partially saturated cells.
    pub(super) fn link_cell_moments(
        &mut self,
        wanted: Option<&HashSet<(usize, usize)>>,
    ) -> Vec<(usize, usize, f64, [f64; 2])> {
        let links = match (&self.grains, &self.curved) {
            (Some(c), _) => c.coupler().link_cells(),
            (None, Some(w)) => w.link_cells(),
            (None, None) => return Vec::new(),
        };
        let stride = self.fluid.lattice().stride();
        let local = |k: u32| (k as usize % stride - 1, k as usize / stride - 1);
        let cells: Vec<u32> = links
            .iter()
            .copied()
            .filter(|&k| wanted.is_none_or(|w| w.contains(&local(k))))
            .collect();
        if cells.is_empty() {
            return Vec::new();
        }
        let force = self.fluid.lattice().body_force();
        let own = self.fluid.whole_cells(&cells);
        cells
            .iter()
            .zip(own)
            .map(|(&k, h)| {
                let m = lbm::collision::moments(&h, [-force[0], -force[1]]);
                let (x, y) = local(k);
                (x, y, m.rho, [m.ux, m.uy])
            })
            .collect()
    }
}
