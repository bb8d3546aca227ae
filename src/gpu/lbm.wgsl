// D2Q9 lattice Boltzmann on the GPU: the same algorithm as the CPU kernels in src/lbm,
// operation for operation, so both backends agree to round-off.
//
// The host prepends a prelude that defines `real` (f32 or f64), the population bindings
// (split over several buffers when one binding cannot hold the lattice) and the accessors
// `ld` (current buffer), `ldd` / `sto` (destination buffer). Populations are shifted,
// h_i = f_i − w_i, structure-of-arrays: population i of padded cell k is at i·plane + k.
// Overridable constants select the collision at pipeline creation, like the CPU's
// const generics: FAMILY 0 BGK, 1 TRT, 2 MRT; SMAG and FORCED are 0 or 1.

override FAMILY: u32 = 0u;
override SMAG: u32 = 0u;
override FORCED: u32 = 0u;

struct Geo {
    nx: u32,
    ny: u32,
    stride: u32,
    plane: u32,
    // Solids (force slots per special cell).
    ns: u32,
    _pad0: u32,
    // Face kinds, 8 bits each (west, east, south, north): see FACE_*.
    faces: u32,
    // Bit 0: the west halo is exchanged with a peer; bit 1: the east halo.
    peers: u32,
    // Offset of the cell types in `geom` (the plain-cell bit mask comes first).
    types_at: u32,
    // Offsets in `aux`: halo staging, moment output.
    halo_at: u32,
    out_at: u32,
    _pad: u32,
}

const FACE_OTHER: u32 = 0u;
const FACE_PERIODIC: u32 = 1u;
const FACE_FREE_SLIP: u32 = 2u;
const FACE_OUTFLOW: u32 = 3u;
const FACE_VELOCITY: u32 = 4u;
const FACE_PRESSURE: u32 = 5u;

const MAX_SOLID: u32 = 0xFFEFu;
const NONE: u32 = 0xFFFFFFFFu;

// Real parameters (`prm`): collision, force, inlet scale, pressure per face, then solid
// velocities (2 per solid) and Zou–He face velocities (2 per face cell: W, E, S, N).
const P_TAU0: u32 = 0u;
const P_MAGIC: u32 = 1u;
const P_SE: u32 = 2u;
const P_SEPS: u32 = 3u;
const P_SNU: u32 = 4u;
const P_SQ: u32 = 5u;
const P_SQ_MAGIC_WEIGHT: u32 = 6u;
const P_SMAG_K: u32 = 7u;
const P_FX: u32 = 8u;
const P_FY: u32 = 9u;
const P_INLET: u32 = 10u;
const P_PRESSURE: u32 = 11u;
const P_SOLIDS: u32 = 16u;

@group(0) @binding(0) var<uniform> geo: Geo;
@group(0) @binding(1) var<storage, read> prm: array<real>;
// Plain-cell bits (one per padded cell), then one cell type per padded cell.
@group(0) @binding(2) var<storage, read> geom: array<u32>;
// Force slots, halo staging and moment output (offsets in `geo`).
@group(0) @binding(3) var<storage, read_write> aux: array<real>;
// First unstable step, the first bad cell (y·nx + x) in it, and the step counter (steps
// done before the one being computed; advanced on the device so that many steps can be
// queued in one submission).
@group(0) @binding(4) var<storage, read_write> bad: array<atomic<u32>, 4>;
// Cell lists: entry 0 holds the count; then (padded cell, force slot) or (x, y).
@group(1) @binding(0) var<storage, read> list: array<vec2<u32>>;

const CX: array<i32, 9> = array<i32, 9>(0, 1, 0, -1, 0, 1, -1, -1, 1);
const CY: array<i32, 9> = array<i32, 9>(0, 0, 1, 0, -1, 1, 1, -1, -1);
const OPP: array<u32, 9> = array<u32, 9>(0u, 3u, 4u, 1u, 2u, 7u, 8u, 5u, 6u);
const MIRROR_X: array<u32, 9> = array<u32, 9>(0u, 3u, 2u, 1u, 4u, 6u, 5u, 8u, 7u);
const MIRROR_Y: array<u32, 9> = array<u32, 9>(0u, 1u, 4u, 3u, 2u, 8u, 7u, 6u, 5u);
const WT: array<real, 9> = array<real, 9>(
    4.0 / 9.0, 1.0 / 9.0, 1.0 / 9.0, 1.0 / 9.0, 1.0 / 9.0,
    1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0);
