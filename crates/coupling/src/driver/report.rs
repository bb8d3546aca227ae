//! What the run loop reads from the coupled grains, gathered over the ranks in id order:
//! the momentum balance, positions, radii, one grain's probe values, and the per-grain
//! state a checkpoint keeps.

use super::LbmDem;
use decomposition::Comm;
use lbm::{FluidBackend, Real};

impl LbmDem {
    /// Momentum (kg·m/s per metre of depth) of the fluid outside the grains and of the
    /// grains (with force averaging, including the half step of force still in transit):
    /// the two halves of the momentum balance, the same bits on any rank count. Collective.
    pub fn momentum<T: Real>(
        &self,
        fluid: &mut dyn FluidBackend<T>,
        comm: &dyn Comm,
    ) -> ([f64; 2], [f64; 2]) {
        let u = self.units;
        let columns: Vec<f64> = self
            .coupler
            .fluid_momentum_columns(fluid)
            .iter()
            .flat_map(|c| *c)
            .collect();
        let all = comm.all_gather_f64(&columns);
        let mut j = [0.0; 2];
        for c in all.chunks_exact(2) {
            j[0] += c[0];
            j[1] += c[1];
        }
        // Lattice momentum of a cell → ρ Δx² (mass per depth) × Δx/Δt.
        let scale = u.density_kg_m3 * u.dx_m.powi(3) / u.dt_s;
        let sys = &self.dem.system;
        let g = &sys.grains;
        let mut rows = Vec::new();
        for i in 0..sys.owned() {
            // Half of the last step's force is still to be handed to the grains.
            let transit: &[f64] = if self.average {
                sys.carry(i)
            } else {
                &[0.0; 3]
            };
            rows.extend_from_slice(&[
                f64::from_bits(g.id[i]),
                g.m[i] * g.vx[i],
                g.m[i] * g.vy[i],
                0.5 * transit[0] * u.dt_s,
                0.5 * transit[1] * u.dt_s,
            ]);
        }
        let all = comm.all_gather_f64(&rows);
        let mut sorted: Vec<&[f64]> = all.chunks_exact(5).collect();
        sorted.sort_by_key(|r| r[0].to_bits());
        let mut p = [0.0; 2];
        for r in &sorted {
            p[0] += r[1];
            p[1] += r[2];
        }
        for r in &sorted {
            p[0] += r[3];
            p[1] += r[4];
        }
        ([j[0] * scale, j[1] * scale], p)
    }

    /// Every grain's (x, y, r) (m), sorted by id. Collective.
    pub fn positions(&self, comm: &dyn Comm) -> Vec<[f64; 3]> {
        let sys = &self.dem.system;
        let g = &sys.grains;
        let mine: Vec<f64> = (0..sys.owned())
            .flat_map(|i| [f64::from_bits(g.id[i]), g.x[i], g.y[i], g.r[i]])
            .collect();
        let all = comm.all_gather_f64(&mine);
        let mut rows: Vec<&[f64]> = all.chunks_exact(4).collect();
        rows.sort_by_key(|r| r[0].to_bits());
        rows.iter().map(|r| [r[1], r[2], r[3]]).collect()
    }

    /// Every grain's (id, radius m), sorted by id. Collective.
    pub fn radii(&self, comm: &dyn Comm) -> Vec<(u64, f64)> {
        let sys = &self.dem.system;
        let mine: Vec<f64> = (0..sys.owned())
            .flat_map(|i| [f64::from_bits(sys.grains.id[i]), sys.grains.r[i]])
            .collect();
        let mut all: Vec<(u64, f64)> = comm
            .all_gather_f64(&mine)
            .chunks_exact(2)
            .map(|p| (p[0].to_bits(), p[1]))
            .collect();
        all.sort_by_key(|p| p.0);
        all
    }

    /// Grain `id`'s x, y, vx, vy, ω and hydrodynamic fx, fy (SI) from the rank that owns
    /// it, on every rank; `None` when no rank has it. Collective.
    pub fn probe(&self, id: u64, comm: &dyn Comm) -> Option<[f64; 7]> {
        let sys = &self.dem.system;
        let g = &sys.grains;
        let mine: Vec<f64> = (0..sys.owned())
            .find(|&i| g.id[i] == id)
            .map(|i| {
                let f = self.hydrodynamic(i);
                vec![g.x[i], g.y[i], g.vx[i], g.vy[i], g.omega[i], f[0], f[1]]
            })
            .unwrap_or_default();
        let all = comm.all_gather_f64(&mine);
        (all.len() >= 7).then(|| std::array::from_fn(|k| all[k]))
    }

    /// Kinetic energy of every grain, translation and rotation (J/m), the same bits on any
    /// rank count and in any storage order. Collective.
    pub fn kinetic_energy(&self, comm: &dyn Comm) -> f64 {
        let sys = &self.dem.system;
        let ke: Vec<f64> = (0..sys.owned())
            .map(|i| sys.grains.kinetic_energy_of_grain(i))
            .collect();
        decomposition::reproducible_sums(&[&ke], comm)[0]
    }

    /// Whether each point (m) lies inside a grain as the fluid sees it (radius r_h), among
    /// the grains this rank holds (owned and ghosts: every grain over this rank's slab).
    pub fn covers(&self, points: &[[f64; 2]]) -> Vec<bool> {
        let g = &self.dem.system.grains;
        let k = self.hydro_ratio;
        points
            .iter()
            .map(|p| {
                (0..g.len()).any(|i| {
                    let (dx, dy, r) = (p[0] - g.x[i], p[1] - g.y[i], k * g.r[i]);
                    dx * dx + dy * dy < r * r
                })
            })
            .collect()
    }

    /// Walls of the DEM (the scene's, then one per wall face of the fluid).
    pub fn wall_count(&self) -> usize {
        self.dem.system.walls.len()
    }

    /// Per owned grain: external force held (SI), previous hydrodynamic force (SI) and the
    /// pending hand-over (lattice units), for checkpoints.
    pub fn per_grain_state(&self) -> Vec<[f64; 9]> {
        let sys = &self.dem.system;
        (0..sys.owned())
            .map(|i| {
                let e = sys.external().get(i).copied().unwrap_or([0.0; 3]);
                let p = sys.carry(i);
                let h = self.handover[i];
                [e[0], e[1], e[2], p[0], p[1], p[2], h[0], h[1], h[2]]
            })
            .collect()
    }
}
