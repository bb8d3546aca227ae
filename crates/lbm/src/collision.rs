//! Collision operators on shifted distributions `h_i = f_i - w_i`, all with Guo forcing
//! and an optional Smagorinsky closure.
//!
//! * BGK (Bhatnagar, Gross & Krook 1954).
//! * TRT (Ginzburg 2005) with magic parameter Λ = (1/ω⁺ − ½)(1/ω⁻ − ½), default 3/16.
//! * MRT with the Lallemand & Luo (2000) moment basis (ρ, e, ε, j_x, q_x, j_y, q_y, p_xx, p_xy).
//!
//! Guo forcing (Guo, Zheng & Shi 2002): u = (Σ f c + F/2)/ρ, plus the source
//! (1 − ω/2) w_i [3(c_i − u) + 9 (c_i·u) c_i]·F, projected per moment/part for TRT and MRT.
//!
//! Smagorinsky (Hou et al. 1996): τ_eff = ½[τ₀ + √(τ₀² + 18√2 C² |Π^neq| / ρ)], with
//! |Π^neq| = √(Π^neq:Π^neq), the momentum-flux non-equilibrium. It follows from
//! ν_t = (C Δ)² |S| with |S| = √(2 S:S) and S = −Π^neq/(2ρ c_s² τ).

use super::d2q9::{CX, CY, Q, W};
use super::lanes::Simd;
use super::real::Real;

/// The collision model a scene picks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Collision {
    /// Single relaxation time.
    Bgk,
    /// Two relaxation times; `magic` is Λ (3/16 puts half-way bounce-back walls exactly
    /// half-way for any viscosity).
    Trt {
        /// Λ = (τ⁺ − ½)(τ⁻ − ½).
        magic: f64,
    },
    /// Multiple relaxation times (Lallemand & Luo 2000). The shear rate s_ν = 1/τ comes
    /// from the viscosity; the others are free.
    Mrt {
        /// Energy moment rate s_e (bulk viscosity), in (0, 2).
        s_e: f64,
        /// Energy-squared moment rate s_ε, in (0, 2).
        s_eps: f64,
        /// Energy-flux moment rate s_q, in (0, 2); `None` derives it from s_ν so that
        /// (1/s_ν − ½)(1/s_q − ½) = 3/16 (the TRT magic value: exact wall location).
        s_q: Option<f64>,
    },
}

impl Collision {
    /// Short name for reports.
    pub fn name(&self) -> &'static str {
        match self {
            Collision::Bgk => "bgk",
            Collision::Trt { .. } => "trt",
            Collision::Mrt { .. } => "mrt",
        }
    }
}

/// Everything a collision needs, in lattice units and the kernel's precision.
///
/// All three operators run in the Lallemand–Luo moment space: BGK relaxes every
/// non-conserved moment with ω = 1/τ; TRT relaxes the even moments (e, ε, p_xx, p_xy) with
/// ω⁺ = 1/τ and the odd ones (q_x, q_y) with ω⁻ from Λ; MRT uses its own s_e, s_ε, s_q.
/// That is algebraically identical to the population-space forms (see the tests) and
/// gives one vectorising kernel for all three. BGK without closure, the common case, runs
/// the cheaper population-space form instead
/// ([`PopulationBgk`](super::population_bgk::PopulationBgk), same operator to round-off);
/// `with_collider!` picks.
#[derive(Debug, Clone, Copy)]
pub struct CollisionParams<T> {
    /// Molecular relaxation time τ₀ = 3ν + ½.
    pub tau0: T,
    /// Λ used to derive s_q from the shear rate.
    pub magic: T,
    /// s_e (resolved).
    pub s_e: T,
    /// s_ε (resolved).
    pub s_eps: T,
    /// s_ν = 1/τ₀.
    pub s_nu: T,
    /// s_q (resolved for τ₀).
    pub s_q: T,
    /// 1 when s_q follows the shear rate through Λ as the Smagorinsky closure changes it, else 0.
    pub s_q_magic_weight: T,
    /// 18√2 C_s² (zero when the closure is off).
    pub smag_k: T,
    /// Body force density per cell, lattice units.
    pub force: [T; 2],
}

