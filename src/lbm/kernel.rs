//! The fused pull stream–collide sweep (CPU, rayon): one parallel pass over rows per step.

use super::collision::{family, Collider, Collision, MomentCollider};
use super::d2q9::{CX, CY, Q};
use super::lanes::Lanes;
use super::lattice::{Lattice, StepError};
use super::real::Real;
use rayon::prelude::*;

/// A raw pointer that rayon tasks may share. Each row task writes only its own row of the
/// destination buffer, so the writes never overlap.
#[derive(Clone, Copy)]
struct RowWriter<T>(*mut T);
// SAFETY: the pointer targets the destination buffer, which outlives the sweep; tasks
// write disjoint rows (see `sweep`).
unsafe impl<T> Send for RowWriter<T> {}
unsafe impl<T> Sync for RowWriter<T> {}

impl<T: Real> Lattice<T> {
    /// Advance one time step: [`Lattice::stream_collide`] then [`Lattice::update_boundaries`].
    pub fn step(&mut self) -> Result<(), StepError> {
        self.stream_collide()?;
        self.update_boundaries();
        Ok(())
    }

    /// Fused stream–collide into the other buffer and swap; bounce-back and Zou–He links are
    /// reconstructed inside the sweep, and the momentum exchanged with each solid is summed
    /// (available from [`Lattice::force_on`]).
    ///
    /// Errors when a fluid cell's density becomes NaN or non-positive; the lattice then
    /// still holds the last good state.
    pub fn stream_collide(&mut self) -> Result<(), StepError> {
        if self.step == 0 {
            self.fill_halo();
        }
        let p = self.params;
        let forced = p.force[0] != T::default() || p.force[1] != T::default();
        macro_rules! dispatch {
            ($fam:expr) => {
                match (self.smagorinsky, forced) {
                    (false, false) => self.sweep(&MomentCollider::<T, false, { $fam }, false>(p)),
                    (false, true) => self.sweep(&MomentCollider::<T, false, { $fam }, true>(p)),
                    (true, false) => self.sweep(&MomentCollider::<T, true, { $fam }, false>(p)),
                    (true, true) => self.sweep(&MomentCollider::<T, true, { $fam }, true>(p)),
                }
            };
        }
        match self.collision {
            Collision::Bgk => dispatch!(family::BGK),
            Collision::Trt { .. } => dispatch!(family::TRT),
            Collision::Mrt { .. } => dispatch!(family::MRT),
        }
        if let Some(y) = self.row_bad.iter().position(|&b| b != 0) {
            return Err(self.locate_instability(y));
        }
        self.step += 1;
        self.cur ^= 1;
        // Deterministic reduction: rows in order, whatever the thread count.
        let ns = self.solids.len();
        for s in 0..ns {
            let mut acc = [0.0; 2];
            for y in 0..self.ny {
                let f = self.row_force[y * ns + s];
                acc[0] += f[0];
                acc[1] += f[1];
            }
            self.force_on[s] = acc;
        }
        Ok(())
    }

    /// Refill the halo from the interior (periodic, free-slip, outflow faces) so the next
    /// sweep and any field read-out see the boundary values.
    pub fn update_boundaries(&mut self) {
        self.fill_halo();
    }

    /// One parallel pass over all rows.
    fn sweep<C: Collider<T>>(&mut self, c: &C) {
        let mut dst = std::mem::take(&mut self.buf[self.cur ^ 1]);
        let writer = RowWriter(dst.as_mut_ptr());
        let ns = self.solids.len().max(1);
        let mut row_bad = std::mem::take(&mut self.row_bad);
        let mut row_force = std::mem::take(&mut self.row_force);
        let this = &*self;
        let src = &this.buf[this.cur];
        row_bad
            .par_iter_mut()
            .zip(row_force.par_chunks_mut(ns))
            .enumerate()
            .with_min_len(4)
            .for_each(|(y, (bad, forces))| {
                forces.fill([0.0; 2]);
                let yp = y + 1;
                let row = &this.plan[y];
                let mut b = false;
                for &(x0, x1) in &row.bulk {
                    // SAFETY: row yp of the destination is written by this task only.
                    // 8 lanes: one AVX register of f32, one 64-byte line of f64 (streamed).
                    b |= unsafe {
                        bulk_run::<T, C, 8>(
                            c,
                            src,
                            writer,
                            this.plane,
                            this.stride,
                            yp,
                            x0 as usize,
                            x1 as usize,
                        )
                    };
                }
                for &x in &row.special {
                    let mut h = this.gather_special(src, x as usize, y, Some(forces));
                    let m = c.collide(&mut h);
                    let k = yp * this.stride + x as usize + 1;
                    for (i, hi) in h.iter().enumerate() {
                        // SAFETY: as above, a cell of this task's own row.
                        unsafe { *writer.0.add(i * this.plane + k) = *hi };
                    }
                    b |= !(m.rho > T::default());
                }
                store_fence();
                *bad = b as u8;
            });
        self.row_bad = row_bad;
        self.row_force = row_force;
        self.buf[self.cur ^ 1] = dst;
    }

