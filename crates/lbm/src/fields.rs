//! Macroscopic fields (density, velocity, vorticity) and conserved totals, in lattice units.

use super::collision::moments;
use super::d2q9::Q;
use super::lattice::Lattice;
use super::real::Real;
use rayon::prelude::*;

/// Density and velocity on the interior cells, row-major `y * nx + x`, f64, lattice units.
/// Solid cells hold ρ = 1, u = 0 and are flagged in `fluid`.
#[derive(Debug, Clone, PartialEq)]
pub struct Fields {
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
    /// Density ρ.
    pub rho: Vec<f64>,
    /// Velocity x.
    pub ux: Vec<f64>,
    /// Velocity y.
    pub uy: Vec<f64>,
    /// Fluid mask.
    pub fluid: Vec<bool>,
}

/// Sums over the fluid cells.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Totals {
    /// Σ ρ (lattice mass).
    pub mass: f64,
    /// Σ ρ u_x.
    pub momentum_x: f64,
    /// Σ ρ u_y.
    pub momentum_y: f64,
    /// Σ ½ ρ |u|².
    pub kinetic_energy: f64,
    /// Largest |u|.
    pub max_speed: f64,
}

impl Totals {
    /// Fold per-column sums (four per column, see [`Fields::column_sums`]) in column order.
    pub fn from_column_sums(sums: &[f64], max_speed: f64) -> Self {
        let mut t = Totals {
            max_speed,
            ..Default::default()
        };
        for c in sums.chunks_exact(4) {
            t.mass += c[0];
            t.momentum_x += c[1];
            t.momentum_y += c[2];
            t.kinetic_energy += c[3];
        }
        t
    }

    /// The five totals as an array (mass, momentum x, momentum y, kinetic energy, max speed).
    pub fn to_array(&self) -> [f64; 5] {
        [
            self.mass,
            self.momentum_x,
            self.momentum_y,
            self.kinetic_energy,
            self.max_speed,
        ]
    }

    /// Inverse of [`Totals::to_array`].
    pub fn from_array(a: [f64; 5]) -> Self {
        Totals {
            mass: a[0],
            momentum_x: a[1],
            momentum_y: a[2],
            kinetic_energy: a[3],
            max_speed: a[4],
        }
    }
}

impl<T: Real> Lattice<T> {
    /// Pre-collision populations of interior cell (x, y) at the current time, boundary
    /// links reconstructed.
    pub(crate) fn gather(&self, x: usize, y: usize) -> [T; Q] {
        let src = super::boundary::Src::of(&self.buf[self.cur]);
        let acc = self.access();
        let k = self.idx(x as isize, y as isize);
        let plain = super::lattice::is_plain(&self.types, self.stride, k);
        if plain {
            std::array::from_fn(|i| src.get(acc.pulled(i, k)))
        } else {
            self.gather_special(src, acc, x, y, None)
        }
    }

    /// Density and velocity (Guo-corrected) of fluid cell (x, y).
    pub fn sample(&self, x: usize, y: usize) -> (f64, [f64; 2]) {
        let m = moments(&self.gather(x, y), self.params.force);
        (m.rho.to_f64(), [m.ux.to_f64(), m.uy.to_f64()])
    }

    /// All interior fields at the current time (parallel over rows).
    pub fn fields(&self) -> Fields {
        let (nx, ny) = (self.nx, self.ny);
        let mut rho = vec![1.0; nx * ny];
        let mut ux = vec![0.0; nx * ny];
        let mut uy = vec![0.0; nx * ny];
        rho.par_chunks_mut(nx)
            .zip(ux.par_chunks_mut(nx))
            .zip(uy.par_chunks_mut(nx))
            .enumerate()
            .for_each(|(y, ((r, a), b))| {
                for x in 0..nx {
                    if self.is_fluid(x, y) {
                        let (d, u) = self.sample(x, y);
                        r[x] = d;
                        a[x] = u[0];
                        b[x] = u[1];
                    }
                }
            });
        let fluid = (0..nx * ny)
            .map(|k| self.is_fluid(k % nx, k / nx))
            .collect();
        Fields {
            nx,
            ny,
            rho,
            ux,
            uy,
            fluid,
        }
    }
}

impl Fields {
    /// Conserved totals over fluid cells: per column (south to north), then over columns
    /// (west to east). Use [`Totals::from_column_sums`] on the concatenated
    /// [`Fields::column_sums`] of every slab to get the same bits on any number of ranks.
    pub fn totals(&self) -> Totals {
        Totals::from_column_sums(&self.column_sums(), self.max_speed())
    }

