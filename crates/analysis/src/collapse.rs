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

/// Run-out (L_f − L_i)/L_i of the published 2-D DEM of disks at aspect ratio `a`:
/// 1.67 a below a ≈ 2.7, 2.7 a^(2/3) above (../shared/reference/README.md).
pub fn dem_law(a: f64) -> f64 {
    if a < 2.7 {
        1.67 * a
    } else {
        2.7 * a.powf(2.0 / 3.0)
    }
}

/// Run-out of the experiments (Lajeunesse et al. 2005): 1.2 a below a ≈ 2.3,
/// 1.9 a^(2/3) above.
pub fn experiment_law(a: f64) -> f64 {
    if a < 2.3 {
        1.2 * a
    } else {
        1.9 * a.powf(2.0 / 3.0)
    }
}

pub use scene::collapse_names::{QUANTITIES, THICK_QUANTITIES};

/// When the front moved and how fast, from its position `fronts` (m from the wall) at
/// `times` (s, from the release): `[t₁₀, t₉₅, speed]`, the first times the front passed
/// 10 % and 95 % of its run-out from `li` to `lf` (s; NaN when it never did) and its mean
/// speed between them, 0.85 (lf − li)/(t₉₅ − t₁₀) (m/s; NaN when the series does not
/// resolve the two apart). A mass that does not move (lf ≤ li) has NaN times and speed 0.
pub fn front_timing(times: &[f64], fronts: &[f64], li: f64, lf: f64) -> [f64; 3] {
    if !(lf > li) {
        return [f64::NAN, f64::NAN, 0.0];
    }
    let at = |frac: f64| {
        let target = li + frac * (lf - li);
        fronts
            .iter()
            .position(|&x| x >= target)
            .map_or(f64::NAN, |j| times[j])
    };
    let (t10, t95) = (at(0.10), at(0.95));
    let speed = if t95 > t10 {
        0.85 * (lf - li) / (t95 - t10)
    } else {
        f64::NAN
    };
    [t10, t95, speed]
}

/// The collapse results, in the order of [`QUANTITIES`], from the column `before` and the
/// deposit `after`, gravity `g` (m/s²) and the time the flow took (s):
/// run-out (L_f − L_i)/L_i, H_f/L_i, a = H_i/L_i, L_f, H_f, L_i, H_i, the flow time in
/// units of τ_c = √(H_i/g), and the run-out over the 2-D DEM law and over the experiments'.
pub fn collapse_results(
    before: PileShape,
    after: PileShape,
    g: f64,
    flow_time_s: f64,
) -> [f64; 10] {
    let (li, hi) = (before.length_m, before.height_m);
    let a = hi / li;
    let runout = (after.length_m - li) / li;
    [
        runout,
        after.height_m / li,
        a,
        after.length_m,
        after.height_m,
        li,
        hi,
        flow_time_s / (hi / g).sqrt(),
        runout / dem_law(a),
        runout / experiment_law(a),
    ]
}

/// The column collapse of a coupled run (see `Analysis::ColumnCollapse`): the geometry of
/// the column at the start and of the deposit at the end, the time the front took to reach
/// 95 % of its run-out (from the deposit probe's series), the packing fraction of the column
/// and the extremes of the pore-pressure probe.
pub fn submerged(
    inp: &super::Inputs,
    (wall_x, floor_y): (f64, f64),
    deposit: &str,
    pore_pressure: Option<&str>,
    r: &mut super::Results,
) -> Result<(), super::AnalysisError> {
    let Some((start, end)) = &inp.grains else {
        return Err(super::err("column-collapse", "the run has no grains"));
    };
    let shape = |g: &[[f64; 3]]| {
        let (x, y, rr): (Vec<f64>, Vec<f64>, Vec<f64>) = (
            g.iter().map(|p| p[0]).collect(),
            g.iter().map(|p| p[1]).collect(),
            g.iter().map(|p| p[2]).collect(),
        );
        pile_shape(&x, &y, &rr, wall_x, floor_y)
    };
    let (before, after) = (shape(start), shape(end));
    let spec = inp.scene.scene.grains.as_ref().expect("validated: grains");
    let g = spec.gravity_m_s2[0].hypot(spec.gravity_m_s2[1]);
    let series = inp
        .series
        .iter()
        .find(|s| s.name == deposit)
        .ok_or_else(|| super::err("column-collapse", format!("no deposit probe `{deposit}`")))?;
    // The front's series: when it passed 10 % and 95 % of its final run-out.
    let fronts: Vec<f64> = (0..series.len())
        .map(|j| series.values[j * series.columns.len()])
        .collect();
    // Times from the release: the last wall removed.
    let release = spec
        .walls
        .iter()
        .filter_map(|w| w.remove_at_s)
        .fold(0.0, f64::max);
    let times: Vec<f64> = series.times.iter().map(|t| t - release).collect();
    let [t10, t95, speed] = front_timing(&times, &fronts, before.length_m, after.length_m);
    let values = collapse_results(before, after, g, t95);
    for (k, v) in QUANTITIES.iter().zip(values) {
        r.insert(format!("collapse.{k}"), v);
    }
    let tau_c = (before.height_m / g).sqrt();
    r.insert("collapse.front_t95".into(), values[7]);
    r.insert("collapse.front_t10".into(), t10 / tau_c);
    r.insert("collapse.front_speed_m_s".into(), speed);
    // The column: grains within it at the start (all of them, for a column behind a gate).
    let area: f64 = start
        .iter()
        .map(|p| std::f64::consts::PI * p[2] * p[2])
        .sum();
    r.insert(
        "collapse.packing_fraction".into(),
        area / (before.length_m * before.height_m),
    );
    let (mut lo, mut hi) = (f64::NAN, f64::NAN);
    if let Some(name) = pore_pressure {
        let s =
            inp.series.iter().find(|s| s.name == name).ok_or_else(|| {
                super::err("column-collapse", format!("no pressure probe `{name}`"))
            })?;
        let col = s
            .columns
            .iter()
            .position(|c| *c == "pressure_pa")
            .unwrap_or(2);
        for j in 0..s.len() {
            let p = s.values[j * s.columns.len() + col];
            lo = if lo.is_nan() { p } else { lo.min(p) };
            hi = if hi.is_nan() { p } else { hi.max(p) };
        }
    }
    r.insert("collapse.pore_pressure_min_pa".into(), lo);
    r.insert("collapse.pore_pressure_max_pa".into(), hi);
    Ok(())
}

