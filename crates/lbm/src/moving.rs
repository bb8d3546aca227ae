//! Moving solid surfaces that live outside the fluid core (grains, see `coupling/`), as
//! plain cell lists the core executes with a sweep. Nothing here knows about grains: a
//! plan names cells, links, rigid motions and solid fractions in lattice units, and the
//! backend (this file, `partial.rs` and `bulk_aa.rs` for the CPU, `gpu/` for a device)
//! recomputes those cells and reports the momentum each link or solid share received, in
//! plan order.
//!
//! * [`LinkPlan`]: fluid cells next to a moving surface, each with the links that come from
//!   it: half-way (Ladd 1994) or interpolated (Bouzidi, Firdaouss & Lallemand 2001)
//!   bounce-back with the moving-wall term.
//! * [`PsmPlan`]: partially saturated cells (Noble & Torczynski 1998), each with its solid
//!   shares (weight B_s and the rigid body whose velocity at the cell centre is the
//!   solid's).
//! * [`Refill`]: a cell a surface has just uncovered, rebuilt from its fluid neighbours.
//! * rest fills (equilibrium at ρ = 1 and a given velocity) and cell momenta.

use super::aligned::Disjoint;
use super::boundary::{pull, Access, Src};
use super::collision::{equilibrium, Collider, Moments};
use super::d2q9::{CX, CY, OPP, Q};
use super::lattice::{Lattice, Layout};
use super::partial::{partial_cell, PartialSweep, ShareSums};
use super::real::Real;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

pub use super::plans::{
    cell_centre, BodyColumns, LinkPlan, MovingLink, PlanKind, PsmPlan, Refill, RigidMotion,
    SolidShare, NO_SLOT,
};

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

