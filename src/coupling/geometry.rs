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

/// Fraction δ ∈ (0, 1] of the link from the point `from` (a fluid cell centre, outside the
/// disk) along `c` (a lattice velocity) at which the link meets the disk's surface
/// (seed eq. 5.50). Returns 1 when the link does not reach the disk (a covered cell whose
/// centre is on the boundary), so the caller falls back to half-way bounce-back there.
pub fn link_fraction(from: [f64; 2], c: [f64; 2], centre: [f64; 2], radius: f64) -> f64 {
    // |from + t c − centre|² = r²: a t² + 2 b t + k = 0 with k > 0 (from is outside).
    let d = [from[0] - centre[0], from[1] - centre[1]];
    let a = c[0] * c[0] + c[1] * c[1];
    let b = d[0] * c[0] + d[1] * c[1];
    let k = d[0] * d[0] + d[1] * d[1] - radius * radius;
    let disc = b * b - a * k;
    if disc < 0.0 || k <= 0.0 {
        return 1.0;
    }
    // The nearer root; written to avoid cancellation when b < 0 (the link points inwards).
    let t = k / (-b + disc.sqrt());
    if t > 0.0 && t <= 1.0 {
        t
    } else {
        1.0
    }
}

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