// Populations leaving through the west face (c_x = −1) and the east face (c_x = +1).
const WESTWARD: array<u32, 3> = array<u32, 3>(3u, 6u, 7u);
const EASTWARD: array<u32, 3> = array<u32, 3>(1u, 5u, 8u);

fn face_kind(face: u32) -> u32 {
    return (geo.faces >> (8u * face)) & 0xFFu;
}

fn is_open(face: u32) -> bool {
    let k = face_kind(face);
    return k == FACE_VELOCITY || k == FACE_PRESSURE;
}

fn cell_type(k: u32) -> u32 {
    return geom[geo.types_at + k];
}

fn is_plain(k: u32) -> bool {
    return ((geom[k >> 5u] >> (k & 31u)) & 1u) == 1u;
}

// Padded index of interior cell (x, y) offset by (dx, dy).
fn idx(x: i32, y: i32) -> u32 {
    return u32(y + 1) * geo.stride + u32(x + 1);
}

// Direction i turned by q quarter turns counter-clockwise (d2q9.rs `rotate`).
fn rot(i: u32, q: u32) -> u32 {
    if i == 0u {
        return 0u;
    }
    if i <= 4u {
        return 1u + (i - 1u + q) % 4u;
    }
    return 5u + (i - 5u + q) % 4u;
}

// Record an unstable cell: only cells of the first unstable step count.
fn flag_bad(x: u32, y: u32) {
    let step = atomicLoad(&bad[2]);
    if atomicLoad(&bad[0]) < step {
        return;
    }
    atomicMin(&bad[0], step);
    atomicMin(&bad[1], y * geo.nx + x);
}

// One thread: the step is done.
@compute @workgroup_size(1)
fn advance_step() {
    atomicAdd(&bad[2], 1u);
}

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

// Velocity of an open face at position s along it, times the inlet ramp (zero when the
// face is a pressure face; `ok` says which).
struct FaceVelocity {
    ok: bool,
    u: vec2<real>,
}

fn face_velocity(face: u32, s: u32) -> FaceVelocity {
    if face_kind(face) != FACE_VELOCITY {
        return FaceVelocity(false, vec2<real>(real(0.0), real(0.0)));
    }
    let ny = geo.ny;
    let nx = geo.nx;
    var base = P_SOLIDS + 2u * geo.ns;
    if face >= 1u {
        base += 2u * ny;
    }
    if face >= 2u {
        base += 2u * ny;
    }
    if face >= 3u {
        base += 2u * nx;
    }
    let at = base + 2u * s;
    let r = prm[P_INLET];
    return FaceVelocity(true, vec2<real>(prm[at] * r, prm[at + 1u] * r));
}

// Zou & He (1997) on one face, written for the west face (eqs. 19–23) and rotated, in
// shifted populations (boundary.rs `zou_he_face`).
fn zou_he_face(face: u32, s: u32, h: ptr<function, array<real, 9>>) {
    var q = 0u;
    if face == 1u {
        q = 2u;
    } else if face == 2u {
        q = 1u;
    } else if face == 3u {
        q = 3u;
    }
    let n = rot(1u, q);
    let t = rot(2u, q);
    let known = (*h)[0] + (*h)[rot(2u, q)] + (*h)[rot(4u, q)]
        + real(2.0) * ((*h)[rot(3u, q)] + (*h)[rot(6u, q)] + (*h)[rot(7u, q)]);
    var rho: real;
    var un: real;
    var ut = real(0.0);
    let v = face_velocity(face, s);
    if v.ok {
        un = real(CX[n]) * v.u.x + real(CY[n]) * v.u.y;
        ut = real(CX[t]) * v.u.x + real(CY[t]) * v.u.y;
        // ρ − 1 = (Σ_known h + u_n) / (1 − u_n) (Zou & He 1997, eq. 19, shifted).
        rho = real(1.0) + (known + un) / (real(1.0) - un);
    } else {
        let d = prm[P_PRESSURE + face];
        rho = real(1.0) + d;
        // u_n = (δρ − Σ_known h) / ρ (Zou & He 1997, shifted).
        un = (d - known) / rho;
    }
    let half_diff = real(0.5) * ((*h)[rot(2u, q)] - (*h)[rot(4u, q)]);
    // Zou & He 1997, eqs. 20–22.
    (*h)[rot(1u, q)] = (*h)[rot(3u, q)] + real(2.0 / 3.0) * rho * un;
    (*h)[rot(5u, q)] = (*h)[rot(7u, q)] - half_diff + rho * un / real(6.0) + real(0.5) * rho * ut;
    (*h)[rot(8u, q)] = (*h)[rot(6u, q)] + half_diff + rho * un / real(6.0) - real(0.5) * rho * ut;
}

