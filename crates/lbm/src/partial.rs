//! Partially saturated cells (Noble & Torczynski 1998; seed eqs. 5.53–5.54): the blend of a
//! cell's fluid collision with the solids' that share it, one cell at a time after a
//! two-array sweep ([`partial_cell`]), or inside an in-place sweep from the values it has
//! just loaded and collided ([`PartialSweep`]). Both give the same bits.

use super::aligned::Disjoint;
use super::boundary::pull;
use super::boundary::{Access, Src};
use super::collision::{Collider, Moments};
use super::d2q9::{by_direction, each_direction, OPP, Q, W};
use super::lanes::Simd;
use super::lattice::Lattice;
use super::plans::{PsmPlan, NO_SLOT};
use super::real::Real;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The new values of partially saturated plan cell `n` and whether its density stayed
/// positive.
///
/// # Safety
/// As `MovingRun::row`: the share slots of cell `n` belong to the caller.
#[inline]
pub(crate) unsafe fn partial_cell<T: Real, C: Collider<T>>(
    lat: &Lattice<T>,
    c: &C,
    src: Src<T>,
    acc: Access,
    plan: &PsmPlan,
    mom: Disjoint<[f64; 2]>,
    n: usize,
) -> ([T; Q], bool) {
    let h = pull(lat, src, acc, plan.cells[n] as usize);
    let mut post = h;
    let m = c.collide(&mut post);
    blend_partial(plan, lat.stride, mom, n, &h, &post, &m)
}

/// The new values of partially saturated plan cell `n` from its pre-collision populations
/// `h`, their fluid collision `post` and the pre-collision moments `m`, and whether its
/// density stayed positive (Noble & Torczynski 1998, eqs. 8–9; seed eqs. 5.53–5.54):
/// f_i ← (1 − B) post_i + Σ_s B_s (h_i + Ω^s_i), in the lattice's precision like the
/// collision itself; a fully covered cell (B = 1) takes Σ_s B_s h^eq_i(ρ, u_s) instead
/// ([`is_full`]). Each share's momentum goes to `mom`. `stride` is the lattice's row
/// stride (the solids' velocities are taken at the cell centre).
///
/// # Safety
/// The momentum slots of cell `n`'s shares belong to the caller.
#[inline]
pub(crate) unsafe fn blend_partial<T: Real>(
    plan: &PsmPlan,
    stride: usize,
    mom: Disjoint<[f64; 2]>,
    n: usize,
    h: &[T; Q],
    post: &[T; Q],
    m: &Moments<T>,
) -> ([T; Q], bool) {
    let b_total = T::from_f64(plan.total[n]);
    let mut new = fluid_part(post, b_total);
    let full = is_full(b_total);
    let mut solid = [T::default(); Q];
    let first = plan.start[n] as usize;
    let k = plan.cells[n] as usize;
    let y = PsmPlan::row_of(stride, k);
    for (s, &share) in plan.shares[first..plan.start[n + 1] as usize]
        .iter()
        .enumerate()
    {
        let u = plan.velocity(stride, k, y, share).map(T::from_f64);
        let b = T::from_f64(share.b);
        let p = add_share(&mut new, h, m, b, u);
        if full {
            add_solid_equilibrium(&mut solid, m, b, u);
        }
        mom.write(first + s, [-p[0].to_f64(), -p[1].to_f64()]);
    }
    if full {
        new = solid;
    }
    let ok = density_ok(&new);
    (new, ok)
}

/// Whether a cell of total solid weight `b_total` (in the lattice's precision) is fully
/// covered, B = 1 (the map gives a cell inside a disk ε = 1 exactly, and so B = 1).
///
/// Such a cell holds no fluid. Noble & Torczynski's B = 1 limit reflects its
/// non-equilibrium part h_ī − h^eq_ī(ρ, u) in place every step and never relaxes it, so a
/// large covered region keeps undamped oscillations that the grain's motion pumps (a disk
/// of 64 cells per diameter settling at Re ≈ 250 went unstable inside itself). A full cell
/// therefore takes the solids' equilibria Σ_s B_s h^eq_i(ρ, u_s): the same mass and, as
/// that reflected part carries neither (Σ_i (h_ī − h^eq_ī) (1, c_i) = 0), the same momentum
/// as eq. 8 gives the cell; only the non-equilibrium part is dropped. (With a body force F
/// on the fluid, eq. 8's u carries Guo's half-force, so its momentum is ρ u_s + F/2 where the
/// equilibrium's is ρ u_s; the grain is charged eq. 8's exchange either way. No shipped
/// coupled scene puts a body force on the fluid.)
#[inline(always)]
pub(crate) fn is_full<T: Real>(b_total: T) -> bool {
    b_total >= T::from_f64(1.0)
}

