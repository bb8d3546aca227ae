//! Sedimentation: terminal settling of one grain, and the draft–kiss–tumble of two, from
//! grain probes (columns x, y, vx, vy, ω, fx, fy).

use super::signals::find;
use super::{err, AnalysisError, Inputs, Results};
use io::probes::Series;

/// Radius (m) of the grain a probe follows.
fn probe_radius(inp: &Inputs, probe: &str, analysis: &str) -> Result<f64, AnalysisError> {
    let id = inp
        .scene
        .scene
        .probes
        .iter()
        .find_map(|p| match p {
            scene::Probe::Grain { name, id } if name == probe => Some(*id),
            _ => None,
        })
        .ok_or_else(|| err(analysis, format!("`{probe}` is not a grain probe")))?;
    inp.grain_radius
        .iter()
        .find(|(i, _)| *i == id)
        .map(|(_, r)| *r)
        .ok_or_else(|| err(analysis, format!("no grain with id {id}")))
}

/// Terminal settling of a grain from its probe (columns x, y, vx, vy, …), averaged over the
/// last `window_s`: the fall speed U (the velocity's component along gravity, so that a
/// sideways zig-zag does not count), Re = U d / ν and C_D = 2 W / (ρ U² d) with
/// W = (ρ_s − ρ) |g| π r² the submerged weight per metre of depth (2-D disk:
/// U_t = √(π g d (ρ_s/ρ − 1) / (2 C_D))), and the root-mean-square lateral velocity. An error
/// when the window is longer than the recorded series.
pub fn settling(
    inp: &Inputs,
    probe: &str,
    window_s: f64,
    r: &mut Results,
) -> Result<(), AnalysisError> {
    let s = find(inp, probe, "settling")?;
    let sc = &inp.scene.scene;
    let (Some(g), Some(scene::Probe::Grain { id, .. })) =
        (&sc.grains, sc.probes.iter().find(|p| p.name() == probe))
    else {
        return Err(err("settling", "needs a grain probe and grains"));
    };
    let radius = inp
        .grain_radius
        .iter()
        .find(|(i, _)| i == id)
        .map(|(_, r)| *r)
        .ok_or_else(|| err("settling", format!("no grain with id {id}")))?;
    let (t_first, t_end) = (s.times[0], *s.times.last().expect("non-empty"));
    if t_end - t_first < window_s {
        return Err(err(
            "settling",
            format!(
                "the averaging window (average_last_s = {window_s} s) is longer than the \
                 recorded run ({:.4e} s): run longer or shorten the window",
                t_end - t_first
            ),
        ));
    }
    let gn = g.gravity_m_s2[0].hypot(g.gravity_m_s2[1]);
    if gn == 0.0 {
        return Err(err("settling", "needs gravity (the fall direction)"));
    }
    let down = [g.gravity_m_s2[0] / gn, g.gravity_m_s2[1] / gn];
    // The velocity along gravity and across it.
    let parts = |i: usize| {
        let row = &s.values[i * s.columns.len()..(i + 1) * s.columns.len()];
        let (vx, vy) = (row[2], row[3]);
        (vx * down[0] + vy * down[1], vy * down[0] - vx * down[1])
    };
    let mean = |from: f64, to: f64, f: &dyn Fn(usize) -> f64| {
        let rows: Vec<usize> = (0..s.len())
            .filter(|&i| s.times[i] >= from && s.times[i] <= to)
            .collect();
        rows.iter().map(|&i| f(i)).sum::<f64>() / rows.len().max(1) as f64
    };
    let fall = |i: usize| parts(i).0;
    let u = mean(t_end - window_s, t_end, &fall);
    let first = mean(t_end - window_s, t_end - 0.5 * window_s, &fall);
    let second = mean(t_end - 0.5 * window_s, t_end, &fall);
    let lateral = mean(t_end - window_s, t_end, &|i| parts(i).1.powi(2)).sqrt();
    let rho = sc.fluid.density_kg_m3;
    let d = 2.0 * radius;
    let w = (g.density_kg_m3 - rho) * gn * std::f64::consts::PI * radius * radius;
    r.insert(format!("{probe}.settling_velocity_m_s"), u);
    r.insert(format!("{probe}.reynolds"), u * d / sc.fluid.viscosity_m2_s);
    r.insert(
        format!("{probe}.drag_coefficient"),
        2.0 * w / (rho * u * u * d),
    );
    r.insert(format!("{probe}.velocity_drift"), (second - first) / second);
    r.insert(format!("{probe}.lateral_velocity_m_s"), lateral);
    Ok(())
}