// Corner of two open faces (Zou & He 1997, sec. 4; Hecht & Harting 2010, sec. 3.2), in
// shifted populations (boundary.rs `zou_he_corner`).
fn zou_he_corner(x: u32, y: u32, xf: u32, yf: u32, h: ptr<function, array<real, 9>>) {
    var q = 3u;
    if xf == 0u && yf == 2u {
        q = 0u;
    } else if xf == 1u && yf == 2u {
        q = 1u;
    } else if xf == 1u && yf == 3u {
        q = 2u;
    }
    var u = vec2<real>(real(0.0), real(0.0));
    let vy = face_velocity(yf, x);
    let vx = face_velocity(xf, y);
    if vy.ok {
        u = vy.u;
    } else if vx.ok {
        u = vx.u;
    }
    let a = rot(1u, q);
    let b = rot(2u, q);
    let ua = real(CX[a]) * u.x + real(CY[a]) * u.y;
    let ub = real(CX[b]) * u.x + real(CY[b]) * u.y;
    // Density of the interior neighbour along the inward diagonal.
    let dn = rot(5u, q);
    let nbr = idx(i32(x) + CX[dn], i32(y) + CY[dn]);
    var drho = real(0.0);
    for (var i = 0u; i < 9u; i++) {
        drho += ld(i, nbr);
    }
    let rho = real(1.0) + drho;
    (*h)[a] = (*h)[rot(3u, q)] + real(2.0 / 3.0) * rho * ua;
    (*h)[b] = (*h)[rot(4u, q)] + real(2.0 / 3.0) * rho * ub;
    (*h)[rot(5u, q)] = (*h)[rot(7u, q)] + rho * (ua + ub) / real(6.0);
    let known = (*h)[0] + (*h)[a] + (*h)[b] + (*h)[rot(3u, q)] + (*h)[rot(4u, q)]
        + (*h)[rot(5u, q)] + (*h)[rot(7u, q)];
    let skew = rho * (ub - ua) / real(6.0);
    (*h)[rot(6u, q)] = real(0.5) * (drho - known + skew);
    (*h)[rot(8u, q)] = real(0.5) * (drho - known - skew);
}

// Pre-collision populations of a fluid cell next to solids or open faces (boundary.rs
// `gather_special`): half-way bounce-back with Ladd's moving-wall term, Zou–He links,
// and, when `slot` is not NONE, the momentum exchanged with each solid stored in it.
fn gather_special(k: u32, x: u32, y: u32, slot: u32) -> array<real, 9> {
    var h: array<real, 9>;
    var unknown = false;
    let ns = geo.ns;
    if slot != NONE {
        for (var s = 0u; s < ns; s++) {
            aux[2u * (slot * ns + s)] = real(0.0);
            aux[2u * (slot * ns + s) + 1u] = real(0.0);
        }
    }
    for (var i = 0u; i < 9u; i++) {
        let n = u32(i32(k) - CX[i] - CY[i] * i32(geo.stride));
        let t = cell_type(n);
        if t == 0u {
            h[i] = ld(i, n);
        } else if t <= MAX_SOLID {
            let vx = prm[P_SOLIDS + 2u * (t - 1u)];
            let vy = prm[P_SOLIDS + 2u * (t - 1u) + 1u];
            let cu = real(CX[i]) * vx + real(CY[i]) * vy;
            let back = ld(OPP[i], k);
            // Half-way bounce-back with wall velocity, ρ_w = 1 (Ladd 1994, eq. 3.3).
            h[i] = back + 6.0 * WT[i] * cu;
            if slot != NONE {
                // The solid receives −(f*_ī + f_i) c_i (Ladd 1994). Only the shifted part
                // h*_ī + h_i is summed here; the host adds the −2 w_i c_i part per slot in
                // f64 (summing 2w_i ≈ 0.2 in f32 would swamp small net forces).
                let m = back + h[i];
                let at = 2u * (slot * ns + t - 1u);
                aux[at] -= m * real(CX[i]);
                aux[at + 1u] -= m * real(CY[i]);
            }
        } else {
            unknown = true;
        }
    }
    if unknown {
        var xf = NONE;
        var yf = NONE;
        if x == 0u && is_open(0u) {
            xf = 0u;
        } else if x + 1u == geo.nx && is_open(1u) {
            xf = 1u;
        }
        if y == 0u && is_open(2u) {
            yf = 2u;
        } else if y + 1u == geo.ny && is_open(3u) {
            yf = 3u;
        }
        if xf != NONE && yf != NONE {
            zou_he_corner(x, y, xf, yf, &h);
        } else if xf != NONE {
            zou_he_face(xf, y, &h);
        } else if yf != NONE {
            zou_he_face(yf, x, &h);
        }
    }
    return h;
}

