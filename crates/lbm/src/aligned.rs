//! A 64-byte-aligned buffer of reals, so that rows of the distribution planes can be written
//! with aligned non-temporal stores. Large buffers ask for transparent huge pages: the
//! sweep streams nine planes hundreds of MB long, and with 4 KiB pages every plane crosses
//! a page (and needs another TLB entry) each 1024 f32 values.

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
    /// `len` zeros (`T::default()`), as one plane of [`AlignedBuf::zeros_in_planes`] (on
    /// huge pages from 4 MiB on).
    pub fn zeros(len: usize) -> Self {
        let mut b = Self::zeros_in_planes(1, len.div_ceil(16) * 16);
        b.len = len;
        b
    }

    /// `planes` planes of `plane` zeros each (`plane` a multiple of 16), advised onto huge
    /// pages ([`advise_huge_pages`]) before their first touch, zero-filled in parallel by
    /// stripes: each task writes the same stretch of every plane, so the pages are first
    /// touched (and, on a NUMA node, placed) by the pool's threads spread over the planes'
    /// rows, as the sweep reads them, rather than all by one thread. (Rayon does not pin a
    /// stretch to the thread that will sweep it, and with many threads a stripe may be
    /// smaller than a huge page.)
    pub fn zeros_in_planes(planes: usize, plane: usize) -> Self {
        use rayon::prelude::*;
        assert_eq!(plane % 16, 0, "a plane is whole blocks");
        if planes * plane == 0 {
            return Self::default();
        }
        let (per_plane, n) = (plane / 16, planes * plane / 16);
        let mut blocks: Vec<Block<T>> = Vec::with_capacity(n);
        advise_huge_pages(
            blocks.as_mut_ptr() as *mut u8,
            n * std::mem::size_of::<Block<T>>(),
        );
        // Stripe t of every plane goes to task t.
        let stripes = 4 * rayon::current_num_threads();
        let stripe = per_plane.div_ceil(stripes).max(1);
        let mut tasks: Vec<Vec<&mut [std::mem::MaybeUninit<Block<T>>]>> =
            (0..stripes).map(|_| Vec::with_capacity(planes)).collect();
        for p in blocks.spare_capacity_mut()[..n].chunks_mut(per_plane) {
            for (t, part) in p.chunks_mut(stripe).enumerate() {
                tasks[t].push(part);
            }
        }
        tasks.into_par_iter().for_each(|parts| {
            for b in parts.into_iter().flatten() {
                b.write(Block([T::default(); 16]));
            }
        });
        // SAFETY: the planes' stripes cover the first n slots, each written above.
        unsafe { blocks.set_len(n) };
        Self {
            blocks,
            len: planes * plane,
        }
    }
}

/// Ask the kernel to back the whole 4 KiB pages of `[ptr, ptr + bytes)`, memory this
/// process allocated, with transparent huge pages (Linux `madvise(MADV_HUGEPAGE)`): where THP
/// is set to `madvise`, as on Debian's default kernels, nothing else gets them. Pages not yet
/// touched get them at their first touch (a fresh mapping, as glibc gives allocations above
/// its mmap threshold, which the binary fixes at 4 MiB; a smaller range may lie in the heap, where the advice
/// outlives the buffer). Only advice: a kernel without THP ignores it, and the contents are
/// unchanged either way. Ranges under 4 MiB are left alone (they would hold at most one huge
/// page). Nothing off Linux.
pub fn advise_huge_pages(ptr: *mut u8, bytes: usize) {
    #[cfg(target_os = "linux")]
    {
        const PAGE: usize = 4096;
        let start = (ptr as usize).next_multiple_of(PAGE);
        let end = (ptr as usize).saturating_add(bytes) / PAGE * PAGE;
        if end >= start + (4 << 20) {
            // SAFETY: advice on whole pages inside the caller's allocation, which changes
            // no contents; a failure (EINVAL without THP) only means no huge pages.
            unsafe {
                libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (ptr, bytes);
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

/// A raw pointer shared by rayon tasks that write disjoint elements.
#[derive(Clone, Copy)]
pub(crate) struct Disjoint<T>(pub(crate) *mut T);
// SAFETY: every task writes elements no other task touches (see each use).
unsafe impl<T> Send for Disjoint<T> {}
unsafe impl<T> Sync for Disjoint<T> {}

impl<T> Disjoint<T> {
    /// Write `v` at `i`.
    ///
    /// # Safety
    /// `i` is in bounds and no other task reads or writes it during the parallel pass.
    #[inline(always)]
    pub(crate) unsafe fn write(&self, i: usize, v: T) {
        *self.0.add(i) = v;
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

    /// A buffer large enough to be advised onto huge pages is still all zeros, aligned and
    /// of its length, whole or filled by planes (plane lengths that the stripes divide or
    /// not, more stripes than blocks).
    #[test]
    fn large_buffers_are_zeroed_and_aligned() {
        let n = (9 << 20) + 5;
        let b = super::AlignedBuf::<f32>::zeros(n);
        assert_eq!(b.len(), n);
        assert_eq!(b.as_ptr() as usize % 64, 0);
        assert!(b.iter().all(|&v| v == 0.0));
        for (planes, plane) in [
            (9, 1 << 20),
            (9, 16 * 12_345),
            (3, 16),
            (1, 32),
            (0, 16),
            (2, 0),
        ] {
            let b = super::AlignedBuf::<f64>::zeros_in_planes(planes, plane);
            assert_eq!(b.len(), planes * plane);
            assert_eq!(b.as_ptr() as usize % 64, 0);
            assert!(b.iter().all(|&v| v == 0.0));
        }
    }
}
