//! Time-series analyses: force coefficients and Strouhal numbers.

use super::{err, AnalysisError, Inputs, Results};
use io::probes::Series;
use rustfft::{num_complex::Complex, FftPlanner};
use scene::Signal;

pub(super) fn find<'a>(
    inp: &'a Inputs,
    probe: &str,
    analysis: &str,
) -> Result<&'a Series, AnalysisError> {
    inp.series
        .iter()
        .find(|s| s.name == probe)
        .filter(|s| !s.is_empty())
        .ok_or_else(|| err(analysis, format!("probe `{probe}` recorded nothing")))
}

/// The statistics of a force or grain probe's coefficients c_D and c_L = 2 F / (ρ U² D)
/// over the last `window_s` of the run (the last sample only when 0), as the Schäfer & Turek
/// (1996) benchmarks define them:
/// - `<probe>.drag_coefficient`, `<probe>.lift_coefficient`: the means;
/// - `..._max`, `..._min` of each;
/// - `<probe>.lift_amplitude`: half the peak-to-peak of c_L;
/// - `<probe>.lift_strouhal`: St = f D / U from the dominant frequency f of c_L (FFT, as
///   [`dominant_frequency`]), 0 when c_L does not oscillate (amplitude below 10⁻⁴ of the
///   mean |c_D|) or the window holds fewer than 16 samples.
pub fn force_coefficients(
    inp: &Inputs,
    probe: &str,
    u: f64,
    d: f64,
    window_s: f64,
    r: &mut Results,
) -> Result<(), AnalysisError> {
    let s = find(inp, probe, "force-coefficients")?;
    let t_end = *s.times.last().expect("non-empty");
    let rows: Vec<usize> = (0..s.len())
        .filter(|&i| s.times[i] >= t_end - window_s)
        .collect();
    let q = 0.5 * inp.scene.scene.fluid.density_kg_m3 * u * u * d;
    let coefficient = |name: &str| -> Result<Vec<f64>, AnalysisError> {
        let c = s.column_index(name).ok_or_else(|| {
            err(
                "force-coefficients",
                format!("probe `{probe}` records no force"),
            )
        })?;
        Ok(rows
            .iter()
            .map(|&i| s.values[i * s.columns.len() + c] / q)
            .collect())
    };
    let (drag, lift) = (coefficient("fx_n_per_m")?, coefficient("fy_n_per_m")?);
    let stats = |v: &[f64]| {
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        (mean, lo, hi)
    };
    let (cd, cd_lo, cd_hi) = stats(&drag);
    let (cl, cl_lo, cl_hi) = stats(&lift);
    let amplitude = 0.5 * (cl_hi - cl_lo);
    let oscillates = lift.len() >= 16 && amplitude > 1e-4 * cd.abs();
    let strouhal = if oscillates {
        let dt = (s.times[rows[rows.len() - 1]] - s.times[rows[0]]) / (rows.len() - 1) as f64;
        dominant_frequency(&lift, dt).0 * d / u
    } else {
        0.0
    };
    for (name, v) in [
        ("drag_coefficient", cd),
        ("drag_coefficient_min", cd_lo),
        ("drag_coefficient_max", cd_hi),
        ("lift_coefficient", cl),
        ("lift_coefficient_min", cl_lo),
        ("lift_coefficient_max", cl_hi),
        ("lift_amplitude", amplitude),
        ("lift_strouhal", strouhal),
    ] {
        r.insert(format!("{probe}.{name}"), v);
    }
    Ok(())
}

/// The results of a force-coefficients analysis, after `<probe>.`.
pub const FORCE_QUANTITIES: [&str; 8] = [
    "drag_coefficient",
    "drag_coefficient_min",
    "drag_coefficient_max",
    "lift_coefficient",
    "lift_coefficient_min",
    "lift_coefficient_max",
    "lift_amplitude",
    "lift_strouhal",
];

