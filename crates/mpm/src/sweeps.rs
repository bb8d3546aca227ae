//! The node update and the two point sweeps (stress update, grid-to-particle). Each sweep
//! is one parallel pass over its data; every point or node is written by one task only.

use super::grid::{apply_side, apply_side_walls, Boundaries, GridSpec, NodeFields, Side};
use super::material::Material;
use super::mohr_coulomb::Prepared;
use super::points::Points;
use super::shape::{half_lengths, node_offset, weights_1d, ShapeKind};
use super::transfer::Columns;
use rayon::prelude::*;

/// Parameters of the node update.
#[derive(Debug, Clone, Copy)]
pub struct NodeUpdate {
    /// Gravity (m/s²).
    pub gravity: [f64; 2],
    /// Time step (s).
    pub dt: f64,
    /// Cundall local damping coefficient α (0 = off).
    pub damping: f64,
    /// Nodes lighter than this (kg/m) are treated as empty.
    pub min_mass: f64,
    /// Whether the nodes' side-wall force (`NodeFields::wall`) applies.
    pub side_walls: bool,
}

/// Apply the domain's boundary conditions to velocity `v` of node (i, j).
#[inline(always)]
fn constrain(b: &Boundaries, spec: &GridSpec, i: i64, j: i64, v: &mut [f64; 2]) {
    if i <= 0 {
        apply_side(b.left, 0, 1.0, v);
    }
    if i >= spec.nx as i64 {
        apply_side(b.right, 0, -1.0, v);
    }
    if j <= 0 {
        apply_side(b.bottom, 1, 1.0, v);
    }
    if j >= spec.ny as i64 {
        apply_side(b.top, 1, -1.0, v);
    }
}

/// Nodal velocities from momentum over the node columns `node_cols`: `v_old = p/m` as
/// mapped (no boundary condition: the FLIP increment v_new − v_old must carry the whole
/// effect of the walls, the impact of material landing on a frictional floor included) and
/// `v_new` = `v_old` with the boundary conditions (the velocity field a USF stress update or
/// MUSL's remap uses; the momentum update overwrites it).
pub fn velocities(
    nodes: &mut NodeFields,
    spec: &GridSpec,
    b: &Boundaries,
    min_mass: f64,
    node_cols: std::ops::Range<i64>,
) {
    let rows = spec.rows();
    let first = (node_cols.start + 1) as usize;
    let range = first * rows..(first + (node_cols.end - node_cols.start) as usize) * rows;
    let NodeFields {
        mass,
        mom,
        v_old,
        v_new,
        active,
        ..
    } = nodes;
    (
        mass[range.clone()].par_chunks(rows),
        mom[range.clone()].par_chunks(rows),
        v_old[range.clone()].par_chunks_mut(rows),
        v_new[range].par_chunks_mut(rows),
    )
        .into_par_iter()
        .with_max_len(2)
        .enumerate()
        .for_each(|(n, (m, p, vo, vn))| {
            let i = node_cols.start + n as i64;
            let (r0, r1) = active[first + n];
            for r in r0 as usize..r1 as usize {
                let mut vel = if m[r] > min_mass {
                    [p[r][0] / m[r], p[r][1] / m[r]]
                } else {
                    [0.0; 2]
                };
                vo[r] = vel;
                constrain(b, spec, i, r as i64 - 1, &mut vel);
                vn[r] = vel;
            }
        });
}

