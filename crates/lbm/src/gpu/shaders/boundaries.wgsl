// Boundary links (the CPU's src/lbm/boundary.rs): Zou–He faces and corners, bounce-back
// with momentum exchange.

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

