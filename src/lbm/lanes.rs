//! Explicit SIMD-friendly lanes: the collision is written once over [`Simd`], instantiated
//! with a plain scalar for boundary cells and with [`Lanes`] (one AVX register of cells at a time) in the bulk
//! row kernel. Element-wise loops over a fixed-size array are reliably turned into vector
//! instructions by LLVM, unlike a long loop body left to the auto-vectoriser.

use super::real::Real;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Arithmetic on one value or a bundle of lanes.
pub trait Simd:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// The element type.
    type Scalar: Real;
    /// Broadcast a scalar.
    fn splat(v: Self::Scalar) -> Self;
    /// Element-wise square root.
    fn sqrt(self) -> Self;
    /// Element-wise `self * a + b`, fused (one rounding) where the build targets FMA
    /// (x86-64-v3, see `.cargo/config.toml`), two roundings otherwise. Scalar and lane
    /// forms round alike, so a cell gives the same bits in either path.
    fn mul_add(self, a: Self, b: Self) -> Self;
}

impl<T: Real> Simd for T {
    type Scalar = T;
    #[inline(always)]
    fn splat(v: T) -> T {
        v
    }
    #[inline(always)]
    fn sqrt(self) -> T {
        Real::sqrt(self)
    }
    #[inline(always)]
    fn mul_add(self, a: T, b: T) -> T {
        self.mul_add_(a, b)
    }
}

/// `N` values processed together.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct Lanes<T, const N: usize>(pub [T; N]);

macro_rules! lane_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl<T: Real, const N: usize> $tr for Lanes<T, N> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                let mut r = self.0;
                for l in 0..N {
                    r[l] = self.0[l] $op o.0[l];
                }
                Lanes(r)
            }
        }
    };
}
lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl<T: Real, const N: usize> Neg for Lanes<T, N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        let mut r = self.0;
        for v in r.iter_mut() {
            *v = -*v;
        }
        Lanes(r)
    }
}

impl<T: Real, const N: usize> Simd for Lanes<T, N> {
    type Scalar = T;
    #[inline(always)]
    fn splat(v: T) -> Self {
        Lanes([v; N])
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        let mut r = self.0;
        for v in r.iter_mut() {
            *v = Real::sqrt(*v);
        }
        Lanes(r)
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        let mut r = self.0;
        for l in 0..N {
            r[l] = self.0[l].mul_add_(a.0[l], b.0[l]);
        }
        Lanes(r)
    }
}