/// Add B_s h^eq_i(ρ, u_s) (Qian et al. 1992, eq. 7, at the cell's density) to `solid`: one
/// solid's part of a fully covered cell ([`is_full`]).
#[inline(always)]
pub(crate) fn add_solid_equilibrium<V: Simd>(solid: &mut [V; Q], m: &Moments<V>, b: V, u: [V; 2]) {
    let eq = super::collision::equilibrium(&Moments {
        ux: u[0],
        uy: u[1],
        ..*m
    });
    each_direction!(i => {
        solid[i] = solid[i] + b * eq[i];
    });
}

/// (1 − B) post_i: the fluid's part of a partially saturated cell whose solid weights add
/// up to `b_total` (Noble & Torczynski 1998, eq. 9).
#[inline(always)]
pub(crate) fn fluid_part<V: Simd>(post: &[V; Q], b_total: V) -> [V; Q] {
    let one = V::splat(V::Scalar::from_f64(1.0));
    by_direction!(i => (one - b_total) * post[i])
}

/// Add one solid's part B_s (h_i + Ω^s_i) to `new`, for a solid of weight `b` moving at `u`
/// (Noble & Torczynski 1998, eqs. 8–9), given the cell's pre-collision populations `h` and
/// moments `m`. Returns the momentum the solid gives the fluid, Σ_i B_s Ω^s_i c_i.
///
/// With Ω^s_i = [h_ī − h^eq_ī(ρ, u)] − [h_i − h^eq_i(ρ, u_s)] (eq. 8, in shifted
/// populations, where the weights cancel), h_i + Ω^s_i = h_ī − h^eq_ī(ρ, u) + h^eq_i(ρ, u_s).
/// Each equilibrium splits into a part even in c_i, w_i [δρ + ρ(4.5 (c_i·u)² − 1.5 u²)],
/// and an odd one, 3 w_i ρ c_i·u (Qian et al. 1992, eq. 7); so for a pair of opposite
/// directions i, ī
///   h_i + Ω^s_i = h_ī + E_i + O_i,   h_ī + Ω^s_ī = h_i + E_i − O_i,
/// with E_i = w_i ρ [4.5 ((c_i·u_s)² − (c_i·u)²) − 1.5 (u_s² − u²)] (δρ cancels) and
/// O_i = 3 w_i ρ (c_i·u + c_i·u_s), and Σ_i Ω^s_i c_i = 2 Σ_pairs c_i (h_ī − h_i + O_i).
/// Those are the same sums as the nine directions' equilibria give, in about a third of
/// the operations (the partially saturated kernel is bound by them).
#[inline(always)]
pub(crate) fn add_share<V: Simd>(
    new: &mut [V; Q],
    h: &[V; Q],
    m: &Moments<V>,
    b: V,
    u: [V; 2],
) -> [V; 2] {
    let s = |v: f64| V::splat(V::Scalar::from_f64(v));
    let (uf, us) = ([m.ux, m.uy], u);
    // 1.5 (u_s² − u²) and w_i ρ per weight class.
    let du2 = s(1.5) * ((us[0] * us[0] + us[1] * us[1]) - (uf[0] * uf[0] + uf[1] * uf[1]));
    let (wr0, wr1, wr2) = (s(W[0]) * m.rho, s(W[1]) * m.rho, s(W[5]) * m.rho);
    // Rest direction: h_0 + Ω^s_0 = h_0 + E_0.
    new[0] = new[0] + b * (h[0] - wr0 * du2);
    // c = (1, 0), (0, 1), (1, 1), (−1, 1): directions 1, 2, 5, 6.
    let d1 = add_pair(new, h, b, du2, 1, wr1, uf[0], us[0]);
    let d2 = add_pair(new, h, b, du2, 2, wr1, uf[1], us[1]);
    let d5 = add_pair(new, h, b, du2, 5, wr2, uf[0] + uf[1], us[0] + us[1]);
    let d6 = add_pair(new, h, b, du2, 6, wr2, uf[1] - uf[0], us[1] - us[0]);
    let two_b = s(2.0) * b;
    [two_b * ((d1 + d5) - d6), two_b * ((d2 + d5) + d6)]
}

