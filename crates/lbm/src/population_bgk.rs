//! BGK in population space, with or without Guo body force, for runs without Smagorinsky
//! closure (the common case of a fluid-only or coupled production run). It gives the same
//! operator as
//! [`MomentCollider`](super::collision::MomentCollider) with every rate equal to ω = 1/τ
//! (tested to round-off), in about half the arithmetic: the equilibrium is built per
//! direction pair (i, ī) from its even part w_i[δρ − 1.5ρu² + 4.5ρ(c_i·u)²] and its odd part
//! 3 w_i ρ(c_i·u), so no moment transform is needed, and every relaxation is one fused
//! multiply-add. The in-place kernel is compute-bound in f32, so this is where its speed
//! comes from.

use super::collision::{Collider, CollisionParams, Moments};
use super::d2q9::Q;
use super::lanes::Simd;
use super::real::Real;

/// BGK without closure on shifted populations (Bhatnagar, Gross & Krook 1954; equilibrium
/// of Qian, d'Humières & Lallemand 1992), with Guo forcing when `FORCED` (Guo, Zheng & Shi
/// 2002). Uses `s_nu` and `force` of the parameters; the caller selects it when the
/// closure is off.
pub struct PopulationBgk<T, const FORCED: bool>(pub CollisionParams<T>);

