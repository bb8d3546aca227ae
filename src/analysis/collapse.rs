//! Granular column collapse geometry (Lajeunesse, Monnier & Homsy 2005): the length and
//! height of a column or deposit of disks standing against a wall on a floor.

/// Length and height of a pile of disks against a wall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PileShape {
    /// Distance from the wall to the front: the farthest disk edge of the continuous
    /// deposit (m).
    pub length_m: f64,
    /// Highest disk edge above the floor in the continuous deposit (m).
    pub height_m: f64,
}

/// The shape of the continuous deposit of disks (`x`, `y`, `r` in m) against the wall at
/// x = `wall_x` on the floor y = `floor_y`, growing in +x. The front is where the deposit
/// first has a gap wider than two largest diameters along x: grains flung beyond it
/// (saltating or isolated) do not count, as in the experiments' front detection.
pub fn pile_shape(x: &[f64], y: &[f64], r: &[f64], wall_x: f64, floor_y: f64) -> PileShape {
    let dmax = 2.0 * r.iter().cloned().fold(0.0, f64::max);
    let mut order: Vec<usize> = (0..x.len()).collect();
    order.sort_by(|&a, &b| (x[a] - r[a]).total_cmp(&(x[b] - r[b])));
    let mut reach = wall_x;
    let mut height: f64 = 0.0;
    for &i in &order {
        if x[i] - r[i] > reach + 2.0 * dmax {
            break;
        }
        reach = reach.max(x[i] + r[i]);
        height = height.max(y[i] + r[i] - floor_y);
    }
    PileShape {
        length_m: reach - wall_x,
        height_m: height,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of touching disks is as long as the row; an isolated disk far out is ignored;
    /// a stack is as high as the stack.
    #[test]
    fn rows_stacks_and_outliers() {
        let r = 0.5;
        let mut x: Vec<f64> = (0..10).map(|i| 0.5 + i as f64).collect();
        let mut y = vec![0.5; 10];
        x.push(0.5);
        y.push(1.5);
        x.push(40.0);
        y.push(0.5);
        let rr = vec![r; x.len()];
        let s = pile_shape(&x, &y, &rr, 0.0, 0.0);
        assert!((s.length_m - 10.0).abs() < 1e-12, "{s:?}");
        assert!((s.height_m - 2.0).abs() < 1e-12, "{s:?}");
    }
}