/// Cells of moving surfaces that a sweep computes with their row (in place: link cells
/// prepared just ahead of it, partially saturated cells inside it) or right after it (two
/// arrays: the data is still in cache), with where the momenta go: one per link or share, or
/// (a backend that can, when the [`BodyColumns`] ask for it) summed per body and column.
pub enum MovingCells<'a> {
    /// Nothing to recompute.
    None,
    /// Links to moving surfaces; `momentum[l]` receives f*_ī + f_i of link l (seed eq. 5.47:
    /// the surface gets −that × c_i; shifted populations, so the rest state's part is left
    /// out).
    Links(&'a LinkPlan, &'a mut Vec<f64>, &'a mut BodyColumns),
    /// Partially saturated cells (Noble & Torczynski 1998, eqs. 8–9; seed eqs. 5.53–5.54):
    /// f_i ← (1 − B) f_i^fluid-collided + Σ_s B_s (f_i + Ω^s_i); `momentum[s]` receives the
    /// momentum solid share s takes from the fluid (−Σ_i B_s Ω^s_i c_i).
    Partial(&'a PsmPlan, &'a mut Vec<[f64; 2]>, &'a mut BodyColumns),
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
    Partial(&'a PsmPlan, Disjoint<[f64; 2]>, Option<ShareSums<'a>>),
}

impl<'a> MovingRun<'a> {
    /// Prepare `cells` for a sweep of a slab whose exchanged edge columns are `edge`;
    /// `None` when there is nothing to do. With `sum_block` (a sweep by blocks of that many
    /// rows, each block's rows in increasing order by one task), partially saturated cells
    /// whose [`BodyColumns`] ask for sums also add the loads of every body whose box lies in
    /// one block, and is its group's only body, to those sums (see
    /// [`MovingRun::sum_block`]); the host collects the other bodies' shares from their
    /// momenta, as without.
    pub(crate) fn new(
        cells: &'a mut MovingCells<'_>,
        edge: [Option<usize>; 2],
        sum_block: Option<usize>,
    ) -> Option<Self> {
        let kind = match cells {
            MovingCells::None => return None,
            // The sweep writes every link's and share's momentum before anything reads it,
            // so the slots kept from the last step are not zeroed (a serial pass over
            // megabytes each step); only new ones are.
            MovingCells::Links(plan, m, sums) => {
                sums.made = false;
                m.resize(plan.links.len(), 0.0);
                RunKind::Links(plan, Disjoint(m.as_mut_ptr()))
            }
            MovingCells::Partial(plan, m, sums) => {
                sums.made = false;
                let sums: &'a mut BodyColumns = sums;
                let summed = sum_block.filter(|_| sums.wanted()).map(|h| {
                    // Every slot starts at +0.0 (the sweep adds its first load to that),
                    // zeroed in parallel: filled serially, the slots (about a megabyte on
                    // the Table 5.3 case) kept one thread busy and the others idle.
                    let n = sums.slots();
                    sums.sums.resize(n, [0.0; 3]);
                    sums.counts.resize(n, 0);
                    zero(&mut sums.sums);
                    zero(&mut sums.counts);
                    block_slots(sums, h);
                    let (s, c) = (sums.sums.as_mut_ptr(), sums.counts.as_mut_ptr());
                    let cols: &'a BodyColumns = sums;
                    ShareSums {
                        sums: Disjoint(s),
                        counts: Disjoint(c),
                        body_slot: &cols.body_slot,
                        boxes: &cols.boxes,
                        block: h,
                    }
                });
                m.resize(plan.shares.len(), [0.0; 2]);
                RunKind::Partial(plan, Disjoint(m.as_mut_ptr()), summed)
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
        let (src, acc) = (
            Src::of(src),
            Access::new(Layout::TwoArray, lat.plane, lat.stride),
        );
        let dst = Disjoint(dst);
        for n in self.row_cells(lat, y, edge_pass) {
            let (h, ok) = self.cell(lat, c, src, acc, n, y);
            let k = self.cells()[n] as usize;
            for (i, v) in h.iter().enumerate() {
                dst.write(i * lat.plane + k, *v);
            }
            if !ok {
                self.bad.fetch_min(n, Ordering::Relaxed);
            }
        }
    }

    /// In place, before the sweep overwrites the values they read: give the link cells of
    /// row `y` (on the exchanged edge columns when `edge_pass`, the others otherwise) their
    /// bounced-back populations (from the step's start state in `base`, read through `acc`)
    /// in the slots they pull them from, where the sweep then collides them with the rest of
    /// their row: the same values as [`MovingRun::row`] from two arrays. Partially saturated
    /// cells need nothing here: the sweep computes them ([`PartialSweep`]).
    ///
    /// # Safety
    /// Nothing has yet written the slots of rows y − 1 to y + 1 in this step.
    pub(crate) unsafe fn precompute_row<T: Real>(
        &self,
        lat: &Lattice<T>,
        base: *mut T,
        acc: Access,
        y: usize,
        edge_pass: bool,
    ) {
        let src = Src(base as *const T);
        if let RunKind::Links(p, m) = &self.kind {
            for n in self.row_cells(lat, y, edge_pass) {
                let k = p.cells[n] as usize;
                // Only cell k reads these slots (its pulled populations from the covered
                // cells), and only when it is swept.
                bounce_links(lat, src, acc, p, *m, n, y, |i, v| {
                    *base.add(acc.pulled(i, k)) = v
                });
            }
        }
    }

    /// Ask for the cache lines that computing row `y`'s plan cells will read (each cell's
    /// column in rows y − 1 to y + 1 of every direction's plane of `base`): these cells
    /// are scattered, so the hardware's stream prefetchers do not fetch them.
    pub(crate) fn prefetch_row<T: Real>(&self, lat: &Lattice<T>, base: *const T, y: usize) {
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (lat, base, y);
        #[cfg(target_arch = "x86_64")]
        {
            let (rows, cells) = match &self.kind {
                RunKind::Links(p, _) => (&p.rows, &p.cells),
                RunKind::Partial(..) => return,
            };
            if rows.is_empty() || y >= lat.ny {
                return;
            }
            // Planes are padded to 16 values, so every plane has the same 64-byte line
            // phase: a cell whose line (in each of the three rows) was just asked for
            // needs no new request. Neighbouring plan cells often share lines.
            let per_line = (64 / std::mem::size_of::<T>()).max(1) as isize;
            let mut last = [isize::MIN; 3];
            for &k in &cells[rows[y] as usize..rows[y + 1] as usize] {
                for (j, dy) in [-1isize, 0, 1].into_iter().enumerate() {
                    let at = k as isize + dy * lat.stride as isize;
                    if at.div_euclid(per_line) == last[j] {
                        continue;
                    }
                    last[j] = at.div_euclid(per_line);
                    for i in 0..Q {
                        let at = (i * lat.plane) as isize + at;
                        // SAFETY: a prefetch is a hint; it does not access memory
                        // architecturally.
                        unsafe {
                            std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
                                base.wrapping_offset(at) as *const i8,
                            )
                        };
                    }
                }
            }
        }
    }

    /// In place, in the task that has just swept row `y` and found it bad: check the
    /// density of the row's link cells (edge columns or not, as `edge_pass`), to name the
    /// first bad one and its surface.
    ///
    /// # Safety
    /// `base` is the lattice's one buffer; the slots of row `y`'s cells belong to the
    /// calling task.
    pub(crate) unsafe fn check_row<T: Real>(
        &self,
        lat: &Lattice<T>,
        base: *const T,
        acc: Access,
        y: usize,
        edge_pass: bool,
    ) {
        if !self.precomputes() {
            return;
        }
        for n in self.row_cells(lat, y, edge_pass) {
            let k = self.cells()[n] as usize;
            let rho = 1.0
                + (0..Q)
                    .map(|j| (*base.add(acc.store(j, k))).to_f64())
                    .sum::<f64>();
            if !(rho > 0.0) {
                self.bad.fetch_min(n, Ordering::Relaxed);
            }
        }
    }

    /// Plan indices of row `y`'s cells off the exchanged edge columns (`edge_pass = false`)
    /// or on them.
    #[inline]
    fn row_cells<'s, T: Real>(
        &'s self,
        lat: &Lattice<T>,
        y: usize,
        edge_pass: bool,
    ) -> impl Iterator<Item = usize> + 's {
        let (rows, cells) = match &self.kind {
            RunKind::Links(p, _) => (&p.rows, &p.cells),
            RunKind::Partial(p, ..) => (&p.rows, &p.cells),
        };
        let range = if rows.is_empty() {
            0..0
        } else {
            rows[y] as usize..rows[y + 1] as usize
        };
        // Local x of padded k in row y, without a division.
        let row0 = (y + 1) * lat.stride + 1;
        range.filter(move |&n| {
            let x = cells[n] as usize - row0;
            self.edge.contains(&Some(x)) == edge_pass
        })
    }

    /// The new values of plan cell `n` (in local row `y`) and whether its density stayed
    /// positive.
    ///
    /// # Safety
    /// As [`MovingRun::row`]: the momentum slots of cell `n` belong to the caller.
    #[inline]
    unsafe fn cell<T: Real, C: Collider<T>>(
        &self,
        lat: &Lattice<T>,
        c: &C,
        src: Src<T>,
        acc: Access,
        n: usize,
        y: usize,
    ) -> ([T; Q], bool) {
        match &self.kind {
            RunKind::Links(p, m) => link_cell(lat, c, src, acc, p, *m, n, y),
            RunKind::Partial(p, m, _) => partial_cell(lat, c, src, acc, p, *m, n),
        }
    }

    /// Whether an in-place sweep prepares the plan's cells ahead of it (link cells, see
    /// [`MovingRun::precompute_row`]) rather than computing them itself (partially
    /// saturated cells, see [`MovingRun::partial_sweep`]).
    pub(crate) fn precomputes(&self) -> bool {
        matches!(self.kind, RunKind::Links(..))
    }

    /// The partially saturated cells, for a sweep that computes them itself in a lattice
    /// of row stride `stride`.
    pub(crate) fn partial_sweep(&self, stride: usize) -> Option<PartialSweep<'_>> {
        match &self.kind {
            RunKind::Partial(plan, mom, sums) => {
                Some(PartialSweep::new(plan, stride, *mom, *sums, &self.bad))
            }
            RunKind::Links(..) => None,
        }
    }

    /// The rows per block when the sweep adds some shares' loads to the plan's per-body
    /// column sums itself (it then goes by those blocks, and the caller marks the sums
    /// made), or `None`.
    pub(crate) fn sum_block(&self) -> Option<usize> {
        match &self.kind {
            RunKind::Partial(_, _, Some(t)) => Some(t.block),
            _ => None,
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
            RunKind::Partial(p, ..) => &p.cells,
        }
    }
}