/// p(upstream) − p(downstream) of two point probes (Pa), averaged over the samples of the
/// last `window_s` (the last sample when 0).
pub fn pressure_difference(
    inp: &Inputs,
    upstream: &str,
    downstream: &str,
    window_s: f64,
    r: &mut Results,
) -> Result<(), AnalysisError> {
    const NAME: &str = "pressure-difference";
    let (a, b) = (find(inp, upstream, NAME)?, find(inp, downstream, NAME)?);
    let pressure = |s: &Series| -> Result<Vec<(f64, f64)>, AnalysisError> {
        let c = s
            .column_index("pressure_pa")
            .ok_or_else(|| err(NAME, format!("probe `{}` records no pressure", s.name)))?;
        let t_end = *s.times.last().expect("non-empty");
        Ok((0..s.len())
            .filter(|&i| s.times[i] >= t_end - window_s)
            .map(|i| (s.times[i], s.values[i * s.columns.len() + c]))
            .collect())
    };
    let (pa, pb) = (pressure(a)?, pressure(b)?);
    // Both probes are sampled at the same steps.
    let n = pa.len().min(pb.len());
    let mean = (0..n).map(|i| pa[i].1 - pb[i].1).sum::<f64>() / n as f64;
    r.insert(format!("{upstream}.pressure_difference_pa"), mean);
    Ok(())
}

/// Dominant frequency of a point probe's pressure or transverse velocity after `skip_s`, by FFT of the
/// Hann-windowed, mean-removed signal with parabolic peak refinement; St = f D / U.
pub fn strouhal(
    inp: &Inputs,
    probe: &str,
    signal: Signal,
    u: f64,
    d: f64,
    skip_s: f64,
    r: &mut Results,
) -> Result<(), AnalysisError> {
    let s = find(inp, probe, "strouhal")?;
    let column = if signal == Signal::Uy {
        "uy_m_s"
    } else {
        "pressure_pa"
    };
    let c = s
        .column_index(column)
        .expect("point probes record pressure and velocity");
    let p: Vec<f64> = (0..s.len())
        .filter(|&i| s.times[i] >= skip_s)
        .map(|i| s.values[i * s.columns.len() + c])
        .collect();
    if p.len() < 16 {
        return Err(err(
            "strouhal",
            format!(
                "only {} samples after skip_s = {skip_s} s; run longer",
                p.len()
            ),
        ));
    }
    let first = s
        .times
        .iter()
        .position(|&t| t >= skip_s)
        .expect("some samples");
    let dt = (s.times[s.len() - 1] - s.times[first]) / (p.len() - 1) as f64;
    let (f, _) = dominant_frequency(&p, dt);
    let (lo, hi) = p
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let q = if signal == Signal::Uy {
        u
    } else {
        0.5 * inp.scene.scene.fluid.density_kg_m3 * u * u
    };
    r.insert(format!("{probe}.strouhal"), f * d / u);
    r.insert(format!("{probe}.relative_oscillation"), (hi - lo) / q);
    Ok(())
}

/// Frequency (Hz) and amplitude of the largest non-zero spectral peak of `x` sampled every `dt`.
pub fn dominant_frequency(x: &[f64], dt: f64) -> (f64, f64) {
    let n = x.len();
    let mean = x.iter().sum::<f64>() / n as f64;
    let mut buf: Vec<Complex<f64>> = x
        .iter()
        .enumerate()
        .map(|(i, v)| {
            // Hann window (Harris 1978).
            let w = 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / (n - 1) as f64).cos();
            Complex::new((v - mean) * w, 0.0)
        })
        .collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buf);
    let mag: Vec<f64> = buf[..n / 2 + 1].iter().map(|c| c.norm()).collect();
    let k = (1..mag.len())
        .max_by(|&a, &b| mag[a].total_cmp(&mag[b]))
        .unwrap_or(1);
    // Parabolic interpolation of the log-magnitude peak (Smith, Spectral Audio Signal Processing).
    let shift = if k + 1 < mag.len() && mag[k - 1] > 0.0 && mag[k + 1] > 0.0 {
        let (a, b, c) = (mag[k - 1].ln(), mag[k].ln(), mag[k + 1].ln());
        let den = a - 2.0 * b + c;
        if den.abs() > 0.0 {
            0.5 * (a - c) / den
        } else {
            0.0
        }
    } else {
        0.0
    };
    ((k as f64 + shift) / (n as f64 * dt), mag[k])
}

#[cfg(test)]
mod tests {
    #[test]
    fn recovers_a_sine_frequency() {
        let dt = 0.01;
        let f0 = 3.37;
        let x: Vec<f64> = (0..2000)
            .map(|i| 2.0 + (2.0 * std::f64::consts::PI * f0 * i as f64 * dt).sin())
            .collect();
        let (f, _) = super::dominant_frequency(&x, dt);
        assert!((f - f0).abs() / f0 < 2e-3, "{f}");
    }
}