/// What a draft-kiss-tumble analysis reads (the scene's `draft-kiss-tumble` keys).
#[derive(Debug, Clone, Copy)]
pub struct DktSetup<'a> {
    /// Grain probe of the grain that starts below.
    pub lower: &'a str,
    /// Grain probe of the grain that starts above.
    pub upper: &'a str,
    /// Gap between the surfaces (m) that counts as touching.
    pub contact_gap_m: f64,
    /// Window at the end of the run for the final speeds (s).
    pub window_s: f64,
    /// Window [from, to] (s) for the fall speeds after separation.
    pub fall_window_s: Option<[f64; 2]>,
    /// One grain's terminal velocity alone in the same channel (m/s).
    pub terminal_velocity_m_s: Option<f64>,
}

/// Draft, kiss and tumble of two grains (Fortes et al. 1987; seed §5.4.1), from the probes
/// of the grain that starts below (`lower`) and above (`upper`). Times are in units of
/// √(D/g). Results `dkt.*`:
/// - `kiss_time`: the first time the gap between the surfaces falls below `contact_gap_m`;
/// - `min_gap`: the smallest gap over D;
/// - `tumble_time`: the first time after the kiss that the upper grain's centre passes
///   below the lower one's (the pair has turned);
/// - `separation_time`: the first time after the tumble that the gap exceeds D/2;
/// - `second_kiss_time`: the first time after the separation that they touch again (a
///   second draft–kiss–tumble cycle), NaN when they do not;
/// - `draft` (1 when the upper grain falls faster than the lower before the kiss, else 0),
///   `tumbled`, `separated` (1 or 0);
/// - `lower_velocity_m_s`, `upper_velocity_m_s`: their speeds averaged over the last
///   `window_s`;
/// - `leader_fall_m_s`, `trailer_fall_m_s`: with `fall_window_s`, each grain's fall speed
///   (velocity along gravity) averaged over the window, the leader being the grain further
///   along gravity at the window's end; NaN when the window is not wholly after the
///   separation, when the pair touches again within it, or when it has no probe rows;
/// - `leader_fall_deviation`, `trailer_fall_deviation`: with `terminal_velocity_m_s` too,
///   fall speed / terminal velocity − 1 (the test: within 5 % after separation).
pub fn draft_kiss_tumble(
    inp: &Inputs,
    setup: &DktSetup<'_>,
    r: &mut Results,
) -> Result<(), AnalysisError> {
    let (lower, upper, contact_gap_m, window_s) = (
        setup.lower,
        setup.upper,
        setup.contact_gap_m,
        setup.window_s,
    );
    let a = find(inp, lower, "draft-kiss-tumble")?;
    let b = find(inp, upper, "draft-kiss-tumble")?;
    let (ra, rb) = (
        probe_radius(inp, lower, "draft-kiss-tumble")?,
        probe_radius(inp, upper, "draft-kiss-tumble")?,
    );
    let Some(g) = &inp.scene.scene.grains else {
        return Err(err("draft-kiss-tumble", "needs grains"));
    };
    let d = ra + rb;
    let g_norm = g.gravity_m_s2[0].hypot(g.gravity_m_s2[1]);
    let t_unit = (d / g_norm).sqrt();
    // Unit vector along gravity (the fall direction).
    let down = [g.gravity_m_s2[0] / g_norm, g.gravity_m_s2[1] / g_norm];
    let n = a.len().min(b.len());
    let col = |s: &Series, i: usize, c: usize| s.values[i * s.columns.len() + c];
    let gap = |i: usize| {
        let (dx, dy) = (col(b, i, 0) - col(a, i, 0), col(b, i, 1) - col(a, i, 1));
        dx.hypot(dy) - ra - rb
    };
    let kiss = (0..n).find(|&i| gap(i) < contact_gap_m);
    let min_gap = (0..n).map(gap).fold(f64::INFINITY, f64::min) / d;
    let draft = kiss.is_some_and(|k| (0..k).any(|i| col(b, i, 3) < col(a, i, 3)));
    let tumble = kiss.and_then(|k| (k..n).find(|&i| col(b, i, 1) < col(a, i, 1)));
    let separate = tumble.and_then(|t| (t..n).find(|&i| gap(i) > 0.5 * d));
    let second_kiss = separate.and_then(|s| (s..n).find(|&i| gap(i) < contact_gap_m));
    let time = |i: Option<usize>| i.map(|i| a.times[i] / t_unit).unwrap_or(f64::NAN);
    let flag = |i: Option<usize>| i.map(|_| 1.0).unwrap_or(0.0);
    let t_end = a.times[n - 1];
    let mean_speed = |s: &Series| {
        let rows: Vec<usize> = (0..n).filter(|&i| s.times[i] >= t_end - window_s).collect();
        rows.iter()
            .map(|&i| col(s, i, 2).hypot(col(s, i, 3)))
            .sum::<f64>()
            / rows.len().max(1) as f64
    };
    // Fall speeds over the window, when it lies wholly after the separation.
    let (mut leader, mut trailer) = (f64::NAN, f64::NAN);
    if let (Some([from, to]), Some(sep)) = (setup.fall_window_s, separate) {
        let rows: Vec<usize> = (0..n)
            .filter(|&i| a.times[i] >= from && a.times[i] <= to)
            .collect();
        // The window must follow the separation, and a second kiss within it would swap the
        // roles part-way: no meaningful average then.
        let usable = |last: usize| from >= a.times[sep] && second_kiss.is_none_or(|k| k > last);
        if let Some(&last) = rows.last().filter(|&&last| usable(last)) {
            let along = |s: &Series, i: usize, c: usize| {
                col(s, i, c) * down[0] + col(s, i, c + 1) * down[1]
            };
            let fall =
                |s: &Series| rows.iter().map(|&i| along(s, i, 2)).sum::<f64>() / rows.len() as f64;
            let (fa, fb) = (fall(a), fall(b));
            (leader, trailer) = if along(a, last, 0) >= along(b, last, 0) {
                (fa, fb)
            } else {
                (fb, fa)
            };
        }
    }
    let deviation = |u: f64| {
        setup
            .terminal_velocity_m_s
            .map(|ut| u / ut - 1.0)
            .unwrap_or(f64::NAN)
    };
    r.insert("dkt.kiss_time".into(), time(kiss));
    r.insert("dkt.min_gap".into(), min_gap);
    r.insert("dkt.tumble_time".into(), time(tumble));
    r.insert("dkt.separation_time".into(), time(separate));
    r.insert("dkt.second_kiss_time".into(), time(second_kiss));
    r.insert("dkt.draft".into(), draft as u8 as f64);
    r.insert("dkt.tumbled".into(), flag(tumble));
    r.insert("dkt.separated".into(), flag(separate));
    r.insert("dkt.lower_velocity_m_s".into(), mean_speed(a));
    r.insert("dkt.upper_velocity_m_s".into(), mean_speed(b));
    r.insert("dkt.leader_fall_m_s".into(), leader);
    r.insert("dkt.trailer_fall_m_s".into(), trailer);
    r.insert("dkt.leader_fall_deviation".into(), deviation(leader));
    r.insert("dkt.trailer_fall_deviation".into(), deviation(trailer));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use lbm::fields::Totals;

    /// A grain probe series (x, y, vx, vy, ω, fx, fy) sampled at t = 0, 1, … s.
    fn series(name: &str, rows: &[[f64; 4]]) -> Series {
        Series {
            name: name.into(),
            columns: vec!["x", "y", "vx", "vy", "omega", "fx", "fy"],
            steps: (0..rows.len() as u64).collect(),
            times: (0..rows.len()).map(|i| i as f64).collect(),
            values: rows
                .iter()
                .flat_map(|r| [r[0], r[1], r[2], r[3], 0.0, 0.0, 0.0])
                .collect(),
        }
    }

    /// The pair of `jobs/dkt/dkt.toml` (d = 2 mm, gravity −y) along a scripted path: the
    /// upper grain drafts (t = 0–1), kisses (t = 2), tumbles past the lower one (t = 3),
    /// separates (t = 4–5), and kisses again at t = 8 (its gap back to zero).
    fn pair() -> (Series, Series) {
        // Lower grain at x = 0.01 throughout; upper grain's (x, y); fall speeds −0.01, −0.02.
        let upper_at = [
            (0.010, 0.0700), // t 0: gap 8 mm
            (0.010, 0.0650), // t 1: drafting
            (0.010, 0.0610), // t 2: kiss (gap 0)
            (0.012, 0.0575), // t 3: tumbled below
            (0.014, 0.0560), // t 4: gap > d/2
            (0.014, 0.0550), // t 5
            (0.014, 0.0540), // t 6
            (0.013, 0.0530), // t 7
            (0.012, 0.0560), // t 8: right beside the lower grain, touching again (gap 0)
            (0.014, 0.0510), // t 9
        ];
        let lower_y = |t: usize| 0.060 - 0.0005 * t as f64;
        let mut lower = Vec::new();
        let mut upper = Vec::new();
        for (t, &(x, y)) in upper_at.iter().enumerate() {
            lower.push([0.010, lower_y(t), 0.0, -0.01]);
            upper.push([x, y, 0.0, -0.02]);
        }
        (series("lower", &lower), series("upper", &upper))
    }

    fn dkt(window: [f64; 2]) -> Results {
        let path = std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../jobs/dkt/dkt.toml"
        ));
        let text = std::fs::read_to_string(path).unwrap();
        let scene = scene::parse(&text, path).unwrap();
        let (lower, upper) = pair();
        let all = [lower, upper];
        let inp = Inputs {
            scene: &scene,
            fields: None,
            steps: 9,
            series: &all,
            totals: (Totals::default(), Totals::default()),
            momentum: None,
            grain_radius: vec![(0, 0.001), (1, 0.001)],
            grains: None,
        };
        let setup = DktSetup {
            lower: "lower",
            upper: "upper",
            contact_gap_m: 1.25e-4,
            window_s: 1.0,
            fall_window_s: Some(window),
            terminal_velocity_m_s: Some(0.01),
        };
        let mut r = Results::new();
        draft_kiss_tumble(&inp, &setup, &mut r).unwrap();
        r
    }

    #[test]
    fn fall_speeds_need_a_window_clear_of_the_second_kiss() {
        // The scripted phases are found (times in units of √(d/g)).
        let r = dkt([5.0, 7.0]);
        let unit = (0.002f64 / 9.81).sqrt();
        for (key, t) in [
            ("dkt.kiss_time", 2.0),
            ("dkt.tumble_time", 3.0),
            ("dkt.separation_time", 4.0),
            ("dkt.second_kiss_time", 8.0),
        ] {
            assert!((r[key] - t / unit).abs() < 1e-9, "{key}: {}", r[key]);
        }
        // Between the separation and the second kiss: both fall speeds, the leader (lower
        // at t = 7: the upper grain) at 0.02 m/s along gravity.
        assert!((r["dkt.leader_fall_m_s"] - 0.02).abs() < 1e-12);
        assert!((r["dkt.trailer_fall_m_s"] - 0.01).abs() < 1e-12);
        assert!((r["dkt.leader_fall_deviation"] - 1.0).abs() < 1e-9);
        // A window that holds the second kiss, or starts before the separation: NaN.
        for window in [[5.0, 8.0], [6.0, 9.0], [3.0, 6.0]] {
            let r = dkt(window);
            for key in ["dkt.leader_fall_m_s", "dkt.trailer_fall_m_s"] {
                assert!(r[key].is_nan(), "{window:?}: {key} = {}", r[key]);
            }
        }
    }
}