/// Set every entry of `v` to its default, in parallel.
fn zero<V: Default + Copy + Send>(v: &mut [V]) {
    v.par_chunks_mut(1 << 13).for_each(|c| c.fill(V::default()));
}

/// Fill `cols.body_slot` for a sweep by blocks of `h` rows: a body whose box lies in one
/// block and is its group's only body gets its slot of local column 0 (each of its slots
/// then has one task, which adds the column's cells in increasing row); any other body gets
/// [`NO_SLOT`] (a group's bodies, or a box across blocks, would be added to by two tasks;
/// the host collects them).
fn block_slots(cols: &mut BodyColumns, h: usize) {
    // Which bodies get a slot, found in parallel (a serial walk over every group kept the
    // other threads idle), then set.
    let found: Vec<(u32, i64)> = {
        let cols: &BodyColumns = cols;
        (0..cols.groups.len().saturating_sub(1))
            .into_par_iter()
            .with_min_len(1024)
            .filter_map(|j| {
                let &[b] = cols.group(j) else {
                    return None;
                };
                let bx = cols.boxes[b as usize];
                let (first, last) = (bx[2] as usize, (bx[2] + bx[3]).max(1) as usize - 1);
                if first / h != last / h {
                    return None;
                }
                let columns = cols.columns(j);
                // The group's slots are its columns (the writes through `ShareSums` rely
                // on it).
                assert_eq!(
                    cols.first[j + 1] - cols.first[j],
                    columns[1],
                    "group {j}'s slots are not its columns"
                );
                Some((b, cols.first[j] as i64 - columns[0] as i64))
            })
            .collect()
    };
    cols.body_slot.clear();
    cols.body_slot.resize(cols.boxes.len(), NO_SLOT);
    for (b, slot) in found {
        cols.body_slot[b as usize] = slot;
    }
}

