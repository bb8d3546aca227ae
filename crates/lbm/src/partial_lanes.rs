//! The in-place sweep's partially saturated cells in lanes ([`PartialSweep::blend_lanes`]):
//! a chunk that is one grain's stretch of cells, or any chunk one share layer at a time,
//! with the operations of [`super::blend_partial`] in the same order (the same bits).

use super::{add_share, add_solid_equilibrium, fluid_part, is_full, PartialSweep};
use crate::collision::Moments;
use crate::d2q9::{each_direction, Q};
use crate::lanes::Lanes;
use crate::plans::PsmPlan;
use crate::real::Real;
use std::sync::atomic::Ordering;

/// The lanes of `b_total` whose cells are fully covered ([`is_full`]).
#[inline(always)]
fn full_mask<T: Real, const L: usize>(b_total: Lanes<T, L>) -> u32 {
    (0..L).fold(0u32, |f, l| f | u32::from(is_full(b_total.0[l])) << l)
}

/// Write the lanes `mask` of `new` into `post`; returns the lanes of `new` whose density
/// stays positive ([`super::density_ok`] in lanes, with its order of additions).
#[inline(always)]
fn merge_new<T: Real, const L: usize>(
    post: &mut [Lanes<T, L>; Q],
    new: &[Lanes<T, L>; Q],
    mask: u32,
) -> u32 {
    let mut sum = Lanes([T::from_f64(-0.0); L]);
    each_direction!(i => {
        sum = sum + new[i];
    });
    let ok = (Lanes([T::from_f64(1.0); L]) + sum).greater_mask(T::default());
    each_direction!(i => {
        post[i] = Lanes::select(mask, new[i], post[i]);
    });
    ok
}

/// The momenta `p` that the fluid gained from a layer of shares, negated: what the grains
/// receive (seed eqs. 5.53–5.54), per lane in f64.
#[inline(always)]
fn negated_loads<T: Real, const L: usize>(p: [Lanes<T, L>; 2]) -> [[f64; L]; 2] {
    p.map(|v| std::array::from_fn(|l| -v.0[l].to_f64()))
}

/// A chunk's plan cells when they are consecutive cells of one share each, all of one body
/// (the common chunk: a grain's row of cells): their inputs then come in lanes, and their
/// loads go to the body's slots with one lookup.
struct Stretch {
    /// Plan index of the first cell.
    n0: usize,
    /// Its share's index.
    at0: usize,
    /// Its lane.
    l0: usize,
    /// How many cells.
    cells: usize,
    /// The body (index into `PsmPlan::bodies`).
    body: usize,
    /// Local x of lane 0's cell.
    local_x0: usize,
}

impl Stretch {
    /// The stretch's lanes.
    #[inline(always)]
    fn mask(&self) -> u32 {
        (((1u64 << self.cells) - 1) << self.l0) as u32
    }
}

