//! Sums whose bits do not depend on the order of their terms: over a rank's items in any
//! storage order, and over any number of ranks. Each term is rounded to a fixed-point
//! integer on a grid set by the largest term (2⁻⁹⁶ of it), the integers are added exactly
//! (i128, then as 32-bit limbs over the ranks) and the total is converted back once.

use crate::Comm;

/// Bits of the largest term's magnitude kept in the fixed-point grid: terms up to 2⁹⁶ and up
/// to 2³¹ of them stay within an i128.
const GRID_BITS: i32 = 96;

/// For each column of per-item values on this rank, the sum over every item of every rank,
/// the same bits whatever the order of the items and however they are spread over the
/// ranks. A column with a non-finite value sums to NaN. Collective.
pub fn reproducible_sums(columns: &[&[f64]], comm: &dyn Comm) -> Vec<f64> {
    // The largest magnitude of each column over every rank, and whether any is non-finite.
    let scales: Vec<Option<i32>> = columns
        .iter()
        .map(|c| {
            let local = c.iter().fold(0.0f64, |m, v| {
                if v.is_finite() {
                    m.max(v.abs())
                } else {
                    f64::NAN
                }
            });
            let max = comm.max_f64(local);
            if !max.is_finite() {
                None
            } else if max == 0.0 {
                Some(0)
            } else {
                // max < 2^e.
                Some(max.log2().floor() as i32 + 1)
            }
        })
        .collect();
    let mut limbs = Vec::with_capacity(4 * columns.len());
    for (c, scale) in columns.iter().zip(&scales) {
        let total: i128 = match scale {
            Some(e) => {
                let factor = (2.0f64).powi(GRID_BITS - e);
                c.iter().map(|&v| (v * factor).round() as i128).sum()
            }
            None => 0,
        };
        let bits = total as u128;
        limbs.extend((0..4).map(|k| ((bits >> (32 * k)) as u32) as f64));
    }
    // Each limb summed over the ranks stays below 2⁵³: exact in f64.
    comm.sum_f64(&mut limbs);
    columns
        .iter()
        .enumerate()
        .map(|(n, _)| {
            let Some(e) = scales[n] else {
                return f64::NAN;
            };
            let total = (0..4).fold(0u128, |acc, k| {
                acc.wrapping_add((limbs[4 * n + k] as u128) << (32 * k))
            }) as i128;
            total as f64 * (2.0f64).powi(e - GRID_BITS)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::reproducible_sums;
    use crate::SingleProcess;

    /// The same terms in another order give the same bits, and the sum is as close as f64
    /// allows.
    #[test]
    fn order_does_not_change_the_bits() {
        let mut v: Vec<f64> = (0..10_000)
            .map(|i| ((i * 7919) % 1000) as f64 * 1e-3 - 0.4 + 1e-9 * i as f64)
            .collect();
        let a = reproducible_sums(&[&v], &SingleProcess)[0];
        v.reverse();
        v.rotate_left(1234);
        let b = reproducible_sums(&[&v], &SingleProcess)[0];
        assert_eq!(a.to_bits(), b.to_bits());
        let exact: f64 = {
            let mut s = v.clone();
            s.sort_by(|x, y| x.abs().total_cmp(&y.abs()));
            s.iter().sum()
        };
        assert!(
            (a - exact).abs() <= 1e-12 * exact.abs().max(1.0),
            "{a} vs {exact}"
        );
        assert!(reproducible_sums(&[&[1.0, f64::NAN]], &SingleProcess)[0].is_nan());
        assert_eq!(reproducible_sums(&[&[0.0, 0.0]], &SingleProcess)[0], 0.0);
        assert_eq!(reproducible_sums(&[&[]], &SingleProcess)[0], 0.0);
    }
}