/// The momentum update on the nodes: `v_new = v_old + dt (f_int + m g + f_damp) / m`, then
/// the side walls' friction (at most `dt` times the node's wall force, never reversing
/// `v_new`), then the boundary conditions, which see the whole normal velocity into a wall
/// (the incoming momentum and this step's forces), so Coulomb friction acts on the whole
/// normal impulse. Requires `v_old` (from [`velocities`]) and the forces.
pub fn update_nodes(
    nodes: &mut NodeFields,
    spec: &GridSpec,
    b: &Boundaries,
    u: &NodeUpdate,
    node_cols: std::ops::Range<i64>,
) {
    let rows = spec.rows();
    let first = (node_cols.start + 1) as usize;
    let range = first * rows..(first + (node_cols.end - node_cols.start) as usize) * rows;
    let NodeFields {
        mass,
        force,
        wall,
        v_old,
        v_new,
        active,
        ..
    } = nodes;
    (
        mass[range.clone()].par_chunks(rows),
        force[range.clone()].par_chunks(rows),
        wall[range.clone()].par_chunks(rows),
        v_old[range.clone()].par_chunks(rows),
        v_new[range].par_chunks_mut(rows),
    )
        .into_par_iter()
        .with_max_len(2)
        .enumerate()
        .for_each(|(n, (m, f, w, vo, vn))| {
            let i = node_cols.start + n as i64;
            let (r0, r1) = active[first + n];
            for r in r0 as usize..r1 as usize {
                if !(m[r] > u.min_mass) {
                    vn[r] = [0.0; 2];
                    continue;
                }
                let mut v = vo[r];
                for d in 0..2 {
                    let mut f_d = f[r][d] + m[r] * u.gravity[d];
                    // Cundall local damping: f −= α |f| sign(v) (Cundall 1987).
                    if u.damping > 0.0 && v[d] != 0.0 {
                        f_d -= u.damping * f_d.abs() * v[d].signum();
                    }
                    v[d] += u.dt * f_d / m[r];
                }
                if u.side_walls {
                    apply_side_walls(u.dt * w[r] / m[r], &mut v);
                }
                constrain(b, spec, i, r as i64 - 1, &mut v);
                vn[r] = v;
            }
        });
}

/// Interpolation context shared by the point sweeps.
#[derive(Debug, Clone, Copy)]
pub struct Interp<'a> {
    /// Grid.
    pub spec: &'a GridSpec,
    /// Shape functions.
    pub kind: ShapeKind,
    /// Cells of the points.
    pub columns: &'a Columns,
}

impl Interp<'_> {
    /// Visit the nodes in the support of a point at `pos` in `cell` with initial
    /// half-length `half0` and deformation gradient `f`: `visit(node, S, [∂S/∂x, ∂S/∂y],
    /// x_I − x_p)`.
    #[inline(always)]
    fn each_node(
        &self,
        pos: [f64; 2],
        cell: [u32; 2],
        half0: f64,
        f: &[f64; 4],
        mut visit: impl FnMut(usize, f64, [f64; 2], [f64; 2]),
    ) {
        let h = self.spec.h;
        let [c, r] = cell;
        let half = half_lengths(self.kind, half0, f, h);
        let wx = weights_1d(self.kind, pos[0], c as i64, h, half[0]);
        let wy = weights_1d(self.kind, pos[1], r as i64, h, half[1]);
        for kx in wx.first..wx.first + wx.count {
            let col = self.spec.node(c as i64 - 1 + kx as i64, r as i64 - 1);
            let dx = node_offset(c as i64, kx, h, pos[0]);
            for ky in wy.first..wy.first + wy.count {
                let w = wx.w[kx] * wy.w[ky];
                let dy = node_offset(r as i64, ky, h, pos[1]);
                let g = [wx.g[kx] * wy.w[ky], wx.w[kx] * wy.g[ky]];
                visit(col + ky, w, g, [dx, dy]);
            }
        }
    }
}

