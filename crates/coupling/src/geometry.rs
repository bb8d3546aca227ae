//! Disk geometry on the lattice, in lattice units (cell (x, y) spans [x, x+1) × [y, y+1),
//! its centre is (x + ½, y + ½)): which cells a disk covers, where a lattice link cuts its
//! surface, and the exact area a disk shares with a cell.

/// Whether the centre of cell (x, y) lies inside the disk (`centre`, `radius`): the same
/// rule the fluid core uses to rasterise circular obstacles, so a grain held still covers
/// the cells of the same obstacle.
#[inline]
pub fn covers(centre: [f64; 2], radius: f64, x: i64, y: i64) -> bool {
    let (dx, dy) = (x as f64 + 0.5 - centre[0], y as f64 + 0.5 - centre[1]);
    dx * dx + dy * dy <= radius * radius
}

pub use lbm::geometry::link_fraction;

/// Antiderivative of √(r² − s²): ½ (s √(r² − s²) + r² asin(s / r)), for |s| ≤ r.
fn half_chord_integral(s: f64, r: f64) -> f64 {
    let s = s.clamp(-r, r);
    0.5 * (s * (r * r - s * s).max(0.0).sqrt() + r * r * (s / r).asin())
}

/// Exact area of the intersection of the disk (`centre`, `radius`) with the axis-aligned
/// rectangle `[x0, x1] × [y0, y1]`.
///
/// In the disk's frame the area is ∫ max(0, min(y1, √(r²−s²)) − max(y0, −√(r²−s²))) ds over
/// s ∈ [x0, x1] ∩ [−r, r]. The integrand changes form only where √(r²−s²) = |y0| or |y1|,
/// so the interval is cut there and each piece is integrated in closed form.
pub fn disk_rectangle_area(centre: [f64; 2], radius: f64, lo: [f64; 2], hi: [f64; 2]) -> f64 {
    let r = radius;
    let (x0, x1) = ((lo[0] - centre[0]).max(-r), (hi[0] - centre[0]).min(r));
    let (y0, y1) = (lo[1] - centre[1], hi[1] - centre[1]);
    if x0 >= x1 || y0 >= r || y1 <= -r {
        return 0.0;
    }
    let mut cuts = [x0, x1, x0, x0, x0, x0];
    let mut n = 2;
    for y in [y0, y1] {
        if y.abs() < r {
            let s = (r * r - y * y).sqrt();
            for c in [-s, s] {
                if c > x0 && c < x1 {
                    cuts[n] = c;
                    n += 1;
                }
            }
        }
    }
    let cuts = &mut cuts[..n];
    cuts.sort_by(f64::total_cmp);
    // The chord integral at each cut, computed once (neighbouring pieces share a cut).
    let mut at: [Option<f64>; 6] = [None; 6];
    let mut chord = |j: usize| *at[j].get_or_insert_with(|| half_chord_integral(cuts[j], r));
    let mut area = 0.0;
    for j in 0..n - 1 {
        let (a, b) = (cuts[j], cuts[j + 1]);
        if b <= a {
            continue;
        }
        // Which bound is active is constant on (a, b): decide at the midpoint.
        let m = 0.5 * (a + b);
        let h = (r * r - m * m).max(0.0).sqrt();
        // Top: y1 if y1 < h else +√; bottom: y0 if y0 > −h else −√.
        let top = if y1 < h {
            y1 * (b - a)
        } else {
            chord(j + 1) - chord(j)
        };
        let bottom = if y0 > -h {
            y0 * (b - a)
        } else {
            -(chord(j + 1) - chord(j))
        };
        if y1.min(h) > y0.max(-h) {
            area += top - bottom;
        }
    }
    area.max(0.0)
}

/// Area the disk shares with cell (x, y) as a fraction of the cell, in [0, 1]
/// (the solid fraction ε of Noble & Torczynski 1998).
#[inline]
pub fn cell_fraction(centre: [f64; 2], radius: f64, x: i64, y: i64) -> f64 {
    let (xf, yf) = (x as f64, y as f64);
    disk_rectangle_area(centre, radius, [xf, yf], [xf + 1.0, yf + 1.0]).clamp(0.0, 1.0)
}