/// The front of a deposit where it is still `min_height` thick (m from the wall): the far
/// edge of the last column, contiguous from the wall's column `first`, whose top
/// `tops[c]` (m above the floor; −∞ when empty) is at least `min_height`. Columns are
/// `width` wide from x = 0; `wall_x` is the wall (m). Returns 0 when the wall's column
/// itself is thinner.
pub fn thick_front(tops: &[f64], width: f64, first: usize, wall_x: f64, min_height: f64) -> f64 {
    let end = tops[first.min(tops.len())..]
        .iter()
        .position(|&t| t < min_height)
        .map_or(tops.len(), |k| first + k);
    if end == first {
        0.0
    } else {
        end as f64 * width - wall_x
    }
}

/// The thick-front results, in the order of [`THICK_QUANTITIES`], from the column
/// `before` and the thick front (m from the wall): the front, its run-out
/// (L_thick − L_i)/L_i and that run-out over the experiments' law.
pub fn thick_front_results(before: PileShape, thick_front_m: f64) -> [f64; 3] {
    let (li, a) = (before.length_m, before.height_m / before.length_m);
    let runout = (thick_front_m - li) / li;
    [thick_front_m, runout, runout / experiment_law(a)]
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

    /// A column 1 wide, 2 high spreading to 4: run-out 3, a = 2, on the DEM law's linear
    /// branch (1.67 a) and above the experiments' transition a = 2.3 only at a = 3.
    #[test]
    fn collapse_results_and_laws() {
        let before = PileShape {
            length_m: 1.0,
            height_m: 2.0,
        };
        let after = PileShape {
            length_m: 4.0,
            height_m: 0.5,
        };
        let r = collapse_results(before, after, 8.0, 1.0);
        assert_eq!(r[0], 3.0);
        assert_eq!(r[2], 2.0);
        assert_eq!(r[7], 2.0, "t / sqrt(H/g) = 1 / 0.5");
        assert!((r[8] - 3.0 / 3.34).abs() < 1e-12);
        assert!((r[9] - 3.0 / 2.4).abs() < 1e-12);
        assert!((dem_law(8.0) - 2.7 * 4.0).abs() < 1e-12);
        assert!((experiment_law(8.0) - 1.9 * 4.0).abs() < 1e-12);
    }

    /// Columns 1 m wide with tops 3, 2, 0.4, 0.6 (a gap in the tail) and an empty one:
    /// thick at 0.5 m the front is the far edge of the second column; at 0.3 m the tail's
    /// thin column still counts and the empty one ends it; above 3 m nothing does.
    #[test]
    fn thick_front_stops_at_the_first_thin_column() {
        let tops = [3.0, 2.0, 0.4, 0.6, f64::NEG_INFINITY];
        assert_eq!(thick_front(&tops, 1.0, 0, 0.0, 0.5), 2.0);
        assert_eq!(thick_front(&tops, 1.0, 0, 0.0, 0.3), 4.0);
        assert_eq!(thick_front(&tops, 1.0, 0, 0.0, 3.5), 0.0);
        assert_eq!(
            thick_front(&tops, 1.0, 1, 0.5, 0.5),
            1.5,
            "measured from a wall inside the first column"
        );
        let before = PileShape {
            length_m: 1.0,
            height_m: 1.0,
        };
        let r = thick_front_results(before, 2.0);
        assert_eq!(r[1], 1.0);
        assert!((r[2] - 1.0 / 1.2).abs() < 1e-12);
    }
}

#[cfg(test)]
mod front_tests {
    use super::front_timing;

    #[test]
    fn a_front_moving_at_constant_speed_has_that_speed() {
        // From 0.1 m at 0.5 m/s for 0.4 s, then at rest at 0.3 m.
        let times: Vec<f64> = (0..=100).map(|k| k as f64 * 0.01).collect();
        let fronts: Vec<f64> = times.iter().map(|&t| 0.1 + 0.5 * t.min(0.4)).collect();
        let [t10, t95, speed] = front_timing(&times, &fronts, 0.1, 0.3);
        assert!(
            (t10 - 0.04).abs() < 1e-12 && (t95 - 0.38).abs() < 1e-12,
            "{t10} {t95}"
        );
        assert!((speed - 0.5).abs() < 1e-9, "{speed}");
        // A mass that stayed put moved at no speed and never passed its marks.
        let still = front_timing(&times, &vec![0.1; times.len()], 0.1, 0.1);
        assert!(still[0].is_nan() && still[1].is_nan() && still[2] == 0.0);
    }
}
