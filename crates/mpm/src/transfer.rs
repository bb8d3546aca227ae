//! Particle-to-grid transfer with a partition-independent summation order.
//!
//! Points are kept sorted by cell column, then cell row, then id. Each cell column `c`
//! accumulates its points' contributions, in that order, into its own *strip*: the node
//! columns `c-1 ..= c+2` over the node rows its points touch. A node's value is then the
//! sum of the strips of the cell columns `I-2 ..= I+1`, added in ascending column order
//! starting from zero. Every node sum therefore has the same operands in the same order
//! whatever the thread count — and whatever the rank count, because slabs are whole cell
//! columns and a strip is exchanged as it is, never pre-summed.

use super::grid::{GridSpec, NodeFields};
use super::points::Points;
use super::shape::{half_lengths, node_offset, weights_1d, ShapeKind, Weights1d};
use rayon::prelude::*;

/// Quantities one node slot accumulates: mass, momentum x/y, internal force x/y.
pub const Q: usize = 5;

/// What a particle-to-grid pass accumulates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum P2g {
    /// Mass and momentum.
    MassMomentum,
    /// Internal force −V σ·∇S only (mass and momentum slots left zero), and the side-wall
    /// force where there are side walls.
    Force,
    /// All five quantities (and the side-wall force).
    All,
}

/// One cell column's contributions: `data[(J - row_lo) * 4 + k]` holds the slot of node
/// (c − 1 + k, J).
#[derive(Debug, Clone, Default)]
pub struct Strip {
    /// Node row of the first entry.
    pub row_lo: i64,
    /// Number of node rows (0 when the column holds no point).
    pub rows: usize,
    /// The slots, row-major with four node columns per row.
    pub data: Vec<[f64; Q]>,
    /// The side walls' largest friction force per slot, laid out as `data` (N/m); empty
    /// without side walls and in mass-and-momentum passes.
    pub wall: Vec<f64>,
}

/// The canonical order of the points and where each cell column starts in it.
#[derive(Debug, Clone, Default)]
pub struct Columns {
    /// `order[start[c] .. start[c + 1]]` are the points of cell column c (length nx + 1).
    pub start: Vec<usize>,
    /// Cell (column, row) of each point, by storage index.
    pub cell: Vec<[u32; 2]>,
    /// Storage indices in canonical order: column, row, id.
    pub order: Vec<u32>,
}

/// Accumulate the strips of every cell column for `what`, from the points in canonical
/// order (see [`Columns`]); empty columns get an empty strip. With `affine` (APIC) the
/// momentum carries the points' affine velocity. `walls` is 2 μ_w / W (1/m) of the side
/// walls, 0 without them.
pub fn particles_to_strips(
    points: &Points,
    columns: &Columns,
    (spec, kind, walls): (&GridSpec, ShapeKind, f64),
    (what, affine): (P2g, bool),
    strips: &mut [Strip],
    first_col: usize,
) {
    let (pad_lo, pad_hi) = if kind == ShapeKind::Linear {
        (0, 1)
    } else {
        (1, 2)
    };
    // Columns differ wildly in load (most are empty): small tasks keep both threads busy.
    strips
        .par_iter_mut()
        .with_max_len(1)
        .enumerate()
        .for_each(|(k, strip)| {
            let c = first_col + k;
            let list = &columns.order[columns.start[c]..columns.start[c + 1]];
            strip.wall.clear();
            let (Some(&first), Some(&last)) = (list.first(), list.last()) else {
                strip.rows = 0;
                strip.data.clear();
                return;
            };
            strip.row_lo = columns.cell[first as usize][1] as i64 - pad_lo;
            strip.rows =
                (columns.cell[last as usize][1] as i64 + pad_hi - strip.row_lo + 1) as usize;
            strip.data.clear();
            strip.data.resize(strip.rows * 4, [0.0; Q]);
            let with_walls = walls > 0.0 && what != P2g::MassMomentum;
            if with_walls {
                strip.wall.resize(strip.rows * 4, 0.0);
            }
            let args = (points, columns, spec, kind, list, walls);
            match (what, affine, with_walls) {
                (P2g::MassMomentum, false, _) => {
                    accumulate::<true, false, false, false>(args, strip)
                }
                (P2g::MassMomentum, true, _) => accumulate::<true, false, true, false>(args, strip),
                (P2g::Force, _, false) => accumulate::<false, true, false, false>(args, strip),
                (P2g::Force, _, true) => accumulate::<false, true, false, true>(args, strip),
                (P2g::All, false, false) => accumulate::<true, true, false, false>(args, strip),
                (P2g::All, true, false) => accumulate::<true, true, true, false>(args, strip),
                (P2g::All, false, true) => accumulate::<true, true, false, true>(args, strip),
                (P2g::All, true, true) => accumulate::<true, true, true, true>(args, strip),
            }
        });
}