/// The grid lines bounding the cells a disk at coordinate `c` with radius `r` can overlap
/// along one axis (cells ⌊c − r⌋ ..= ⌊c + r⌋, the same range the share maps visit): the
/// first line and the number of lines (one more than cells).
#[inline]
pub fn box_lines(c: f64, r: f64) -> (i64, usize) {
    let (lo, hi) = ((c - r).floor() as i64, (c + r).floor() as i64);
    (lo, (hi - lo + 2) as usize)
}

/// Entries past a disk's box that the partially saturated map adds to each column table,
/// so a lane walk of a row ([`CellAreas::strips`]) may read beyond the box's last line
/// (the lanes there are dropped).
pub const TABLE_PAD: usize = 8;

/// The lesser of `a` and `b` (`b` when they are equal or either is NaN): one vector
/// instruction in lanes, where `f64::min` takes three (it must ignore a NaN). The
/// exact-area code holds no NaN.
#[inline(always)]
pub fn lesser(a: f64, b: f64) -> f64 {
    if a < b {
        a
    } else {
        b
    }
}

/// The greater of `a` and `b` (`b` when they are equal or either is NaN); see [`lesser`].
#[inline(always)]
pub fn greater(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// A vertical grid line's entry in a disk's [`CellAreas`]: [s, G(s)], with s the line's
/// offset from the centre clamped to [−r, r] and G(s) = ∫_{−r}^{s} √(r² − t²) dt, the
/// area of the upper half-disk left of the line.
pub type ColumnLine = [f64; 2];

/// A horizontal grid line's entry in a disk's [`CellAreas`]: [v, a, G(a)], with v the
/// line's offset from the centre, a = √(max(r² − v², 0)) the half-width of the chord it
/// cuts, and G as in [`ColumnLine`].
pub type RowLine = [f64; 3];

/// The column entry of the vertical line at `x` for the disk (`centre`, `radius`).
#[inline]
pub fn column_line(centre: [f64; 2], radius: f64, x: f64) -> ColumnLine {
    let s = (x - centre[0]).clamp(-radius, radius);
    [s, upper_area_left_of(s, radius)]
}

/// The row entry of the horizontal line at `y` for the disk (`centre`, `radius`).
#[inline]
pub fn row_line(centre: [f64; 2], radius: f64, y: f64) -> RowLine {
    let v = y - centre[1];
    let a = (radius * radius - v * v).max(0.0).sqrt();
    [v, a, upper_area_left_of(a, radius)]
}

/// G(s) = ∫_{−r}^{s} √(r² − t²) dt for |s| ≤ r: the area of the upper half-disk left of s.
#[inline]
fn upper_area_left_of(s: f64, r: f64) -> f64 {
    half_chord_integral(s, r) + std::f64::consts::FRAC_PI_4 * r * r
}

/// Area of the disk (radius r, centred at the origin) left of the vertical line `col` and
/// below the horizontal line `row`; `half` = πr²/2. With h(t) = √(r² − t²), the region's
/// height at abscissa t is h + min(v, h) for v ≥ 0 and max(0, v + h) for v < 0. For v ≥ 0,
/// min(v, h) = v exactly where |t| < a; for v < 0, v + h > 0 exactly where |t| < a. So the
/// integral over t < s takes G at s and ±a only (G(−a) = πr²/2 − G(a)).
#[inline(always)]
fn corner_area(col: ColumnLine, row: RowLine, half: f64) -> f64 {
    let ([s, gs], [v, a, ga]) = (col, row);
    // Both forms are evaluated and one kept (no branch on the data, so lanes of cells
    // take it together: `CellAreas::strips`).
    let strip = v * (lesser(s, a) + a);
    // v ≥ 0: ∫ h + [∫_{−r}^{−a} h + v (min(s, a) + a) + ∫_a^{max(s, a)} h].
    let upper = gs + (half - ga) + strip + if s > a { gs - ga } else { 0.0 };
    // v < 0: ∫_{−a}^{min(s, a)} (v + h).
    let lower = strip + lesser(gs, ga) - (half - ga);
    // Left of the chord (s ≤ −a): whole columns of the disk below v ≥ 0, nothing below
    // v < 0.
    let (inside, left_of_chord) = if v >= 0.0 {
        (upper, 2.0 * gs)
    } else {
        (lower, 0.0)
    };
    if s <= -a {
        left_of_chord
    } else {
        inside
    }
}

/// The exact areas a disk shares with the cells of its box, from one entry per grid line
/// ([`column_line`], [`row_line`]): each cell's area is a difference of four corner areas
/// (inclusion–exclusion), so the square roots and arcsines are computed once per line
/// instead of per cell. `columns[j]` is the line at x = `x_lo` + j, `rows[m]` the line at
/// y = `y_lo` + m, both covering the disk's box ([`box_lines`]).
#[derive(Debug, Clone, Copy)]
pub struct CellAreas<'a> {
    /// One entry per vertical line, from `x_lo`.
    pub columns: &'a [ColumnLine],
    /// One entry per horizontal line, from `y_lo`.
    pub rows: &'a [RowLine],
    /// First vertical line (global lattice x).
    pub x_lo: i64,
    /// First horizontal line (lattice y).
    pub y_lo: i64,
    /// The disk's radius (lattice units).
    pub radius: f64,
}

