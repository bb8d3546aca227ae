// Entry points: sweeps, halo fills, halo pack/unpack, moments.

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
