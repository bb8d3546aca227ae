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
        let mut fluid = vec![false; nx * ny];
        fluid.par_chunks_mut(nx).enumerate().for_each(|(y, row)| {
            for (x, f) in row.iter_mut().enumerate() {
                *f = self.is_fluid(x, y);
            }
        });
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
    /// the same bits as [`Fields::vorticity`] of the whole lattice. Holds no copy of the
    /// fields: the result is the only allocation (parallel over rows).
    pub fn vorticity_with(
        &self,
        west: Option<(&[f64], &[bool])>,
        east: Option<(&[f64], &[bool])>,
    ) -> Vec<f64> {
        let (nx, ny) = (self.nx, self.ny);
        // Column x ∈ [−1, nx] of row y: whether it is fluid, and its u_y.
        let fluid_at = |x: isize, y: usize| match x {
            -1 => west.is_some_and(|(_, f)| f[y]),
            x if x as usize == nx => east.is_some_and(|(_, f)| f[y]),
            x => self.fluid[y * nx + x as usize],
        };
        let uy_at = |x: isize, y: usize| match (x, west, east) {
            (-1, Some((u, _)), _) => u[y],
            (x, _, Some((u, _))) if x as usize == nx => u[y],
            (x, _, _) => self.uy[y * nx + x as usize],
        };
        // Central differences, one-sided next to solids and the domain edge.
        let one_sided = |ahead: bool, behind: bool, f: &dyn Fn(isize) -> f64| match (ahead, behind)
        {
            (true, true) => 0.5 * (f(1) - f(-1)),
            (true, false) => f(1) - f(0),
            (false, true) => f(0) - f(-1),
            _ => 0.0,
        };
        let mut w = vec![0.0; nx * ny];
        if nx == 0 {
            return w;
        }
        w.par_chunks_mut(nx).enumerate().for_each(|(y, row)| {
            for (x, w) in row.iter_mut().enumerate() {
                if !self.fluid[y * nx + x] {
                    continue;
                }
                let xi = x as isize;
                let duy_dx = one_sided(fluid_at(xi + 1, y), fluid_at(xi - 1, y), &|d| {
                    uy_at(xi + d, y)
                });
                let row_ok = |d: isize| {
                    let yy = y as isize + d;
                    yy >= 0 && (yy as usize) < ny && self.fluid[yy as usize * nx + x]
                };
                let dux_dy = one_sided(row_ok(1), row_ok(-1), &|d| {
                    self.ux[(y as isize + d) as usize * nx + x]
                });
                *w = duy_dx - dux_dy;
            }
        });
        w
    }

    /// Vorticity ω = ∂u_y/∂x − ∂u_x/∂y by central differences (one-sided next to solids
    /// and the domain edge), lattice units; zero in solids.
    pub fn vorticity(&self) -> Vec<f64> {
        self.vorticity_with(None, None)
    }
}

#[cfg(test)]
mod tests {
    use super::Fields;

    /// An `nx × ny` field at rest, every cell fluid.
    fn still(nx: usize, ny: usize) -> Fields {
        Fields {
            nx,
            ny,
            rho: vec![1.0; nx * ny],
            ux: vec![0.0; nx * ny],
            uy: vec![0.0; nx * ny],
            fluid: vec![true; nx * ny],
        }
    }

    /// A 9 × 6 field with u = (−Ω y + a x², Ω x) (solid-body rotation, plus a term in u_x
    /// that ω does not contain: it shows a mix-up of the axes), a solid cell in the middle
    /// and one at an edge.
    fn field() -> Fields {
        let (nx, ny, omega) = (9, 6, 0.01);
        let mut f = still(nx, ny);
        for y in 0..ny {
            for x in 0..nx {
                let k = y * nx + x;
                f.ux[k] = -omega * y as f64 + 1e-3 * (x * x) as f64;
                f.uy[k] = omega * x as f64;
            }
        }
        f.fluid[3 * nx + 4] = false;
        f.fluid[8] = false;
        f
    }

    /// Solid-body rotation has ω = 2Ω: exact for central and one-sided differences of a
    /// linear field, next to solids and the domain edge too; zero in solids.
    #[test]
    fn rotation_has_twice_its_rate_everywhere() {
        let f = field();
        let w = f.vorticity();
        for (k, w) in w.iter().enumerate() {
            let want = if f.fluid[k] { 0.02 } else { 0.0 };
            assert!((w - want).abs() < 1e-15, "cell {k}: {w} against {want}");
        }
    }

