//! Rasterising solid shapes onto the lattice (lattice length units: cell (x, y) spans
//! [x, x+1) × [y, y+1) and is solid when its centre is inside the shape).

/// A solid shape in lattice units.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// Axis-aligned rectangle `[min, max]`.
    Rectangle {
        /// Lower-left corner.
        min: [f64; 2],
        /// Upper-right corner.
        max: [f64; 2],
    },
    /// Disk.
    Circle {
        /// Centre.
        centre: [f64; 2],
        /// Radius.
        radius: f64,
    },
    /// Simple polygon (even–odd rule), vertices in order.
    Polygon(Vec<[f64; 2]>),
    /// Per-cell mask, row-major from the south row, `true` = solid; size nx × ny.
    Mask(Vec<bool>),
}

impl Shape {
    /// Whether the point `p` lies inside the shape.
    pub fn contains(&self, p: [f64; 2], nx: usize) -> bool {
        match self {
            Shape::Rectangle { min, max } => {
                p[0] >= min[0] && p[0] <= max[0] && p[1] >= min[1] && p[1] <= max[1]
            }
            Shape::Circle { centre, radius } => {
                let (dx, dy) = (p[0] - centre[0], p[1] - centre[1]);
                dx * dx + dy * dy <= radius * radius
            }
            Shape::Polygon(v) => {
                // Crossing-number test (Shimrat 1962).
                let mut inside = false;
                let mut j = v.len() - 1;
                for i in 0..v.len() {
                    let (a, b) = (v[i], v[j]);
                    if (a[1] > p[1]) != (b[1] > p[1])
                        && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0]
                    {
                        inside = !inside;
                    }
                    j = i;
                }
                inside
            }
            Shape::Mask(m) => {
                let (x, y) = (p[0].floor() as usize, p[1].floor() as usize);
                m.get(y * nx + x).copied().unwrap_or(false)
            }
        }
    }

    /// Bounding box `(min, max)` in lattice units.
    pub fn bounds(&self, nx: usize, ny: usize) -> ([f64; 2], [f64; 2]) {
        match self {
            Shape::Rectangle { min, max } => (*min, *max),
            Shape::Circle { centre, radius } => (
                [centre[0] - radius, centre[1] - radius],
                [centre[0] + radius, centre[1] + radius],
            ),
            Shape::Polygon(v) => {
                let mut lo = [f64::INFINITY; 2];
                let mut hi = [f64::NEG_INFINITY; 2];
                for p in v {
                    for a in 0..2 {
                        lo[a] = lo[a].min(p[a]);
                        hi[a] = hi[a].max(p[a]);
                    }
                }
                (lo, hi)
            }
            Shape::Mask(_) => ([0.0, 0.0], [nx as f64, ny as f64]),
        }
    }

    /// Mark every cell whose centre lies inside with `id`. Returns how many cells it took.
    pub fn rasterise(&self, cells: &mut [u16], nx: usize, ny: usize, id: u16) -> usize {
        self.visit(nx, ny, |k| cells[k] = id)
    }

    /// How many cells of an nx × ny lattice have their centre inside.
    pub fn covered_cells(&self, nx: usize, ny: usize) -> usize {
        self.visit(nx, ny, |_| {})
    }

    /// Call `f(y * nx + x)` for every cell whose centre lies inside; returns their number.
    fn visit(&self, nx: usize, ny: usize, mut f: impl FnMut(usize)) -> usize {
        let (lo, hi) = self.bounds(nx, ny);
        let x0 = lo[0].floor().max(0.0) as usize;
        let y0 = lo[1].floor().max(0.0) as usize;
        let x1 = (hi[0].ceil().max(0.0) as usize).min(nx);
        let y1 = (hi[1].ceil().max(0.0) as usize).min(ny);
        let mut count = 0;
        for y in y0..y1 {
            for x in x0..x1 {
                if self.contains([x as f64 + 0.5, y as f64 + 0.5], nx) {
                    f(y * nx + x);
                    count += 1;
                }
            }
        }
        count
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_area_converges() {
        let (nx, ny) = (200, 200);
        let mut cells = vec![0u16; nx * ny];
        let n = Shape::Circle {
            centre: [100.0, 100.0],
            radius: 40.0,
        }
        .rasterise(&mut cells, nx, ny, 1);
        let area = std::f64::consts::PI * 1600.0;
        assert!((n as f64 - area).abs() / area < 0.01);
    }

    #[test]
    fn polygon_and_rectangle_agree() {
        let (nx, ny) = (30, 20);
        let mut a = vec![0u16; nx * ny];
        let mut b = vec![0u16; nx * ny];
        Shape::Rectangle {
            min: [3.0, 4.0],
            max: [12.0, 9.0],
        }
        .rasterise(&mut a, nx, ny, 1);
        Shape::Polygon(vec![[3.0, 4.0], [12.0, 4.0], [12.0, 9.0], [3.0, 9.0]])
            .rasterise(&mut b, nx, ny, 1);
        assert_eq!(a, b);
        assert_eq!(a.iter().filter(|&&c| c == 1).count(), 9 * 5);
    }
}