    /// Find the first bad cell of row `y` in the freshly written buffer.
    fn locate_instability(&self, y: usize) -> StepError {
        let dst = &self.buf[self.cur ^ 1];
        let mut worst = (0, f64::NAN);
        for x in 0..self.nx {
            if !self.is_fluid(x, y) {
                continue;
            }
            let k = self.idx(x as isize, y as isize);
            let rho = 1.0
                + (0..Q)
                    .map(|i| dst[i * self.plane + k].to_f64())
                    .sum::<f64>();
            if !(rho > 0.0) {
                worst = (x, rho);
                break;
            }
        }
        StepError {
            step: self.step,
            x: worst.0,
            y,
            density: worst.1,
        }
    }
}

/// Stream–collide the bulk cells `[x0, x1)` of padded row `yp`, `LANES` cells at a time
/// (scalar for the remainder). Returns true if any cell's density went NaN or non-positive.
///
/// # Safety
/// `dst` must point to a buffer of the same layout as `src`, and no other thread may touch
/// row `yp` of it during the call.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn bulk_run<T: Real, C: Collider<T>, const LANES: usize>(
    c: &C,
    src: &[T],
    dst: RowWriter<T>,
    plane: usize,
    stride: usize,
    yp: usize,
    x0: usize,
    x1: usize,
) -> bool {
    let n = x1 - x0;
    // Pull: population i at x comes from x − c_i.
    let s: [&[T]; Q] = std::array::from_fn(|i| {
        let start = i * plane
            + (yp as isize - CY[i] as isize) as usize * stride
            + (x0 as isize + 1 - CX[i] as isize) as usize;
        &src[start..start + n]
    });
    let d: [*mut T; Q] = std::array::from_fn(|i| dst.0.add(i * plane + yp * stride + x0 + 1));
    let zero = T::default();
    let mut bad = false;
    let mut k = 0;
    // Scalar cells up to the first lane-aligned destination (all planes share the phase).
    let misaligned = (d[0] as usize / std::mem::size_of::<T>()) % LANES;
    let peel = ((LANES - misaligned) % LANES).min(n);
    // Scalar cells: the alignment peel here and the remainder below are written out twice on
    // purpose; sharing them through a closure measured 17 % slower (f32, one thread).
    while k < peel {
        let mut h: [T; Q] = std::array::from_fn(|i| s[i][k]);
        let m = c.collide(&mut h);
        for i in 0..Q {
            *d[i].add(k) = h[i];
        }
        bad |= !(m.rho > zero);
        k += 1;
    }
    while k + LANES <= n {
        let mut h: [Lanes<T, LANES>; Q] = std::array::from_fn(|i| {
            let mut v = [zero; LANES];
            v.copy_from_slice(&s[i][k..k + LANES]);
            Lanes(v)
        });
        let m = c.collide(&mut h);
        for i in 0..Q {
            store_streaming(d[i].add(k), &h[i].0);
        }
        let mut lane_bad = false;
        for r in m.rho.0 {
            lane_bad |= !(r > zero);
        }
        bad |= lane_bad;
        k += LANES;
    }
    while k < n {
        let mut h: [T; Q] = std::array::from_fn(|i| s[i][k]);
        let m = c.collide(&mut h);
        for i in 0..Q {
            *d[i].add(k) = h[i];
        }
        bad |= !(m.rho > zero);
        k += 1;
    }
    bad
}

/// Store a bundle of lanes at an aligned address. A full 64-byte line of f64 bypasses the
/// cache (non-temporal), so the destination line is never read first: that removes a third of
/// a two-array kernel's memory traffic. Everything else is a plain copy.
///
/// # Safety
/// `dst` must be valid for `N` writes and aligned to `N × size_of::<T>()` bytes.
#[inline(always)]
unsafe fn store_streaming<T: Real, const N: usize>(dst: *mut T, v: &[T; N]) {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use std::arch::x86_64::{_mm256_loadu_pd, _mm256_stream_pd};
        // A whole 64-byte line per plane, back to back, so the write-combining buffer
        // flushes full lines even though nine planes are written in turn. (f32 is compute-
        // bound here and measured slower with streaming stores, so it keeps plain ones.)
        if T::BYTES == 8 && N == 8 {
            let (d, p) = (dst as *mut f64, v.as_ptr() as *const f64);
            _mm256_stream_pd(d, _mm256_loadu_pd(p));
            _mm256_stream_pd(d.add(4), _mm256_loadu_pd(p.add(4)));
            return;
        }
    }
    std::ptr::copy_nonoverlapping(v.as_ptr(), dst, N);
}

/// Order this thread's non-temporal stores before anything that follows (the end of a sweep).
#[inline(always)]
fn store_fence() {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    // SAFETY: `sfence` has no preconditions.
    unsafe {
        std::arch::x86_64::_mm_sfence()
    };
}