fn gather(k: u32, x: u32, y: u32) -> array<real, 9> {
    if is_plain(k) {
        return pull(k);
    }
    return gather_special(k, x, y, NONE);
}

// Linear index of a 1-D job over a 2-D dispatch of 64-wide workgroups.
fn job(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.y * groups.x * 64u + gid.x;
}

// Bulk cells: all 8 neighbours plain fluid, not next to an exchanged face (the others
// are in the cell lists: a SIMD-per-lane driver such as lavapipe runs a divergent
// boundary path for every lane, which made one merged kernel 2x slower there). One thread
// per cell; rows strided over the y dispatch.
@compute @workgroup_size(64)
fn sweep_bulk(@builtin(global_invocation_id) gid: vec3<u32>,
         @builtin(num_workgroups) groups: vec3<u32>) {
    let x = gid.x;
    if x >= geo.nx {
        return;
    }
    for (var y = gid.y; y < geo.ny; y += groups.y) {
        let k = (y + 1u) * geo.stride + x + 1u;
        if !is_plain(k) {
            continue;
        }
        var h = pull(k);
        let rho = collide(&h);
        store(k, h);
        if !(rho > real(0.0)) {
            flag_bad(x, y);
        }
    }
}

// Special or edge cells from the list bound in group 1: (padded cell, force slot).
@compute @workgroup_size(64)
fn sweep_list(@builtin(global_invocation_id) gid: vec3<u32>,
              @builtin(num_workgroups) groups: vec3<u32>) {
    let j = job(gid, groups);
    if j >= list[0].x {
        return;
    }
    let e = list[j + 1u];
    let k = e.x;
    let x = k % geo.stride - 1u;
    let y = k / geo.stride - 1u;
    var h = gather_special(k, x, y, e.y);
    let rho = collide(&h);
    store(k, h);
    if !(rho > real(0.0)) {
        flag_bad(x, y);
    }
}

// Halo of the x faces of the destination buffer: periodic wrap, free-slip mirror or
// zero-gradient copy (boundary.rs `fill_halo`, first half).
@compute @workgroup_size(64)
fn fill_halo_x(@builtin(global_invocation_id) gid: vec3<u32>,
               @builtin(num_workgroups) groups: vec3<u32>) {
    let yp = job(gid, groups) + 1u;
    if yp > geo.ny {
        return;
    }
    let nx = geo.nx;
    for (var side = 0u; side < 2u; side++) {
        let kind = face_kind(side);
        var halo_x = 0u;
        var inner_x = 1u;
        var wrap_x = nx;
        if side == 1u {
            halo_x = nx + 1u;
            inner_x = nx;
            wrap_x = 1u;
        }
        var from_x = inner_x;
        if kind == FACE_PERIODIC {
            from_x = wrap_x;
        } else if kind != FACE_FREE_SLIP && kind != FACE_OUTFLOW {
            continue;
        }
        let row = yp * geo.stride;
        for (var i = 0u; i < 9u; i++) {
            var from_i = i;
            if kind == FACE_FREE_SLIP {
                from_i = MIRROR_X[i];
            }
            sto(i, row + halo_x, ldd(from_i, row + from_x));
        }
    }
}

