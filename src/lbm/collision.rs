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

use super::d2q9::{CX, CY, OPP, Q, W};
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
#[derive(Debug, Clone, Copy)]
pub struct CollisionParams<T> {
    /// Molecular relaxation time τ₀ = 3ν + ½.
    pub tau0: T,
    /// TRT Λ.
    pub magic: T,
    /// MRT rates (s_e, s_ε, s_q); s_q < 0 means "derive from s_ν".
    pub s_e: T,
    /// See `s_e`.
    pub s_eps: T,
    /// See `s_e`.
    pub s_q: T,
    /// 18√2 C_s² (zero when the closure is off).
    pub smag_k: T,
    /// Body force density per cell, lattice units.
    pub force: [T; 2],
}

impl<T: Real> CollisionParams<T> {
    /// Build from the physical choice. `smagorinsky` is the constant C_s, if enabled.
    pub fn new(model: Collision, tau0: f64, smagorinsky: Option<f64>, force: [f64; 2]) -> Self {
        let (magic, s_e, s_eps, s_q) = match model {
            Collision::Bgk => (0.25, 0.0, 0.0, -1.0),
            Collision::Trt { magic } => (magic, 0.0, 0.0, -1.0),
            Collision::Mrt { s_e, s_eps, s_q } => (3.0 / 16.0, s_e, s_eps, s_q.unwrap_or(-1.0)),
        };
        let c = smagorinsky.unwrap_or(0.0);
        Self {
            tau0: T::from_f64(tau0),
            magic: T::from_f64(magic),
            s_e: T::from_f64(s_e),
            s_eps: T::from_f64(s_eps),
            s_q: T::from_f64(s_q),
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
#[inline(always)]
pub fn equilibrium<T: Real>(m: &Moments<T>) -> [T; Q] {
    let usq = m.ux * m.ux + m.uy * m.uy;
    let mut eq = [T::default(); Q];
    for i in 0..Q {
        let cu = T::from_f64(CX[i] as f64) * m.ux + T::from_f64(CY[i] as f64) * m.uy;
        let poly = T::from_f64(3.0) * cu + T::from_f64(4.5) * cu * cu - T::from_f64(1.5) * usq;
        eq[i] = T::from_f64(W[i]) * (m.drho + m.rho * poly);
    }
    eq
}

/// Smagorinsky relaxation time from the non-equilibrium momentum flux (Hou et al. 1996).
#[inline(always)]
fn smagorinsky_tau<T: Real>(p: &CollisionParams<T>, pxx: T, pyy: T, pxy: T, rho: T) -> T {
    let q = (pxx * pxx + pyy * pyy + T::from_f64(2.0) * pxy * pxy).sqrt();
    T::from_f64(0.5) * (p.tau0 + (p.tau0 * p.tau0 + p.smag_k * q / rho).sqrt())
}

/// Π^neq from the population deviations `h − h^eq`.
#[inline(always)]
fn pi_neq<T: Real>(h: &[T; Q], eq: &[T; Q]) -> (T, T, T) {
    let d = |i: usize| h[i] - eq[i];
    let diag = d(5) + d(6) + d(7) + d(8);
    (
        d(1) + d(3) + diag,
        d(2) + d(4) + diag,
        d(5) - d(6) + d(7) - d(8),
    )
}

/// A collision operator the row kernels can inline. `SMAG` switches the closure on.
pub trait Collider<T: Real>: Sync {
    /// Collide the shifted populations of one cell in place; returns the cell's moments
    /// (pre-collision, Guo-corrected velocity).
    fn collide(&self, h: &mut [T; Q]) -> Moments<T>;
}

/// BGK with Guo forcing.
pub struct Bgk<T, const SMAG: bool>(pub CollisionParams<T>);
/// TRT with Guo forcing split into symmetric and antisymmetric parts.
pub struct Trt<T, const SMAG: bool>(pub CollisionParams<T>);
/// Lallemand–Luo MRT with Guo forcing in moment space.
pub struct Mrt<T, const SMAG: bool>(pub CollisionParams<T>);

/// Guo source term F_i = w_i [3(c_i − u) + 9 (c_i·u) c_i]·F, returned as (symmetric, antisymmetric) parts.
#[inline(always)]
fn guo_parts<T: Real>(i: usize, m: &Moments<T>, f: [T; 2]) -> (T, T) {
    let cx = T::from_f64(CX[i] as f64);
    let cy = T::from_f64(CY[i] as f64);
    let w = T::from_f64(W[i]);
    let cu = cx * m.ux + cy * m.uy;
    let cf = cx * f[0] + cy * f[1];
    let uf = m.ux * f[0] + m.uy * f[1];
    (
        w * (T::from_f64(9.0) * cu * cf - T::from_f64(3.0) * uf),
        w * T::from_f64(3.0) * cf,
    )
}

impl<T: Real, const SMAG: bool> Collider<T> for Bgk<T, SMAG> {
    #[inline(always)]
    fn collide(&self, h: &mut [T; Q]) -> Moments<T> {
        let p = &self.0;
        let m = moments(h, p.force);
        let eq = equilibrium(&m);
        let tau = if SMAG {
            let (xx, yy, xy) = pi_neq(h, &eq);
            smagorinsky_tau(p, xx, yy, xy, m.rho)
        } else {
            p.tau0
        };
        let omega = T::from_f64(1.0) / tau;
        let fpre = T::from_f64(1.0) - T::from_f64(0.5) * omega;
        for i in 0..Q {
            let (s, a) = guo_parts(i, &m, p.force);
            h[i] = h[i] - omega * (h[i] - eq[i]) + fpre * (s + a);
        }
        m
    }
}

impl<T: Real, const SMAG: bool> Collider<T> for Trt<T, SMAG> {
    #[inline(always)]
    fn collide(&self, h: &mut [T; Q]) -> Moments<T> {
        let p = &self.0;
        let m = moments(h, p.force);
        let eq = equilibrium(&m);
        let tau = if SMAG {
            let (xx, yy, xy) = pi_neq(h, &eq);
            smagorinsky_tau(p, xx, yy, xy, m.rho)
        } else {
            p.tau0
        };
        let half = T::from_f64(0.5);
        let one = T::from_f64(1.0);
        let wp = one / tau;
        // Λ = (τ⁺ − ½)(τ⁻ − ½) (Ginzburg 2005).
        let wm = one / (p.magic / (tau - half) + half);
        let (fp, fm) = (one - half * wp, one - half * wm);
        let h_in = *h;
        for i in 0..Q {
            let o = OPP[i];
            let (hp, hm) = (half * (h_in[i] + h_in[o]), half * (h_in[i] - h_in[o]));
            let (ep, em) = (half * (eq[i] + eq[o]), half * (eq[i] - eq[o]));
            let (s, a) = guo_parts(i, &m, p.force);
            h[i] = h_in[i] - wp * (hp - ep) - wm * (hm - em) + fp * s + fm * a;
        }
        m
    }
}

impl<T: Real, const SMAG: bool> Collider<T> for Mrt<T, SMAG> {
    #[inline(always)]
    fn collide(&self, h: &mut [T; Q]) -> Moments<T> {
        let p = &self.0;
        let c = |v: f64| T::from_f64(v);
        // Moments of the shifted populations (Lallemand & Luo 2000, eq. 11 basis).
        let s1 = h[1] + h[2] + h[3] + h[4];
        let s2 = h[5] + h[6] + h[7] + h[8];
        let drho = h[0] + s1 + s2;
        let e = c(-4.0) * h[0] - s1 + c(2.0) * s2;
        let eps = c(4.0) * h[0] - c(2.0) * s1 + s2;
        let jx = h[1] - h[3] + h[5] - h[6] - h[7] + h[8];
        let jy = h[2] - h[4] + h[5] + h[6] - h[7] - h[8];
        let qx = c(-2.0) * (h[1] - h[3]) + h[5] - h[6] - h[7] + h[8];
        let qy = c(-2.0) * (h[2] - h[4]) + h[5] + h[6] - h[7] - h[8];
        let pxx = h[1] - h[2] + h[3] - h[4];
        let pxy = h[5] - h[6] + h[7] - h[8];
        let rho = c(1.0) + drho;
        let inv = c(1.0) / rho;
        let (fx, fy) = (p.force[0], p.force[1]);
        let ux = (jx + c(0.5) * fx) * inv;
        let uy = (jy + c(0.5) * fy) * inv;
        let (rux, ruy) = (rho * ux, rho * uy);
        let ru2 = rux * ux + ruy * uy;
        // Shifted equilibria (M w = (1, −2, 1, 0, …) removed).
        let e_eq = c(-2.0) * drho + c(3.0) * ru2;
        let eps_eq = drho - c(3.0) * ru2;
        let pxx_eq = rux * ux - ruy * uy;
        let pxy_eq = rux * uy;
        let s_nu = if SMAG {
            // Π^neq from the moments: tr Π = (e + 4ρ)/3, Π_xx − Π_yy = p_xx, Π_xy = p_xy.
            let tr = (e - e_eq) * c(1.0 / 3.0);
            let dxx = pxx - pxx_eq;
            let dxy = pxy - pxy_eq;
            c(1.0) / smagorinsky_tau(p, c(0.5) * (tr + dxx), c(0.5) * (tr - dxx), dxy, rho)
        } else {
            c(1.0) / p.tau0
        };
        let s_q = if p.s_q < c(0.0) {
            c(1.0) / (c(0.5) + c(3.0 / 16.0) / (c(1.0) / s_nu - c(0.5)))
        } else {
            p.s_q
        };
        // Guo source in moment space: M F_i.
        let uf = ux * fx + uy * fy;
        let relax = |m: T, meq: T, s: T, src: T| m - s * (m - meq) + (c(1.0) - c(0.5) * s) * src;
        let e = relax(e, e_eq, p.s_e, c(6.0) * uf);
        let eps = relax(eps, eps_eq, p.s_eps, c(-6.0) * uf);
        let qx = relax(qx, -rux, s_q, -fx);
        let qy = relax(qy, -ruy, s_q, -fy);
        let pxx = relax(pxx, pxx_eq, s_nu, c(2.0) * (ux * fx - uy * fy));
        let pxy = relax(pxy, pxy_eq, s_nu, ux * fy + uy * fx);
        let jx = jx + fx;
        let jy = jy + fy;
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
        let axis = a0 - a1 - c(2.0) * a2;
        let diag = a0 + c(2.0) * a1 + a2;
        h[0] = a0 - c(4.0) * a1 + c(4.0) * a2;
        h[1] = axis + a3 - c(2.0) * a4 + a7;
        h[2] = axis + a5 - c(2.0) * a6 - a7;
        h[3] = axis - a3 + c(2.0) * a4 + a7;
        h[4] = axis - a5 + c(2.0) * a6 - a7;
        h[5] = diag + a3 + a4 + a5 + a6 + a8;
        h[6] = diag - a3 - a4 + a5 + a6 - a8;
        h[7] = diag - a3 - a4 - a5 - a6 + a8;
        h[8] = diag + a3 + a4 - a5 - a6 - a8;
        Moments { drho, rho, ux, uy }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> [f64; Q] {
        [
            0.011, -0.003, 0.004, 0.002, -0.001, 0.0005, 0.0012, -0.0007, 0.0003,
        ]
    }

    /// MRT with every rate equal to 1/τ must reduce to BGK, forcing included.
    #[test]
    fn mrt_with_equal_rates_is_bgk() {
        let tau = 0.8;
        let force = [1e-4, -2e-4];
        let bgk = Bgk::<f64, false>(CollisionParams::new(Collision::Bgk, tau, None, force));
        let mrt_model = Collision::Mrt {
            s_e: 1.0 / tau,
            s_eps: 1.0 / tau,
            s_q: Some(1.0 / tau),
        };
        let mrt = Mrt::<f64, false>(CollisionParams::new(mrt_model, tau, None, force));
        let (mut a, mut b) = (sample(), sample());
        bgk.collide(&mut a);
        mrt.collide(&mut b);
        for i in 0..Q {
            assert!((a[i] - b[i]).abs() < 1e-15, "dir {i}: {} vs {}", a[i], b[i]);
        }
    }

    /// TRT with Λ = (τ − ½)² has ω⁻ = ω⁺ and must reduce to BGK.
    #[test]
    fn trt_with_equal_rates_is_bgk() {
        let tau = 0.7;
        let force = [3e-5, 1e-5];
        let bgk = Bgk::<f64, false>(CollisionParams::new(Collision::Bgk, tau, None, force));
        let trt = Trt::<f64, false>(CollisionParams::new(
            Collision::Trt {
                magic: (tau - 0.5) * (tau - 0.5),
            },
            tau,
            None,
            force,
        ));
        let (mut a, mut b) = (sample(), sample());
        bgk.collide(&mut a);
        trt.collide(&mut b);
        for i in 0..Q {
            assert!((a[i] - b[i]).abs() < 1e-15);
        }
    }

    /// Every operator conserves mass and adds exactly F to the momentum (Guo 2002).
    #[test]
    fn conservation_and_momentum_source() {
        let force = [2e-5, -1e-5];
        let models = [
            Collision::Bgk,
            Collision::Trt { magic: 3.0 / 16.0 },
            Collision::Mrt {
                s_e: 1.3,
                s_eps: 1.1,
                s_q: None,
            },
        ];
        for model in models {
            for smag in [None, Some(0.16)] {
                let p = CollisionParams::<f64>::new(model, 0.56, smag, force);
                let mut h = sample();
                let before = moments(&h, [0.0, 0.0]);
                match (model, smag.is_some()) {
                    (Collision::Bgk, false) => Bgk::<_, false>(p).collide(&mut h),
                    (Collision::Bgk, true) => Bgk::<_, true>(p).collide(&mut h),
                    (Collision::Trt { .. }, false) => Trt::<_, false>(p).collide(&mut h),
                    (Collision::Trt { .. }, true) => Trt::<_, true>(p).collide(&mut h),
                    (Collision::Mrt { .. }, false) => Mrt::<_, false>(p).collide(&mut h),
                    (Collision::Mrt { .. }, true) => Mrt::<_, true>(p).collide(&mut h),
                };
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
        let p = CollisionParams::<f64>::new(
            Collision::Mrt {
                s_e: 1.2,
                s_eps: 1.5,
                s_q: None,
            },
            0.6,
            Some(0.17),
            [0.0, 0.0],
        );
        let mut h = eq;
        Mrt::<_, true>(p).collide(&mut h);
        for i in 0..Q {
            assert!((h[i] - eq[i]).abs() < 1e-15);
        }
    }
}
