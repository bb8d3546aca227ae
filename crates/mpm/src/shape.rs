//! Shape functions of the background grid: standard linear (tent) functions, uGIMP and
//! contiguous-particle GIMP. A point in cell column `c` touches at most the four node
//! columns `c-1 ..= c+2` (GIMP with half-length ≤ h/2) or `c ..= c+1` (linear); the
//! weights are returned for those four slots, zero outside the support.

/// Which interpolation the scene asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShapeKind {
    /// Standard MPM: bilinear tent functions. Cheapest; cell-crossing noise.
    Linear,
    /// Uniform GIMP (Bardenhagen & Kober 2004): the point's domain keeps its initial size.
    Gimp,
    /// Contiguous-particle GIMP: the domain half-lengths follow the stretches F_xx, F_yy,
    /// capped at h/2 so that the support stays within four nodes.
    CpGimp,
}

/// Weights and gradients of one point in one direction. Slot `k` is node `c − 1 + k`;
/// only the slots `first .. first + count` can be non-zero (3 for GIMP, whose half-length
/// ≤ h/2 reaches at most one of the outer nodes; 2 for linear shapes).
#[derive(Debug, Clone, Copy, Default)]
pub struct Weights1d {
    /// First slot that may be non-zero.
    pub first: usize,
    /// Number of slots from `first`.
    pub count: usize,
    /// S(x_I) for the four slots.
    pub w: [f64; 4],
    /// dS/dx (1/m) for the four slots.
    pub g: [f64; 4],
}

/// x_I − x (m) for slot `slot` of the [`Weights1d`] of a point at `x` (m) in cell `cell`:
/// slot k is node `cell − 1 + k`, at (cell − 1 + k) h.
#[inline(always)]
pub fn node_offset(cell: i64, slot: usize, h: f64, x: f64) -> f64 {
    (cell - 1 + slot as i64) as f64 * h - x
}

/// Weights of a point at coordinate `x` (m) along one axis, for a grid of spacing `h` (m)
/// whose node `I` sits at `I h`. `cell` is `floor(x / h)`; `half` is the point's domain
/// half-length (m), ignored for [`ShapeKind::Linear`]. Precondition: `0 < half ≤ h/2`.
#[inline(always)]
pub fn weights_1d(kind: ShapeKind, x: f64, cell: i64, h: f64, half: f64) -> Weights1d {
    let inv_h = 1.0 / h;
    let mut out = Weights1d::default();
    match kind {
        ShapeKind::Linear => {
            // Tent functions N_I = 1 − |x − x_I| / h (Sulsky et al. 1994).
            let xi = x * inv_h - cell as f64;
            out.first = 1;
            out.count = 2;
            out.w[1] = 1.0 - xi;
            out.w[2] = xi;
            out.g[1] = -inv_h;
            out.g[2] = inv_h;
        }
        ShapeKind::Gimp | ShapeKind::CpGimp => {
            let base = cell as f64 * h;
            // Node c − 1 is reached only when the point is within `half` of node c.
            out.first = if x - base < half { 0 } else { 1 };
            out.count = 3;
            for k in out.first..out.first + 3 {
                let node = base + (k as f64 - 1.0) * h;
                let (w, g) = gimp(x - node, h, half);
                out.w[k] = w;
                out.g[k] = g;
            }
        }
    }
    out
}

/// uGIMP weight and gradient at distance `r = x_p − x_I` (Bardenhagen & Kober 2004, eq. 41
/// for the weight; its derivative for the gradient), for spacing `h` and half-length `lp`.
#[inline(always)]
fn gimp(r: f64, h: f64, lp: f64) -> (f64, f64) {
    let a = r.abs();
    let s = if r < 0.0 { -1.0 } else { 1.0 };
    if a < lp {
        (1.0 - (r * r + lp * lp) / (2.0 * h * lp), -r / (h * lp))
    } else if a < h - lp {
        (1.0 - a / h, -s / h)
    } else if a < h + lp {
        let d = h + lp - a;
        (d * d / (4.0 * h * lp), -s * d / (2.0 * h * lp))
    } else {
        (0.0, 0.0)
    }
}