/// One pair of [`add_share`] (i, ī = `OPP[i]`) with c_i·u = `cf`, c_i·u_s = `cs`, weight
/// w_i ρ = `wr` and 1.5 (u_s² − u²) = `du2`: its E_i and O_i into `new`; returns
/// h_ī − h_i + O_i. A function rather than a closure so that it is always inlined: as a
/// closure LLVM kept it out of line in the lane kernel, with `new` in memory.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn add_pair<V: Simd>(
    new: &mut [V; Q],
    h: &[V; Q],
    b: V,
    du2: V,
    i: usize,
    wr: V,
    cf: V,
    cs: V,
) -> V {
    let s = |v: f64| V::splat(V::Scalar::from_f64(v));
    let j = OPP[i];
    // Qian et al. 1992, eq. 7: the even part E_i and the odd part O_i.
    let e = wr * (s(4.5) * ((cs - cf) * (cs + cf)) - du2);
    let o = s(3.0) * wr * (cf + cs);
    new[i] = new[i] + b * ((h[j] + e) + o);
    new[j] = new[j] + b * ((h[i] + e) - o);
    (h[j] - h[i]) + o
}

/// Whether the density of the shifted populations `new`, 1 + Σ_i new_i (summed in direction
/// order), is positive (false for NaN).
#[inline(always)]
pub(crate) fn density_ok<T: Real>(new: &[T; Q]) -> bool {
    let sum = new.iter().fold(T::from_f64(-0.0), |a, &v| a + v);
    T::from_f64(1.0) + sum > T::default()
}

/// Partially saturated cells that an in-place sweep computes itself, from the values it has
/// just loaded and collided (no second read of their populations): the plan, where the
/// momenta go, and where the first bad cell is recorded.
pub(crate) struct PartialSweep<'a> {
    plan: &'a PsmPlan,
    stride: usize,
    mom: Disjoint<[f64; 2]>,
    sums: Option<ShareSums<'a>>,
    bad: &'a AtomicUsize,
}

/// The per-body column sums ([`super::moving::BodyColumns`]) that a sweep by blocks of rows
/// adds the loads of the bodies that have a slot there to, as it blends each cell, instead
/// of leaving them to the host's collect: each such body lies in one block, whose task
/// sweeps its rows in increasing order, and a slot (a body's column) takes one cell per
/// row, a cell's shares in plan order; so its slots receive the host collect's terms in
/// its order (the column's cells in increasing row) with its arithmetic: the same bits.
#[derive(Clone, Copy)]
pub(crate) struct ShareSums<'a> {
    /// Per slot: p_x, p_y, torque.
    pub(crate) sums: Disjoint<[f64; 3]>,
    /// Per slot: the shares added.
    pub(crate) counts: Disjoint<u32>,
    /// Per body: the slot of local column 0, or `NO_SLOT` (`BodyColumns::body_slot`).
    pub(crate) body_slot: &'a [i64],
    /// Per body: its box (`BodyColumns::boxes`).
    pub(crate) boxes: &'a [[u32; 4]],
    /// Rows per block of the sweep.
    pub(crate) block: usize,
}

impl ShareSums<'_> {
    /// Add `load` ([p_x, p_y, torque] of a share, seed eqs. 5.53–5.54) to slot `slot` and
    /// count it, in the host collect's arithmetic (`coupling/psm.rs`): the slots start at
    /// +0.0 (`MovingRun::new`), so the first load is 0.0 + load, as the host adds.
    ///
    /// # Safety
    /// The slot belongs to the calling task.
    #[inline(always)]
    unsafe fn add(&self, slot: usize, load: [f64; 3]) {
        let (sum, n) = (&mut *self.sums.0.add(slot), &mut *self.counts.0.add(slot));
        for (a, l) in sum.iter_mut().zip(load) {
            *a += l;
        }
        *n += 1;
    }
}

impl<'a> PartialSweep<'a> {
    /// The cells of `plan` in a lattice of row stride `stride`, their shares' momenta going
    /// to `mom` (and with `sums`, for a sweep by blocks of rows, the loads of the bodies that
    /// have a slot there to those, as each cell is blended), the first bad one to
    /// `bad`.
    pub(crate) fn new(
        plan: &'a PsmPlan,
        stride: usize,
        mom: Disjoint<[f64; 2]>,
        sums: Option<ShareSums<'a>>,
        bad: &'a AtomicUsize,
    ) -> Self {
        Self {
            plan,
            stride,
            mom,
            sums,
            bad,
        }
    }

    /// Whether some shares' loads go to per-body column sums (the sweep must then go by the
    /// blocks of rows they were made for, see [`ShareSums`]).
    pub(crate) fn sums_bodies(&self) -> bool {
        self.sums.is_some()
    }

