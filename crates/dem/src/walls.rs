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

/// Walls binned into a uniform grid over a region, so that finding the walls near a grain
/// costs O(walls in its cell), not O(all walls): a wall is listed in every cell its bounding
/// box, widened by `reach`, overlaps.
#[derive(Debug, Clone)]
pub struct WallGrid {
    origin: [f64; 2],
    size: f64,
    nx: usize,
    ny: usize,
    /// Walls of cell c: `items[start[c]..start[c + 1]]`, increasing index.
    start: Vec<u32>,
    items: Vec<u32>,
}

impl WallGrid {
    /// Bin the walls that are not removed over the box `[lo, hi]` (m) with cells of about
    /// `reach` (m; at most `max_cells` cells), each wall widened by `reach`.
    pub fn build(walls: &[Wall], lo: [f64; 2], hi: [f64; 2], reach: f64, max_cells: usize) -> Self {
        let mut size = reach.max(1e-12);
        let count =
            |s: f64| (((hi[0] - lo[0]) / s) as usize + 1) * (((hi[1] - lo[1]) / s) as usize + 1);
        while count(size) > max_cells.max(1) {
            size *= 2.0;
        }
        let nx = ((hi[0] - lo[0]) / size) as usize + 1;
        let ny = ((hi[1] - lo[1]) / size) as usize + 1;
        let clamp =
            |v: f64, o: f64, n: usize| (((v - o) / size).floor().max(0.0) as usize).min(n - 1);
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
        for (w, wall) in walls.iter().enumerate() {
            if wall.removed {
                continue;
            }
            let (x0, x1) = (
                wall.a[0].min(wall.b[0]) - reach,
                wall.a[0].max(wall.b[0]) + reach,
            );
            let (y0, y1) = (
                wall.a[1].min(wall.b[1]) - reach,
                wall.a[1].max(wall.b[1]) + reach,
            );
            if x1 < lo[0] || x0 > hi[0] || y1 < lo[1] || y0 > hi[1] {
                continue;
            }
            for cy in clamp(y0, lo[1], ny)..=clamp(y1, lo[1], ny) {
                for cx in clamp(x0, lo[0], nx)..=clamp(x1, lo[0], nx) {
                    lists[cy * nx + cx].push(w as u32);
                }
            }
        }
        let mut start = Vec::with_capacity(nx * ny + 1);
        let mut items = Vec::new();
        start.push(0);
        for l in lists {
            items.extend(l);
            start.push(items.len() as u32);
        }
        Self {
            origin: lo,
            size,
            nx,
            ny,
            start,
            items,
        }
    }

    /// The walls listed for the cell holding `p` (a superset of those within `reach`).
    pub fn near(&self, p: [f64; 2]) -> &[u32] {
        let cell =
            |v: f64, o: f64, n: usize| (((v - o) / self.size).floor().max(0.0) as usize).min(n - 1);
        let c = cell(p[1], self.origin[1], self.ny) * self.nx + cell(p[0], self.origin[0], self.nx);
        &self.items[self.start[c] as usize..self.start[c + 1] as usize]
    }
}

/// Wall ends and removal flags as a checkpoint holds them.
pub type WallStates = Vec<([f64; 2], [f64; 2], bool)>;

/// Apply restored wall ends and removal flags to `walls` (in scene order).
pub fn apply_walls(walls: &mut [Wall], restored: &[([f64; 2], [f64; 2], bool)]) {
    for (w, &(a, b, removed)) in walls.iter_mut().zip(restored) {
        w.a = a;
        w.b = b;
        w.removed = removed;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid lists every wall within `reach` of a point (checked against all walls).
    #[test]
    fn wall_grid_finds_every_near_wall() {
        let mut rng = crate::sample::Rng::new(5);
        let mut walls = Vec::new();
        for _ in 0..300 {
            let a = [rng.uniform(), rng.uniform()];
            let b = [
                a[0] + 0.2 * (rng.uniform() - 0.5),
                a[1] + 0.2 * (rng.uniform() - 0.5),
            ];
            walls.push(Wall::fixed(a, b, 0.3));
        }
        walls[7].removed = true;
        let reach = 0.03;
        let grid = WallGrid::build(&walls, [0.0, 0.0], [1.0, 1.0], reach, 1000);
        let mut found = 0;
        for _ in 0..2000 {
            let p = [rng.uniform(), rng.uniform()];
            let listed = grid.near(p);
            for (w, wall) in walls.iter().enumerate() {
                let c = wall.closest_point(p);
                let near = (p[0] - c[0]).hypot(p[1] - c[1]) < reach && !wall.removed;
                if near {
                    found += 1;
                    assert!(
                        listed.contains(&(w as u32)),
                        "wall {w} near {p:?} not listed"
                    );
                }
            }
            assert!(!listed.contains(&7), "a removed wall is listed");
            assert!(listed.windows(2).all(|x| x[0] < x[1]), "in index order");
        }
        assert!(found > 100, "{found}");
    }
}
