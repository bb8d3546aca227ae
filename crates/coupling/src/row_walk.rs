//! The partially saturated map's walk of one grain image's row: which cells the disk
//! overlaps and each one's exact solid fraction, a register of cells at a time.

use super::geometry::{greater, lesser, CellAreas};
use super::map::{Share, SlabFrame};
use lbm::lattice::FLUID;

/// Cells of a row taken together (one AVX-512 register of f64).
pub const LANES: usize = 8;

/// Distance along one axis from `v` to the nearest point of the cell [lo, lo + 1].
#[inline(always)]
fn near(lo: f64, v: f64) -> f64 {
    (v - greater(lo, lesser(v, lo + 1.0))).abs()
}

/// Distance along one axis from `v` to the farthest point of the cell [lo, lo + 1].
#[inline(always)]
fn far(lo: f64, v: f64) -> f64 {
    greater((v - lo).abs(), (v - lo - 1.0).abs())
}

/// What every walk of row `y` of a disk at `c` with radius `r` starts from: the local x of
/// the slab's first column (`x0`), the row's box clipped to the slab's interior columns
/// (`xa..=xb`), and the nearest and farthest distances along y from the centre to the row.
struct RowStart {
    x0: i64,
    xa: i64,
    xb: i64,
    near_y: f64,
    far_y: f64,
}

impl RowStart {
    #[inline(always)]
    fn new(frame: &SlabFrame, c: [f64; 2], r: f64, y: i64) -> Self {
        let x0 = frame.x0 as i64;
        Self {
            x0,
            xa: ((c[0] - r).floor() as i64 - x0).max(0),
            xb: ((c[0] + r).floor() as i64 - x0).min(frame.nx as i64 - 1),
            near_y: near(y as f64, c[1]),
            far_y: far(y as f64, c[1]),
        }
    }
}

/// Append to `out` the shares in row `y` of grain image `image` (a disk of `radius` cells
/// centred at `c`, global frame): every interior plain-fluid cell (`types`: the lattice's
/// padded cell types) of that row it overlaps, in increasing x, with its exact solid
/// fraction from `exact` (the image's
/// [`CellAreas`], its column table padded by [`super::geometry::TABLE_PAD`]); a cell
/// wholly inside takes 1. `avx512`: the CPU has AVX-512F and VL (`lbm::lanes::has_avx512`).
///
/// [`LANES`] cells at a time, all with the same arithmetic (the tests, the strips at both
/// vertical lines, the fraction) and no branch on the data, so the edge cells cost no
/// mispredicted branch; the same bits as the cell-by-cell walk (tested).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn shares_in_row(
    avx512: bool,
    frame: &SlabFrame,
    types: &[u16],
    radius: f64,
    image: u32,
    c: [f64; 2],
    y: i64,
    exact: &CellAreas<'_>,
    out: &mut Vec<Share>,
) {
    #[cfg(target_arch = "x86_64")]
    if avx512 {
        // SAFETY: the caller found AVX-512F and VL on this CPU; BMI2 is in the build's
        // baseline (x86-64-v3, `.cargo/config.toml`) and in every AVX-512 CPU.
        return unsafe { walk_avx512(frame, types, radius, image, c, y, exact, out) };
    }
    let _ = avx512;
    walk(frame, types, radius, image, c, y, exact, out)
}

