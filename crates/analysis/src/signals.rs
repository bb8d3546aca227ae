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

/// c_D and c_L = 2 F / (ρ U² D), averaged over the last `window_s` of the run.
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
    let mean = |c: usize| {
        rows.iter()
            .map(|&i| s.values[i * s.columns.len() + c])
            .sum::<f64>()
            / rows.len() as f64
    };
    let q = 0.5 * inp.scene.scene.fluid.density_kg_m3 * u * u * d;
    r.insert(format!("{probe}.drag_coefficient"), mean(0) / q);
    r.insert(format!("{probe}.lift_coefficient"), mean(1) / q);
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