/// s_q such that (1/s_ν − ½)(1/s_q − ½) = Λ (Ginzburg 2005).
#[inline(always)]
fn odd_rate<V: Simd>(s_nu: V, magic: V) -> V {
    let half = V::splat(<V::Scalar as Real>::from_f64(0.5));
    let one = V::splat(<V::Scalar as Real>::from_f64(1.0));
    one / (magic / (one / s_nu - half) + half)
}

impl<T: Real> CollisionParams<T> {
    /// Build from the physical choice. `smagorinsky` is the constant C_s, if enabled.
    pub fn new(model: Collision, tau0: f64, smagorinsky: Option<f64>, force: [f64; 2]) -> Self {
        let w = 1.0 / tau0;
        let magic_rate = |l: f64| 1.0 / (l / (tau0 - 0.5) + 0.5);
        let (magic, s_e, s_eps, s_q, from_magic) = match model {
            Collision::Bgk => ((tau0 - 0.5) * (tau0 - 0.5), w, w, w, true),
            Collision::Trt { magic } => (magic, w, w, magic_rate(magic), true),
            Collision::Mrt { s_e, s_eps, s_q } => (
                3.0 / 16.0,
                s_e,
                s_eps,
                s_q.unwrap_or(magic_rate(3.0 / 16.0)),
                s_q.is_none(),
            ),
        };
        let c = smagorinsky.unwrap_or(0.0);
        Self {
            tau0: T::from_f64(tau0),
            magic: T::from_f64(magic),
            s_e: T::from_f64(s_e),
            s_eps: T::from_f64(s_eps),
            s_nu: T::from_f64(w),
            s_q: T::from_f64(s_q),
            s_q_magic_weight: T::from_f64(if from_magic { 1.0 } else { 0.0 }),
            smag_k: T::from_f64(18.0 * std::f64::consts::SQRT_2 * c * c),
            force: [T::from_f64(force[0]), T::from_f64(force[1])],
        }
    }
}

/// Macroscopic state of one cell: density deviation, density and velocity (Guo-corrected).
#[derive(Debug, Clone, Copy)]
pub struct Moments<T> {
    /// ρ − 1.
    pub drho: T,
    /// ρ.
    pub rho: T,
    /// Velocity x.
    pub ux: T,
    /// Velocity y.
    pub uy: T,
}

/// Density and velocity of pre-collision shifted populations (Guo 2002: u = (j + F/2)/ρ).
#[inline(always)]
pub fn moments<T: Real>(h: &[T; Q], force: [T; 2]) -> Moments<T> {
    let drho = h[0] + h[1] + h[2] + h[3] + h[4] + h[5] + h[6] + h[7] + h[8];
    let jx = h[1] - h[3] + h[5] - h[6] - h[7] + h[8];
    let jy = h[2] - h[4] + h[5] + h[6] - h[7] - h[8];
    let rho = T::from_f64(1.0) + drho;
    let inv = T::from_f64(1.0) / rho;
    let half = T::from_f64(0.5);
    Moments {
        drho,
        rho,
        ux: (jx + half * force[0]) * inv,
        uy: (jy + half * force[1]) * inv,
    }
}

/// Shifted equilibrium h_i^eq = w_i [δρ + ρ(3 c·u + 4.5 (c·u)² − 1.5 u²)] (Qian et al. 1992).
/// Used for initial conditions and as the reference in tests (the kernels fold it into their
/// relaxation).
#[inline(always)]
pub fn equilibrium<V: Simd>(m: &Moments<V>) -> [V; Q] {
    let s = |v: f64| V::splat(V::Scalar::from_f64(v));
    let usq = m.ux * m.ux + m.uy * m.uy;
    std::array::from_fn(|i| {
        let cu = s(CX[i] as f64) * m.ux + s(CY[i] as f64) * m.uy;
        let poly = s(3.0) * cu + s(4.5) * cu * cu - s(1.5) * usq;
        s(W[i]) * (m.drho + m.rho * poly)
    })
}

