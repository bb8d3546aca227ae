//! The D2Q9 velocity set (Qian, d'Humières & Lallemand 1992).
//!
//! Ordering: 0 rest, 1 E, 2 N, 3 W, 4 S, 5 NE, 6 NW, 7 SW, 8 SE. Rotating a direction by
//! 90° counter-clockwise maps 1→2→3→4→1 and 5→6→7→8→5, which [`rotate`] exploits to
//! write each boundary rule once for the west face.

/// Number of discrete velocities.
pub const Q: usize = 9;
/// x components of the lattice velocities.
pub const CX: [i32; Q] = [0, 1, 0, -1, 0, 1, -1, -1, 1];
/// y components of the lattice velocities.
pub const CY: [i32; Q] = [0, 0, 1, 0, -1, 1, 1, -1, -1];
/// Quadrature weights.
pub const W: [f64; Q] = [
    4.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
];
/// Opposite direction: `c[OPP[i]] = -c[i]`.
pub const OPP: [usize; Q] = [0, 3, 4, 1, 2, 7, 8, 5, 6];
/// Mirror across a horizontal wall (flips c_y).
pub const MIRROR_Y: [usize; Q] = [0, 1, 4, 3, 2, 8, 7, 6, 5];
/// Mirror across a vertical wall (flips c_x).
pub const MIRROR_X: [usize; Q] = [0, 3, 2, 1, 4, 6, 5, 8, 7];
/// Lattice speed of sound squared, c_s² = 1/3.
pub const CS2: f64 = 1.0 / 3.0;

/// Direction `i` rotated by `quarter_turns` × 90° counter-clockwise.
pub const fn rotate(i: usize, quarter_turns: usize) -> usize {
    match i {
        0 => 0,
        1..=4 => 1 + (i - 1 + quarter_turns) % 4,
        _ => 5 + (i - 5 + quarter_turns) % 4,
    }
}

/// The array `[f(0), …, f(8)]` of `$e` with `$i` each direction in turn, written out with
/// `$i` a literal: no loop is left for the optimiser to keep, so arrays indexed by `$i` (or
/// by a table entry such as `OPP[$i]`) stay in registers in the SIMD kernels.
macro_rules! by_direction {
    ($i:ident => $e:expr) => {
        [
            { let $i: usize = 0; $e },
            { let $i: usize = 1; $e },
            { let $i: usize = 2; $e },
            { let $i: usize = 3; $e },
            { let $i: usize = 4; $e },
            { let $i: usize = 5; $e },
            { let $i: usize = 6; $e },
            { let $i: usize = 7; $e },
            { let $i: usize = 8; $e },
        ]
    };
}
pub(crate) use by_direction;

/// `$body` once for each direction `$i` = 0, …, 8 in turn, written out as
/// [`by_direction`] writes them (an array's elements are evaluated in order).
macro_rules! each_direction {
    ($i:ident => $body:block) => {{
        let _: [(); 9] = $crate::d2q9::by_direction!($i => $body);
    }};
}
pub(crate) use each_direction;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_set_is_consistent() {
        let sw: f64 = W.iter().sum();
        assert!((sw - 1.0).abs() < 1e-15);
        for i in 0..Q {
            assert_eq!(CX[OPP[i]], -CX[i]);
            assert_eq!(CY[OPP[i]], -CY[i]);
            assert_eq!(CY[MIRROR_Y[i]], -CY[i]);
            assert_eq!(CX[MIRROR_Y[i]], CX[i]);
            assert_eq!(CX[MIRROR_X[i]], -CX[i]);
            // 90° CCW: (x, y) -> (-y, x)
            let r = rotate(i, 1);
            assert_eq!((CX[r], CY[r]), (-CY[i], CX[i]));
            assert_eq!(rotate(i, 4), i);
        }
        // Second-order isotropy: sum w c_a c_b = cs2 delta_ab.
        let sxx: f64 = (0..Q).map(|i| W[i] * (CX[i] * CX[i]) as f64).sum();
        let sxy: f64 = (0..Q).map(|i| W[i] * (CX[i] * CY[i]) as f64).sum();
        assert!((sxx - CS2).abs() < 1e-15 && sxy.abs() < 1e-15);
    }
}