/// [`walk`] in AVX-512 registers: the same operations lane by lane, in the same order, so
/// the same bits (`lesser`/`greater` are `vminpd`/`vmaxpd`, `clamp` two compares and
/// blends). Left to itself, LLVM splits [`walk`]'s lanes over registers of three widths and
/// builds its masks a bit at a time. The cells' types are tested in one load, and the kept
/// shares are packed in registers and stored whole (no branch per share).
#[cfg(target_arch = "x86_64")]
#[allow(clippy::too_many_arguments)]
#[target_feature(enable = "avx512f,avx512vl,bmi2")]
unsafe fn walk_avx512(
    frame: &SlabFrame,
    types: &[u16],
    radius: f64,
    image: u32,
    c: [f64; 2],
    y: i64,
    exact: &CellAreas<'_>,
    out: &mut Vec<Share>,
) {
    use std::arch::x86_64::*;
    let r = radius;
    let RowStart {
        x0,
        xa,
        xb,
        near_y: ny_,
        far_y: fy_,
    } = RowStart::new(frame, c, r, y);
    let (cx, rr) = (_mm512_set1_pd(c[0]), _mm512_set1_pd(r * r));
    let (ny2, fy2) = (_mm512_set1_pd(ny_ * ny_), _mm512_set1_pd(fy_ * fy_));
    let (zero, one) = (_mm512_setzero_pd(), _mm512_set1_pd(1.0));
    let iota = _mm512_setr_pd(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0);
    // The row's two horizontal lines, as `corner_area` takes them.
    let half = std::f64::consts::FRAC_PI_2 * r * r;
    let m = (y - exact.y_lo) as usize;
    let line = |[v, a, ga]: [f64; 3]| {
        (
            v >= 0.0,
            _mm512_set1_pd(v),
            _mm512_set1_pd(a),
            _mm512_set1_pd(-a),
            _mm512_set1_pd(ga),
            _mm512_set1_pd(half - ga),
        )
    };
    let (below, above) = (line(exact.rows[m]), line(exact.rows[m + 1]));
    // `corner_area` of the vertical lines (s, G(s)) in lanes below one horizontal line.
    let corner = |s: __m512d,
                  gs: __m512d,
                  row: &(bool, __m512d, __m512d, __m512d, __m512d, __m512d)| {
        let &(upper_half, v, a, minus_a, ga, half_minus_ga) = row;
        let strip = _mm512_mul_pd(v, _mm512_add_pd(_mm512_min_pd(s, a), a));
        let (inside, left_of_chord) = if upper_half {
            let past = _mm512_maskz_sub_pd(_mm512_cmp_pd_mask::<_CMP_GT_OQ>(s, a), gs, ga);
            let upper = _mm512_add_pd(_mm512_add_pd(_mm512_add_pd(gs, half_minus_ga), strip), past);
            (upper, _mm512_mul_pd(_mm512_set1_pd(2.0), gs))
        } else {
            let lower = _mm512_sub_pd(_mm512_add_pd(strip, _mm512_min_pd(gs, ga)), half_minus_ga);
            (lower, zero)
        };
        _mm512_mask_blend_pd(
            _mm512_cmp_pd_mask::<_CMP_LE_OQ>(s, minus_a),
            inside,
            left_of_chord,
        )
    };
    let strip = |s, gs| _mm512_sub_pd(corner(s, gs, &above), corner(s, gs, &below));
    // Even and odd f64 of two registers: the lines' s and G(s).
    let (evens, odds) = (
        _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14),
        _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15),
    );
    let mut x = xa;
    while x <= xb {
        let first = _mm512_add_pd(_mm512_set1_pd((x + x0) as f64), iota);
        // Nearest distance: |c − max(lo, min(c, lo + 1))|; farthest: max(|c − lo|, |c − lo − 1|).
        let nearest = _mm512_abs_pd(_mm512_sub_pd(
            cx,
            _mm512_max_pd(first, _mm512_min_pd(cx, _mm512_add_pd(first, one))),
        ));
        let d = _mm512_sub_pd(cx, first);
        let farthest = _mm512_max_pd(_mm512_abs_pd(d), _mm512_abs_pd(_mm512_sub_pd(d, one)));
        let overlaps = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(
            _mm512_add_pd(_mm512_mul_pd(nearest, nearest), ny2),
            rr,
        );
        let whole = _mm512_cmp_pd_mask::<_CMP_LE_OQ>(
            _mm512_add_pd(_mm512_mul_pd(farthest, farthest), fy2),
            rr,
        );
        // The nine vertical lines x .. x + 8 (the table is padded past the box).
        let j = (x + x0 - exact.x_lo) as usize;
        let lines = &exact.columns[j..j + LANES + 1];
        let (p0, p1) = (
            _mm512_loadu_pd(lines[0..4].as_ptr().cast()),
            _mm512_loadu_pd(lines[4..8].as_ptr().cast()),
        );
        let (s_left, g_left) = (
            _mm512_permutex2var_pd(p0, evens, p1),
            _mm512_permutex2var_pd(p0, odds, p1),
        );
        let shift = |v: __m512d, last: f64| {
            _mm512_castsi512_pd(_mm512_alignr_epi64::<1>(
                _mm512_castpd_si512(_mm512_set1_pd(last)),
                _mm512_castpd_si512(v),
            ))
        };
        let (s_right, g_right) = (shift(s_left, lines[8][0]), shift(g_left, lines[8][1]));
        // `CellAreas::between`: (right − left).clamp(0, 1).
        let area = _mm512_sub_pd(strip(s_right, g_right), strip(s_left, g_left));
        let area = _mm512_mask_blend_pd(_mm512_cmp_pd_mask::<_CMP_LT_OQ>(area, zero), area, zero);
        let area = _mm512_mask_blend_pd(_mm512_cmp_pd_mask::<_CMP_GT_OQ>(area, one), area, one);
        let fraction = _mm512_castpd_si512(_mm512_mask_blend_pd(whole, area, one));
        // Lanes past the row's box are dropped, and cells that are not plain fluid.
        let live = (xb - x + 1).min(LANES as i64) as u32;
        let k0 = frame.padded(x, y);
        let plain = match types.get(k0..k0 + LANES) {
            Some(t) => _mm512_cmpeq_epi64_mask(
                _mm512_cvtepu16_epi64(_mm_loadu_si128(t.as_ptr().cast())),
                _mm512_set1_epi64(i64::from(FLUID)),
            ),
            None => (0..live as usize).fold(0, |m, l| m | u8::from(types[k0 + l] == FLUID) << l),
        };
        let take = u32::from(overlaps & plain) & ((1u32 << live) - 1);
        // Each share two u64 (`Share` is repr(C)): the fraction, then cell | image << 32.
        // The kept ones packed to the front of two registers (the first four cells, the
        // last four), stored whole past the vector's end, and the length moved over them.
        let ids = _mm512_add_epi64(
            _mm512_set1_epi64(k0 as i64 | i64::from(image) << 32),
            _mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7),
        );
        let front =
            _mm512_permutex2var_epi64(fraction, _mm512_setr_epi64(0, 8, 1, 9, 2, 10, 3, 11), ids);
        let back =
            _mm512_permutex2var_epi64(fraction, _mm512_setr_epi64(4, 12, 5, 13, 6, 14, 7, 15), ids);
        let pairs = _pdep_u32(take, 0x5555) * 3;
        let (front_mask, back_mask) = (pairs as u8, (pairs >> 8) as u8);
        out.reserve(LANES);
        let end = out.as_mut_ptr().add(out.len()).cast::<i64>();
        // SAFETY: the reserve leaves room for LANES shares (16 u64) past the length; the
        // two stores write 8 u64 each, the second from at most 8 u64 past the first.
        _mm512_storeu_si512(end.cast(), _mm512_maskz_compress_epi64(front_mask, front));
        let after = end.add(front_mask.count_ones() as usize);
        _mm512_storeu_si512(after.cast(), _mm512_maskz_compress_epi64(back_mask, back));
        // SAFETY: the shares up to the new length were just written whole (any bits are a
        // valid f64 and u32).
        out.set_len(out.len() + take.count_ones() as usize);
        x += LANES as i64;
    }
}