/// Velocity gradient of every point, L = Σ v_I ⊗ ∇S_I = [∂vx/∂x, ∂vx/∂y, ∂vy/∂x,
/// ∂vy/∂y] (1/s), from the nodal velocity `v` the scheme prescribes; into `out`.
pub fn velocity_gradients(points: &Points, it: &Interp, v: &[[f64; 2]], out: &mut Vec<[f64; 4]>) {
    out.resize(points.len(), [0.0; 4]);
    (
        points.pos.par_iter(),
        points.half0.par_iter(),
        points.defgrad.par_iter(),
        it.columns.cell.par_iter(),
        out.par_iter_mut(),
    )
        .into_par_iter()
        .for_each(|(&x, &h0, f, &cell, l)| {
            *l = [0.0; 4];
            it.each_node(x, cell, h0, f, |n, _, g, _| {
                let vn = v[n];
                l[0] += vn[0] * g[0];
                l[1] += vn[0] * g[1];
                l[2] += vn[1] * g[0];
                l[3] += vn[1] * g[1];
            });
        });
}

/// Replace each point's volumetric strain rate tr L by the volume-weighted mean over the
/// points of its cell (cell-averaged volumetric strain, a B-bar-like remedy for the
/// volumetric noise and locking of MPM; Coombs et al. 2018). Sums run in canonical order
/// within each cell, so the result does not depend on threads or ranks.
pub fn average_volumetric(points: &Points, columns: &Columns, grads: &mut [[f64; 4]]) {
    let order = &columns.order;
    let mut k = 0;
    while k < order.len() {
        let cell = columns.cell[order[k] as usize];
        let mut end = k;
        let (mut sv, mut svtr) = (0.0, 0.0);
        while end < order.len() && columns.cell[order[end] as usize] == cell {
            let i = order[end] as usize;
            let vol = points.volume(i);
            sv += vol;
            svtr += vol * (grads[i][0] + grads[i][3]);
            end += 1;
        }
        let mean = svtr / sv;
        for &i in &order[k..end] {
            let l = &mut grads[i as usize];
            let shift = 0.5 * (mean - (l[0] + l[3]));
            l[0] += shift;
            l[3] += shift;
        }
        k = end;
    }
}

/// Stress sweep with the velocity gradients `grads` (see [`velocity_gradients`]): the
/// material update, deformation gradient F ← (I + L dt) F and the accumulated strain. A
/// point whose volume ratio J = det F exceeds its material's separation ratio carries no
/// stress. Returns the number of points that yielded and the stress-carrying point with
/// the largest squared wave speed c² J (m²/s², storage index).
pub fn update_stress(
    points: &mut Points,
    grads: &[[f64; 4]],
    materials: &[Material],
    prepared: &[Prepared],
    dt: f64,
) -> (usize, (f64, usize)) {
    let Points {
        defgrad,
        stress,
        strain,
        eps_p,
        material,
        ..
    } = points;
    (
        grads.par_iter(),
        defgrad.par_iter_mut(),
        stress.par_iter_mut(),
        strain.par_iter_mut(),
        eps_p.par_iter_mut(),
        material.par_iter(),
    )
        .into_par_iter()
        .enumerate()
        .map(|(i, (&l, f, s, e, ep, &mat))| {
            // F_{n+1} = (I + L Δt) F_n.
            let a = [1.0 + l[0] * dt, l[1] * dt, l[2] * dt, 1.0 + l[3] * dt];
            *f = [
                a[0] * f[0] + a[1] * f[2],
                a[0] * f[1] + a[1] * f[3],
                a[2] * f[0] + a[3] * f[2],
                a[2] * f[1] + a[3] * f[3],
            ];
            let m = &materials[mat as usize];
            let j = f[0] * f[3] - f[1] * f[2];
            if j > m.separation_volume_ratio {
                // Separated: no contact, no stress (Dunatunga & Kamrin 2015, §2.3).
                *s = [0.0; 4];
                e[0] += l[0] * dt;
                e[1] += l[3] * dt;
                e[2] += 0.5 * (l[1] + l[2]) * dt;
                return (0, (0.0, i));
            }
            let (d, yielded) = m.update(&prepared[mat as usize], s, l, dt, ep);
            e[0] += d[0];
            e[1] += d[1];
            e[2] += d[2];
            let c = m.wave_speed();
            (yielded as usize, (c * c * j, i))
        })
        .reduce(
            || (0, (0.0, 0)),
            |a, b| (a.0 + b.0, if b.1 .0 > a.1 .0 { b.1 } else { a.1 }),
        )
}