/// Add the contributions of the points `list` (one cell column, canonical order) to
/// `strip`: mass and momentum when `MASS`, internal force when `FORCE`; with `AFFINE` the
/// momentum carries the points' affine velocity (APIC); with `WALLS` (and `FORCE`) the side
/// walls' largest friction force goes to `strip.wall`.
#[inline(always)]
fn accumulate<const MASS: bool, const FORCE: bool, const AFFINE: bool, const WALLS: bool>(
    (points, columns, spec, kind, list, walls): (
        &Points,
        &Columns,
        &GridSpec,
        ShapeKind,
        &[u32],
        f64,
    ),
    strip: &mut Strip,
) {
    let h = spec.h;
    for &p in list {
        let p = p as usize;
        let [pc, pr] = columns.cell[p];
        let [x, y] = points.pos[p];
        let half = half_lengths(kind, points.half0[p], &points.defgrad[p], h);
        let wx = weights_1d(kind, x, pc as i64, h, half[0]);
        let wy = weights_1d(kind, y, pr as i64, h, half[1]);
        let m = points.mass[p];
        let [vx, vy] = points.vel[p];
        let c = if AFFINE {
            // C_p = B_p D_p⁻¹ at the current position (Jiang et al. 2015, eq. 12).
            let d = inertia_1d(&wx, pc, h, x);
            let e = inertia_1d(&wy, pr, h, y);
            let b = points.affine[p];
            [b[0] / d, b[1] / e, b[2] / d, b[3] / e]
        } else {
            [0.0; 4]
        };
        let (vol, s) = if FORCE {
            (points.volume(p), points.stress[p])
        } else {
            (0.0, [0.0; 4])
        };
        // The side walls' largest friction force, 2 μ_w/W V_p |σ_zz| (Janssen 1895).
        let wall = if WALLS { walls * vol * s[3].abs() } else { 0.0 };
        let base = (pr as i64 - 1 - strip.row_lo) as usize;
        for ky in wy.first..wy.first + wy.count {
            let row = (base + ky) * 4;
            for kx in wx.first..wx.first + wx.count {
                let slot = &mut strip.data[row + kx];
                if MASS {
                    let wm = wx.w[kx] * wy.w[ky] * m;
                    slot[0] += wm;
                    if AFFINE {
                        // APIC: m_I v_I = Σ_p S_Ip m_p (v_p + C_p (x_I − x_p)) (Jiang et al. 2015, eq. 13).
                        let dx = node_offset(pc as i64, kx, h, x);
                        let dy = node_offset(pr as i64, ky, h, y);
                        slot[1] += wm * (vx + c[0] * dx + c[1] * dy);
                        slot[2] += wm * (vy + c[2] * dx + c[3] * dy);
                    } else {
                        slot[1] += wm * vx;
                        slot[2] += wm * vy;
                    }
                }
                if FORCE {
                    let gx = wx.g[kx] * wy.w[ky];
                    let gy = wx.w[kx] * wy.g[ky];
                    // f_int = −Σ_p V_p σ_p · ∇S_Ip (Sulsky et al. 1994, eq. 23).
                    slot[3] -= vol * (s[0] * gx + s[2] * gy);
                    slot[4] -= vol * (s[2] * gx + s[1] * gy);
                }
                if WALLS {
                    strip.wall[row + kx] += wx.w[kx] * wy.w[ky] * wall;
                }
            }
        }
    }
}

