//! Partially saturated cells (Noble & Torczynski 1998; seed eqs. 5.53–5.54): the blend of a
//! cell's fluid collision with the solids' that share it, one cell at a time after a
//! two-array sweep ([`partial_cell`]), or inside an in-place sweep from the values it has
//! just loaded and collided ([`PartialSweep`]). Both give the same bits.

use super::boundary::{Access, Src};
use super::collision::{equilibrium, Collider, Moments};
use super::d2q9::{CX, CY, OPP, Q};
use super::lattice::Lattice;
use super::moving::{pull, Disjoint};
use super::plans::PsmPlan;
use super::real::Real;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The new values of partially saturated plan cell `n` and whether its density stayed
/// positive.
///
/// # Safety
/// As [`MovingRun::row`]; the share slots of cell `n` belong to the caller.
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
    blend_partial(plan, mom, n, &h, &post, &m)
}

/// The new values of partially saturated plan cell `n` from its pre-collision populations
/// `h`, their fluid collision `post` and the pre-collision moments `m`, and whether its
/// density stayed positive (Noble & Torczynski 1998, eqs. 8–9; seed eqs. 5.53–5.54):
/// f_i ← (1 − B) post_i + Σ_s B_s (h_i + Ω^s_i). Each share's momentum goes to `mom`.
///
/// # Safety
/// The momentum slots of cell `n`'s shares belong to the caller.
#[inline]
pub(crate) unsafe fn blend_partial<T: Real>(
    plan: &PsmPlan,
    mom: Disjoint<[f64; 2]>,
    n: usize,
    h: &[T; Q],
    post: &[T; Q],
    m: &Moments<T>,
) -> ([T; Q], bool) {
    let hf: [f64; Q] = h.map(|v| v.to_f64());
    let b_total = plan.total[n];
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
    (new.map(T::from_f64), rho > 0.0)
}

/// Partially saturated cells that an in-place sweep computes itself, from the values it has
/// just loaded and collided (no second read of their populations): the plan, where the
/// momenta go, and where the first bad cell is recorded.
pub(crate) struct PartialSweep<'a> {
    plan: &'a PsmPlan,
    mom: Disjoint<[f64; 2]>,
    bad: &'a AtomicUsize,
}

impl<'a> PartialSweep<'a> {
    /// The cells of `plan`, their shares' momenta going to `mom`, the first bad one to
    /// `bad`.
    pub(crate) fn new(plan: &'a PsmPlan, mom: Disjoint<[f64; 2]>, bad: &'a AtomicUsize) -> Self {
        Self { plan, mom, bad }
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
        let (new, ok) = blend_partial(self.plan, self.mom, n, h, post, m);
        *post = new;
        if !ok {
            self.bad.fetch_min(n, Ordering::Relaxed);
        }
    }
}
