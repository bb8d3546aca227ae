//! Straight walls (segments) that grains touch from either side; a wall may move.

/// A wall segment from `a` to `b` (m), moving with `velocity` (m/s), with its own Coulomb
/// friction coefficient.
#[derive(Debug, Clone, PartialEq)]
pub struct Wall {
    /// First end (m).
    pub a: [f64; 2],
    /// Second end (m).
    pub b: [f64; 2],
    /// Velocity (m/s): the gate of a column collapse moves up.
    pub velocity: [f64; 2],
    /// Friction coefficient grain–wall.
    pub friction: f64,
    /// Removed from the run (e.g. a lifted gate): no longer touches grains. Removal keeps
    /// the wall's index, which keys its contact history.
    pub removed: bool,
}

impl Wall {
    /// A fixed wall from `a` to `b` (m) with friction coefficient `friction`.
    pub fn fixed(a: [f64; 2], b: [f64; 2], friction: f64) -> Self {
        Wall {
            a,
            b,
            velocity: [0.0, 0.0],
            friction,
            removed: false,
        }
    }

    /// Closest point of the segment to `p`.
    pub fn closest_point(&self, p: [f64; 2]) -> [f64; 2] {
        let d = [self.b[0] - self.a[0], self.b[1] - self.a[1]];
        let len2 = d[0] * d[0] + d[1] * d[1];
        let t = if len2 > 0.0 {
            (((p[0] - self.a[0]) * d[0] + (p[1] - self.a[1]) * d[1]) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        [self.a[0] + t * d[0], self.a[1] + t * d[1]]
    }

    /// Move the wall by its velocity over `dt` (s).
    pub fn advance(&mut self, dt: f64) {
        for p in [&mut self.a, &mut self.b] {
            p[0] += self.velocity[0] * dt;
            p[1] += self.velocity[1] * dt;
        }
    }
}

/// The four fixed walls of the box `[lo, hi]` (m): floor, right, lid, left.
pub fn closed_box(lo: [f64; 2], hi: [f64; 2], friction: f64) -> Vec<Wall> {
    let corners = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]];
    (0..4)
        .map(|k| Wall::fixed(corners[k], corners[(k + 1) % 4], friction))
        .collect()
}
