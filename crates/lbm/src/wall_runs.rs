//! Runs of cells along a straight wall: consecutive special cells whose nine neighbours have
//! the same types (each fluid or a solid, no open face), as a flat wall makes the whole
//! first and last row of a tank. The in-place sweep takes them `BULK_LANES` at a time with
//! the scalar path's operations in lanes ([`Lattice::gather_special`] and the collision), so
//! with the same bits: lanes and scalars round alike, and each cell's momentum to the walls
//! is summed in the scalar path's order.

use super::boundary::{exchanged_momentum, moving_wall_term, Access};
use super::bulk_aa::BULK_LANES;
use super::cells::FLUID;
use super::collision::Collider;
use super::d2q9::{CX, CY, OPP, Q};
use super::lanes::{Lanes, Simd};
use super::lattice::Lattice;
use super::real::Real;
use super::rows::neighbour_types;

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