/// Smagorinsky relaxation time from the non-equilibrium momentum flux (Hou et al. 1996).
#[inline(always)]
fn smagorinsky_tau<T: Real, V: Simd<Scalar = T>>(
    p: &CollisionParams<T>,
    pxx: V,
    pyy: V,
    pxy: V,
    rho: V,
) -> V {
    let s = V::splat;
    let q = (pxx * pxx + pyy * pyy + s(T::from_f64(2.0)) * pxy * pxy).sqrt();
    s(T::from_f64(0.5)) * (s(p.tau0) + (s(p.tau0 * p.tau0) + s(p.smag_k) * q / rho).sqrt())
}

/// Π^neq from the population deviations `h − h^eq` (test oracle for the moment form).
#[cfg(test)]
fn pi_neq<T: Real>(h: &[T; Q], eq: &[T; Q]) -> (T, T, T) {
    let d = |i: usize| h[i] - eq[i];
    let diag = d(5) + d(6) + d(7) + d(8);
    (
        d(1) + d(3) + diag,
        d(2) + d(4) + diag,
        d(5) - d(6) + d(7) - d(8),
    )
}

/// A collision operator the row kernels can inline.
pub trait Collider<T: Real>: Sync {
    /// Collide the shifted populations of one cell (or one bundle of lanes) in place;
    /// returns the pre-collision moments (Guo-corrected velocity).
    fn collide<V: Simd<Scalar = T>>(&self, h: &mut [V; Q]) -> Moments<V>;
}

/// Operator family for [`MomentCollider`]: how the rates follow the (possibly
/// Smagorinsky-modified) shear rate.
pub mod family {
    /// Every rate equals s_ν.
    pub const BGK: u8 = 0;
    /// Even rates equal s_ν, s_q from Λ.
    pub const TRT: u8 = 1;
    /// s_e, s_ε fixed; s_q fixed or from Λ = 3/16.
    pub const MRT: u8 = 2;
}

/// The moment-space collision of BGK, TRT and MRT, with Guo forcing in moment space and an
/// optional Smagorinsky closure (`SMAG`). `FAMILY` is one of [`family`].
///
/// `FORCED = false` drops the Guo terms at compile time (scenes without body force).
pub struct MomentCollider<T, const SMAG: bool, const FAMILY: u8, const FORCED: bool>(
    pub CollisionParams<T>,
);

