// Per-body column sums of the momenta moving_links or moving_psm just wrote (BodyColumns in
// src/lbm/plans.rs; the host's per-link collect in src/coupling/links.rs and psm.rs does the
// same sums): one thread per group of bodies (a body, or its images across a periodic y
// face). Appended to moving.wgsl (its bindings, group 2):
//   mv_idx: [n, m, cells[n], start[n + 1], word[m] (links: body · 16 + dir; PSM: body),
//            ng, nb, ny, origins_at, work_at, out_at, rows[ny + 1],
//            groups[5 ng] (first local column, columns, first slot, members' start, end),
//            members[nb], bodies[4 nb] (first row, rows, anchor column, anchor row)];
//   mv_real: the moving kernel's data (links: momentum of link l at 2m + l; PSM: of share s
//            at n + 3m + 2s), then 1 (at origins_at − 1), then per body the arm of its anchor cell's centre from the
//            body's centre (2 reals at origins_at), per slot 7 reals of work at work_at
//            (three sums, their three compensations, the count) and 4 at out_at (the three
//            sums and the count, read back).
// A slot sums its column's cells in increasing row (the group's bodies in turn, in
// increasing first row), each cell's links or shares in plan order: the order of the host's
// serial collect, whatever the slab. The anchor is the cell that holds the body's centre
// (local column, as i32, and row): a cell's arm is the anchor's plus a whole number of
// cells, so it has the same bits on any slab.

// mv_real[at] (with its compensation at at + 3) += v: Knuth's TwoSum, so that an f32 run's
// sums keep about twice f32's precision (the host sums in f64). `one` is 1 read from the
// buffer: a compiler that may reassociate inexact arithmetic (Mesa's NIR does) cannot
// prove (s + v) · one − s = v, so the error term is not folded away to 0.
fn add_compensated(at: u32, v: real, one: real) {
    let s = mv_real[at];
    let t = s + v;
    let z = t * one - s;
    mv_real[at + 3u] += (s - (t - z)) + (v - z);
    mv_real[at] = t;
}

fn body_columns(grp: u32, psm: bool) {
    let n = mv_idx[0];
    let m = mv_idx[1];
    let per = 3u + 2u * n;
    let sec = per + m;
    let ng = mv_idx[sec];
    if grp >= ng {
        return;
    }
    let nb = mv_idx[sec + 1u];
    let ny = mv_idx[sec + 2u];
    let origins_at = mv_idx[sec + 3u];
    let work_at = mv_idx[sec + 4u];
    let out_at = mv_idx[sec + 5u];
    let one = mv_real[origins_at - 1u];
    let rows = sec + 6u;
    let groups = rows + ny + 1u;
    let members = groups + 5u * ng;
    let body_rows = members + nb;
    let x_lo = mv_idx[groups + 5u * grp];
    let x_n = mv_idx[groups + 5u * grp + 1u];
    let first = mv_idx[groups + 5u * grp + 2u];
    for (var j = 0u; j < 7u * x_n; j++) {
        mv_real[work_at + 7u * first + j] = real(0.0);
    }
    for (var mi = mv_idx[groups + 5u * grp + 3u]; mi < mv_idx[groups + 5u * grp + 4u]; mi++) {
        let b = mv_idx[members + mi];
        let y_lo = mv_idx[body_rows + 4u * b];
        let y_n = mv_idx[body_rows + 4u * b + 1u];
        let anchor_x = bitcast<i32>(mv_idx[body_rows + 4u * b + 2u]);
        let anchor_y = bitcast<i32>(mv_idx[body_rows + 4u * b + 3u]);
        let ox = mv_real[origins_at + 2u * b];
        let oy = mv_real[origins_at + 2u * b + 1u];
        for (var y = y_lo; y < y_lo + y_n; y++) {
            var c = mv_idx[rows + y];
            let end = mv_idx[rows + y + 1u];
            if psm {
                // A partially saturated plan's rows are sorted by cell: start at the first
                // cell of the box's first column or beyond (binary search).
                let k_lo = (y + 1u) * geo.stride + x_lo + 1u;
                var hi = end;
                while c < hi {
                    let mid = (c + hi) / 2u;
                    if mv_idx[2u + mid] < k_lo {
                        c = mid + 1u;
                    } else {
                        hi = mid;
                    }
                }
            }
            for (; c < end; c++) {
                let x = mv_idx[2u + c] % geo.stride - 1u;
                if x < x_lo || x >= x_lo + x_n {
                    if psm && x >= x_lo {
                        break;
                    }
                    continue;
                }
                // Arm of the cell centre from the body's centre.
                let ax = ox + real(i32(x) - anchor_x);
                let ay = oy + real(i32(y) - anchor_y);
                let slot = work_at + 7u * (first + x - x_lo);
                for (var e = mv_idx[2u + n + c]; e < mv_idx[3u + n + c]; e++) {
                    let word = mv_idx[per + e];
                    var px: real;
                    var py: real;
                    var arm_x = ax;
                    var arm_y = ay;
                    if psm {
                        if word != b {
                            continue;
                        }
                        // The share's momentum at the cell centre (seed eq. 5.54).
                        px = mv_real[n + 3u * m + 2u * e];
                        py = mv_real[n + 3u * m + 2u * e + 1u];
                    } else {
                        if (word >> 4u) != b {
                            continue;
                        }
                        // −(f*_ī + f_i) c_i at the link's midpoint (seed eqs. 5.47–5.48).
                        let i = word & 15u;
                        let mom = mv_real[2u * m + e];
                        px = -mom * real(CX[i]);
                        py = -mom * real(CY[i]);
                        arm_x = ax - real(0.5) * real(CX[i]);
                        arm_y = ay - real(0.5) * real(CY[i]);
                    }
                    add_compensated(slot, px, one);
                    add_compensated(slot + 1u, py, one);
                    add_compensated(slot + 2u, arm_x * py - arm_y * px, one);
                    mv_real[slot + 6u] += real(1.0);
                }
            }
        }
    }
    for (var j = 0u; j < x_n; j++) {
        let w = work_at + 7u * (first + j);
        let o = out_at + 4u * (first + j);
        for (var a = 0u; a < 3u; a++) {
            mv_real[o + a] = mv_real[w + a] + mv_real[w + 3u + a];
        }
        mv_real[o + 3u] = mv_real[w + 6u];
    }
}

@compute @workgroup_size(64)
fn body_columns_links(@builtin(global_invocation_id) gid: vec3<u32>,
                      @builtin(num_workgroups) groups: vec3<u32>) {
    body_columns(job(gid, groups), false);
}

@compute @workgroup_size(64)
fn body_columns_psm(@builtin(global_invocation_id) gid: vec3<u32>,
                    @builtin(num_workgroups) groups: vec3<u32>) {
    body_columns(job(gid, groups), true);
}