impl CellAreas<'_> {
    /// Area the disk shares with cell (x, y) (inside the box) as a fraction of the cell, in
    /// [0, 1]: [`cell_fraction`] to rounding (the error grows with πr²; tested to within
    /// 1e-14 (1 + r²)). The cell-by-cell form; the map takes runs of cells in lanes
    /// ([`CellAreas::strips`]), tested against this.
    #[cfg(test)]
    pub fn fraction(&self, x: i64, y: i64) -> f64 {
        let [left, right] = self.strips::<2>(x, y);
        Self::between(left, right)
    }

    /// The disk's area in row `y` (between the horizontal lines y and y + 1) left of each of
    /// the `N` vertical lines from `x` on, in lanes (the same arithmetic per lane). A cell's
    /// area is the difference of the strips at its two vertical lines, so a run of cells in
    /// a row takes one strip per line. The column table must hold the lines: line `x + N − 1`
    /// may lie past the box, where the partially saturated map pads each image's table
    /// ([`TABLE_PAD`] entries).
    #[inline(always)]
    pub fn strips<const N: usize>(&self, x: i64, y: i64) -> [f64; N] {
        let (j, m) = ((x - self.x_lo) as usize, (y - self.y_lo) as usize);
        let half = std::f64::consts::FRAC_PI_2 * self.radius * self.radius;
        let (r0, r1) = (self.rows[m], self.rows[m + 1]);
        let columns = &self.columns[j..j + N];
        let mut out = [0.0; N];
        for l in 0..N {
            out[l] = corner_area(columns[l], r1, half) - corner_area(columns[l], r0, half);
        }
        out
    }

    /// A cell's fraction from the strips at its left and right lines ([`CellAreas::strips`]).
    #[inline]
    pub fn between(left: f64, right: f64) -> f64 {
        (right - left).clamp(0.0, 1.0)
    }
}

/// One disk's line tables, built directly (the partially saturated map builds them for all
/// images in one pass): for tests.
#[cfg(test)]
pub(crate) struct LineTables {
    columns: Vec<ColumnLine>,
    rows: Vec<RowLine>,
    x_lo: i64,
    y_lo: i64,
    radius: f64,
}

#[cfg(test)]
impl LineTables {
    /// The tables of a disk at `c` with radius `r` over its box ([`box_lines`]), the column
    /// table followed by `pad` copies of its last line (as [`TABLE_PAD`]).
    pub(crate) fn new(c: [f64; 2], r: f64, pad: usize) -> Self {
        let (x_lo, nx) = box_lines(c[0], r);
        let (y_lo, ny) = box_lines(c[1], r);
        Self {
            columns: (0..nx + pad)
                .map(|j| column_line(c, r, (x_lo + j.min(nx - 1) as i64) as f64))
                .collect(),
            rows: (0..ny)
                .map(|m| row_line(c, r, (y_lo + m as i64) as f64))
                .collect(),
            x_lo,
            y_lo,
            radius: r,
        }
    }