impl<T: Real, const SMAG: bool, const FAMILY: u8, const FORCED: bool> Collider<T>
    for MomentCollider<T, SMAG, FAMILY, FORCED>
{
    #[inline(always)]
    fn collide<V: Simd<Scalar = T>>(&self, h: &mut [V; Q]) -> Moments<V> {
        let p = &self.0;
        let c = |v: f64| V::splat(T::from_f64(v));
        let sp = V::splat;
        // Moments of the shifted populations (Lallemand & Luo 2000, eq. 11 basis).
        // Shared sums and differences first: fewer operations, same moments.
        let (p13, p24) = (h[1] + h[3], h[2] + h[4]);
        let (d13, d24) = (h[1] - h[3], h[2] - h[4]);
        let (p57, p68) = (h[5] + h[7], h[6] + h[8]);
        let (d57, d86) = (h[5] - h[7], h[8] - h[6]);
        let s1 = p13 + p24;
        let s2 = p57 + p68;
        let drho = h[0] + s1 + s2;
        let e = h[0].mul_add(c(-4.0), s2.mul_add(c(2.0), -s1));
        let eps = h[0].mul_add(c(4.0), s1.mul_add(c(-2.0), s2));
        let (dx, dy) = (d57 + d86, d57 - d86);
        let jx = d13 + dx;
        let jy = d24 + dy;
        let qx = d13.mul_add(c(-2.0), dx);
        let qy = d24.mul_add(c(-2.0), dy);
        let pxx = p13 - p24;
        let pxy = p57 - p68;
        let rho = c(1.0) + drho;
        let inv = c(1.0) / rho;
        let (fx, fy) = (sp(p.force[0]), sp(p.force[1]));
        let (ux, uy) = if FORCED {
            ((jx + c(0.5) * fx) * inv, (jy + c(0.5) * fy) * inv)
        } else {
            (jx * inv, jy * inv)
        };
        let (rux, ruy) = if FORCED {
            (rho * ux, rho * uy)
        } else {
            (jx, jy)
        };
        let ru2 = rux * ux + ruy * uy;
        // Shifted equilibria (M w = (1, −2, 1, 0, …) removed), Lallemand & Luo 2000, eq. 23.
        let e_eq = c(-2.0) * drho + c(3.0) * ru2;
        let eps_eq = drho - c(3.0) * ru2;
        let pxx_eq = rux * ux - ruy * uy;
        let pxy_eq = rux * uy;
        let (s_e, s_eps, s_nu, s_q) = if SMAG {
            // Π^neq from the moments: tr Π = (e + 4ρ)/3, Π_xx − Π_yy = p_xx, Π_xy = p_xy.
            let tr = (e - e_eq) * c(1.0 / 3.0);
            let dxx = pxx - pxx_eq;
            let dxy = pxy - pxy_eq;
            let s_nu =
                c(1.0) / smagorinsky_tau(p, c(0.5) * (tr + dxx), c(0.5) * (tr - dxx), dxy, rho);
            match FAMILY {
                family::BGK => (s_nu, s_nu, s_nu, s_nu),
                family::TRT => (s_nu, s_nu, s_nu, odd_rate(s_nu, sp(p.magic))),
                // Blend instead of branching so the row loop still vectorises.
                _ => {
                    let w = sp(p.s_q_magic_weight);
                    (
                        sp(p.s_e),
                        sp(p.s_eps),
                        s_nu,
                        w * odd_rate(s_nu, sp(p.magic)) + (c(1.0) - w) * sp(p.s_q),
                    )
                }
            }
        } else {
            (sp(p.s_e), sp(p.s_eps), sp(p.s_nu), sp(p.s_q))
        };
        let (e, eps, qx, qy, pxx, pxy, jx, jy) = if FORCED {
            // Guo source in moment space: M F_i (Guo, Zheng & Shi 2002; Lallemand & Luo 2000).
            let uf = ux * fx + uy * fy;
            let relax = |m: V, meq: V, s: V, src: V| {
                (meq - m).mul_add(s, src.mul_add(s.mul_add(c(-0.5), c(1.0)), m))
            };
            (
                relax(e, e_eq, s_e, c(6.0) * uf),
                relax(eps, eps_eq, s_eps, c(-6.0) * uf),
                relax(qx, -rux, s_q, -fx),
                relax(qy, -ruy, s_q, -fy),
                relax(pxx, pxx_eq, s_nu, c(2.0) * (ux * fx - uy * fy)),
                relax(pxy, pxy_eq, s_nu, ux * fy + uy * fx),
                jx + fx,
                jy + fy,
            )
        } else {
            let relax = |m: V, meq: V, s: V| (meq - m).mul_add(s, m);
            (
                relax(e, e_eq, s_e),
                relax(eps, eps_eq, s_eps),
                relax(qx, -rux, s_q),
                relax(qy, -ruy, s_q),
                relax(pxx, pxx_eq, s_nu),
                relax(pxy, pxy_eq, s_nu),
                jx,
                jy,
            )
        };
        // Back to populations: h = Mᵀ D⁻¹ m with D = diag(9, 36, 36, 6, 12, 6, 12, 4, 4).
        let a0 = drho * c(1.0 / 9.0);
        let a1 = e * c(1.0 / 36.0);
        let a2 = eps * c(1.0 / 36.0);
        let a3 = jx * c(1.0 / 6.0);
        let a4 = qx * c(1.0 / 12.0);
        let a5 = jy * c(1.0 / 6.0);
        let a6 = qy * c(1.0 / 12.0);
        let a7 = pxx * c(0.25);
        let a8 = pxy * c(0.25);
        let axis = a2.mul_add(c(-2.0), a0 - a1);
        let diag = a1.mul_add(c(2.0), a0 + a2);
        let (tx, ty) = (a4.mul_add(c(-2.0), a3), a6.mul_add(c(-2.0), a5));
        let (ap, am) = (axis + a7, axis - a7);
        let (sx, sy) = (a3 + a4, a5 + a6);
        let (dp, dm) = (diag + a8, diag - a8);
        h[0] = (a2 - a1).mul_add(c(4.0), a0);
        h[1] = ap + tx;
        h[3] = ap - tx;
        h[2] = am + ty;
        h[4] = am - ty;
        h[5] = dp + (sx + sy);
        h[7] = dp - (sx + sy);
        h[6] = dm + (sy - sx);
        h[8] = dm - (sy - sx);
        Moments { drho, rho, ux, uy }
    }
}

