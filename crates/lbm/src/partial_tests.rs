//! Tests of the partially saturated cells (`partial.rs`): the solid share against Noble &
//! Torczynski's nine-direction form, and the fully covered cell's equilibrium.

use super::*;
use crate::collision::equilibrium;
use crate::d2q9::{CX, CY};

/// Noble & Torczynski 1998, eq. 8 term by term, as the seed writes it (eqs. 5.53–5.54):
/// the nine directions' Ω^s_i from the two equilibria, B_s (h_i + Ω^s_i) and
/// Σ_i B_s Ω^s_i c_i.
fn by_the_book(h: &[f64; Q], m: &Moments<f64>, b: f64, u: [f64; 2]) -> ([f64; Q], [f64; 2]) {
    let eq_fluid = equilibrium(m);
    let eq_solid = equilibrium(&Moments {
        ux: u[0],
        uy: u[1],
        ..*m
    });
    let (mut new, mut p) = ([0.0; Q], [0.0; 2]);
    for i in 0..Q {
        let j = OPP[i];
        let omega = (h[j] - eq_fluid[j]) - (h[i] - eq_solid[i]);
        new[i] = b * (h[i] + omega);
        p[0] += b * omega * CX[i] as f64;
        p[1] += b * omega * CY[i] as f64;
    }
    (new, p)
}

/// A fully covered cell's solid equilibrium has the mass and momentum that
/// Noble & Torczynski's B = 1 limit gives it: only the reflected non-equilibrium part,
/// which carries neither, is dropped (`is_full`).
#[test]
fn full_cell_keeps_mass_and_momentum_and_drops_the_reflected_part() {
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut next = || crate::test_rng::next(&mut seed) - 0.5;
    for _ in 0..200 {
        let h: [f64; Q] = std::array::from_fn(|_| 0.02 * next());
        let drho: f64 = h.iter().sum();
        let (jx, jy) = (0..Q).fold((0.0, 0.0), |(x, y), i| {
            (x + h[i] * CX[i] as f64, y + h[i] * CY[i] as f64)
        });
        let rho = 1.0 + drho;
        let m = Moments {
            drho,
            rho,
            ux: jx / rho,
            uy: jy / rho,
        };
        let u = [0.2 * next(), 0.2 * next()];
        let mut by_eq8 = [0.0; Q];
        add_share(&mut by_eq8, &h, &m, 1.0, u);
        let mut solid = [0.0; Q];
        add_solid_equilibrium(&mut solid, &m, 1.0, u);
        let moment =
            |f: &[f64; Q], c: &[i32; Q]| -> f64 { (0..Q).map(|i| f[i] * c[i] as f64).sum() };
        let ones = [1; Q];
        for c in [&ones, &CX, &CY] {
            let (a, b) = (moment(&by_eq8, c), moment(&solid, c));
            assert!((a - b).abs() < 1e-15, "moment {c:?}: {a} vs {b}");
        }
        // The solid's equilibrium moves at u_s.
        assert!((moment(&solid, &CX) - rho * u[0]).abs() < 1e-15);
        // And the reflected part is really dropped: the two differ.
        assert!((0..Q).any(|i| (by_eq8[i] - solid[i]).abs() > 1e-6));
    }
    assert!(is_full(1.0f64) && !is_full(1.0f64 - 1e-15) && is_full(1.0f32));
}

#[test]
fn solid_share_matches_the_nine_direction_form() {
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || crate::test_rng::next(&mut seed) - 0.5;
    for _ in 0..200 {
        // Populations near rest, fluid and solid velocities up to Ma ≈ 0.2.
        let h: [f64; Q] = std::array::from_fn(|_| 0.02 * next());
        let drho: f64 = h.iter().sum();
        let rho = 1.0 + drho;
        let (jx, jy) = (0..Q).fold((0.0, 0.0), |(x, y), i| {
            (x + h[i] * CX[i] as f64, y + h[i] * CY[i] as f64)
        });
        let m = Moments {
            drho,
            rho,
            ux: jx / rho,
            uy: jy / rho,
        };
        let (b, u) = (0.5 + next(), [0.2 * next(), 0.2 * next()]);
        let (want, want_p) = by_the_book(&h, &m, b, u);
        let mut new = [0.0; Q];
        let p = add_share(&mut new, &h, &m, b, u);
        for i in 0..Q {
            assert!(
                (new[i] - want[i]).abs() < 1e-15,
                "direction {i}: {} vs {}",
                new[i],
                want[i]
            );
        }
        for a in 0..2 {
            assert!(
                (p[a] - want_p[a]).abs() < 1e-15,
                "momentum {a}: {} vs {}",
                p[a],
                want_p[a]
            );
        }
    }
}