// Halo of the y faces over the full padded width (after the x faces: corners agree).
@compute @workgroup_size(64)
fn fill_halo_y(@builtin(global_invocation_id) gid: vec3<u32>,
               @builtin(num_workgroups) groups: vec3<u32>) {
    let xp = job(gid, groups);
    if xp >= geo.stride {
        return;
    }
    let ny = geo.ny;
    for (var side = 0u; side < 2u; side++) {
        let kind = face_kind(2u + side);
        var halo_y = 0u;
        var inner_y = 1u;
        var wrap_y = ny;
        if side == 1u {
            halo_y = ny + 1u;
            inner_y = ny;
            wrap_y = 1u;
        }
        var from_y = inner_y;
        if kind == FACE_PERIODIC {
            from_y = wrap_y;
        } else if kind != FACE_FREE_SLIP && kind != FACE_OUTFLOW {
            continue;
        }
        for (var i = 0u; i < 9u; i++) {
            var from_i = i;
            if kind == FACE_FREE_SLIP {
                from_i = MIRROR_Y[i];
            }
            sto(i, halo_y * geo.stride + xp, ldd(from_i, from_y * geo.stride + xp));
        }
    }
}

// Copy the 3 populations that leave each exchanged face (whole padded column) from the
// current buffer into the halo staging area: [side][3][ny + 2].
@compute @workgroup_size(64)
fn pack_halo(@builtin(global_invocation_id) gid: vec3<u32>,
             @builtin(num_workgroups) groups: vec3<u32>) {
    let yp = job(gid, groups);
    let rows = geo.ny + 2u;
    if yp >= rows {
        return;
    }
    for (var d = 0u; d < 3u; d++) {
        if (geo.peers & 1u) != 0u {
            aux[geo.halo_at + d * rows + yp] = ld(WESTWARD[d], yp * geo.stride + 1u);
        }
        if (geo.peers & 2u) != 0u {
            aux[geo.halo_at + (3u + d) * rows + yp] = ld(EASTWARD[d], yp * geo.stride + geo.nx);
        }
    }
}

// Write the received columns ([side][3][ny + 2] after the send area) into the exchanged
// x halos of the destination binding (bind the group whose destination is the current buffer).
@compute @workgroup_size(64)
fn unpack_halo(@builtin(global_invocation_id) gid: vec3<u32>,
               @builtin(num_workgroups) groups: vec3<u32>) {
    let yp = job(gid, groups);
    let rows = geo.ny + 2u;
    if yp >= rows {
        return;
    }
    let inbox = geo.halo_at + 6u * rows;
    for (var d = 0u; d < 3u; d++) {
        if (geo.peers & 1u) != 0u {
            sto(EASTWARD[d], yp * geo.stride, aux[inbox + d * rows + yp]);
        }
        if (geo.peers & 2u) != 0u {
            sto(WESTWARD[d], yp * geo.stride + geo.nx + 1u, aux[inbox + (3u + d) * rows + yp]);
        }
    }
}

fn cell_moments(x: u32, y: u32) -> Moments {
    let k = idx(i32(x), i32(y));
    if cell_type(k) != 0u {
        return Moments(real(1.0), real(0.0), real(0.0));
    }
    return moments(gather(k, x, y));
}

// Density and velocity of every interior cell: [ρ | u_x | u_y] × (ny · nx) at `out_at`.
@compute @workgroup_size(64)
fn moments_all(@builtin(global_invocation_id) gid: vec3<u32>,
               @builtin(num_workgroups) groups: vec3<u32>) {
    let x = gid.x;
    if x >= geo.nx {
        return;
    }
    let n = geo.nx * geo.ny;
    for (var y = gid.y; y < geo.ny; y += groups.y) {
        let m = cell_moments(x, y);
        let c = geo.out_at + y * geo.nx + x;
        aux[c] = m.rho;
        aux[c + n] = m.ux;
        aux[c + 2u * n] = m.uy;
    }
}

// Density and velocity of the cells (x, y) in the list: 3 values each at `out_at`.
@compute @workgroup_size(64)
fn moments_list(@builtin(global_invocation_id) gid: vec3<u32>,
                @builtin(num_workgroups) groups: vec3<u32>) {
    let j = job(gid, groups);
    if j >= list[0].x {
        return;
    }
    let e = list[j + 1u];
    let m = cell_moments(e.x, e.y);
    aux[geo.out_at + 3u * j] = m.rho;
    aux[geo.out_at + 3u * j + 1u] = m.ux;
    aux[geo.out_at + 3u * j + 2u] = m.uy;
}