/// How [`grid_to_points`] updates the point velocities.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VelocityUpdate {
    /// FLIP blended with a fraction `pic` in [0, 1] of the PIC velocity (0: pure FLIP).
    Flip {
        /// PIC fraction.
        pic: f64,
    },
    /// APIC (Jiang et al. 2015): the PIC velocity plus the affine velocity C = B D⁻¹, which
    /// the next particle-to-grid pass carries (the points store B): exact for affine
    /// velocity fields, conserves angular momentum. GIMP shapes only: with linear tents D
    /// vanishes on a node.
    Apic,
}

/// Grid-to-particle sweep: the point velocity update of `update` and the position update
/// x ← x + Δt Σ S v_new written to `pos_next`.
pub fn grid_to_points(
    points: &mut Points,
    it: &Interp,
    nodes: &NodeFields,
    b: &Boundaries,
    dt: f64,
    update: VelocityUpdate,
    pos_next: &mut Vec<[f64; 2]>,
) {
    let (pic, apic) = match update {
        VelocityUpdate::Flip { pic } => (pic, false),
        VelocityUpdate::Apic => (1.0, true),
    };
    // Closed sides are rigid walls: a centre that would cross one stays on it, with its
    // velocity into the wall removed (the grid condition acts on nodes only, so a point
    // just inside can be interpolated across).
    let open = |s: Side| s == Side::Open;
    let lo = [!open(b.left), !open(b.bottom)];
    let hi = [!open(b.right), !open(b.top)];
    let top = [it.spec.width(), it.spec.height()].map(|l| l * (1.0 - 1e-12));
    let Points {
        pos,
        half0,
        defgrad,
        vel,
        affine,
        ..
    } = points;
    pos_next.resize(pos.len(), [0.0; 2]);
    (
        pos.par_iter(),
        half0.par_iter(),
        defgrad.par_iter(),
        it.columns.cell.par_iter(),
        vel.par_iter_mut(),
        affine.par_iter_mut(),
        pos_next.par_iter_mut(),
    )
        .into_par_iter()
        .for_each(|(&x, &h0, f, &cell, v, c, xn)| {
            let (mut dv, mut vp, mut bm) = ([0.0; 2], [0.0; 2], [0.0; 4]);
            it.each_node(x, cell, h0, f, |n, w, _, d| {
                let (a, b) = (nodes.v_new[n], nodes.v_old[n]);
                dv[0] += w * (a[0] - b[0]);
                dv[1] += w * (a[1] - b[1]);
                vp[0] += w * a[0];
                vp[1] += w * a[1];
                if apic {
                    // B_p = Σ_I S v_I (x_I − x_p)ᵀ (Jiang et al. 2015, eq. 10).
                    bm[0] += w * a[0] * d[0];
                    bm[1] += w * a[0] * d[1];
                    bm[2] += w * a[1] * d[0];
                    bm[3] += w * a[1] * d[1];
                }
            });
            if apic {
                // Stored as B_p; the next particle-to-grid pass divides by D_p at the point's
                // new position, so that C_p D_p = B_p there and angular momentum is exact.
                *c = bm;
            }
            for d in 0..2 {
                // FLIP: v_p += Σ S_I (v_I^new − v_I^old); PIC: v_p = Σ S_I v_I^new.
                v[d] = (1.0 - pic) * (v[d] + dv[d]) + pic * vp[d];
                xn[d] = x[d] + dt * vp[d];
                if lo[d] && xn[d] < 0.0 {
                    xn[d] = 0.0;
                    v[d] = v[d].max(0.0);
                } else if hi[d] && xn[d] > top[d] {
                    xn[d] = top[d];
                    v[d] = v[d].min(0.0);
                }
            }
        });
}