impl<T: Real, const FORCED: bool> Collider<T> for PopulationBgk<T, FORCED> {
    #[inline(always)]
    fn collide<V: Simd<Scalar = T>>(&self, h: &mut [V; Q]) -> Moments<V> {
        let c = |v: f64| V::splat(T::from_f64(v));
        let w = V::splat(self.0.s_nu);
        // Populations by the sign of c_x and c_y (D2Q9 order: 1 E, 2 N, 3 W, 4 S, 5 NE,
        // 6 NW, 7 SW, 8 SE).
        let east = h[1] + h[5] + h[8];
        let west = h[3] + h[6] + h[7];
        let north = h[2] + h[5] + h[6];
        let south = h[4] + h[7] + h[8];
        let drho = h[0] + h[2] + h[4] + east + west;
        let jx = east - west;
        let jy = north - south;
        let rho = c(1.0) + drho;
        let inv = c(1.0) / rho;
        let (fx, fy) = (V::splat(self.0.force[0]), V::splat(self.0.force[1]));
        // ρu = j + F/2 (Guo et al. 2002, eq. 19).
        let (rux, ruy) = if FORCED {
            (fx.mul_add(c(0.5), jx), fy.mul_add(c(0.5), jy))
        } else {
            (jx, jy)
        };
        let (ux, uy) = (rux * inv, ruy * inv);
        // ρ(c·u)² per axis and diagonal: ρu_x u_x, ρu_y u_y, ρ(u_x ± u_y)(u_x ± u_y).
        let (xx, yy) = (rux * ux, ruy * uy);
        let (jp, jm) = (rux + ruy, ruy - rux);
        let (up, um) = (ux + uy, uy - ux);
        let (pp, mm) = (jp * up, jm * um);
        // δρ − 1.5 ρ u² (Qian et al. 1992, eq. 7, shifted by w_i).
        let base = (xx + yy).mul_add(c(-1.5), drho);
        // h_i ← (1 − ω) h_i + ω h_i^eq + (1 − ω/2) S_i (BGK with Guo's source), with the
        // weights folded into each direction pair's even and odd terms.
        let keep = c(1.0) - w;
        let (w0, w1, w2) = (w * c(4.0 / 9.0), w * c(1.0 / 9.0), w * c(1.0 / 36.0));
        let pair = |wi: V, rcu2: V, j: V| {
            // Even part ω w_i[base + 4.5 ρ(c·u)²] and odd part 3 ω w_i ρ(c·u).
            (wi * rcu2.mul_add(c(4.5), base), wi * c(3.0) * j)
        };
        let (mut ex, mut ox) = pair(w1, xx, rux);
        let (mut ey, mut oy) = pair(w1, yy, ruy);
        let (mut ep, mut op) = pair(w2, pp, jp);
        let (mut em, mut om) = pair(w2, mm, jm);
        let mut rest = w0 * base;
        if FORCED {
            // Guo et al. 2002, eq. 20: S_i = w_i[3(c_i − u)·F + 9(c_i·u)(c_i·F)], times
            // (1 − ω/2); even part w_i[9(c·u)(c·F) − 3u·F], odd part 3 w_i c·F.
            let k = w.mul_add(c(-0.5), c(1.0));
            let (k0, k1, k2) = (k * c(4.0 / 9.0), k * c(1.0 / 9.0), k * c(1.0 / 36.0));
            let uf3 = c(-3.0) * ux.mul_add(fx, uy * fy);
            let (fp, fm) = (fx + fy, fy - fx);
            let source =
                |ki: V, cu: V, cf: V| (ki * (cu * cf).mul_add(c(9.0), uf3), ki * c(3.0) * cf);
            let add = |e: &mut V, o: &mut V, (se, so): (V, V)| {
                *e = *e + se;
                *o = *o + so;
            };
            add(&mut ex, &mut ox, source(k1, ux, fx));
            add(&mut ey, &mut oy, source(k1, uy, fy));
            add(&mut ep, &mut op, source(k2, up, fp));
            add(&mut em, &mut om, source(k2, um, fm));
            rest = k0.mul_add(uf3, rest);
        }
        h[0] = h[0].mul_add(keep, rest);
        h[1] = h[1].mul_add(keep, ex + ox);
        h[3] = h[3].mul_add(keep, ex - ox);
        h[2] = h[2].mul_add(keep, ey + oy);
        h[4] = h[4].mul_add(keep, ey - oy);
        h[5] = h[5].mul_add(keep, ep + op);
        h[7] = h[7].mul_add(keep, ep - op);
        h[6] = h[6].mul_add(keep, em + om);
        h[8] = h[8].mul_add(keep, em - om);
        Moments { drho, rho, ux, uy }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::{family, Collision, MomentCollider};

    /// Same post-collision state and moments as the moment-space BGK, to round-off, over
    /// a spread of densities, velocities (to Ma ≈ 0.3) and τ, with and without force.
    #[test]
    fn matches_moment_space_bgk() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = || crate::test_rng::next(&mut seed) - 0.5;
        for (tau, force) in [0.5001, 0.53, 0.8, 1.7]
            .into_iter()
            .flat_map(|t| [(t, [0.0, 0.0]), (t, [3e-5, -1e-4])])
        {
            let p = CollisionParams::<f64>::new(Collision::Bgk, tau, None, force);
            for _ in 0..200 {
                let mut a: [f64; Q] = std::array::from_fn(|_| 0.04 * rnd());
                a[1] += 0.1 * rnd();
                a[5] += 0.05 * rnd();
                let mut b = a;
                let (ma, mb) = if force[0] == 0.0 {
                    (
                        PopulationBgk::<_, false>(p).collide(&mut a),
                        MomentCollider::<f64, false, { family::BGK }, false>(p).collide(&mut b),
                    )
                } else {
                    (
                        PopulationBgk::<_, true>(p).collide(&mut a),
                        MomentCollider::<f64, false, { family::BGK }, true>(p).collide(&mut b),
                    )
                };
                for i in 0..Q {
                    assert!(
                        (a[i] - b[i]).abs() < 1e-15,
                        "tau {tau}, h[{i}]: {a:?} vs {b:?}"
                    );
                }
                assert!((ma.drho - mb.drho).abs() < 1e-16);
                assert!((ma.ux - mb.ux).abs() < 1e-15 && (ma.uy - mb.uy).abs() < 1e-15);
            }
        }
    }

    /// The lane form gives the scalar form's bits for every lane (the bulk kernel and the
    /// boundary path agree on a cell).
    #[test]
    fn lanes_match_scalar_bits() {
        use crate::lanes::Lanes;
        let p = CollisionParams::<f32>::new(Collision::Bgk, 0.53, None, [0.0, 0.0]);
        let cells: [[f32; Q]; 8] = std::array::from_fn(|l| {
            std::array::from_fn(|i| 1e-3 * ((l * 7 + i * 3) % 11) as f32 - 4e-3)
        });
        let mut lanes: [Lanes<f32, 8>; Q] = std::array::from_fn(|i| Lanes(cells.map(|c| c[i])));
        PopulationBgk::<_, false>(p).collide(&mut lanes);
        for (l, cell) in cells.iter().enumerate() {
            let mut h = *cell;
            PopulationBgk::<_, false>(p).collide(&mut h);
            for i in 0..Q {
                assert_eq!(h[i].to_bits(), lanes[i].0[l].to_bits(), "lane {l}, h[{i}]");
            }
        }
    }
}