/// One diagonal entry of the APIC inertia-like matrix, D = Σ_I S_I (x_I − x_p)² (m²), of
/// the 1-D weights `w` of a point at `x` (m) in cell `cell` on a grid of spacing `h` (m).
/// Tensor-product weights with linear completeness make D diagonal (Σ S (x_I − x_p) = 0).
#[inline(always)]
pub fn inertia_1d(w: &Weights1d, cell: u32, h: f64, x: f64) -> f64 {
    let mut d = 0.0;
    for k in w.first..w.first + w.count {
        let dx = node_offset(cell as i64, k, h, x);
        d += w.w[k] * dx * dx;
    }
    d
}

/// Sum the strips into the node fields for the node columns `node_cols` (global node
/// column indices, −1 ≤ I ≤ nx+1), in ascending cell-column order. `what` selects which
/// node fields are (over)written; `active` is recomputed for mass passes. With `walls` the
/// force passes also sum the side-wall force.
pub fn strips_to_nodes(
    strips: &[Strip],
    spec: &GridSpec,
    (what, walls): (P2g, bool),
    node_cols: std::ops::Range<i64>,
    nodes: &mut NodeFields,
) {
    let rows = spec.rows();
    let nx = spec.nx as i64;
    let first = (node_cols.start + 1) as usize;
    let count = (node_cols.end - node_cols.start) as usize;
    let range = first * rows..(first + count) * rows;
    let NodeFields {
        mass,
        mom,
        force,
        wall,
        active,
        ..
    } = nodes;
    (
        mass[range.clone()].par_chunks_mut(rows),
        mom[range.clone()].par_chunks_mut(rows),
        (
            force[range.clone()].par_chunks_mut(rows),
            wall[range].par_chunks_mut(rows),
        ),
        active[first..first + count].par_iter_mut(),
    )
        .into_par_iter()
        .with_max_len(2)
        .enumerate()
        .for_each(|(n, (mass, mom, (force, wall), act))| {
            let i = node_cols.start + n as i64;
            let cs = (i - 2).max(0)..=(i + 1).min(nx - 1);
            let (mut lo, mut hi) = (i64::MAX, i64::MIN);
            for c in cs.clone() {
                let s = &strips[c as usize];
                if s.rows > 0 {
                    lo = lo.min(s.row_lo);
                    hi = hi.max(s.row_lo + s.rows as i64);
                }
            }
            if lo >= hi {
                if what != P2g::Force {
                    *act = (0, 0);
                }
                return;
            }
            let (r0, r1) = ((lo + 1) as usize, (hi + 1) as usize);
            if what != P2g::Force {
                *act = (r0 as u32, r1 as u32);
            }
            for r in r0..r1 {
                let j = r as i64 - 1;
                let mut acc = [0.0; Q];
                let mut w = 0.0;
                for c in cs.clone() {
                    let s = &strips[c as usize];
                    let k = (i - c + 1) as usize;
                    if j >= s.row_lo && j < s.row_lo + s.rows as i64 {
                        let at = (j - s.row_lo) as usize * 4 + k;
                        let v = &s.data[at];
                        for q in 0..Q {
                            acc[q] += v[q];
                        }
                        if walls && what != P2g::MassMomentum {
                            w += s.wall[at];
                        }
                    }
                }
                if what != P2g::Force {
                    mass[r] = acc[0];
                    mom[r] = [acc[1], acc[2]];
                }
                if what != P2g::MassMomentum {
                    force[r] = [acc[3], acc[4]];
                    if walls {
                        wall[r] = w;
                    }
                }
            }
        });
}
