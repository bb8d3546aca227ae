//! Granular column collapse geometry (Lajeunesse, Monnier & Homsy 2005): the length and
//! height of a column or deposit of disks standing against a wall on a floor.

/// Length and height of a pile of disks against a wall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PileShape {
    /// Distance from the wall to the front: the farthest disk edge of the deposit (m).
    pub length_m: f64,
    /// Highest disk edge above the floor in the deposit (m).
    pub height_m: f64,
}

/// The shape of the deposit of disks (`x`, `y`, `r` in m) against the wall at
/// x = `wall_x` on the floor y = `floor_y`, growing in +x: the grains connected to the wall
/// through contacts (gaps below a tenth of the smaller radius count as contact). Grains that
/// left the mass — rolling alone on the floor or flung ahead — do not count, as they do not
/// in the experiments' front detection.
pub fn pile_shape(x: &[f64], y: &[f64], r: &[f64], wall_x: f64, floor_y: f64) -> PileShape {
    let n = x.len();
    let rmax = r.iter().cloned().fold(0.0, f64::max);
    let cell = 2.2 * rmax.max(1e-300);
    let key = |i: usize| {
        (
            ((x[i] - wall_x) / cell).floor() as i64,
            ((y[i] - floor_y) / cell).floor() as i64,
        )
    };
    let mut grid: std::collections::HashMap<(i64, i64), Vec<usize>> = Default::default();
    for i in 0..n {
        grid.entry(key(i)).or_default().push(i);
    }
    let touches = |i: usize, j: usize| {
        let d = (x[i] - x[j]).hypot(y[i] - y[j]);
        d < r[i] + r[j] + 0.1 * r[i].min(r[j])
    };
    // Flood fill from the grains touching the wall.
    let mut seen = vec![false; n];
    let mut stack: Vec<usize> = (0..n)
        .filter(|&i| x[i] - r[i] <= wall_x + 0.1 * r[i])
        .collect();
    for &i in &stack {
        seen[i] = true;
    }
    let (mut reach, mut height) = (wall_x, 0.0f64);
    while let Some(i) = stack.pop() {
        reach = reach.max(x[i] + r[i]);
        height = height.max(y[i] + r[i] - floor_y);
        let (cx, cy) = key(i);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for &j in grid
                    .get(&(cx + dx, cy + dy))
                    .map(Vec::as_slice)
                    .unwrap_or(&[])
                {
                    if !seen[j] && touches(i, j) {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
    }
    PileShape {
        length_m: reach - wall_x,
        height_m: height,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of touching disks is as long as the row; an isolated disk out on the floor is
    /// ignored; a stack is as high as the stack.
    #[test]
    fn rows_stacks_and_outliers() {
        let r = 0.5;
        let mut x: Vec<f64> = (0..10).map(|i| 0.5 + i as f64).collect();
        let mut y = vec![0.5; 10];
        x.push(0.5);
        y.push(1.5);
        x.push(12.0);
        y.push(0.5);
        let rr = vec![r; x.len()];
        let s = pile_shape(&x, &y, &rr, 0.0, 0.0);
        assert!((s.length_m - 10.0).abs() < 1e-12, "{s:?}");
        assert!((s.height_m - 2.0).abs() < 1e-12, "{s:?}");
    }
}
