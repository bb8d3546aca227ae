//! Moving solid surfaces that live outside the fluid core (grains, see `coupling/`), as
//! plain cell lists the core executes after a sweep. Nothing here knows about grains: a
//! plan names cells, links, wall velocities and solid fractions in lattice units, and the
//! backend (this file for the CPU, `gpu/` for a device) recomputes those cells and reports
//! the momentum each link or solid share received, in plan order.
//!
//! * [`LinkPlan`]: fluid cells next to a moving surface, each with the links that come from
//!   it: half-way (Ladd 1994) or interpolated (Bouzidi, Firdaouss & Lallemand 2001)
//!   bounce-back with the moving-wall term.
//! * [`PsmPlan`]: partially saturated cells (Noble & Torczynski 1998), each with its solid
//!   shares (weight B_s and solid velocity).
//! * [`Refill`]: a cell a surface has just uncovered, rebuilt from its fluid neighbours.
//! * rest fills (equilibrium at ρ = 1 and a given velocity) and cell momenta.

use super::collision::{equilibrium, Collider, Moments};
use super::d2q9::{CX, CY, OPP, Q};
use super::lattice::{is_plain, Lattice};
use super::real::Real;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// One link of a fluid cell to a moving surface: population `dir` enters the cell from its
/// solid neighbour at x − c_dir.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MovingLink {
    /// The incoming population (1..=8).
    pub dir: u8,
    /// Where the link meets the surface, as a fraction of the link from the cell centre
    /// (½: half-way bounce-back). Below ½ the post-collision value of the fluid neighbour
    /// at x + c_dir is interpolated, so the planner must give ½ where that neighbour is not
    /// plain fluid outside every surface.
    pub q: f64,
    /// Ladd's moving-wall term 2 w_i ρ_w (c_i·u_w)/c_s², ρ_w = 1 (Ladd 1994, eq. 3.3).
    pub wall: f64,
}

/// Fluid cells next to moving surfaces with their links, compressed by cell: the links of
/// `cells[c]` are `links[start[c]..start[c + 1]]`. Cells are padded indices of interior
/// plain-fluid cells, each at most once, grouped by row: row y's are
/// `cells[rows[y]..rows[y + 1]]` (any order within a row).
#[derive(Debug, Clone, Default)]
pub struct LinkPlan {
    /// Offsets of each row's cells (ny + 1 values; empty for an empty plan).
    pub rows: Vec<u32>,
    /// Padded cell indices.
    pub cells: Vec<u32>,
    /// Offsets into `links`, one more than `cells`.
    pub start: Vec<u32>,
    /// The links, cell by cell.
    pub links: Vec<MovingLink>,
}

impl LinkPlan {
    /// Empty the plan, keeping its allocations.
    pub fn clear(&mut self) {
        self.rows.clear();
        self.cells.clear();
        self.start.clear();
        self.start.push(0);
        self.links.clear();
    }
}

/// One solid's share of a partially saturated cell.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SolidShare {
    /// Its weight B_s in the collision (the cell's B split by solid fraction).
    pub b: f64,
    /// Velocity of the solid at the cell centre (lattice units).
    pub velocity: [f64; 2],
}

/// Partially saturated cells with their solid shares, compressed and grouped by row like
/// [`LinkPlan`].
#[derive(Debug, Clone, Default)]
pub struct PsmPlan {
    /// Offsets of each row's cells (ny + 1 values; empty for an empty plan).
    pub rows: Vec<u32>,
    /// Padded cell indices (interior plain fluid, each at most once).
    pub cells: Vec<u32>,
    /// Offsets into `shares`, one more than `cells`.
    pub start: Vec<u32>,
    /// Total weight B of each cell (Noble & Torczynski 1998, eq. 9).
    pub total: Vec<f64>,
    /// The shares, cell by cell.
    pub shares: Vec<SolidShare>,
}