    /// Per column: Σρ, Σρu_x, Σρu_y, Σ½ρ|u|² over its fluid cells, summed south to north;
    /// four values per column, west to east.
    pub fn column_sums(&self) -> Vec<f64> {
        let mut out = vec![0.0; 4 * self.nx];
        for y in 0..self.ny {
            for x in 0..self.nx {
                let k = y * self.nx + x;
                if !self.fluid[k] {
                    continue;
                }
                let (r, u, v) = (self.rho[k], self.ux[k], self.uy[k]);
                let c = &mut out[4 * x..4 * x + 4];
                c[0] += r;
                c[1] += r * u;
                c[2] += r * v;
                c[3] += 0.5 * r * (u * u + v * v);
            }
        }
        out
    }

    /// Largest |u| over fluid cells.
    pub fn max_speed(&self) -> f64 {
        (0..self.rho.len())
            .filter(|&k| self.fluid[k])
            .map(|k| (self.ux[k] * self.ux[k] + self.uy[k] * self.uy[k]).sqrt())
            .fold(0.0, f64::max)
    }

    /// Vorticity of a slab whose neighbour columns are known: `west`/`east` hold the
    /// u_y and fluid flags of the column just outside it (None at the domain edge). Gives
    /// the same bits as [`Fields::vorticity`] of the whole lattice.
    pub fn vorticity_with(
        &self,
        west: Option<(&[f64], &[bool])>,
        east: Option<(&[f64], &[bool])>,
    ) -> Vec<f64> {
        let (l, r) = (west.is_some() as usize, east.is_some() as usize);
        let (nx, ny, wide) = (self.nx, self.ny, self.nx + l + r);
        let mut ext = Fields {
            nx: wide,
            ny,
            rho: vec![1.0; wide * ny],
            ux: vec![0.0; wide * ny],
            uy: vec![0.0; wide * ny],
            fluid: vec![false; wide * ny],
        };
        for y in 0..ny {
            let (d, s) = (y * wide + l, y * nx);
            ext.ux[d..d + nx].copy_from_slice(&self.ux[s..s + nx]);
            ext.uy[d..d + nx].copy_from_slice(&self.uy[s..s + nx]);
            ext.fluid[d..d + nx].copy_from_slice(&self.fluid[s..s + nx]);
            if let Some((uy, fl)) = west {
                ext.uy[y * wide] = uy[y];
                ext.fluid[y * wide] = fl[y];
            }
            if let Some((uy, fl)) = east {
                ext.uy[y * wide + wide - 1] = uy[y];
                ext.fluid[y * wide + wide - 1] = fl[y];
            }
        }
        let w = ext.vorticity();
        (0..ny)
            .flat_map(|y| w[y * wide + l..y * wide + l + nx].to_vec())
            .collect()
    }

    /// Vorticity ω = ∂u_y/∂x − ∂u_x/∂y by central differences (one-sided next to solids
    /// and the domain edge), lattice units; zero in solids.
    pub fn vorticity(&self) -> Vec<f64> {
        let (nx, ny) = (self.nx, self.ny);
        let ok = |x: isize, y: isize| {
            x >= 0
                && y >= 0
                && (x as usize) < nx
                && (y as usize) < ny
                && self.fluid[y as usize * nx + x as usize]
        };
        let deriv = |f: &[f64], x: usize, y: usize, dx: isize, dy: isize| {
            let (xi, yi) = (x as isize, y as isize);
            let at = |a: isize, b: isize| f[b as usize * nx + a as usize];
            match (ok(xi + dx, yi + dy), ok(xi - dx, yi - dy)) {
                (true, true) => 0.5 * (at(xi + dx, yi + dy) - at(xi - dx, yi - dy)),
                (true, false) => at(xi + dx, yi + dy) - at(xi, yi),
                (false, true) => at(xi, yi) - at(xi - dx, yi - dy),
                _ => 0.0,
            }
        };
        let mut w = vec![0.0; nx * ny];
        for y in 0..ny {
            for x in 0..nx {
                if self.fluid[y * nx + x] {
                    w[y * nx + x] = deriv(&self.uy, x, y, 1, 0) - deriv(&self.ux, x, y, 0, 1);
                }
            }
        }
        w
    }
}
