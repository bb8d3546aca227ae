//! Partially saturated cells (Noble & Torczynski 1998) eight at a time: the cells of a plan
//! row that one solid shares are gathered into lanes and computed with the same operations
//! in the same order as the one-cell form (`moving::partial_cell`), so they give the same
//! bits; cells that several solids share stay one at a time.

use super::boundary::{Access, Src};
use super::collision::{equilibrium, Collider, Moments};
use super::d2q9::{CX, CY, OPP, Q};
use super::lanes::{Lanes, Simd};
use super::lattice::Lattice;
use super::moving::{pull, Disjoint, PsmPlan};
use super::real::Real;

/// Cells computed together.
pub(crate) const LANES: usize = 8;

/// The new values of the single-share plan cells `ns` and whether each one's density stayed
/// positive (Noble & Torczynski 1998, eqs. 8–9; seed eqs. 5.53–5.54), each share's momentum
/// written to `mom`.
///
/// # Safety
/// As `MovingRun::row`: the share slots of the cells `ns` belong to the caller; each of
/// them has exactly one share.
pub(crate) unsafe fn partial_cells<T: Real, C: Collider<T>>(
    lat: &Lattice<T>,
    c: &C,
    src: Src<T>,
    acc: Access,
    plan: &PsmPlan,
    mom: Disjoint<[f64; 2]>,
    ns: &[usize; LANES],
) -> ([[T; Q]; LANES], [bool; LANES]) {
    type F = Lanes<f64, LANES>;
    let lanes_of = |v: [f64; LANES]| Lanes(v);
    let cells: [[T; Q]; LANES] =
        std::array::from_fn(|l| pull(lat, src, acc, plan.cells[ns[l]] as usize));
    let h: [Lanes<T, LANES>; Q] =
        std::array::from_fn(|i| Lanes(std::array::from_fn(|l| cells[l][i])));
    let to64 = |v: Lanes<T, LANES>| lanes_of(v.0.map(|x| x.to_f64()));
    let hf: [F; Q] = h.map(to64);
    let b_total = lanes_of(std::array::from_fn(|l| plan.total[ns[l]]));
    let share = |l: usize| plan.shares[plan.start[ns[l]] as usize];
    let b = lanes_of(std::array::from_fn(|l| share(l).b));
    let mut post = h;
    let m = c.collide(&mut post);
    let m64 = Moments {
        drho: to64(m.drho),
        rho: to64(m.rho),
        ux: to64(m.ux),
        uy: to64(m.uy),
    };
    let eq_fluid = equilibrium(&m64);
    let mut new: [F; Q] = std::array::from_fn(|i| (F::splat(1.0) - b_total) * to64(post[i]));
    let eq_solid = equilibrium(&Moments {
        ux: lanes_of(std::array::from_fn(|l| share(l).velocity[0])),
        uy: lanes_of(std::array::from_fn(|l| share(l).velocity[1])),
        ..m64
    });
    let mut p = [F::splat(0.0); 2];
    for i in 0..Q {
        let j = OPP[i];
        // Noble & Torczynski 1998, eq. 8:
        // Ω^s_i = [f_ī − f^eq_ī(ρ, u)] − [f_i − f^eq_i(ρ, u_s)].
        let omega_s = (hf[j] - eq_fluid[j]) - (hf[i] - eq_solid[i]);
        new[i] = new[i] + b * (hf[i] + omega_s);
        p[0] = p[0] + b * omega_s * F::splat(CX[i] as f64);
        p[1] = p[1] + b * omega_s * F::splat(CY[i] as f64);
    }
    let mut out = [[T::default(); Q]; LANES];
    let mut ok = [false; LANES];
    for l in 0..LANES {
        mom.write(plan.start[ns[l]] as usize, [-p[0].0[l], -p[1].0[l]]);
        let cell: [f64; Q] = std::array::from_fn(|i| new[i].0[l]);
        let rho = 1.0 + cell.iter().sum::<f64>();
        out[l] = cell.map(T::from_f64);
        ok[l] = rho > 0.0;
    }
    (out, ok)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lbm::collision::{with_collider, Collision};
    use crate::lbm::lattice::{FaceCondition, LatticeSetup, Layout, FLUID};
    use crate::lbm::moving::{partial_cell, SolidShare};

    /// Sixteen cells of one row with varied states, solid fractions and solid velocities:
    /// eight at a time they give the one-at-a-time values, momenta and checks bit for bit.
    fn lanes_match_one_at_a_time<T: Real>(collision: Collision) {
        let (nx, ny) = (16, 4);
        let mut lat = Lattice::<T>::new(LatticeSetup {
            nx,
            ny,
            cells: vec![FLUID; nx * ny],
            faces: std::array::from_fn(|_| FaceCondition::Periodic),
            solids: Vec::new(),
            collision,
            tau0: 0.63,
            smagorinsky: None,
            force: [0.0; 2],
        });
        for y in 0..ny {
            for x in 0..nx {
                let a = (x * 7 + y * 3) as f64;
                let u = [0.04 * (0.3 * a).sin(), 0.03 * (0.7 * a).cos()];
                lat.set_equilibrium(x, y, 1.0 + 0.01 * (0.5 * a).sin(), u);
            }
        }
        lat.update_boundaries();
        let mut plan = PsmPlan::default();
        plan.clear();
        for x in 0..nx {
            plan.cells.push((2 * lat.stride + x + 1) as u32);
            let b = 0.05 + 0.9 * (x as f64 / nx as f64);
            plan.total.push(b);
            let v = [0.01 * x as f64, -0.005 * x as f64];
            plan.shares.push(SolidShare { b, velocity: v });
            plan.start.push(plan.shares.len() as u32);
        }
        let src = Src::of(lat.current_buffer());
        let acc = Access::new(Layout::TwoArray, lat.plane, lat.stride);
        let (mut one, mut eight) = (vec![[0.0; 2]; nx], vec![[0.0; 2]; nx]);
        let (m1, m8) = (Disjoint(one.as_mut_ptr()), Disjoint(eight.as_mut_ptr()));
        with_collider!(lat.collision, lat.smagorinsky, lat.params, |c| {
            for first in [0, LANES] {
                let ns: [usize; LANES] = std::array::from_fn(|l| first + l);
                // SAFETY: the momentum buffers hold one slot per share.
                let (hs, oks) = unsafe { partial_cells(&lat, c, src, acc, &plan, m8, &ns) };
                for (l, &n) in ns.iter().enumerate() {
                    let (h, ok) = unsafe { partial_cell(&lat, c, src, acc, &plan, m1, n) };
                    let bits = |v: &[T; Q]| v.map(|x| x.to_f64().to_bits());
                    assert_eq!(bits(&h), bits(&hs[l]), "cell {n}");
                    assert_eq!(ok, oks[l]);
                    assert!(ok);
                }
            }
        });
        let bits = |m: &Vec<[f64; 2]>| m.iter().map(|p| p.map(f64::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&one), bits(&eight));
        assert!(one.iter().all(|p| p[0] != 0.0 || p[1] != 0.0));
    }

    #[test]
    fn eight_cells_at_a_time_give_the_same_bits() {
        lanes_match_one_at_a_time::<f64>(Collision::Bgk);
        lanes_match_one_at_a_time::<f32>(Collision::Bgk);
        lanes_match_one_at_a_time::<f64>(Collision::Mrt {
            s_e: 1.2,
            s_eps: 1.5,
            s_q: None,
        });
    }
}
