//! The in-place (AA pattern) bulk row kernels: runs of plain cells swept `BULK_LANES` at a
//! time, and the stretches of them that hold partially saturated cells of a moving surface,
//! which the sweep computes itself from the values it has just loaded and collided (see
//! [`super::partial::PartialSweep`]).

use super::boundary::Access;
use super::collision::Collider;
use super::d2q9::{OPP, Q};
use super::lanes::{has_avx512, prefetch_ahead, Lanes};
use super::partial::PartialSweep;
use super::real::Real;
use std::ops::Range;

/// Cells the bulk row kernels compute together.
pub(crate) const BULK_LANES: usize = 8;

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

/// Load `LANES` cells from `k` on of each stream.
#[inline(always)]
unsafe fn load_lanes<T: Real, const LANES: usize>(
    ld: &[*mut T; Q],
    k: usize,
) -> [Lanes<T, LANES>; Q] {
    std::array::from_fn(|i| {
        let mut v = [T::default(); LANES];
        std::ptr::copy_nonoverlapping(ld[i].add(k), v.as_mut_ptr(), LANES);
        Lanes(v)
    })
}

/// Store `LANES` cells from `k` on: direction j where direction opp(j) was loaded.
#[inline(always)]
unsafe fn store_lanes<T: Real, const LANES: usize>(
    ld: &[*mut T; Q],
    k: usize,
    h: &[Lanes<T, LANES>; Q],
) {
    for j in 0..Q {
        std::ptr::copy_nonoverlapping(h[j].0.as_ptr(), ld[OPP[j]].add(k), LANES);
    }
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
/// solid's ([`PartialSweep::blend_lanes`]: a chunk's one-share cells together, others lane
/// by lane) before the lanes are stored. Those are the one-cell form's values
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
        let mut h = load_lanes::<T, LANES>(&ld, k);
        let pre = h;
        let m = c.collide(&mut h);
        if next < k + LANES {
            let first = cells.start;
            while next < k + LANES {
                cells.start += 1;
                next = offset(cells.start);
            }
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
mod tests {
    use super::super::collision::Collision;
    use super::super::lattice::{FaceCondition, Lattice, LatticeSetup, SolidInfo, FLUID};
    use super::super::moving::{BodyColumns, MovingCells, PsmPlan, RigidMotion, SolidShare};
    use super::*;
    use decomposition::SingleProcess;

    /// Columns 30–33 of rows 3–6 are an obstacle: those rows have two bulk runs.
    fn obstacle(x: usize, y: usize) -> bool {
        (30..34).contains(&x) && (3..7).contains(&y)
    }

    /// A walled box with an obstacle and a varied flow.
    fn lattice<T: Real>(collision: Collision) -> Lattice<T> {
        let (nx, ny) = (61, 9);
        let cells = (0..nx * ny)
            .map(|k| if obstacle(k % nx, k / nx) { 1 } else { FLUID })
            .collect();
        let mut lat = Lattice::<T>::new(LatticeSetup {
            nx,
            ny,
            cells,
            faces: std::array::from_fn(|_| FaceCondition::Wall { solid: 1 }),
            solids: vec![SolidInfo {
                name: "walls".into(),
                velocity: [0.0; 2],
            }],
            collision,
            tau0: 0.63,
            smagorinsky: None,
            force: [1e-6, -2e-6],
        });
        for y in 0..ny {
            for x in (0..nx).filter(|&x| !obstacle(x, y)) {
                let a = (x * 7 + y * 3) as f64;
                let u = [0.04 * (0.3 * a).sin(), 0.03 * (0.7 * a).cos()];
                lat.set_equilibrium(x, y, 1.0 + 0.01 * (0.5 * a).sin(), u);
            }
        }
        lat.update_boundaries();
        lat
    }

    /// Partially saturated cells in all rows but one: next to the walls and the obstacle
    /// (special cells), a long stretch whose alignment to the kernel's chunks changes from
    /// row to row, lone cells with empty chunks between them, the first and last columns of
    /// even rows; in every
    /// third row, every fifth cell shared by two solids (the other rows' chunks are blended
    /// in lanes, these lane by lane).
    fn plan<T: Real>(lat: &Lattice<T>) -> PsmPlan {
        let (nx, ny) = (lat.nx(), lat.ny());
        let mut plan = PsmPlan::default();
        plan.clear();
        for y in 0..ny {
            plan.rows.push(plan.cells.len() as u32);
            for x in 0..nx {
                // Odd rows leave the runs' first or last chunks plain.
                let even = y % 2 == 0;
                let take = (x < 3 && even)
                    || (4 + y..=20 + y).contains(&x)
                    || x == 27
                    || (34..=36).contains(&x)
                    || x == 47
                    || (x + 2 >= nx && even);
                if !take || y == 7 || obstacle(x, y) {
                    continue;
                }
                let n = plan.cells.len();
                plan.cells.push(((y + 1) * lat.stride + x + 1) as u32);
                let b = 0.05 + 0.9 * ((x + 3 * y) % 11) as f64 / 10.0;
                let two = y % 3 == 0 && n % 5 == 0;
                let parts: &[f64] = if two { &[0.6, 0.4] } else { &[1.0] };
                for (s, part) in parts.iter().enumerate() {
                    // A body per share, spinning about a point off the cell.
                    plan.shares.push(SolidShare {
                        b: b * part,
                        body: plan.bodies.len() as u32,
                    });
                    plan.bodies.push(RigidMotion {
                        velocity: [0.01 * (x + s) as f64 - 0.1, 0.005 * y as f64 - 0.02],
                        omega: 0.002 * (s as f64 - 0.5),
                        centre: [x as f64 - 3.0, y as f64 + 2.5],
                    });
                }
                plan.total.push(b);
                plan.start.push(plan.shares.len() as u32);
            }
        }
        plan.rows.push(plan.cells.len() as u32);
        plan
    }

    /// The two lattices' fluid cells hold the same bits (the first difference named).
    fn same_fields<T: Real>(a: &Lattice<T>, b: &Lattice<T>, what: &str) {
        let (nx, ny) = (a.nx(), a.ny());
        let (ea, eb) = (a.export_interior(), b.export_interior());
        for (at, (u, v)) in ea.iter().zip(&eb).enumerate() {
            let (i, y, x) = (at / (nx * ny), at / nx % ny, at % nx);
            if !obstacle(x, y) && u.to_f64().to_bits() != v.to_f64().to_bits() {
                panic!("{what}: cell ({x}, {y}) direction {i}: {u:?} vs {v:?}");
            }
        }
    }

    fn bits<T: Real>(v: &[T]) -> Vec<u64> {
        v.iter().map(|x| x.to_f64().to_bits()).collect()
    }

    /// The in-place sweep computes the partially saturated cells inside its bulk runs and
    /// special cells, on push and local steps: the same bits, fields and momenta, as the
    /// two-array kernel, which computes them one by one after its sweep.
    fn in_place_partial_cells_match_two_arrays<T: Real>(collision: Collision) {
        let mut two = lattice::<T>(collision);
        let mut one = lattice::<T>(collision);
        one.make_in_place();
        let plan = plan(&two);
        assert!(plan.cells.len() > 150);
        let (mut m2, mut m1) = (Vec::new(), Vec::new());
        for step in 0..4 {
            for (lat, m) in [(&mut two, &mut m2), (&mut one, &mut m1)] {
                let bad = lat
                    .stream_collide_moving(
                        &SingleProcess,
                        &mut MovingCells::Partial(&plan, m, &mut BodyColumns::default()),
                    )
                    .unwrap();
                assert!(bad.is_none());
                lat.update_boundaries();
            }
            same_fields(&two, &one, &format!("step {step}"));
            let flat = |m: &Vec<[f64; 2]>| m.iter().flatten().copied().collect::<Vec<_>>();
            assert_eq!(bits(&flat(&m2)), bits(&flat(&m1)), "step {step}");
            assert!(m1.iter().all(|p| p[0] != 0.0 || p[1] != 0.0));
        }
    }

    /// An empty plan (no rows at all) leaves the sweep as it is without one.
    #[test]
    fn an_empty_partial_plan_changes_nothing() {
        let mut with = lattice::<f64>(Collision::Bgk);
        let mut without = lattice::<f64>(Collision::Bgk);
        with.make_in_place();
        without.make_in_place();
        let (plan, mut m) = (PsmPlan::default(), Vec::new());
        for _ in 0..2 {
            with.stream_collide_moving(
                &SingleProcess,
                &mut MovingCells::Partial(&plan, &mut m, &mut BodyColumns::default()),
            )
            .unwrap();
            without
                .stream_collide_moving(&SingleProcess, &mut MovingCells::None)
                .unwrap();
            with.update_boundaries();
            without.update_boundaries();
        }
        same_fields(&with, &without, "empty plan");
    }

    /// The plan index of the cell the sweep reports bad, on two arrays and in place, after
    /// one step in which only cell `n`'s solid moves at NaN.
    fn bad_cell<T: Real>(n: usize) -> [Option<usize>; 2] {
        let mut plan = plan(&lattice::<T>(Collision::Bgk));
        // Each share has a body of its own: only this cell's shares go NaN.
        for at in plan.start[n]..plan.start[n + 1] {
            let body = plan.shares[at as usize].body as usize;
            plan.bodies[body].velocity = [f64::NAN, 0.0];
        }
        [false, true].map(|in_place| {
            let mut lat = lattice::<T>(Collision::Bgk);
            if in_place {
                lat.make_in_place();
            }
            let mut m = Vec::new();
            lat.stream_collide_moving(
                &SingleProcess,
                &mut MovingCells::Partial(&plan, &mut m, &mut BodyColumns::default()),
            )
            .unwrap()
            .map(|(bad, _)| bad)
        })
    }

    /// A cell that goes bad is named by its plan index, whichever lane of its chunk it
    /// sits in and whether the chunk is blended in lanes or lane by lane (cells of two
    /// shares), in bulk runs and special cells, as the two-array kernel names it.
    #[test]
    fn in_place_partial_sweep_names_the_bad_cell() {
        let plan = plan(&lattice::<f32>(Collision::Bgk));
        let (mut one, mut two) = (0, 0);
        for n in (0..plan.cells.len()).step_by(3) {
            for got in [bad_cell::<f32>(n), bad_cell::<f64>(n)] {
                assert_eq!(got, [Some(n); 2], "plan cell {n}");
            }
            if plan.start[n + 1] - plan.start[n] == 1 {
                one += 1;
            } else {
                two += 1;
            }
        }
        assert!(
            one > 40 && two > 3,
            "{one} one-share and {two} two-share cells"
        );
    }

    #[test]
    fn in_place_partial_cells_give_the_two_array_bits() {
        in_place_partial_cells_match_two_arrays::<f64>(Collision::Bgk);
        in_place_partial_cells_match_two_arrays::<f32>(Collision::Bgk);
        for collision in [
            Collision::Mrt {
                s_e: 1.2,
                s_eps: 1.5,
                s_q: None,
            },
            Collision::Trt { magic: 0.25 },
        ] {
            in_place_partial_cells_match_two_arrays::<f64>(collision);
            in_place_partial_cells_match_two_arrays::<f32>(collision);
        }
    }
}
