//! A packed sample against the scene's walls: no wall may run through the packing rectangle
//! (its grains would be packed into it), and a gate (a wall with `remove_at_s`) must open
//! before the run ends and stand against the sample, or removing it releases nothing.

use super::context::Context;
use super::grains::{GrainsSpec, SampleSpec};
use super::grains_check::size_distribution;
use super::SceneError;

/// Check the walls of `g` against its packing rectangle, and its gates against the run's end
/// `run_end_s` (s; None when it is known only later).
pub(super) fn validate(
    g: &GrainsSpec,
    run_end_s: Option<f64>,
    ctx: &Context,
) -> Result<(), SceneError> {
    for (n, w) in g.walls.iter().enumerate() {
        let Some(t) = w.remove_at_s else { continue };
        if let Some(end) = run_end_s.filter(|&end| t >= end) {
            return Err(ctx.err(
                "remove_at_s",
                nth_removal(g, n),
                format!(
                    "gate `{}` opens at {t} s, not before the run ends ({end} s): it releases \
                     nothing; open it earlier or run longer",
                    w.name
                ),
            ));
        }
    }
    let SampleSpec::Pack {
        min_m: lo,
        max_m: hi,
        sizes,
        ..
    } = &g.sample
    else {
        return Ok(());
    };
    let d = size_distribution(sizes);
    let (r_min, r_max) = (d.min_radius(), d.max_radius());
    for (n, w) in g.walls.iter().enumerate() {
        // Through the rectangle shrunk by the smallest radius: grains packed on both sides.
        let inner = (
            [lo[0] + r_min, lo[1] + r_min],
            [hi[0] - r_min, hi[1] - r_min],
        );
        if inner.0[0] < inner.1[0]
            && inner.0[1] < inner.1[1]
            && crosses(w.from_m, w.to_m, inner.0, inner.1)
        {
            return Err(ctx.err(
                "from_m",
                n,
                format!(
                    "wall `{}` ({:?}–{:?} m) runs through the packing rectangle {lo:?}–{hi:?} \
                     m: grains would be packed into it; move the rectangle (min_m, max_m) to \
                     one side of the wall",
                    w.name, w.from_m, w.to_m
                ),
            ));
        }
        if w.remove_at_s.is_some() {
            let gap = distance_to_rectangle(w.from_m, w.to_m, *lo, *hi);
            if gap > r_max {
                return Err(ctx.err(
                    "remove_at_s",
                    nth_removal(g, n),
                    format!(
                        "gate `{}` stands {gap:.4} m from the packing rectangle {lo:?}–{hi:?} m, \
                         more than the largest grain radius ({r_max} m): removing it releases \
                         nothing; put it against the sample",
                        w.name
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Which `remove_at_s = …` of the file wall `n`'s is (for the line in messages).
fn nth_removal(g: &GrainsSpec, n: usize) -> usize {
    g.walls[..n]
        .iter()
        .filter(|w| w.remove_at_s.is_some())
        .count()
}

/// Whether the segment a–b meets the open rectangle lo–hi (Liang–Barsky clipping).
fn crosses(a: [f64; 2], b: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> bool {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..2 {
        let d = b[k] - a[k];
        for (p, q) in [(-d, a[k] - lo[k]), (d, hi[k] - a[k])] {
            if p == 0.0 {
                if q <= 0.0 {
                    return false;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
    }
    t0 < t1
}

/// Shortest distance (m) between the segment a–b and the closed rectangle lo–hi.
fn distance_to_rectangle(a: [f64; 2], b: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> f64 {
    let inside = |p: [f64; 2]| (0..2).all(|k| lo[k] <= p[k] && p[k] <= hi[k]);
    if inside(a) || inside(b) || crosses(a, b, lo, hi) {
        return 0.0;
    }
    let corners = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]];
    let mut best = f64::INFINITY;
    for k in 0..4 {
        let (c, e) = (corners[k], corners[(k + 1) % 4]);
        best = best
            .min(point_to_segment(a, c, e))
            .min(point_to_segment(b, c, e))
            .min(point_to_segment(c, a, b))
            .min(point_to_segment(e, a, b));
    }
    best
}

/// Distance (m) from p to the segment a–b.
fn point_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_against_rectangles() {
        let (lo, hi) = ([0.0, 0.0], [1.0, 1.0]);
        assert!(crosses([-1.0, 0.5], [2.0, 0.5], lo, hi), "straight through");
        assert!(crosses([0.5, 0.5], [0.6, 0.6], lo, hi), "inside");
        assert!(!crosses([0.0, -1.0], [0.0, 2.0], lo, hi), "along the edge");
        assert!(!crosses([-1.0, 0.0], [2.0, 0.0], lo, hi), "along the floor");
        assert!(!crosses([1.5, 0.0], [1.5, 1.0], lo, hi), "beside it");
        assert_eq!(distance_to_rectangle([1.0, 0.0], [1.0, 1.0], lo, hi), 0.0);
        assert!((distance_to_rectangle([1.5, 0.0], [1.5, 1.0], lo, hi) - 0.5).abs() < 1e-15);
        assert!(
            (distance_to_rectangle([2.0, 2.0], [3.0, 2.0], lo, hi) - 2f64.sqrt()).abs() < 1e-15
        );
    }
}
