//! The floating-point type of a kernel: `f32` or `f64`, chosen per run.

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// Arithmetic the LBM kernels need. Implemented for `f32` and `f64` only; precision is a
/// type parameter of kernels and lattices, never of the whole program.
pub trait Real:
    Copy
    + Send
    + Sync
    + Debug
    + Default
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + decomposition::Word
    + bytemuck::Pod
    + 'static
{
    /// Name used in reports ("f32"/"f64").
    const NAME: &'static str;
    /// Conversion from f64 (rounding for f32).
    fn from_f64(v: f64) -> Self;
    /// Widening conversion to f64.
    fn to_f64(self) -> f64;
    /// Square root.
    fn sqrt(self) -> Self;
    /// `self * a + b`: fused (one rounding) where the build targets FMA, plain otherwise
    /// (a fused multiply-add without the instruction would be a slow library call).
    fn mul_add_(self, a: Self, b: Self) -> Self;
}

macro_rules! impl_real {
    ($t:ty, $name:expr) => {
        impl Real for $t {
            const NAME: &'static str = $name;
            #[inline(always)]
            fn from_f64(v: f64) -> Self {
                v as $t
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline(always)]
            fn mul_add_(self, a: Self, b: Self) -> Self {
                #[cfg(target_feature = "fma")]
                {
                    <$t>::mul_add(self, a, b)
                }
                #[cfg(not(target_feature = "fma"))]
                {
                    self * a + b
                }
            }
        }
    };
}
impl_real!(f32, "f32");
impl_real!(f64, "f64");