/// [`shares_in_row`] without AVX-512: the lanes as plain arrays, the same arithmetic.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn walk(
    frame: &SlabFrame,
    types: &[u16],
    radius: f64,
    image: u32,
    c: [f64; 2],
    y: i64,
    exact: &CellAreas<'_>,
    out: &mut Vec<Share>,
) {
    let r = radius;
    let RowStart {
        x0,
        xa,
        xb,
        near_y: ny_,
        far_y: fy_,
    } = RowStart::new(frame, c, r, y);
    let mut x = xa;
    while x <= xb {
        // The strips left of each cell's two vertical lines; their difference is its area.
        let left = exact.strips::<LANES>(x + x0, y);
        let right = exact.strips::<LANES>(x + x0 + 1, y);
        let first = (x + x0) as f64;
        let (mut overlaps, mut fraction) = (0u32, [0.0; LANES]);
        for l in 0..LANES {
            // Integers below 2⁵³: the same value as converting x + x0 + l.
            let gx = first + l as f64;
            let (nx_, fx_) = (near(gx, c[0]), far(gx, c[0]));
            // Some of the cell within r of the centre: it overlaps; all of it: whole.
            overlaps |= u32::from(nx_ * nx_ + ny_ * ny_ < r * r) << l;
            let whole = fx_ * fx_ + fy_ * fy_ <= r * r;
            let area = CellAreas::between(left[l], right[l]);
            fraction[l] = if whole { 1.0 } else { area };
        }
        // Lanes past the row's box are dropped.
        let live = (xb - x + 1).min(LANES as i64) as u32;
        let mut take = overlaps & ((1u32 << live) - 1);
        let k0 = frame.padded(x, y);
        while take != 0 {
            let l = take.trailing_zeros() as usize;
            take &= take - 1;
            if types[k0 + l] == FLUID {
                out.push(Share {
                    fraction: fraction[l],
                    cell: (k0 + l) as u32,
                    image,
                });
            }
        }
        x += LANES as i64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{LineTables, TABLE_PAD};
    use crate::test_slabs::{next, slab};

    /// The cell-by-cell walk the lanes replace: each cell of the row's box tested on its
    /// own, the exact area ([`CellAreas::fraction`]) only for the cells cut by the circle.
    #[allow(clippy::too_many_arguments)]
    fn cell_by_cell(
        frame: &SlabFrame,
        types: &[u16],
        r: f64,
        image: u32,
        c: [f64; 2],
        y: i64,
        exact: &CellAreas<'_>,
        out: &mut Vec<Share>,
    ) {
        let x0 = frame.x0 as i64;
        let xa = ((c[0] - r).floor() as i64 - x0).max(0);
        let xb = ((c[0] + r).floor() as i64 - x0).min(frame.nx as i64 - 1);
        for x in xa..=xb {
            let k = frame.padded(x, y);
            if types[k] != FLUID {
                continue;
            }
            let gx = (x + x0) as f64;
            let (nx_, ny_) = (near(gx, c[0]), near(y as f64, c[1]));
            if nx_ * nx_ + ny_ * ny_ >= r * r {
                continue;
            }
            let (fx_, fy_) = (far(gx, c[0]), far(y as f64, c[1]));
            let fraction = if fx_ * fx_ + fy_ * fy_ <= r * r {
                1.0
            } else {
                exact.fraction(x + x0, y)
            };
            out.push(Share {
                fraction,
                cell: k as u32,
                image,
            });
        }
    }

    /// On slabs cut from a lattice (walls and a solid cell or two in the rows), disks of
    /// radius 0.3 to 20 cells, centred on and off the grid lines and across the slab's
    /// edges: the lane walk, with and without AVX-512, gives the cell-by-cell walk's shares
    /// bit for bit. Fails if a lane past the box is kept, a whole cell is given its area or
    /// the strips are offset by a line.
    #[test]
    fn lane_walk_matches_the_cell_by_cell_walk() {
        let mut seed = 0x6a09_e667_f3bc_c909u64;
        let avx512 = lbm::lanes::has_avx512();
        let mut checked = 0usize;
        for case in 0..3 {
            let (f, _) = slab(case);
            // A few cells of every row are not plain fluid.
            let types: Vec<u16> = (0..f.stride * (f.ny + 2))
                .map(|k| if k % 17 == 3 { FLUID + 1 } else { FLUID })
                .collect();
            let mut disks: Vec<([f64; 2], f64)> = vec![
                ([f.x0 as f64 + 4.0, 4.0], 3.0),
                ([f.x0 as f64 + 0.5, 2.5], 2.5),
                ([(f.x0 + f.nx) as f64, 6.0], 4.0),
            ];
            for _ in 0..150 {
                let r = 0.3 + 20.0 * next(&mut seed) * next(&mut seed);
                let cx = f.x0 as f64 - r + (f.nx as f64 + 2.0 * r) * next(&mut seed);
                let cy = -r + (f.ny as f64 + 2.0 * r) * next(&mut seed);
                disks.push(([cx, cy], r));
            }
            for (c, r) in disks {
                let tables = LineTables::new(c, r, TABLE_PAD);
                let exact = tables.areas();
                let (ya, yb) = crate::map::share_rows(&f, c, r);
                for y in ya..=yb {
                    let (mut want, mut lanes, mut plain) = (Vec::new(), Vec::new(), Vec::new());
                    cell_by_cell(&f, &types, r, 7, c, y, &exact, &mut want);
                    shares_in_row(avx512, &f, &types, r, 7, c, y, &exact, &mut lanes);
                    shares_in_row(false, &f, &types, r, 7, c, y, &exact, &mut plain);
                    let bits = |v: &[Share]| {
                        v.iter()
                            .map(|s| (s.fraction.to_bits(), s.cell, s.image))
                            .collect::<Vec<_>>()
                    };
                    assert_eq!(bits(&lanes), bits(&want), "disk {c:?} r {r}, row {y}");
                    assert_eq!(bits(&plain), bits(&want), "disk {c:?} r {r}, row {y}");
                    checked += want.len();
                }
            }
        }
        assert!(checked > 10_000, "only {checked} shares compared");
    }
}
