//! Macroscopic fields (density, velocity, vorticity) and conserved totals, in lattice units.

use super::collision::moments;
use super::d2q9::{CX, CY, Q};
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

impl<T: Real> Lattice<T> {
    /// Pre-collision populations of interior cell (x, y) at the current time, boundary
    /// links reconstructed.
    pub(crate) fn gather(&self, x: usize, y: usize) -> [T; Q] {
        let src = &self.buf[self.cur];
        let k = self.idx(x as isize, y as isize);
        let plain = super::lattice::is_plain(&self.types, self.stride, k);
        if plain {
            std::array::from_fn(|i| {
                let n =
                    (k as isize - CX[i] as isize - CY[i] as isize * self.stride as isize) as usize;
                src[i * self.plane + n]
            })
        } else {
            self.gather_special(src, x, y, None)
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
    /// Conserved totals over fluid cells, summed in a fixed order.
    pub fn totals(&self) -> Totals {
        let mut t = Totals::default();
        for k in 0..self.rho.len() {
            if !self.fluid[k] {
                continue;
            }
            let (r, u, v) = (self.rho[k], self.ux[k], self.uy[k]);
            t.mass += r;
            t.momentum_x += r * u;
            t.momentum_y += r * v;
            t.kinetic_energy += 0.5 * r * (u * u + v * v);
            t.max_speed = t.max_speed.max((u * u + v * v).sqrt());
        }
        t
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