impl PsmPlan {
    /// Empty the plan, keeping its allocations.
    pub fn clear(&mut self) {
        self.rows.clear();
        self.cells.clear();
        self.start.clear();
        self.start.push(0);
        self.total.clear();
        self.shares.clear();
    }
}

/// A cell that a moving surface has just uncovered, to be rebuilt.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Refill {
    /// Padded cell index.
    pub cell: u32,
    /// Bit i set: the neighbour at x + c_i is fluid to average the density from.
    pub neighbours: u16,
    /// Direction of the neighbour whose non-equilibrium part is copied (Caiazzo 2005), or 0
    /// for the equilibrium alone.
    pub extrapolate: u8,
    /// Velocity of the surface at the cell (lattice units).
    pub velocity: [f64; 2],
}

/// A raw pointer shared by rayon tasks that write disjoint elements.
#[derive(Clone, Copy)]
struct Disjoint<T>(*mut T);
// SAFETY: every task writes elements no other task touches (see each use).
unsafe impl<T> Send for Disjoint<T> {}
unsafe impl<T> Sync for Disjoint<T> {}

impl<T> Disjoint<T> {
    /// Write `v` at `i`.
    ///
    /// # Safety
    /// `i` is in bounds and no other task reads or writes it during the parallel pass.
    #[inline(always)]
    unsafe fn write(&self, i: usize, v: T) {
        *self.0.add(i) = v;
    }
}

/// Shifted equilibrium at ρ = 1 + δρ and velocity u (f64).
#[inline]
pub fn equilibrium_at(drho: f64, u: [f64; 2]) -> [f64; Q] {
    equilibrium(&Moments {
        drho,
        rho: 1.0 + drho,
        ux: u[0],
        uy: u[1],
    })
}

/// Σ h_i c_i of shifted populations.
#[inline]
pub fn momentum_of(h: &[f64; Q]) -> [f64; 2] {
    let mut j = [0.0; 2];
    for i in 1..Q {
        j[0] += h[i] * CX[i] as f64;
        j[1] += h[i] * CY[i] as f64;
    }
    j
}

/// Cells of moving surfaces that a sweep recomputes right after it has swept their row (the
/// data is still in cache), with where the momenta go.
pub enum MovingCells<'a> {
    /// Nothing to recompute.
    None,
    /// Links to moving surfaces; `momentum[l]` receives f*_ī + f_i of link l (seed eq. 5.47:
    /// the surface gets −that × c_i; shifted populations, so the rest state's part is left
    /// out).
    Links(&'a LinkPlan, &'a mut Vec<f64>),
    /// Partially saturated cells (Noble & Torczynski 1998, eqs. 8–9; seed eqs. 5.53–5.54):
    /// f_i ← (1 − B) f_i^fluid-collided + Σ_s B_s (f_i + Ω^s_i); `momentum[s]` receives the
    /// momentum solid share s takes from the fluid (−Σ_i B_s Ω^s_i c_i).
    Partial(&'a PsmPlan, &'a mut Vec<[f64; 2]>),
}

/// A plan being executed by one sweep.
pub(crate) struct MovingRun<'a> {
    kind: RunKind<'a>,
    /// Plan index of the first cell that went bad (usize::MAX: none).
    bad: AtomicUsize,
    /// Local x of the columns next to exchanged faces (swept after the halo arrives).
    edge: [Option<usize>; 2],
}