/// Domain half-lengths (m) of a point along x and y: the initial `half0` for uGIMP, the
/// stretched one for cpGIMP (capped at h/2), unused for linear shapes.
#[inline(always)]
pub fn half_lengths(kind: ShapeKind, half0: f64, defgrad: &[f64; 4], h: f64) -> [f64; 2] {
    match kind {
        ShapeKind::CpGimp => {
            // Stretch of the domain along the axes: |F e_x|, |F e_y| (Sadeghirad et al. 2011
            // track the full parallelogram; the axis-aligned stretch keeps the tensor product).
            let sx = (defgrad[0] * defgrad[0] + defgrad[2] * defgrad[2]).sqrt();
            let sy = (defgrad[1] * defgrad[1] + defgrad[3] * defgrad[3]).sqrt();
            [(half0 * sx).min(0.5 * h), (half0 * sy).min(0.5 * h)]
        }
        _ => [half0, half0],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_partition(kind: ShapeKind, half: f64) {
        let h = 0.1;
        for i in 0..200 {
            let x = 0.3 + i as f64 * 0.000_5;
            let cell = (x / h).floor() as i64;
            let w = weights_1d(kind, x, cell, h, half);
            let sum: f64 = w.w.iter().sum();
            let gsum: f64 = w.g.iter().sum();
            // Partition of unity and its derivative: Σ S = 1, Σ dS/dx = 0.
            assert!((sum - 1.0).abs() < 1e-12, "{kind:?} Σw = {sum} at {x}");
            assert!(gsum.abs() < 1e-9, "{kind:?} Σg = {gsum} at {x}");
            // Linear completeness: Σ S x_I = x.
            let xs: f64 = (0..4)
                .map(|k| w.w[k] * (cell - 1 + k as i64) as f64 * h)
                .sum();
            assert!((xs - x).abs() < 1e-12, "{kind:?} Σ w x_I = {xs} at {x}");
            // Σ dS/dx x_I = 1.
            let gx: f64 = (0..4)
                .map(|k| w.g[k] * (cell - 1 + k as i64) as f64 * h)
                .sum();
            assert!((gx - 1.0).abs() < 1e-9, "{kind:?} Σ g x_I = {gx} at {x}");
            assert!(w.w.iter().all(|&v| v >= 0.0));
        }
    }

    #[test]
    fn partition_of_unity_and_linear_completeness() {
        check_partition(ShapeKind::Linear, 0.025);
        check_partition(ShapeKind::Gimp, 0.025);
        check_partition(ShapeKind::Gimp, 0.05);
        check_partition(ShapeKind::Gimp, 0.0125);
    }

    #[test]
    fn gimp_gradient_is_the_derivative_of_the_weight() {
        let (h, lp) = (1.0, 0.25);
        for i in 0..400 {
            let r = -1.4 + i as f64 * 0.007;
            let e = 1e-7;
            let fd = (gimp(r + e, h, lp).0 - gimp(r - e, h, lp).0) / (2.0 * e);
            assert!((fd - gimp(r, h, lp).1).abs() < 1e-6, "r = {r}");
        }
        // Continuity at the piece boundaries.
        for r in [lp, h - lp, h + lp] {
            let (a, b) = (gimp(r - 1e-12, h, lp).0, gimp(r + 1e-12, h, lp).0);
            assert!((a - b).abs() < 1e-9);
        }
    }

    #[test]
    fn cpgimp_half_lengths_stretch_and_cap() {
        let h = 0.1;
        assert_eq!(
            half_lengths(ShapeKind::Gimp, 0.02, &[2.0, 0.0, 0.0, 1.0], h),
            [0.02; 2]
        );
        let s = half_lengths(ShapeKind::CpGimp, 0.02, &[1.5, 0.0, 0.0, 0.8], h);
        assert!((s[0] - 0.03).abs() < 1e-15 && (s[1] - 0.016).abs() < 1e-15);
        let c = half_lengths(ShapeKind::CpGimp, 0.025, &[3.0, 0.0, 0.0, 1.0], h);
        assert_eq!(c[0], 0.05);
    }
}
