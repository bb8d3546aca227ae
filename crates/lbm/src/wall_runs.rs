//! Runs of cells along a straight wall: consecutive special cells whose nine neighbours have
//! the same types (each fluid or a solid, no open face), as a flat wall makes the whole
//! first and last row of a tank. The in-place sweep takes them `BULK_LANES` at a time with
//! the scalar path's operations in lanes ([`Lattice::gather_special`] and the collision), so
//! with the same bits: lanes and scalars round alike, and each cell's momentum to the walls
//! is summed in the scalar path's order.

use super::boundary::{exchanged_momentum, moving_wall_term, Access};
use super::bulk_aa::BULK_LANES;
use super::collision::Collider;
use super::d2q9::{CX, CY, OPP, Q};
use super::lanes::{Lanes, Simd};
use super::lattice::{Lattice, FLUID, MAX_SOLID};
use super::real::Real;

/// The types of the nine cells padded cell `k` pulls from (its own first), if none is an
/// open face.
fn neighbour_types(types: &[u16], stride: usize, k: usize) -> Option<[u16; Q]> {
    let t: [u16; Q] = std::array::from_fn(|i| {
        types[(k as isize - CX[i] as isize - CY[i] as isize * stride as isize) as usize]
    });
    t.iter().all(|&t| t <= MAX_SOLID).then_some(t)
}

/// The wall runs among `special` (the special cells of padded row `yp`, in increasing x):
/// `(first, count)` for each stretch of at least `BULK_LANES` consecutive cells whose
/// neighbours' types agree direction by direction and include no open face.
pub(crate) fn wall_runs(
    types: &[u16],
    stride: usize,
    yp: usize,
    special: &[u32],
) -> Vec<(u32, u32)> {
    let of = |x: u32| neighbour_types(types, stride, yp * stride + x as usize + 1);
    let mut runs = Vec::new();
    let mut j = 0;
    while j < special.len() {
        let Some(first) = of(special[j]) else {
            j += 1;
            continue;
        };
        let mut e = j + 1;
        while e < special.len() && special[e] == special[e - 1] + 1 && of(special[e]) == Some(first)
        {
            e += 1;
        }
        if e - j >= BULK_LANES {
            runs.push((j as u32, (e - j) as u32));
        }
        j = e;
    }
    runs
}

/// Sweep `n` cells (a multiple of `BULK_LANES`) of a wall run in place, from local column
/// `x0` of interior row `y`, `BULK_LANES` at a time: each direction pulled from its fluid
/// neighbour, or bounced back from the cell's own opposite value with the wall's velocity
/// term (half-way bounce-back, Ladd 1994, eq. 3.3), as [`Lattice::gather_special`] does;
/// then collided with `c` and stored. Each cell's momentum to the solids (Ladd 1994) goes to
/// its `ns` slots at `forces` (cell after cell, zeroed first). Returns true if any cell's
/// density went NaN or non-positive.
///
/// # Safety
/// `base` is the lattice's one buffer (in place, `acc`); the cells lie in one wall run
/// ([`wall_runs`]) and their slots, and their `n × ns` force slots, belong to the caller.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) unsafe fn sweep_wall_run<T: Real, C: Collider<T>>(
    lat: &Lattice<T>,
    c: &C,
    base: *mut T,
    acc: Access,
    y: usize,
    x0: usize,
    n: usize,
    forces: *mut [f64; 2],
    ns: usize,
) -> bool {
    const L: usize = BULK_LANES;
    debug_assert_eq!(n % L, 0);
    let k0 = (y + 1) * lat.stride + x0 + 1;
    let types = neighbour_types(&lat.types, lat.stride, k0).expect("a wall run has no open face");
    // Per direction: where the run's values come from, and for a solid neighbour its
    // index and the wall term 6 w_i c_i · u_w (Ladd 1994, eq. 3.3).
    let from: [*const T; Q] = std::array::from_fn(|i| {
        let at = if types[i] == FLUID {
            acc.pulled(i, k0)
        } else {
            acc.own(OPP[i], k0)
        };
        base.add(at) as *const T
    });
    let wall: [Option<(usize, T)>; Q] = std::array::from_fn(|i| {
        (types[i] != FLUID).then(|| {
            let s = types[i] as usize - 1;
            (s, T::from_f64(moving_wall_term(i, lat.solids[s].velocity)))
        })
    });
    let to: [*mut T; Q] = std::array::from_fn(|j| base.add(acc.store(j, k0)));
    let mut bad = false;
    let mut k = 0;
    while k < n {
        let back: [Lanes<T, L>; Q] = std::array::from_fn(|i| {
            let mut v = [T::default(); L];
            std::ptr::copy_nonoverlapping(from[i].add(k), v.as_mut_ptr(), L);
            Lanes(v)
        });
        let mut h = back;
        for (hi, w) in h.iter_mut().zip(&wall) {
            if let Some((_, term)) = w {
                *hi = *hi + Lanes::splat(*term);
            }
        }
        for l in 0..L {
            let f = std::slice::from_raw_parts_mut(forces.add((k + l) * ns), ns);
            f.fill([0.0; 2]);
            for i in 0..Q {
                if let Some((s, _)) = wall[i] {
                    let m = exchanged_momentum(i, back[i].0[l].to_f64(), h[i].0[l].to_f64());
                    f[s][0] -= m * CX[i] as f64;
                    f[s][1] -= m * CY[i] as f64;
                }
            }
        }
        let m = c.collide(&mut h);
        for j in 0..Q {
            std::ptr::copy_nonoverlapping(h[j].0.as_ptr(), to[j].add(k), L);
        }
        for r in m.rho.0 {
            bad |= !(r > T::default());
        }
        k += L;
    }
    bad
}