    /// Split into slabs at every column, each slab with its neighbours' edge columns, the
    /// vorticity has the whole field's bits.
    #[test]
    fn slabs_with_their_neighbour_columns_give_the_whole_fields_bits() {
        let f = field();
        let whole = f.vorticity();
        let (nx, ny) = (f.nx, f.ny);
        let column = |x: usize| -> (Vec<f64>, Vec<bool>) {
            (0..ny)
                .map(|y| (f.uy[y * nx + x], f.fluid[y * nx + x]))
                .unzip()
        };
        for cut in 1..nx {
            for (a, b) in [(0, cut), (cut, nx)] {
                let w = b - a;
                let pick = |v: &[f64]| -> Vec<f64> {
                    (0..ny)
                        .flat_map(|y| v[y * nx + a..y * nx + b].to_vec())
                        .collect()
                };
                let slab = Fields {
                    nx: w,
                    ny,
                    rho: pick(&f.rho),
                    ux: pick(&f.ux),
                    uy: pick(&f.uy),
                    fluid: (0..ny)
                        .flat_map(|y| f.fluid[y * nx + a..y * nx + b].to_vec())
                        .collect(),
                };
                let (west, east) = ((a > 0).then(|| column(a - 1)), (b < nx).then(|| column(b)));
                let got = slab.vorticity_with(
                    west.as_ref().map(|(u, g)| (u.as_slice(), g.as_slice())),
                    east.as_ref().map(|(u, g)| (u.as_slice(), g.as_slice())),
                );
                for y in 0..ny {
                    for x in 0..w {
                        assert_eq!(
                            got[y * w + x].to_bits(),
                            whole[y * nx + a + x].to_bits(),
                            "cut {cut}, slab {a}..{b}, cell ({x}, {y})"
                        );
                    }
                }
            }
        }
    }

    /// The widened-copy vorticity this implementation replaced, kept as the reference: the
    /// slab widened by its neighbour columns, then central differences (one-sided next to
    /// solids and the edge) on the widened field.
    fn reference(
        f: &Fields,
        west: Option<(&[f64], &[bool])>,
        east: Option<(&[f64], &[bool])>,
    ) -> Vec<f64> {
        let (l, r) = (west.is_some() as usize, east.is_some() as usize);
        let (nx, ny, wide) = (f.nx, f.ny, f.nx + l + r);
        let (mut ux, mut uy, mut fl) = (
            vec![0.0; wide * ny],
            vec![0.0; wide * ny],
            vec![false; wide * ny],
        );
        for y in 0..ny {
            let (d, s) = (y * wide + l, y * nx);
            ux[d..d + nx].copy_from_slice(&f.ux[s..s + nx]);
            uy[d..d + nx].copy_from_slice(&f.uy[s..s + nx]);
            fl[d..d + nx].copy_from_slice(&f.fluid[s..s + nx]);
            if let Some((u, g)) = west {
                (uy[y * wide], fl[y * wide]) = (u[y], g[y]);
            }
            if let Some((u, g)) = east {
                (uy[y * wide + wide - 1], fl[y * wide + wide - 1]) = (u[y], g[y]);
            }
        }
        let ok = |x: isize, y: isize| {
            x >= 0
                && y >= 0
                && (x as usize) < wide
                && (y as usize) < ny
                && fl[y as usize * wide + x as usize]
        };
        let deriv = |v: &[f64], x: usize, y: usize, dx: isize, dy: isize| {
            let (xi, yi) = (x as isize, y as isize);
            let at = |a: isize, b: isize| v[b as usize * wide + a as usize];
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
                if fl[y * wide + x + l] {
                    w[y * nx + x] = deriv(&uy, x + l, y, 1, 0) - deriv(&ux, x + l, y, 0, 1);
                }
            }
        }
        w
    }

    /// Random velocities (zero in solids, as `Lattice::fields` gives them) on random solids,
    /// with and without neighbour columns on either side: the same bits as the reference.
    #[test]
    fn random_fields_give_the_widened_copys_bits() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for case in 0..40 {
            let (nx, ny) = (1 + case % 7, 1 + case % 5);
            let mut f = still(nx, ny);
            for k in 0..nx * ny {
                f.fluid[k] = next() > 0.3;
                if f.fluid[k] {
                    (f.ux[k], f.uy[k]) = (next() - 0.5, next() - 0.5);
                }
            }
            let side = |next: &mut dyn FnMut() -> f64| -> (Vec<f64>, Vec<bool>) {
                (0..ny).map(|_| (next() - 0.5, next() > 0.3)).unzip()
            };
            let (w, e) = (side(&mut next), side(&mut next));
            for (west, east) in [(false, false), (true, false), (false, true), (true, true)] {
                let a = west.then_some((w.0.as_slice(), w.1.as_slice()));
                let b = east.then_some((e.0.as_slice(), e.1.as_slice()));
                let got: Vec<u64> = f.vorticity_with(a, b).iter().map(|v| v.to_bits()).collect();
                let want: Vec<u64> = reference(&f, a, b).iter().map(|v| v.to_bits()).collect();
                assert_eq!(got, want, "case {case}, west {west}, east {east}");
            }
        }
    }
}