/// Evaluate `$body` with `$c` bound to (a reference to) the collider a lattice's settings
/// select: [`PopulationBgk`](super::population_bgk::PopulationBgk) for BGK without
/// closure, else the [`MomentCollider`] of the operator's family with the closure and
/// Guo terms compiled in only where used. `$p` is the lattice's [`CollisionParams`]. Every
/// kernel dispatches through here, so they all collide a cell alike (same bits).
macro_rules! with_collider {
    (@bind $ctor:expr, $c:ident, $body:expr) => {{
        let $c = &$ctor;
        $body
    }};
    ($collision:expr, $smag:expr, $p:expr, |$c:ident| $body:expr) => {{
        #[allow(unused_imports)]
        use $crate::collision::{family::*, Collision, MomentCollider as M};
        use $crate::population_bgk::PopulationBgk as P;
        let p = $p;
        let forced = p.force[0] != Default::default() || p.force[1] != Default::default();
        match ($collision, $smag, forced) {
            (Collision::Bgk, false, false) => {
                with_collider!(@bind P::<_, false>(p), $c, $body)
            }
            (Collision::Bgk, false, true) => {
                with_collider!(@bind P::<_, true>(p), $c, $body)
            }
            (Collision::Bgk, true, false) => {
                with_collider!(@bind M::<_, true, { BGK }, false>(p), $c, $body)
            }
            (Collision::Bgk, true, true) => {
                with_collider!(@bind M::<_, true, { BGK }, true>(p), $c, $body)
            }
            (Collision::Trt { .. }, false, false) => {
                with_collider!(@bind M::<_, false, { TRT }, false>(p), $c, $body)
            }
            (Collision::Trt { .. }, false, true) => {
                with_collider!(@bind M::<_, false, { TRT }, true>(p), $c, $body)
            }
            (Collision::Trt { .. }, true, false) => {
                with_collider!(@bind M::<_, true, { TRT }, false>(p), $c, $body)
            }
            (Collision::Trt { .. }, true, true) => {
                with_collider!(@bind M::<_, true, { TRT }, true>(p), $c, $body)
            }
            (Collision::Mrt { .. }, false, false) => {
                with_collider!(@bind M::<_, false, { MRT }, false>(p), $c, $body)
            }
            (Collision::Mrt { .. }, false, true) => {
                with_collider!(@bind M::<_, false, { MRT }, true>(p), $c, $body)
            }
            (Collision::Mrt { .. }, true, false) => {
                with_collider!(@bind M::<_, true, { MRT }, false>(p), $c, $body)
            }
            (Collision::Mrt { .. }, true, true) => {
                with_collider!(@bind M::<_, true, { MRT }, true>(p), $c, $body)
            }
        }
    }};
}
pub(crate) use with_collider;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::d2q9::OPP;

    fn sample() -> [f64; Q] {
        [
            0.011, -0.003, 0.004, 0.002, -0.001, 0.0005, 0.0012, -0.0007, 0.0003,
        ]
    }

    /// Reference BGK in population space with Guo forcing (Guo, Zheng & Shi 2002, eq. 20).
    fn reference_bgk(h: &mut [f64; Q], tau: f64, f: [f64; 2]) {
        let m = moments(h, f);
        let eq = equilibrium(&m);
        let w = 1.0 / tau;
        for i in 0..Q {
            let (cx, cy) = (CX[i] as f64, CY[i] as f64);
            let src = W[i]
                * (3.0 * ((cx - m.ux) * f[0] + (cy - m.uy) * f[1])
                    + 9.0 * (cx * m.ux + cy * m.uy) * (cx * f[0] + cy * f[1]));
            h[i] += -w * (h[i] - eq[i]) + (1.0 - 0.5 * w) * src;
        }
    }

    /// Reference TRT in population space (Ginzburg 2005), Guo source split by parity.
    fn reference_trt(h: &mut [f64; Q], tau: f64, magic: f64, f: [f64; 2]) {
        let m = moments(h, f);
        let eq = equilibrium(&m);
        let wp = 1.0 / tau;
        let wm = 1.0 / (magic / (tau - 0.5) + 0.5);
        let hin = *h;
        for i in 0..Q {
            let o = OPP[i];
            let (cx, cy) = (CX[i] as f64, CY[i] as f64);
            let cu = cx * m.ux + cy * m.uy;
            let cf = cx * f[0] + cy * f[1];
            let uf = m.ux * f[0] + m.uy * f[1];
            let (sp, sm) = (W[i] * (9.0 * cu * cf - 3.0 * uf), W[i] * 3.0 * cf);
            h[i] = hin[i]
                - wp * 0.5 * (hin[i] + hin[o] - eq[i] - eq[o])
                - wm * 0.5 * (hin[i] - hin[o] - eq[i] + eq[o])
                + (1.0 - 0.5 * wp) * sp
                + (1.0 - 0.5 * wm) * sm;
        }
    }

    #[test]
    fn moment_space_bgk_matches_population_space() {
        let (tau, force) = (0.8, [1e-4, -2e-4]);
        let (mut a, mut b) = (sample(), sample());
        reference_bgk(&mut a, tau, force);
        MomentCollider::<f64, false, { family::BGK }, true>(CollisionParams::new(
            Collision::Bgk,
            tau,
            None,
            force,
        ))
        .collide(&mut b);
        for i in 0..Q {
            assert!((a[i] - b[i]).abs() < 1e-15, "dir {i}: {} vs {}", a[i], b[i]);
        }
    }

    #[test]
    fn moment_space_trt_matches_population_space() {
        let (tau, magic, force) = (0.7, 3.0 / 16.0, [3e-5, 1e-5]);
        let (mut a, mut b) = (sample(), sample());
        reference_trt(&mut a, tau, magic, force);
        MomentCollider::<f64, false, { family::TRT }, true>(CollisionParams::new(
            Collision::Trt { magic },
            tau,
            None,
            force,
        ))
        .collide(&mut b);
        for i in 0..Q {
            assert!((a[i] - b[i]).abs() < 1e-15, "dir {i}: {} vs {}", a[i], b[i]);
        }
    }

    /// MRT with every rate 1/τ is BGK.
    #[test]
    fn mrt_with_equal_rates_is_bgk() {
        let (tau, force) = (0.9, [2e-5, 4e-5]);
        let (mut a, mut b) = (sample(), sample());
        reference_bgk(&mut a, tau, force);
        let model = Collision::Mrt {
            s_e: 1.0 / tau,
            s_eps: 1.0 / tau,
            s_q: Some(1.0 / tau),
        };
        MomentCollider::<f64, false, { family::MRT }, true>(CollisionParams::new(
            model, tau, None, force,
        ))
        .collide(&mut b);
        for i in 0..Q {
            assert!((a[i] - b[i]).abs() < 1e-15);
        }
    }

    fn collide_any(model: Collision, smag: bool, p: CollisionParams<f64>, h: &mut [f64; Q]) {
        use family::*;
        match (model, smag) {
            (Collision::Bgk, false) => MomentCollider::<_, false, BGK, true>(p).collide(h),
            (Collision::Bgk, true) => MomentCollider::<_, true, BGK, true>(p).collide(h),
            (Collision::Trt { .. }, false) => MomentCollider::<_, false, TRT, true>(p).collide(h),
            (Collision::Trt { .. }, true) => MomentCollider::<_, true, TRT, true>(p).collide(h),
            (Collision::Mrt { .. }, false) => MomentCollider::<_, false, MRT, true>(p).collide(h),
            (Collision::Mrt { .. }, true) => MomentCollider::<_, true, MRT, true>(p).collide(h),
        };
    }

    /// Every operator conserves mass and adds exactly F to the momentum (Guo 2002).
    #[test]
    fn conservation_and_momentum_source() {
        let force = [2e-5, -1e-5];
        for model in [
            Collision::Bgk,
            Collision::Trt { magic: 3.0 / 16.0 },
            Collision::Mrt {
                s_e: 1.3,
                s_eps: 1.1,
                s_q: None,
            },
        ] {
            for smag in [None, Some(0.16)] {
                let p = CollisionParams::<f64>::new(model, 0.56, smag, force);
                let mut h = sample();
                let before = moments(&h, [0.0, 0.0]);
                collide_any(model, smag.is_some(), p, &mut h);
                let after = moments(&h, [0.0, 0.0]);
                assert!((after.drho - before.drho).abs() < 1e-16, "{model:?} mass");
                let jb = [before.ux * before.rho, before.uy * before.rho];
                let ja = [after.ux * after.rho, after.uy * after.rho];
                assert!(
                    (ja[0] - jb[0] - force[0]).abs() < 1e-16,
                    "{model:?} {smag:?} jx"
                );
                assert!(
                    (ja[1] - jb[1] - force[1]).abs() < 1e-16,
                    "{model:?} {smag:?} jy"
                );
            }
        }
    }

    /// The Smagorinsky closure raises τ where the strain is large and leaves equilibrium alone.
    #[test]
    fn smagorinsky_raises_tau_only_off_equilibrium() {
        let p = CollisionParams::<f64>::new(Collision::Bgk, 0.51, Some(0.17), [0.0, 0.0]);
        let h = sample();
        let m = moments(&h, [0.0; 2]);
        let eq = equilibrium(&m);
        let (xx, yy, xy) = pi_neq(&h, &eq);
        assert!(smagorinsky_tau(&p, xx, yy, xy, m.rho) > 0.51 + 1e-3);
        let (xx, yy, xy) = pi_neq(&eq, &eq);
        assert!((smagorinsky_tau(&p, xx, yy, xy, m.rho) - 0.51).abs() < 1e-15);
    }

    /// The equilibrium is a fixed point of every operator without force.
    #[test]
    fn equilibrium_is_fixed_point() {
        let m = Moments {
            drho: 0.01,
            rho: 1.01,
            ux: 0.03,
            uy: -0.02,
        };
        let eq = equilibrium(&m);
        for model in [
            Collision::Bgk,
            Collision::Trt { magic: 0.25 },
            Collision::Mrt {
                s_e: 1.2,
                s_eps: 1.5,
                s_q: None,
            },
        ] {
            let mut h = eq;
            collide_any(
                model,
                true,
                CollisionParams::<f64>::new(model, 0.6, Some(0.17), [0.0, 0.0]),
                &mut h,
            );
            for i in 0..Q {
                assert!((h[i] - eq[i]).abs() < 1e-15);
            }
        }
    }
}