impl PartialSweep<'_> {
    /// Replace, in the lanes of `post` (the fluid collision of `h`, moments `m`, for the
    /// `L` cells from padded index `k`), those of the plan cells `cells` (which lie among
    /// them) by the cells' new values, recording the first bad one. The cells are blended in
    /// lanes, with the operations of [`super::blend_partial`] in the same order (the same bits), and
    /// merged into `post` by a lane mask (a lane written alone would send the whole chunk
    /// through memory): a stretch of one body's cells with its inputs taken as whole windows
    /// ([`Self::blend_stretch`]), any other chunk one share layer at a time
    /// ([`Self::blend_layers`]).
    ///
    /// # Safety
    /// The momentum slots of the cells' shares belong to the caller.
    #[inline(always)]
    pub(crate) unsafe fn blend_lanes<T: Real, const L: usize>(
        &self,
        cells: std::ops::Range<usize>,
        k: usize,
        h: &[Lanes<T, L>; Q],
        post: &mut [Lanes<T, L>; Q],
        m: &Moments<Lanes<T, L>>,
    ) {
        match self.one_body_stretch::<L>(cells.clone(), k) {
            Some(st) => self.blend_stretch(&st, k, h, post, m),
            None => self.blend_layers(cells, k, h, post, m),
        }
    }

    /// [`Self::blend_lanes`] for the cells of stretch `st`, one share each, all of one body.
    ///
    /// # Safety
    /// As [`Self::blend_lanes`].
    #[inline(always)]
    unsafe fn blend_stretch<T: Real, const L: usize>(
        &self,
        st: &Stretch,
        k: usize,
        h: &[Lanes<T, L>; Q],
        post: &mut [Lanes<T, L>; Q],
        m: &Moments<Lanes<T, L>>,
    ) {
        let plan = self.plan;
        // A chunk lies in one row.
        let y = PsmPlan::row_of(self.stride, k);
        let motion = &plan.bodies[st.body];
        // Each lane's plan cell, share and centre, as if the stretch filled the chunk (the
        // lanes outside it are masked off below): taken as whole windows (one bounds check
        // each) and computed in lanes, in `PsmPlan::velocity`'s arithmetic.
        let (bn, bs) = (st.n0 - st.l0, st.at0 - st.l0);
        let (total, shares) = (&plan.total[bn..bn + L], &plan.shares[bs..bs + L]);
        let b_total: [T; L] = std::array::from_fn(|l| T::from_f64(total[l]));
        let b: [T; L] = std::array::from_fn(|l| T::from_f64(shares[l].b));
        let r_y = (y as f64 + 0.5) - motion.centre[1];
        let ux = T::from_f64(motion.velocity[0] - motion.omega * r_y);
        // Lane l's centre x, ((x₀ + l) + x0) + ½, is the lane-0 centre plus l exactly (whole
        // numbers and halves, far below 2⁵²).
        let centre0 = self.centre_x(st.local_x0);
        let arm_x: [f64; L] = std::array::from_fn(|l| (centre0 + l as f64) - motion.centre[0]);
        let uy: [T; L] =
            std::array::from_fn(|l| T::from_f64(motion.velocity[1] + motion.omega * arm_x[l]));
        let mask = st.mask();
        let b_total = Lanes(b_total);
        let mut new = fluid_part(post, b_total);
        let (b, u) = (Lanes(b), [Lanes([ux; L]), Lanes(uy)]);
        let p = add_share(&mut new, h, m, b, u);
        // Fully covered cells take the solid's equilibrium (`is_full`).
        let full = full_mask(b_total) & mask;
        if full != 0 {
            let mut solid = [Lanes([T::default(); L]); Q];
            add_solid_equilibrium(&mut solid, m, b, u);
            each_direction!(i => {
                new[i] = Lanes::select(full, solid[i], new[i]);
            });
        }
        let ok = merge_new(post, &new, mask);
        // The grain receives what the fluid gains, negated (seed eqs. 5.53–5.54).
        let loads = negated_loads(p);
        // A body summed here needs no momenta reported (see `BodyColumns`): its shares'
        // entries are left as they were.
        if !self.sum_stretch(st, y, &arm_x, &loads) {
            for t in 0..st.cells {
                let l = st.l0 + t;
                self.mom.write(st.at0 + t, [loads[0][l], loads[1][l]]);
            }
        }
        let bad = !ok & mask;
        if bad != 0 {
            let first = st.n0 + bad.trailing_zeros() as usize - st.l0;
            self.bad.fetch_min(first, Ordering::Relaxed);
        }
    }

    /// [`Self::blend_lanes`] for any chunk, one share layer at a time: layer j takes the
    /// j-th share of every cell that has one (a cell's shares in plan order, as
    /// [`super::blend_partial`] adds them), and each layer's sums are merged by its lane mask, so a
    /// cell of one share sees the operations of one layer only. In a packing, most chunks
    /// hold a cell of two grains (a contact), so this is the common path there.
    ///
    /// # Safety
    /// As [`Self::blend_lanes`].
    #[inline(always)]
    unsafe fn blend_layers<T: Real, const L: usize>(
        &self,
        cells: std::ops::Range<usize>,
        k: usize,
        h: &[Lanes<T, L>; Q],
        post: &mut [Lanes<T, L>; Q],
        m: &Moments<Lanes<T, L>>,
    ) {
        let plan = self.plan;
        // A chunk lies in one row.
        let y = PsmPlan::row_of(self.stride, k);
        let zero = T::default();
        let lane = |n: usize| plan.cells[n] as usize - k;
        // The lanes that hold no plan cell get weight 0 and are not written back.
        let mut b_total = [zero; L];
        let (mut mask, mut layers) = (0u32, 0usize);
        for n in cells.clone() {
            // Stored lane by lane, loaded once per chunk (a masked blend per value and cell
            // compiles to a longer shuffle chain).
            b_total[lane(n)] = T::from_f64(plan.total[n]);
            mask |= 1 << lane(n);
            layers = layers.max((plan.start[n + 1] - plan.start[n]) as usize);
        }
        let b_total = Lanes(b_total);
        let mut new = fluid_part(post, b_total);
        // Fully covered cells take the solids' equilibria (`is_full`).
        let full = full_mask(b_total) & mask;
        let mut solid = [Lanes([zero; L]); Q];
        for j in 0..layers {
            let (mut b, mut ux, mut uy) = ([zero; L], [zero; L], [zero; L]);
            let mut layer = 0u32;
            for n in cells.clone() {
                let at = plan.start[n] as usize + j;
                if at < plan.start[n + 1] as usize {
                    let (l, share) = (lane(n), plan.shares[at]);
                    let u = plan.velocity(self.stride, plan.cells[n] as usize, y, share);
                    b[l] = T::from_f64(share.b);
                    ux[l] = T::from_f64(u[0]);
                    uy[l] = T::from_f64(u[1]);
                    layer |= 1 << l;
                }
            }
            let (b, u) = (Lanes(b), [Lanes(ux), Lanes(uy)]);
            let mut added = new;
            let p = add_share(&mut added, h, m, b, u);
            each_direction!(i => {
                new[i] = Lanes::select(layer, added[i], new[i]);
            });
            if full & layer != 0 {
                let mut added = solid;
                add_solid_equilibrium(&mut added, m, b, u);
                each_direction!(i => {
                    solid[i] = Lanes::select(full & layer, added[i], solid[i]);
                });
            }
            // The grain receives what the fluid gains, negated (seed eqs. 5.53–5.54).
            let loads = negated_loads(p);
            for n in cells.clone() {
                let at = plan.start[n] as usize + j;
                if at < plan.start[n + 1] as usize {
                    let l = lane(n);
                    let momentum = [loads[0][l], loads[1][l]];
                    // A body summed here needs no momenta reported (see `BodyColumns`).
                    if !self.sum_share(at, plan.cells[n] as usize, y, momentum) {
                        self.mom.write(at, momentum);
                    }
                }
            }
        }
        if full != 0 {
            each_direction!(i => {
                new[i] = Lanes::select(full, solid[i], new[i]);
            });
        }
        let ok = merge_new(post, &new, mask);
        let bad = !ok & mask;
        if bad != 0 {
            if let Some(first) = cells.clone().find(|&n| bad >> lane(n) & 1 != 0) {
                self.bad.fetch_min(first, Ordering::Relaxed);
            }
        }
    }

    /// The plan cells `cells` of the `L`-cell chunk from padded index `k` as a
    /// [`Stretch`], if they are one: consecutive cells of one share each, all of one body,
    /// with a whole chunk's worth of plan entries around them (so that the lanes outside
    /// the stretch read entries of the plan too, whose values are then masked off).
    #[inline(always)]
    fn one_body_stretch<const L: usize>(
        &self,
        cells: std::ops::Range<usize>,
        k: usize,
    ) -> Option<Stretch> {
        let plan = self.plan;
        let (n0, count) = (cells.start, cells.len());
        let l0 = plan.cells[n0] as usize - k;
        let at0 = plan.start[n0] as usize;
        // A row's cells increase, and every plan cell has a share: the cells are
        // consecutive when the last lies `count − 1` after the first, and have one share
        // each when their shares number `count`.
        let consecutive = plan.cells[cells.end - 1] as usize - k == l0 + count - 1
            && plan.start[cells.end] as usize == at0 + count;
        if !consecutive
            || n0 < l0
            || at0 < l0
            || n0 - l0 + L > plan.total.len()
            || at0 - l0 + L > plan.shares.len()
        {
            return None;
        }
        let body = plan.shares[at0].body;
        if plan.shares[at0 + 1..at0 + count]
            .iter()
            .any(|s| s.body != body)
        {
            return None;
        }
        let y = PsmPlan::row_of(self.stride, k);
        Some(Stretch {
            n0,
            at0,
            l0,
            cells: count,
            body: body as usize,
            local_x0: self.local_x(k, y),
        })
    }

    /// Add the loads of the cells of stretch `st` (in local row `y`) to its body's slots of
    /// their columns, when the sums take that body, as [`Self::sum_share`] adds one: formed
    /// in lanes from the arms' x (`arm_x`) and the shares' momenta (`[px, py]`, as the grain
    /// receives them), then added one cell at a time. Returns whether it did.
    ///
    /// # Safety
    /// As [`Self::sum_share`].
    #[inline(always)]
    unsafe fn sum_stretch<const L: usize>(
        &self,
        st: &Stretch,
        y: usize,
        arm_x: &[f64; L],
        [px, py]: &[[f64; L]; 2],
    ) -> bool {
        let Some((t, slot0)) = self.slots_of(st.body, y, st.local_x0 + st.l0, st.cells) else {
            return false;
        };
        let arm_y = (y as f64 + 0.5) - self.plan.bodies[st.body].centre[1];
        let torque: [f64; L] = std::array::from_fn(|l| arm_x[l] * py[l] - arm_y * px[l]);
        let lane0 = (slot0 + st.local_x0 as i64) as usize;
        for l in st.l0..st.l0 + st.cells {
            t.add(lane0 + l, [px[l], py[l], torque[l]]);
        }
        true
    }
}