/// The new values of link-plan cell `n` (its links bounced back, then collided) and whether
/// its density stayed positive.
///
/// # Safety
/// As [`MovingRun::row`]; the link slots of cell `n` belong to the caller.
#[allow(clippy::too_many_arguments)]
#[inline]
unsafe fn link_cell<T: Real, C: Collider<T>>(
    lat: &Lattice<T>,
    c: &C,
    src: Src<T>,
    acc: Access,
    plan: &LinkPlan,
    mom: Disjoint<f64>,
    n: usize,
    y: usize,
) -> ([T; Q], bool) {
    let mut h = pull(lat, src, acc, plan.cells[n] as usize);
    bounce_links(lat, src, acc, plan, mom, n, y, |i, v| h[i] = v);
    let m = c.collide(&mut h);
    (h, m.rho > T::default())
}

/// The populations that enter link-plan cell `n` (in local row `y`) from the surface, one
/// call `set(i, h_i)` per link (in the lattice's precision), each link's momentum
/// f*_ī + h_i recorded.
/// Reads only slots of the cell's neighbours and the cell's own non-link slots.
///
/// # Safety
/// As [`MovingRun::row`]; the link slots of cell `n` belong to the caller.
#[allow(clippy::too_many_arguments)]
#[inline]
unsafe fn bounce_links<T: Real>(
    lat: &Lattice<T>,
    src: Src<T>,
    acc: Access,
    plan: &LinkPlan,
    mom: Disjoint<f64>,
    n: usize,
    y: usize,
    mut set: impl FnMut(usize, T),
) {
    let k = plan.cells[n] as usize;
    let first = plan.start[n] as usize;
    for (l, &link) in plan.links[first..plan.start[n + 1] as usize]
        .iter()
        .enumerate()
    {
        let i = link.dir();
        let out_i = src.get(acc.own(OPP[i], k)).to_f64();
        let wall = plan.wall(lat.stride, k, y, link);
        let q = plan.q(first + l);
        let hi = if q == 0.5 {
            // Half-way bounce-back on a moving wall (Ladd 1994, eq. 3.3).
            out_i + wall
        } else if q < 0.5 {
            // Bouzidi, Firdaouss & Lallemand 2001, eq. 5 (q < ½), moving wall.
            let ff = (k as isize + CX[i] as isize + CY[i] as isize * lat.stride as isize) as usize;
            2.0 * q * out_i + (1.0 - 2.0 * q) * src.get(acc.own(OPP[i], ff)).to_f64() + wall
        } else {
            // Bouzidi et al. 2001, eq. 5 (q ≥ ½).
            let same = src.get(acc.own(i, k)).to_f64();
            (out_i + (2.0 * q - 1.0) * same + wall) / (2.0 * q)
        };
        let v = T::from_f64(hi);
        set(i, v);
        mom.write(first + l, out_i + v.to_f64());
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