    /// Add the load of plan share `s`, which took momentum `p` from the fluid at the cell at
    /// padded index `k` in local row `y`, to its body's slot of the cell's column when the
    /// sums take that body (a sweep by blocks of rows, see [`ShareSums`]): [p_x, p_y, r × p]
    /// with r the arm from the body's image centre to the cell's. Returns whether it did.
    ///
    /// # Safety
    /// Row `y` is swept by the calling task, to which the slots of the bodies with one in
    /// its block belong.
    #[inline(always)]
    unsafe fn sum_share(&self, s: usize, k: usize, y: usize, p: [f64; 2]) -> bool {
        let x = self.local_x(k, y);
        let body = self.plan.shares[s].body as usize;
        let Some((t, slot0)) = self.slots_of(body, y, x, 1) else {
            return false;
        };
        let image = self.plan.bodies[body].centre;
        let arm = [self.centre_x(x) - image[0], (y as f64 + 0.5) - image[1]];
        t.add(
            (slot0 + x as i64) as usize,
            [p[0], p[1], arm[0] * p[1] - arm[1] * p[0]],
        );
        true
    }

    /// The sums and the slot of local column 0 of `body`, when the sums take that body, for
    /// `cells` of its shares from local column `x` of local row `y` on (checked to lie in
    /// the body's box).
    #[inline(always)]
    fn slots_of(
        &self,
        body: usize,
        y: usize,
        x: usize,
        cells: usize,
    ) -> Option<(&ShareSums<'a>, i64)> {
        let t = self.sums.as_ref()?;
        let slot0 = t.body_slot[body];
        if slot0 == NO_SLOT {
            return None;
        }
        // A share outside its body's box could be in another task's block or column.
        let bx = t.boxes[body];
        assert!(
            bx[0] as usize <= x
                && x + cells <= (bx[0] + bx[1]) as usize
                && (bx[2] as usize..(bx[2] + bx[3]) as usize).contains(&y),
            "a share outside its body's box"
        );
        Some((t, slot0))
    }

    /// Local x of padded cell `k`, which lies in local row `y`.
    #[inline(always)]
    fn local_x(&self, k: usize, y: usize) -> usize {
        k - (y + 1) * self.stride - 1
    }

    /// Global x of the centre of the cell in local column `x`, (x + x0) + ½ as
    /// [`super::plans::cell_centre`] forms it.
    #[inline(always)]
    fn centre_x(&self, x: usize) -> f64 {
        (x as i64 + self.plan.x0) as f64 + 0.5
    }

    /// Plan indices of local row `y`'s cells, in increasing padded index.
    #[inline]
    pub(crate) fn row(&self, y: usize) -> std::ops::Range<usize> {
        let rows = &self.plan.rows;
        if rows.is_empty() {
            0..0
        } else {
            rows[y] as usize..rows[y + 1] as usize
        }
    }

    /// Padded index of plan cell `n`.
    #[inline(always)]
    pub(crate) fn cell(&self, n: usize) -> usize {
        self.plan.cells[n] as usize
    }

    /// Whether a plan cell among `range` (a row's cells) lies in the padded cells `ks`.
    #[inline]
    pub(crate) fn any_in(&self, range: std::ops::Range<usize>, ks: std::ops::Range<usize>) -> bool {
        let cells = &self.plan.cells[range];
        let from = cells.partition_point(|&k| (k as usize) < ks.start);
        cells.get(from).is_some_and(|&k| (k as usize) < ks.end)
    }

    /// The plan index of padded cell `k` among `range` (a row's cells), if it is one.
    #[inline]
    pub(crate) fn find(&self, range: std::ops::Range<usize>, k: usize) -> Option<usize> {
        let cells = &self.plan.cells[range.clone()];
        cells
            .binary_search(&(k as u32))
            .ok()
            .map(|j| range.start + j)
    }

    /// Replace `post`, plan cell `n`'s fluid collision of `h` (moments `m`), by the
    /// partially saturated cell's new values ([`blend_partial`]), recording `n` if its
    /// density went bad.
    ///
    /// # Safety
    /// The momentum slots of cell `n`'s shares belong to the caller.
    #[inline]
    pub(crate) unsafe fn blend<T: Real>(
        &self,
        n: usize,
        h: &[T; Q],
        post: &mut [T; Q],
        m: &Moments<T>,
    ) {
        let (new, ok) = blend_partial(self.plan, self.stride, self.mom, n, h, post, m);
        *post = new;
        if self.sums.is_some() {
            let k = self.plan.cells[n] as usize;
            let y = PsmPlan::row_of(self.stride, k);
            for s in self.plan.start[n] as usize..self.plan.start[n + 1] as usize {
                self.sum_share(s, k, y, *self.mom.0.add(s));
            }
        }
        if !ok {
            self.bad.fetch_min(n, Ordering::Relaxed);
        }
    }
}

#[path = "partial_lanes.rs"]
mod in_lanes;

#[cfg(test)]
#[path = "partial_tests.rs"]
mod tests;
