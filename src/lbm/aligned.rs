//! A 64-byte-aligned buffer of reals, so that rows of the distribution planes can be written
//! with aligned non-temporal stores.

use super::real::Real;
use std::ops::{Deref, DerefMut};

/// 16 values on a 64-byte boundary (one cache line of f32, two of f64).
#[derive(Clone, Copy)]
#[repr(C, align(64))]
struct Block<T>([T; 16]);

/// A fixed-length slice of `T` whose start is 64-byte aligned.
#[derive(Clone, Default)]
pub struct AlignedBuf<T> {
    blocks: Vec<Block<T>>,
    len: usize,
}

impl<T: Real> AlignedBuf<T> {
    /// `len` zeros (`T::default()`).
    pub fn zeros(len: usize) -> Self {
        Self {
            blocks: vec![Block([T::default(); 16]); len.div_ceil(16)],
            len,
        }
    }
}

impl<T> Deref for AlignedBuf<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        // SAFETY: `Block<T>` is `repr(C)` around `[T; 16]` with no padding (64 is a multiple
        // of 16·size_of::<T>() for f32 and f64), so the blocks are `len.div_ceil(16) * 16`
        // contiguous, initialised `T`s; `len` never exceeds that.
        unsafe { std::slice::from_raw_parts(self.blocks.as_ptr() as *const T, self.len) }
    }
}

impl<T> DerefMut for AlignedBuf<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        // SAFETY: as in `deref`, with exclusive access through `&mut self`.
        unsafe { std::slice::from_raw_parts_mut(self.blocks.as_mut_ptr() as *mut T, self.len) }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn aligned_and_sized() {
        let mut b = super::AlignedBuf::<f64>::zeros(37);
        assert_eq!(b.len(), 37);
        assert_eq!(b.as_ptr() as usize % 64, 0);
        b[36] = 2.0;
        assert_eq!(b.iter().sum::<f64>(), 2.0);
    }
}
