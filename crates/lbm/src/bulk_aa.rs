//! The in-place (AA pattern) bulk row kernels: runs of plain cells swept `BULK_LANES` at a
//! time, and the stretches of them that hold partially saturated cells of a moving surface,
//! which the sweep computes itself from the values it has just loaded and collided (see
//! [`super::partial::PartialSweep`]).

use super::boundary::Access;
use super::collision::Collider;
use super::d2q9::{each_direction, OPP, Q};
use super::lanes::{has_avx512, prefetch_ahead, Lanes};
use super::partial::PartialSweep;
use super::real::Real;
use std::ops::Range;

pub(crate) use super::lanes::BULK_LANES;

/// A bulk row kernel: `(collider, buffer, access, first cell, cells)`, as [`bulk_run_aa`].
pub(crate) type BulkFn<T, C> = unsafe fn(&C, *mut T, Access, usize, usize) -> bool;

/// The partially saturated plan cells inside a stretch of a bulk run (their plan indices,
/// in increasing padded index), which the stretch's kernel computes from the values it has
/// loaded and collided.
pub(crate) type RunCells<'a> = (&'a PartialSweep<'a>, Range<usize>);

/// A bulk row kernel for stretches that hold partially saturated cells: `(collider,
/// buffer, access, first cell, cells, plan cells)`, as [`bulk_run_aa_partial`].
pub(crate) type PartialFn<T, C> = unsafe fn(&C, *mut T, Access, usize, usize, RunCells<'_>) -> bool;

/// The bulk row kernels for this CPU: compiled for AVX-512 (32 vector registers, so the
/// collision's temporaries stay in registers) where the CPU has it, else for the build's
/// target (AVX2 + FMA). Both run the same operations in the same order, so they give the
/// same bits.
pub(crate) fn bulk_kernels<T: Real, C: Collider<T>>() -> (BulkFn<T, C>, PartialFn<T, C>) {
    #[cfg(target_arch = "x86_64")]
    if has_avx512() {
        return (
            bulk_run_aa_avx512::<T, C>,
            bulk_run_aa_partial_avx512::<T, C>,
        );
    }
    (
        bulk_run_aa::<T, C, BULK_LANES>,
        bulk_run_aa_partial::<T, C, BULK_LANES>,
    )
}

/// [`bulk_run_aa`] compiled with AVX-512.
///
/// # Safety
/// As [`bulk_run_aa`]; the CPU has AVX-512F and AVX-512VL.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl")]
unsafe fn bulk_run_aa_avx512<T: Real, C: Collider<T>>(
    c: &C,
    base: *mut T,
    acc: Access,
    k0: usize,
    n: usize,
) -> bool {
    bulk_run_aa::<T, C, BULK_LANES>(c, base, acc, k0, n)
}

/// [`bulk_run_aa_partial`] compiled with AVX-512.
///
/// # Safety
/// As [`bulk_run_aa_partial`]; the CPU has AVX-512F and AVX-512VL.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl")]
unsafe fn bulk_run_aa_partial_avx512<T: Real, C: Collider<T>>(
    c: &C,
    base: *mut T,
    acc: Access,
    k0: usize,
    n: usize,
    partial: RunCells<'_>,
) -> bool {
    bulk_run_aa_partial::<T, C, BULK_LANES>(c, base, acc, k0, n, partial)
}

/// The nine population pointers a bulk run loads from and stores to, at its first cell
/// `k0`: in place, cell k stores direction j where it pulled direction opp(j) (both
/// layouts), so nine addresses, not eighteen, and the pointers stay in registers.
#[inline(always)]
unsafe fn run_pointers<T: Real>(base: *mut T, acc: Access, k0: usize) -> [*mut T; Q] {
    debug_assert!((0..Q).all(|j| acc.store(j, k0) == acc.pulled(OPP[j], k0)));
    std::array::from_fn(|i| base.add(acc.pulled(i, k0)))
}

/// Load `LANES` cells from `k` on of each stream into `h`: in place, since an array
/// returned by value is built in a scratch and copied over in wider vectors than it was
/// written with, which stalls each chunk on store forwarding.
#[inline(always)]
unsafe fn load_lanes<T: Real, const LANES: usize>(
    ld: &[*mut T; Q],
    k: usize,
    h: &mut [Lanes<T, LANES>; Q],
) {
    each_direction!(i => {
        std::ptr::copy_nonoverlapping(ld[i].add(k), h[i].0.as_mut_ptr(), LANES);
    });
}

/// Store `LANES` cells from `k` on: direction j where direction opp(j) was loaded.
#[inline(always)]
unsafe fn store_lanes<T: Real, const LANES: usize>(
    ld: &[*mut T; Q],
    k: usize,
    h: &[Lanes<T, LANES>; Q],
) {
    each_direction!(j => {
        std::ptr::copy_nonoverlapping(h[j].0.as_ptr(), ld[OPP[j]].add(k), LANES);
    });
}

/// The bulk cells `[k0, k0 + n)` of one row, in place, `LANES` at a time (scalar for the
/// remainder). Returns true if any cell's density went NaN or non-positive.
///
/// # Safety
/// `base` is the lattice's one buffer; no other task touches these cells' slots.
#[inline(always)]
unsafe fn bulk_run_aa<T: Real, C: Collider<T>, const LANES: usize>(
    c: &C,
    base: *mut T,
    acc: Access,
    k0: usize,
    n: usize,
) -> bool {
    let ld: [*const T; Q] = std::array::from_fn(|i| base.add(acc.pulled(i, k0)) as *const T);
    // In place, cell k stores direction j where it pulled direction opp(j) (both layouts):
    // nine addresses, not eighteen, so the pointers stay in registers.
    debug_assert!((0..Q).all(|j| acc.store(j, k0) == acc.pulled(OPP[j], k0)));
    let st: [*mut T; Q] = std::array::from_fn(|j| ld[OPP[j]] as *mut T);
    let zero = T::default();
    let mut bad = false;
    let mut k = 0;
    while k + LANES <= n {
        prefetch_ahead(&ld, k);
        let mut h: [Lanes<T, LANES>; Q] = std::array::from_fn(|i| {
            let mut v = [zero; LANES];
            std::ptr::copy_nonoverlapping(ld[i].add(k), v.as_mut_ptr(), LANES);
            Lanes(v)
        });
        let m = c.collide(&mut h);
        for j in 0..Q {
            std::ptr::copy_nonoverlapping(h[j].0.as_ptr(), st[j].add(k), LANES);
        }
        for r in m.rho.0 {
            bad |= !(r > zero);
        }
        k += LANES;
    }
    while k < n {
        let mut h: [T; Q] = std::array::from_fn(|i| *ld[i].add(k));
        let m = c.collide(&mut h);
        for j in 0..Q {
            *st[j].add(k) = h[j];
        }
        bad |= !(m.rho > zero);
        k += 1;
    }
    bad
}

/// As [`bulk_run_aa`], for a stretch `[k0, k0 + n)` of a bulk run that holds the partially
/// saturated cells `partial`: each of them takes the blend of its fluid collision with the
/// solid's ([`PartialSweep::blend_lanes`]: one grain's stretch of cells together, any other
/// chunk one share layer at a time) before the lanes are stored. Those are the one-cell form's values
/// (`partial::partial_cell`), since lanes and scalars round alike. A kernel of its own, so
/// that the plain one keeps its registers.
///
/// # Safety
/// As [`bulk_run_aa`]; the plan cells of `partial` lie in `[k0, k0 + n)`, and their momentum
/// slots belong to the calling task.
#[inline(always)]
unsafe fn bulk_run_aa_partial<T: Real, C: Collider<T>, const LANES: usize>(
    c: &C,
    base: *mut T,
    acc: Access,
    k0: usize,
    n: usize,
    partial: RunCells<'_>,
) -> bool {
    let (p, mut cells) = partial;
    let ld = run_pointers(base, acc, k0);
    let zero = T::default();
    let mut bad = false;
    // Offset from k0 of the next plan cell (n when none is left).
    let offset = |j: usize| if j < cells.end { p.cell(j) - k0 } else { n };
    let mut next = offset(cells.start);
    let mut k = 0;
    while k + LANES <= n {
        prefetch_ahead(&ld.map(|p| p as *const T), k);
        let mut h = [Lanes([zero; LANES]); Q];
        load_lanes(&ld, k, &mut h);
        let m = c.collide(&mut h);
        if next < k + LANES {
            let first = cells.start;
            while next < k + LANES {
                cells.start += 1;
                next = offset(cells.start);
            }
            // The pre-collision values loaded again (still in the buffer, and in L1): a copy
            // kept across the collision went through the stack in vectors of another width,
            // which stalled every chunk on store forwarding.
            let mut pre = [Lanes([zero; LANES]); Q];
            load_lanes(&ld, k, &mut pre);
            p.blend_lanes(first..cells.start, k0 + k, &pre, &mut h, &m);
        }
        store_lanes(&ld, k, &h);
        for r in m.rho.0 {
            bad |= !(r > zero);
        }
        k += LANES;
    }
    while k < n {
        let mut h: [T; Q] = std::array::from_fn(|i| *ld[i].add(k));
        let pre = h;
        let m = c.collide(&mut h);
        if next == k {
            p.blend(cells.start, &pre, &mut h, &m);
            cells.start += 1;
            next = offset(cells.start);
        }
        for j in 0..Q {
            *ld[OPP[j]].add(k) = h[j];
        }
        bad |= !(m.rho > zero);
        k += 1;
    }
    bad
}

/// Sweep the bulk run `[k0, k0 + n)`: the stretches of whole `BULK_LANES`-cell chunks that
/// hold partially saturated plan cells (`partial`: those of the run) with the partial kernel,
/// the others with the plain one. The chunks are the plain kernel's, so the split changes no
/// value. Returns true if any cell's density went NaN or non-positive.
///
/// # Safety
/// As [`bulk_run_aa_partial`].
pub(crate) unsafe fn sweep_run<T: Real, C: Collider<T>>(
    c: &C,
    (plain, mixed): (BulkFn<T, C>, PartialFn<T, C>),
    base: *mut T,
    acc: Access,
    k0: usize,
    n: usize,
    partial: Option<RunCells<'_>>,
) -> bool {
    let Some((p, cells)) = partial.filter(|(_, r)| !r.is_empty()) else {
        return plain(c, base, acc, k0, n);
    };
    // The plan's rule (`PsmPlan::cells`): a row's cells increase. These lie in the run, as
    // the sweep's cursor found them. The stretches' lengths rely on both: checked.
    let mut last = None;
    for j in cells.clone() {
        let o = p.cell(j).wrapping_sub(k0);
        assert!(
            o < n && last.is_none_or(|l| o > l),
            "partially saturated plan cells out of order in a row"
        );
        last = Some(o);
    }
    let chunk = |j: usize| (p.cell(j) - k0) / BULK_LANES * BULK_LANES;
    let mut bad = false;
    let (mut at, mut j) = (0, cells.start);
    while j < cells.end {
        let start = chunk(j);
        if start > at {
            bad |= plain(c, base, acc, k0 + at, start - at);
        }
        // Whole chunks while the next plan cell lies in the one just taken or the next.
        let first = j;
        let mut end = start;
        while j < cells.end && chunk(j) <= end {
            end = chunk(j) + BULK_LANES;
            j += 1;
        }
        let end = end.min(n);
        bad |= mixed(c, base, acc, k0 + start, end - start, (p, first..j));
        at = end;
    }
    if at < n {
        bad |= plain(c, base, acc, k0 + at, n - at);
    }
    bad
}

#[cfg(test)]
#[path = "bulk_aa_tests.rs"]
mod tests;
