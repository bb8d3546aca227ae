// Moving surfaces outside the fluid core (the CPU's src/lbm/moving.rs): cells next to a
// moving surface recomputed after a sweep with their links bounced back, partially saturated
// cells, and plain gathers and scatters of whole cells for the host's rules (rest fills,
// refills, momenta, full halos). Bound as group 2:
//   mv_idx  [n cells, n links or shares, cells[n], start[n + 1], links: body · 16 + dir,
//            then (PSM, with per-body sums) each share's body, then body_columns.wgsl's section]
//   mv_real links: [q[L], wall[L], momentum out[L]]
//           PSM:   [B[n], b[S], u_x[S], u_y[S], momentum out[2S]]
//           gather / scatter: [9 values per cell]
// The moving kernels bind the lattice group whose source is the buffer the sweep read and
// whose destination is the one it wrote.

@group(2) @binding(0) var<storage, read> mv_idx: array<u32>;
@group(2) @binding(1) var<storage, read_write> mv_real: array<real>;

// Shifted equilibrium at density 1 + δρ and velocity u (collision.rs `equilibrium`).
fn equilibrium(drho: real, rho: real, ux: real, uy: real) -> array<real, 9> {
    var eq: array<real, 9>;
    let usq = ux * ux + uy * uy;
    for (var i = 0u; i < 9u; i++) {
        let cu = real(CX[i]) * ux + real(CY[i]) * uy;
        let poly = real(3.0) * cu + real(4.5) * cu * cu - real(1.5) * usq;
        eq[i] = WT[i] * (drho + rho * poly);
    }
    return eq;
}

// Note a bad plan cell (the lowest index wins).
fn flag_bad_cell(c: u32) {
    atomicMin(&bad[3], c);
}

// One plan cell per thread: half-way (q = ½) or interpolated bounce-back with the moving
// wall term (Ladd 1994, eq. 3.3; Bouzidi, Firdaouss & Lallemand 2001, eq. 5), then the
// lattice's collision. Momentum f*_ī + f_i per link (seed eq. 5.47).
@compute @workgroup_size(64)
fn moving_links(@builtin(global_invocation_id) gid: vec3<u32>,
                @builtin(num_workgroups) groups: vec3<u32>) {
    let c = job(gid, groups);
    let n = mv_idx[0];
    let nl = mv_idx[1];
    if c >= n {
        return;
    }
    let k = mv_idx[2u + c];
    let x = k % geo.stride - 1u;
    let y = k / geo.stride - 1u;
    var h = gather(k, x, y);
    let first = mv_idx[2u + n + c];
    let last = mv_idx[3u + n + c];
    let dirs = 3u + 2u * n;
    for (var l = first; l < last; l++) {
        let i = mv_idx[dirs + l] & 15u;
        let q = mv_real[l];
        let wall = mv_real[nl + l];
        let out_i = ld(OPP[i], k);
        var hi: real;
        if q == real(0.5) {
            hi = out_i + wall;
        } else if q < real(0.5) {
            let ff = u32(i32(k) + CX[i] + CY[i] * i32(geo.stride));
            hi = real(2.0) * q * out_i + (real(1.0) - real(2.0) * q) * ld(OPP[i], ff) + wall;
        } else {
            let same = ld(i, k);
            hi = (out_i + (real(2.0) * q - real(1.0)) * same + wall) / (real(2.0) * q);
        }
        h[i] = hi;
        mv_real[2u * nl + l] = out_i + hi;
    }
    let rho = collide(&h);
    store(k, h);
    if !(rho > real(0.0)) {
        flag_bad_cell(c);
    }
}

// One partially saturated cell per thread (Noble & Torczynski 1998, eqs. 8–9; seed eqs.
// 5.53–5.54): f_i ← (1 − B) f_i^collided + Σ_s b_s (f_i + Ω^s_i); per share the momentum the
// solid takes, −Σ_i b_s Ω^s_i c_i.
@compute @workgroup_size(64)
fn moving_psm(@builtin(global_invocation_id) gid: vec3<u32>,
              @builtin(num_workgroups) groups: vec3<u32>) {
    let c = job(gid, groups);
    let n = mv_idx[0];
    let ns = mv_idx[1];
    if c >= n {
        return;
    }
    let k = mv_idx[2u + c];
    let x = k % geo.stride - 1u;
    let y = k / geo.stride - 1u;
    let h = gather(k, x, y);
    var post = h;
    let m = moments(h);
    collide(&post);
    let eq_fluid = equilibrium(m.rho - real(1.0), m.rho, m.ux, m.uy);
    let b_total = mv_real[c];
    var res: array<real, 9>;
    for (var i = 0u; i < 9u; i++) {
        res[i] = (real(1.0) - b_total) * post[i];
    }
    // A fully covered cell takes the solids' equilibria Σ_s b_s f^eq(ρ, u_s): the same mass
    // and momentum exchange, without the undamped reflected non-equilibrium part (the CPU's
    // partial.rs, `is_full`).
    var solid: array<real, 9>;
    let full = b_total >= real(1.0);
    let first = mv_idx[2u + n + c];
    let last = mv_idx[3u + n + c];
    for (var s = first; s < last; s++) {
        let b = mv_real[n + s];
        let eq_solid = equilibrium(m.rho - real(1.0), m.rho, mv_real[n + ns + s], mv_real[n + 2u * ns + s]);
        for (var i = 0u; i < 9u; i++) {
            solid[i] += b * eq_solid[i];
        }
        var px = real(0.0);
        var py = real(0.0);
        for (var i = 0u; i < 9u; i++) {
            let j = OPP[i];
            // Ω^s_i = [f_ī − f^eq_ī(ρ, u)] − [f_i − f^eq_i(ρ, u_s)] (Noble & Torczynski 1998, eq. 8).
            let omega_s = (h[j] - eq_fluid[j]) - (h[i] - eq_solid[i]);
            res[i] += b * (h[i] + omega_s);
            px += b * omega_s * real(CX[i]);
            py += b * omega_s * real(CY[i]);
        }
        let out = n + 3u * ns + 2u * s;
        mv_real[out] = -px;
        mv_real[out + 1u] = -py;
    }
    if full {
        res = solid;
    }
    store(k, res);
    var rho = real(1.0);
    for (var i = 0u; i < 9u; i++) {
        rho += res[i];
    }
    if !(rho > real(0.0)) {
        flag_bad_cell(c);
    }
}

// The 9 populations of each listed cell of the source buffer, into mv_real.
@compute @workgroup_size(64)
fn gather_cells(@builtin(global_invocation_id) gid: vec3<u32>,
                @builtin(num_workgroups) groups: vec3<u32>) {
    let c = job(gid, groups);
    if c >= mv_idx[0] {
        return;
    }
    let k = mv_idx[2u + c];
    for (var i = 0u; i < 9u; i++) {
        mv_real[9u * c + i] = ld(i, k);
    }
}

// Write the 9 populations of each listed cell from mv_real into the destination buffer.
@compute @workgroup_size(64)
fn scatter_cells(@builtin(global_invocation_id) gid: vec3<u32>,
                 @builtin(num_workgroups) groups: vec3<u32>) {
    let c = job(gid, groups);
    if c >= mv_idx[0] {
        return;
    }
    let k = mv_idx[2u + c];
    for (var i = 0u; i < 9u; i++) {
        sto(i, k, mv_real[9u * c + i]);
    }
}
