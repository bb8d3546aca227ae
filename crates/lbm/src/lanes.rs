//! Explicit SIMD-friendly lanes (and the bulk kernels' CPU helpers: AVX-512 detection and
//! the stream prefetch): the collision is written once over [`Simd`], instantiated
//! with a plain scalar for boundary cells and with [`Lanes`] (one AVX register of cells at a time) in the bulk
//! row kernel. Element-wise loops over a fixed-size array are reliably turned into vector
//! instructions by LLVM, unlike a long loop body left to the auto-vectoriser.

use super::d2q9::Q;
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

impl<T: Real, const N: usize> Lanes<T, N> {
    /// Lane l of `a` where bit l of `mask` is set, of `b` elsewhere (one masked blend: no
    /// lane is written alone, so the values stay in a register). At most 32 lanes.
    #[inline(always)]
    pub fn select(mask: u32, a: Self, b: Self) -> Self {
        const { assert!(N <= 32, "a u32 mask holds 32 lanes") };
        Lanes(std::array::from_fn(|l| {
            if mask >> l & 1 != 0 {
                a.0[l]
            } else {
                b.0[l]
            }
        }))
    }

    /// Bit l set where lane l is greater than `v` (clear for NaN). At most 32 lanes.
    #[inline(always)]
    pub fn greater_mask(self, v: T) -> u32 {
        const { assert!(N <= 32, "a u32 mask holds 32 lanes") };
        let mut mask = 0;
        for l in 0..N {
            mask |= u32::from(self.0[l] > v) << l;
        }
        mask
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

/// Cells the bulk row kernels compute together.
pub(crate) const BULK_LANES: usize = 8;

/// Whether this CPU runs the AVX-512 builds of the bulk row kernels (AVX-512F and VL: 32
/// vector registers, so the collision's temporaries stay in registers). Detected once by
/// the standard library and cached.
#[inline]
pub fn has_avx512() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512vl")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// How far ahead of the sweep the bulk kernels ask for their nine streams, in bytes. With
/// nine read streams (plus nine write streams in the two-array kernel) the hardware
/// prefetchers fall behind, and one core keeps too few misses in flight; asking ~2 KiB
/// ahead took the f32 in-place kernel from ~300 to ~550 MLUPS on one core (AMD EPYC,
/// 1024² and 4096² boxes; 1–4 KiB all do about as well).
pub(crate) const PREFETCH_BYTES: usize = 2048;

/// Ask for the cache lines [`PREFETCH_BYTES`] ahead of element `k` of each stream (a hint:
/// never faults, even past the end of a buffer).
#[inline(always)]
pub(crate) fn prefetch_ahead<T>(streams: &[*const T; Q], k: usize) {
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (streams, k);
    #[cfg(target_arch = "x86_64")]
    for p in streams {
        let ahead = p.wrapping_add(k + PREFETCH_BYTES / std::mem::size_of::<T>());
        // SAFETY: a prefetch is a hint; it does not access memory architecturally.
        unsafe {
            std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
                ahead as *const i8,
            )
        };
    }
}

#[cfg(test)]
mod tests {
    use super::Lanes;

    #[test]
    fn select_takes_the_masked_lanes_and_greater_mask_clears_nan() {
        let a = Lanes([1.0f32, 2.0, 3.0, 4.0]);
        let b = Lanes([-1.0f32, -0.0, f32::NAN, 0.5]);
        let s = Lanes::select(0b1010, a, b);
        assert_eq!(s.0[0].to_bits(), (-1.0f32).to_bits());
        assert_eq!(s.0[1], 2.0);
        assert!(s.0[2].is_nan());
        assert_eq!(s.0[3], 4.0);
        // -0.0 kept as it is: a lane not selected is not rewritten.
        assert_eq!(Lanes::select(0, a, b).0[1].to_bits(), (-0.0f32).to_bits());
        assert_eq!(b.greater_mask(0.0), 0b1000);
        assert_eq!(a.greater_mask(2.5), 0b1100);
    }
}
