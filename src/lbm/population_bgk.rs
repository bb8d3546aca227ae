//! BGK in population space, for runs without body force or Smagorinsky closure (the common
//! case of a fluid-only or coupled production run). It gives the same operator as
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

/// Unforced BGK without closure on shifted populations (Bhatnagar, Gross & Krook 1954;
/// equilibrium of Qian, d'Humières & Lallemand 1992). Uses `s_nu` of the parameters only;
/// the caller selects it when the force is zero and the closure off.
pub struct PopulationBgk<T>(pub CollisionParams<T>);

impl<T: Real> Collider<T> for PopulationBgk<T> {
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
        let (ux, uy) = (jx * inv, jy * inv);
        // ρ(c·u)² per axis and diagonal: j_x u_x, j_y u_y, (j_x ± j_y)(u_x ± u_y).
        let (xx, yy) = (jx * ux, jy * uy);
        let (jp, jm) = (jx + jy, jy - jx);
        let (pp, mm) = (jp * (ux + uy), jm * (uy - ux));
        // δρ − 1.5 ρ u² (Qian et al. 1992, eq. 7, shifted by w_i).
        let base = (xx + yy).mul_add(c(-1.5), drho);
        // h_i ← (1 − ω) h_i + ω h_i^eq (BGK), with ω w_i folded into the pair's terms.
        let keep = c(1.0) - w;
        let (w0, w1, w2) = (w * c(4.0 / 9.0), w * c(1.0 / 9.0), w * c(1.0 / 36.0));
        let pair = |wi: V, rcu2: V, j: V| {
            // Even part w_i[base + 4.5 ρ(c·u)²] and odd part 3 w_i ρ(c·u), both × ω.
            (wi * rcu2.mul_add(c(4.5), base), wi * c(3.0) * j)
        };
        let (ex, ox) = pair(w1, xx, jx);
        let (ey, oy) = pair(w1, yy, jy);
        let (ep, op) = pair(w2, pp, jp);
        let (em, om) = pair(w2, mm, jm);
        h[0] = h[0].mul_add(keep, w0 * base);
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
    use crate::lbm::collision::{family, Collision, MomentCollider};

    /// Same post-collision state and moments as the moment-space BGK, to round-off, over
    /// a spread of densities, velocities (to Ma ≈ 0.3) and τ.
    #[test]
    fn matches_moment_space_bgk() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for tau in [0.5001, 0.53, 0.8, 1.7] {
            let p = CollisionParams::<f64>::new(Collision::Bgk, tau, None, [0.0, 0.0]);
            for _ in 0..200 {
                let mut a: [f64; Q] = std::array::from_fn(|_| 0.04 * rnd());
                a[1] += 0.1 * rnd();
                a[5] += 0.05 * rnd();
                let mut b = a;
                let ma = PopulationBgk(p).collide(&mut a);
                let mb = MomentCollider::<f64, false, { family::BGK }, false>(p).collide(&mut b);
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
        use crate::lbm::lanes::Lanes;
        let p = CollisionParams::<f32>::new(Collision::Bgk, 0.53, None, [0.0, 0.0]);
        let cells: [[f32; Q]; 8] = std::array::from_fn(|l| {
            std::array::from_fn(|i| 1e-3 * ((l * 7 + i * 3) % 11) as f32 - 4e-3)
        });
        let mut lanes: [Lanes<f32, 8>; Q] = std::array::from_fn(|i| Lanes(cells.map(|c| c[i])));
        PopulationBgk(p).collide(&mut lanes);
        for (l, cell) in cells.iter().enumerate() {
            let mut h = *cell;
            PopulationBgk(p).collide(&mut h);
            for i in 0..Q {
                assert_eq!(h[i].to_bits(), lanes[i].0[l].to_bits(), "lane {l}, h[{i}]");
            }
        }
    }
}