enum RunKind<'a> {
    Links(&'a LinkPlan, Disjoint<f64>),
    Partial(&'a PsmPlan, Disjoint<[f64; 2]>),
}

impl<'a> MovingRun<'a> {
    /// Prepare `cells` for a sweep of a slab whose exchanged edge columns are `edge`;
    /// `None` when there is nothing to do.
    pub(crate) fn new(cells: &'a mut MovingCells<'_>, edge: [Option<usize>; 2]) -> Option<Self> {
        let kind = match cells {
            MovingCells::None => return None,
            MovingCells::Links(plan, m) => {
                m.clear();
                m.resize(plan.links.len(), 0.0);
                RunKind::Links(plan, Disjoint(m.as_mut_ptr()))
            }
            MovingCells::Partial(plan, m) => {
                m.clear();
                m.resize(plan.shares.len(), [0.0; 2]);
                RunKind::Partial(plan, Disjoint(m.as_mut_ptr()))
            }
        };
        Some(Self {
            kind,
            bad: AtomicUsize::new(usize::MAX),
            edge,
        })
    }

    /// Recompute the plan's cells of row `y` from `src` into `dst`, with the collider `c`:
    /// those off the exchanged edge columns (`edge_pass = false`) or on them (`true`).
    ///
    /// # Safety
    /// `dst` is the sweep's destination buffer and row `y` of it belongs to the calling
    /// task; every plan cell is listed once.
    pub(crate) unsafe fn row<T: Real, C: Collider<T>>(
        &self,
        lat: &Lattice<T>,
        c: &C,
        src: &[T],
        dst: *mut T,
        y: usize,
        edge_pass: bool,
    ) {
        let (rows, cells) = match &self.kind {
            RunKind::Links(p, _) => (&p.rows, &p.cells),
            RunKind::Partial(p, _) => (&p.rows, &p.cells),
        };
        if rows.is_empty() {
            return;
        }
        let dst = Disjoint(dst);
        for n in rows[y] as usize..rows[y + 1] as usize {
            let k = cells[n] as usize;
            let x = k % lat.stride - 1;
            if self.edge.contains(&Some(x)) != edge_pass {
                continue;
            }
            let ok = match &self.kind {
                RunKind::Links(p, m) => link_cell(lat, c, src, dst, p, *m, n),
                RunKind::Partial(p, m) => partial_cell(lat, c, src, dst, p, *m, n),
            };
            if !ok {
                self.bad.fetch_min(n, Ordering::Relaxed);
            }
        }
    }

    /// Plan index of the first cell that went bad, if any.
    pub(crate) fn first_bad(&self) -> Option<usize> {
        let b = self.bad.load(Ordering::Relaxed);
        (b != usize::MAX).then_some(b)
    }

    /// The plan's cells.
    pub(crate) fn cells(&self) -> &[u32] {
        match &self.kind {
            RunKind::Links(p, _) => &p.cells,
            RunKind::Partial(p, _) => &p.cells,
        }
    }
}

/// Pre-collision populations of interior fluid cell `k` (padded) pulled from `src`: a plain
/// pull where every neighbour is plain fluid, the lattice's own wall and open-face rules
/// otherwise.
#[inline]
fn pull<T: Real>(lat: &Lattice<T>, src: &[T], k: usize) -> [T; Q] {
    if is_plain(&lat.types, lat.stride, k) {
        let s = lat.stride as isize;
        std::array::from_fn(|i| {
            src[i * lat.plane + (k as isize - CX[i] as isize - CY[i] as isize * s) as usize]
        })
    } else {
        let (x, y) = (k % lat.stride - 1, k / lat.stride - 1);
        let acc =
            super::boundary::Access::new(super::lattice::Layout::TwoArray, lat.plane, lat.stride);
        lat.gather_special(super::boundary::Src::of(src), acc, x, y, None)
    }
}

/// Recompute link-plan cell `n`; false when its density went NaN or non-positive.
///
/// # Safety
/// As [`MovingRun::row`]; the link slots of cell `n` belong to the caller.
#[inline]
unsafe fn link_cell<T: Real, C: Collider<T>>(
    lat: &Lattice<T>,
    c: &C,
    src: &[T],
    dst: Disjoint<T>,
    plan: &LinkPlan,
    mom: Disjoint<f64>,
    n: usize,
) -> bool {
    let (plane, k) = (lat.plane, plan.cells[n] as usize);
    let mut h = pull(lat, src, k);
    let first = plan.start[n] as usize;
    for (l, link) in plan.links[first..plan.start[n + 1] as usize]
        .iter()
        .enumerate()
    {
        let i = link.dir as usize;
        let out_i = src[OPP[i] * plane + k].to_f64();
        let q = link.q;
        let hi = if q == 0.5 {
            // Half-way bounce-back on a moving wall (Ladd 1994, eq. 3.3).
            out_i + link.wall
        } else if q < 0.5 {
            // Bouzidi, Firdaouss & Lallemand 2001, eq. 5 (q < ½), moving wall.
            let ff = (k as isize + CX[i] as isize + CY[i] as isize * lat.stride as isize) as usize;
            2.0 * q * out_i + (1.0 - 2.0 * q) * src[OPP[i] * plane + ff].to_f64() + link.wall
        } else {
            // Bouzidi et al. 2001, eq. 5 (q ≥ ½).
            let same = src[i * plane + k].to_f64();
            (out_i + (2.0 * q - 1.0) * same + link.wall) / (2.0 * q)
        };
        h[i] = T::from_f64(hi);
        mom.write(first + l, out_i + h[i].to_f64());
    }
    let m = c.collide(&mut h);
    for (i, v) in h.iter().enumerate() {
        dst.write(i * plane + k, *v);
    }
    m.rho > T::default()
}

/// Recompute partially saturated plan cell `n`; false when its density went NaN or
/// non-positive.
///
/// # Safety
/// As [`MovingRun::row`]; the share slots of cell `n` belong to the caller.
#[inline]
unsafe fn partial_cell<T: Real, C: Collider<T>>(
    lat: &Lattice<T>,
    c: &C,
    src: &[T],
    dst: Disjoint<T>,
    plan: &PsmPlan,
    mom: Disjoint<[f64; 2]>,
    n: usize,
) -> bool {
    let (plane, k) = (lat.plane, plan.cells[n] as usize);
    let h = pull(lat, src, k);
    let hf: [f64; Q] = h.map(|v| v.to_f64());
    let b_total = plan.total[n];
    let mut post = h;
    let m = c.collide(&mut post);
    let m64 = Moments {
        drho: m.drho.to_f64(),
        rho: m.rho.to_f64(),
        ux: m.ux.to_f64(),
        uy: m.uy.to_f64(),
    };
    let eq_fluid = equilibrium(&m64);
    let mut new: [f64; Q] = std::array::from_fn(|i| (1.0 - b_total) * post[i].to_f64());
    let first = plan.start[n] as usize;
    for (s, share) in plan.shares[first..plan.start[n + 1] as usize]
        .iter()
        .enumerate()
    {
        let eq_solid = equilibrium(&Moments {
            ux: share.velocity[0],
            uy: share.velocity[1],
            ..m64
        });
        let mut p = [0.0; 2];
        for i in 0..Q {
            let j = OPP[i];
            // Noble & Torczynski 1998, eq. 8:
            // Ω^s_i = [f_ī − f^eq_ī(ρ, u)] − [f_i − f^eq_i(ρ, u_s)].
            let omega_s = (hf[j] - eq_fluid[j]) - (hf[i] - eq_solid[i]);
            new[i] += share.b * (hf[i] + omega_s);
            p[0] += share.b * omega_s * CX[i] as f64;
            p[1] += share.b * omega_s * CY[i] as f64;
        }
        mom.write(first + s, [-p[0], -p[1]]);
    }
    let rho = 1.0 + new.iter().sum::<f64>();
    for (i, v) in new.iter().enumerate() {
        dst.write(i * plane + k, T::from_f64(*v));
    }
    rho > 0.0
}

impl<T: Real> Lattice<T> {
    /// Density of padded cell `k` in the current state.
    pub(crate) fn density_at(&self, k: usize) -> f64 {
        let buf = self.current_buffer();
        1.0 + (0..Q)
            .map(|i| buf[i * self.plane + k].to_f64())
            .sum::<f64>()
    }

    /// Set each of `cells` (padded, each at most once) in the current buffer to the
    /// equilibrium at ρ = 1 and the matching velocity (the fluid at rest inside a solid).
    pub fn set_rest(&mut self, cells: &[u32], velocity: &[[f64; 2]]) {
        let plane = self.plane;
        let buf = Disjoint(self.buf[self.cur].as_mut_ptr());
        cells
            .par_iter()
            .zip(velocity.par_iter())
            .with_min_len(1024)
            .for_each(|(&k, &u)| {
                let eq = equilibrium_at(0.0, u);
                for (i, v) in eq.iter().enumerate() {
                    // SAFETY: each cell is listed once.
                    unsafe { buf.write(i * plane + k as usize, T::from_f64(*v)) };
                }
            });
    }

    /// Σ h_i c_i of each of `cells` (padded) in the current buffer.
    pub fn momentum_of_cells(&self, cells: &[u32], out: &mut Vec<[f64; 2]>) {
        let buf = self.current_buffer();
        out.clear();
        out.extend(cells.iter().map(|&k| {
            let h: [f64; Q] = std::array::from_fn(|i| buf[i * self.plane + k as usize].to_f64());
            momentum_of(&h)
        }));
    }

    /// Rebuild each cell of `refills` as [`refill_cell`] says. `momentum[r]` receives
    /// Σ h_i c_i of the new cell. Precondition: no refilled cell is a listed neighbour of
    /// another.
    pub fn apply_refills(&mut self, refills: &[Refill], momentum: &mut Vec<[f64; 2]>) {
        let (plane, stride) = (self.plane, self.stride);
        momentum.clear();
        let buf = &mut self.buf[self.cur];
        for r in refills {
            let h = refill_cell(r, stride, |m| {
                std::array::from_fn(|j| buf[j * plane + m].to_f64())
            });
            let mut stored = [0.0; Q];
            for i in 0..Q {
                let v = T::from_f64(h[i]);
                buf[i * plane + r.cell as usize] = v;
                stored[i] = v.to_f64();
            }
            momentum.push(momentum_of(&stored));
        }
    }
}

/// The padded cells a refill reads: its listed neighbours and the extrapolation source.
pub fn refill_sources(r: &Refill, stride: usize) -> impl Iterator<Item = usize> {
    let (k, mask, ex) = (r.cell as isize, r.neighbours, r.extrapolate as usize);
    (1..Q)
        .filter(move |&i| mask & (1 << i) != 0 || ex == i)
        .map(move |i| (k + CX[i] as isize + CY[i] as isize * stride as isize) as usize)
}

/// The populations of a cell a moving surface uncovered (f64, before rounding to the
/// lattice's precision): the equilibrium at its surface velocity and the mean density of
/// its listed fluid neighbours, plus (where `extrapolate` names one) that neighbour's
/// non-equilibrium part (Caiazzo 2005). `cell(m)` gives padded cell m's populations.
pub fn refill_cell(r: &Refill, stride: usize, cell: impl Fn(usize) -> [f64; Q]) -> [f64; Q] {
    let k = r.cell as isize;
    let nbr = |i: usize| (k + CX[i] as isize + CY[i] as isize * stride as isize) as usize;
    let (mut sum, mut n) = (0.0, 0);
    for i in 1..Q {
        if r.neighbours & (1 << i) != 0 {
            sum += 1.0 + cell(nbr(i)).iter().sum::<f64>();
            n += 1;
        }
    }
    let rho = if n > 0 { sum / n as f64 } else { 1.0 };
    let mut h = equilibrium_at(rho - 1.0, r.velocity);
    if r.extrapolate != 0 {
        // Caiazzo 2005: f = f^eq(ρ̄, u_s) + f^neq of the neighbour along the normal.
        let hm = cell(nbr(r.extrapolate as usize));
        let drho: f64 = hm.iter().sum();
        let j = momentum_of(&hm);
        let eq_m = equilibrium_at(drho, [j[0] / (1.0 + drho), j[1] / (1.0 + drho)]);
        for i in 0..Q {
            h[i] += hm[i] - eq_m[i];
        }
    }
    h
}