    /// The disk's [`CellAreas`] over these tables.
    pub(crate) fn areas(&self) -> CellAreas<'_> {
        CellAreas {
            columns: &self.columns,
            rows: &self.rows,
            x_lo: self.x_lo,
            y_lo: self.y_lo,
            radius: self.radius,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_fractions_add_up_to_the_disk_area() {
        for (c, r) in [
            ([10.3, 7.77], 4.1),
            ([5.0, 5.0], 2.5),
            ([8.5, 8.5], 0.4),
            ([20.123, 19.9], 8.0),
        ] {
            let mut total = 0.0;
            for y in 0..40 {
                for x in 0..40 {
                    let e = cell_fraction(c, r, x, y);
                    assert!((0.0..=1.0).contains(&e));
                    total += e;
                }
            }
            let exact = std::f64::consts::PI * r * r;
            assert!((total - exact).abs() < 1e-11 * exact, "{total} vs {exact}");
        }
    }

    #[test]
    fn line_tables_give_the_exact_cell_areas() {
        // Radii from under a cell to 40 cells, centres on and off the grid lines.
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || lbm::test_rng::next(&mut seed);
        let mut cases: Vec<([f64; 2], f64)> = vec![
            ([10.0, 10.0], 3.0),
            ([10.5, 10.5], 2.5),
            ([-3.25, 7.0], 5.0),
            ([0.0, 0.0], 0.4),
        ];
        for _ in 0..200 {
            let r = 0.3 + 40.0 * next() * next();
            cases.push(([200.0 * next() - 100.0, 200.0 * next() - 100.0], r));
        }
        for (c, r) in cases {
            let tables = LineTables::new(c, r, 0);
            let areas = tables.areas();
            let (x_lo, nx) = box_lines(c[0], r);
            let (y_lo, ny) = box_lines(c[1], r);
            let tol = 1e-14 * (1.0 + r * r);
            let mut total = 0.0;
            for y in y_lo..y_lo + ny as i64 - 1 {
                for x in x_lo..x_lo + nx as i64 - 1 {
                    let (e, want) = (areas.fraction(x, y), cell_fraction(c, r, x, y));
                    assert!(
                        (e - want).abs() <= tol,
                        "disk {c:?} r {r}: cell ({x}, {y}) {e} vs {want}"
                    );
                    total += e;
                }
            }
            let exact = std::f64::consts::PI * r * r;
            assert!((total - exact).abs() < 1e-11 * exact, "{total} vs {exact}");
        }
    }

    #[test]
    fn rectangle_areas_match_simple_cases() {
        let pi = std::f64::consts::PI;
        // Whole disk inside.
        let a = disk_rectangle_area([0.0, 0.0], 1.0, [-2.0, -2.0], [2.0, 2.0]);
        assert!((a - pi).abs() < 1e-14);
        // A quadrant.
        let q = disk_rectangle_area([0.0, 0.0], 1.0, [0.0, 0.0], [3.0, 3.0]);
        assert!((q - pi / 4.0).abs() < 1e-14);
        // Half.
        let h = disk_rectangle_area([0.0, 0.0], 2.0, [-3.0, 0.0], [3.0, 3.0]);
        assert!((h - 2.0 * pi).abs() < 1e-13);
        // A square inside the disk.
        let s = disk_rectangle_area([0.0, 0.0], 2.0, [-1.0, -1.0], [0.5, 1.0]);
        assert!((s - 3.0).abs() < 1e-14);
        // A circular segment: r = 1, cut at y = 0.5: r² acos(d/r) − d √(r² − d²).
        let seg = disk_rectangle_area([0.0, 0.0], 1.0, [-1.0, 0.5], [1.0, 1.0]);
        let exact = (0.5f64).acos() - 0.5 * (0.75f64).sqrt();
        assert!((seg - exact).abs() < 1e-14);
        // Disjoint.
        assert_eq!(
            disk_rectangle_area([0.0, 0.0], 1.0, [1.0, 1.0], [2.0, 2.0]),
            0.0
        );
    }

    #[test]
    fn link_fractions_hit_the_surface() {
        let (c, r) = ([10.0, 10.0], 3.2);
        // From (6.5, 10.5) east: surface where (x − 10)² + 0.25 = 10.24.
        let q = link_fraction([6.5, 10.5], [1.0, 0.0], c, r);
        let x = 10.0 - (10.24f64 - 0.25).sqrt();
        assert!((q - (x - 6.5)).abs() < 1e-14);
        // Diagonal: the hit point lies on the circle.
        let from = [12.5, 13.5];
        let q = link_fraction(from, [-1.0, -1.0], c, r);
        assert!(q > 0.0 && q <= 1.0);
        let p = [from[0] - q, from[1] - q];
        let d = ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt();
        assert!((d - r).abs() < 1e-13);
        // A link that misses.
        assert_eq!(link_fraction([0.5, 0.5], [1.0, 0.0], c, r), 1.0);
    }
}
