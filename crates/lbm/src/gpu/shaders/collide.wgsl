// Collision and moments (the CPU's src/lbm/collision.rs), plus the plain-cell pull.

struct Moments {
    rho: real,
    ux: real,
    uy: real,
}

// Density and Guo-corrected velocity of pre-collision populations (collision.rs `moments`).
fn moments(h: array<real, 9>) -> Moments {
    let drho = h[0] + h[1] + h[2] + h[3] + h[4] + h[5] + h[6] + h[7] + h[8];
    let jx = h[1] - h[3] + h[5] - h[6] - h[7] + h[8];
    let jy = h[2] - h[4] + h[5] + h[6] - h[7] - h[8];
    let rho = real(1.0) + drho;
    let inv = real(1.0) / rho;
    return Moments(rho, (jx + real(0.5) * prm[P_FX]) * inv, (jy + real(0.5) * prm[P_FY]) * inv);
}

// s_q such that (1/s_ν − ½)(1/s_q − ½) = Λ (Ginzburg 2005).
fn odd_rate(s_nu: real, magic: real) -> real {
    return real(1.0) / (magic / (real(1.0) / s_nu - real(0.5)) + real(0.5));
}

fn relax(m: real, meq: real, s: real) -> real {
    return m - s * (m - meq);
}

fn relax_forced(m: real, meq: real, s: real, src: real) -> real {
    return m - s * (m - meq) + (real(1.0) - real(0.5) * s) * src;
}

// Moment-space collision of BGK, TRT and MRT with Guo forcing and the optional Smagorinsky
// closure (collision.rs `MomentCollider`; Lallemand & Luo 2000; Guo et al. 2002; Hou et al.
// 1996). Returns the pre-collision density (for the stability check).
fn collide(h: ptr<function, array<real, 9>>) -> real {
    let h0 = (*h)[0];
    let h1 = (*h)[1];
    let h2 = (*h)[2];
    let h3 = (*h)[3];
    let h4 = (*h)[4];
    let h5 = (*h)[5];
    let h6 = (*h)[6];
    let h7 = (*h)[7];
    let h8 = (*h)[8];
    // Moments (Lallemand & Luo 2000, eq. 11 basis).
    let s1 = h1 + h2 + h3 + h4;
    let s2 = h5 + h6 + h7 + h8;
    let drho = h0 + s1 + s2;
    var e = real(-4.0) * h0 - s1 + real(2.0) * s2;
    var eps = real(4.0) * h0 - real(2.0) * s1 + s2;
    var jx = h1 - h3 + h5 - h6 - h7 + h8;
    var jy = h2 - h4 + h5 + h6 - h7 - h8;
    var qx = real(-2.0) * (h1 - h3) + h5 - h6 - h7 + h8;
    var qy = real(-2.0) * (h2 - h4) + h5 + h6 - h7 - h8;
    var pxx = h1 - h2 + h3 - h4;
    var pxy = h5 - h6 + h7 - h8;
    let rho = real(1.0) + drho;
    let inv = real(1.0) / rho;
    let fx = prm[P_FX];
    let fy = prm[P_FY];
    var ux = jx * inv;
    var uy = jy * inv;
    var rux = jx;
    var ruy = jy;
    if FORCED == 1u {
        ux = (jx + real(0.5) * fx) * inv;
        uy = (jy + real(0.5) * fy) * inv;
        rux = rho * ux;
        ruy = rho * uy;
    }
    let ru2 = rux * ux + ruy * uy;
    // Shifted equilibria (Lallemand & Luo 2000, eq. 23).
    let e_eq = real(-2.0) * drho + real(3.0) * ru2;
    let eps_eq = drho - real(3.0) * ru2;
    let pxx_eq = rux * ux - ruy * uy;
    let pxy_eq = rux * uy;
    var s_e = prm[P_SE];
    var s_eps = prm[P_SEPS];
    var s_nu = prm[P_SNU];
    var s_q = prm[P_SQ];
    if SMAG == 1u {
        // Π^neq from the moments; τ_eff = ½[τ₀ + √(τ₀² + 18√2 C² |Π^neq| / ρ)] (Hou et al. 1996).
        let tr = (e - e_eq) * real(1.0 / 3.0);
        let dxx = pxx - pxx_eq;
        let dxy = pxy - pxy_eq;
        let pixx = real(0.5) * (tr + dxx);
        let piyy = real(0.5) * (tr - dxx);
        let q = sqrt(pixx * pixx + piyy * piyy + real(2.0) * dxy * dxy);
        let tau0 = prm[P_TAU0];
        let tau = real(0.5) * (tau0 + sqrt(tau0 * tau0 + prm[P_SMAG_K] * q / rho));
        s_nu = real(1.0) / tau;
        if FAMILY == 0u {
            s_e = s_nu;
            s_eps = s_nu;
            s_q = s_nu;
        } else if FAMILY == 1u {
            s_e = s_nu;
            s_eps = s_nu;
            s_q = odd_rate(s_nu, prm[P_MAGIC]);
        } else {
            let w = prm[P_SQ_MAGIC_WEIGHT];
            s_q = w * odd_rate(s_nu, prm[P_MAGIC]) + (real(1.0) - w) * prm[P_SQ];
        }
    }
    if FORCED == 1u {
        // Guo source in moment space (Guo, Zheng & Shi 2002; Lallemand & Luo 2000).
        let uf = ux * fx + uy * fy;
        e = relax_forced(e, e_eq, s_e, real(6.0) * uf);
        eps = relax_forced(eps, eps_eq, s_eps, real(-6.0) * uf);
        qx = relax_forced(qx, -rux, s_q, -fx);
        qy = relax_forced(qy, -ruy, s_q, -fy);
        pxx = relax_forced(pxx, pxx_eq, s_nu, real(2.0) * (ux * fx - uy * fy));
        pxy = relax_forced(pxy, pxy_eq, s_nu, ux * fy + uy * fx);
        jx = jx + fx;
        jy = jy + fy;
    } else {
        e = relax(e, e_eq, s_e);
        eps = relax(eps, eps_eq, s_eps);
        qx = relax(qx, -rux, s_q);
        qy = relax(qy, -ruy, s_q);
        pxx = relax(pxx, pxx_eq, s_nu);
        pxy = relax(pxy, pxy_eq, s_nu);
    }
    // Back to populations: h = Mᵀ D⁻¹ m, D = diag(9, 36, 36, 6, 12, 6, 12, 4, 4).
    let a0 = drho * real(1.0 / 9.0);
    let a1 = e * real(1.0 / 36.0);
    let a2 = eps * real(1.0 / 36.0);
    let a3 = jx * real(1.0 / 6.0);
    let a4 = qx * real(1.0 / 12.0);
    let a5 = jy * real(1.0 / 6.0);
    let a6 = qy * real(1.0 / 12.0);
    let a7 = pxx * real(0.25);
    let a8 = pxy * real(0.25);
    let axis = a0 - a1 - real(2.0) * a2;
    let diag = a0 + real(2.0) * a1 + a2;
    (*h)[0] = a0 - real(4.0) * a1 + real(4.0) * a2;
    (*h)[1] = axis + a3 - real(2.0) * a4 + a7;
    (*h)[2] = axis + a5 - real(2.0) * a6 - a7;
    (*h)[3] = axis - a3 + real(2.0) * a4 + a7;
    (*h)[4] = axis - a5 + real(2.0) * a6 - a7;
    (*h)[5] = diag + a3 + a4 + a5 + a6 + a8;
    (*h)[6] = diag - a3 - a4 + a5 + a6 - a8;
    (*h)[7] = diag - a3 - a4 - a5 - a6 + a8;
    (*h)[8] = diag + a3 + a4 - a5 - a6 - a8;
    return rho;
}

// Pull of a plain cell: population i at k comes from k − c_i.
fn pull(k: u32) -> array<real, 9> {
    let s = geo.stride;
    return array<real, 9>(
        ld(0u, k), ld(1u, k - 1u), ld(2u, k - s), ld(3u, k + 1u), ld(4u, k + s),
        ld(5u, k - s - 1u), ld(6u, k - s + 1u), ld(7u, k + s + 1u), ld(8u, k + s - 1u));
}

// Written out: a loop with a run-time index keeps `h` in memory on SIMD-per-lane drivers.
fn store(k: u32, h: array<real, 9>) {
    sto(0u, k, h[0]);
    sto(1u, k, h[1]);
    sto(2u, k, h[2]);
    sto(3u, k, h[3]);
    sto(4u, k, h[4]);
    sto(5u, k, h[5]);
    sto(6u, k, h[6]);
    sto(7u, k, h[7]);
    sto(8u, k, h[8]);
}

