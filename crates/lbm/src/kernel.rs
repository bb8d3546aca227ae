//! The fused pull stream–collide sweep (CPU, rayon): one parallel pass over rows per step.

use super::collision::{with_collider, Collider};
use super::d2q9::{CX, CY, Q};
use super::forces::reduce_forces;
use super::lanes::{has_avx512, prefetch_ahead, Lanes};
use super::lattice::{FaceCondition, Lattice, Layout, StepError, HALO_DIRS};
use super::moving::{MovingCells, MovingRun};
use super::real::Real;
use decomposition::{pack_words, unpack_words, Comm, Side, SingleProcess};
use rayon::prelude::*;

/// A raw pointer that rayon tasks may share. Each row task writes only its own row of the
/// destination buffer (and its own force slots), so the writes never overlap.
#[derive(Clone, Copy)]
struct RowWriter<T>(*mut T);
// SAFETY: the pointer targets the destination buffer, which outlives the sweep; tasks
// write disjoint rows (see `sweep`).
unsafe impl<T> Send for RowWriter<T> {}
unsafe impl<T> Sync for RowWriter<T> {}

impl<T> RowWriter<T> {
    /// The pointer (a method, so closures capture the whole `Send` wrapper).
    #[inline(always)]
    fn ptr(&self) -> *mut T {
        self.0
    }
}

/// Which cells a sweep covers.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Part {
    /// Bulk and special cells: everything that does not read an exchanged halo.
    Inner,
    /// Cells next to an exchanged face, after the halo has arrived.
    Edge,
}

/// Populations that leave through the west face (c_x = −1) and the east face (c_x = +1).
const WESTWARD: [usize; HALO_DIRS] = [3, 6, 7];
const EASTWARD: [usize; HALO_DIRS] = [1, 5, 8];

impl<T: Real> Lattice<T> {
    /// Advance one time step on a lattice that owns the whole domain.
    pub fn step(&mut self) -> Result<(), StepError> {
        self.step_with(&SingleProcess)
    }

    /// Advance one time step: [`Lattice::stream_collide`] then [`Lattice::update_boundaries`].
    pub fn step_with(&mut self, comm: &dyn Comm) -> Result<(), StepError> {
        self.stream_collide(comm)?;
        self.update_boundaries();
        Ok(())
    }

    /// Fused stream–collide into the other buffer and swap. Bounce-back and Zou–He links
    /// are reconstructed inside the sweep, and the momentum exchanged with each solid is
    /// stored per cell (see [`Lattice::forces`]). On a slab, the x halos are exchanged
    /// while the inner cells are computed; the cells next to the exchanged faces follow
    /// once the halos have arrived. Collective when the slab has neighbours.
    ///
    /// Errors when a fluid cell's density becomes NaN or non-positive on any rank; every
    /// rank then still holds the last good state.
    pub fn stream_collide(&mut self, comm: &dyn Comm) -> Result<(), StepError> {
        self.stream_collide_moving(comm, &mut MovingCells::None)
            .map(|_| ())
    }

    /// [`Lattice::stream_collide`], recomputing the cells of moving surfaces in `moving`
    /// right after their row is swept (see [`super::moving`]). Returns the plan index and
    /// density of the first such cell that went NaN or non-positive (on this rank). When
    /// such a cell went bad on any rank, the step completes on every rank without the
    /// fluid's own error (`Lattice::check_sweep`): the coupling reports it.
    pub fn stream_collide_moving(
        &mut self,
        comm: &dyn Comm,
        moving: &mut MovingCells<'_>,
    ) -> Result<Option<(usize, f64)>, StepError> {
        if self.in_place() {
            return self.stream_collide_in_place(comm, moving);
        }
        // Checked before any exchange, so that no rank is left waiting.
        assert!(
            !self.buf[self.cur ^ 1].is_empty(),
            "a lattice built with one buffer steps in place only (make_in_place first)"
        );
        if self.step == 0 {
            self.fill_halo();
        }
        let exchange = |f: &FaceCondition| *f == FaceCondition::Exchange;
        let edge = [
            exchange(&self.faces[0]).then_some(0),
            exchange(&self.faces[1]).then_some(self.nx - 1),
        ];
        let run = MovingRun::new(moving, edge, None);
        self.pack_halo();
        let mut halo = std::mem::take(&mut self.halo);
        let waited = halo.exchange(comm, &mut || self.sweep_part(Part::Inner, run.as_ref()));
        self.halo = halo;
        self.halo_wait_s += waited;
        if self.halo.peer(Side::Left).is_some() || self.halo.peer(Side::Right).is_some() {
            self.unpack_halo();
            self.sweep_part(Part::Edge, run.as_ref());
        }
        self.check_sweep(comm, run.as_ref())?;
        self.step += 1;
        self.cur ^= 1;
        Ok(run.and_then(|r| {
            let n = r.first_bad()?;
            Some((n, self.density_at(r.cells()[n] as usize)))
        }))
    }

    /// Total momentum-exchange force (lattice units) on every solid during the last step,
    /// indexed by solid id − 1; the same bits on any number of ranks. Collective.
    pub fn forces(&self, comm: &dyn Comm) -> Vec<[f64; 2]> {
        reduce_forces(comm, &self.forces)
    }

    /// Refill the halo from the interior (periodic, free-slip, outflow faces) so the next
    /// sweep and any field read-out see the boundary values. Exchanged faces are refilled
    /// by the next [`Lattice::stream_collide`] or by [`Lattice::refresh_exchange`].
    pub fn update_boundaries(&mut self) {
        if self.layout != Layout::Pushed {
            self.fill_halo();
        }
    }

    /// Fill the exchanged x halos of the current buffer now (before reading fields on a
    /// slab). Collective when the slab has neighbours.
    pub fn refresh_exchange(&mut self, comm: &dyn Comm) {
        if self.layout == Layout::Pushed {
            // Again what the last step's drain brought in, with any values set since
            // (the fluid under grains at rest, refilled cells) pushed across the faces as
            // they are on one rank.
            self.drain(comm);
            return;
        }
        self.pack_halo();
        let mut halo = std::mem::take(&mut self.halo);
        self.halo_wait_s += halo.exchange(comm, &mut || {});
        self.halo = halo;
        if self.halo.peer(Side::Left).is_some() || self.halo.peer(Side::Right).is_some() {
            self.unpack_halo();
        }
    }

    /// Whether the west and the east face are shared with another rank.
    pub fn exchanged_faces(&self) -> [bool; 2] {
        [Side::Left, Side::Right].map(|s| self.halo.peer(s).is_some())
    }

    /// Fill the exchanged x halos of the current buffer with all nine populations of the
    /// neighbours' edge columns, for rules that read whole neighbour cells (refilling a
    /// cell a moving surface uncovered). Collective when the slab has neighbours.
    pub fn refresh_exchange_full(&mut self, comm: &dyn Comm) {
        let peers = [Side::Left, Side::Right].map(|s| self.halo.peer(s).is_some());
        if !peers[0] && !peers[1] {
            return;
        }
        if self.in_place() {
            self.refresh_exchange_full_in_place(comm);
            return;
        }
        let (nx, stride, plane, rows) = (self.nx, self.stride, self.plane, self.ny + 2);
        let per = Q * rows * T::BYTES;
        self.halo.set_message_bytes(per);
        let src = &self.buf[self.cur];
        for (side, xp) in [(Side::Left, 1), (Side::Right, nx)] {
            if self.halo.peer(side).is_none() {
                continue;
            }
            let column = (0..Q).flat_map(|i| (0..rows).map(move |yp| i * plane + yp * stride + xp));
            pack_words(self.halo.send_mut(side), column.map(|k| src[k]));
        }
        let mut halo = std::mem::take(&mut self.halo);
        self.halo_wait_s += halo.exchange(comm, &mut || {});
        self.halo = halo;
        let dst = &mut self.buf[self.cur];
        for (side, xp) in [(Side::Left, 0), (Side::Right, nx + 1)] {
            if self.halo.peer(side).is_none() {
                continue;
            }
            let column = (0..Q).flat_map(|i| (0..rows).map(move |yp| i * plane + yp * stride + xp));
            for (k, v) in column.zip(unpack_words::<T>(self.halo.recv(side))) {
                dst[k] = v;
            }
        }
        self.halo.set_message_bytes(HALO_DIRS * rows * T::BYTES);
    }

    /// Copy the populations that leave each exchanged face (3 of 9, the full padded
    /// column including its y-halo rows, which makes the corners right) into the send buffers.
    pub(crate) fn pack_halo(&mut self) {
        let (nx, stride, rows) = (self.nx, self.stride, self.ny + 2);
        let acc = self.access();
        let src = &self.buf[self.cur];
        for (side, xp, dirs) in [(Side::Left, 1, WESTWARD), (Side::Right, nx, EASTWARD)] {
            if self.halo.peer(side).is_none() {
                continue;
            }
            let face = dirs
                .into_iter()
                .flat_map(|i| (0..rows).map(move |yp| acc.own(i, yp * stride + xp)));
            pack_words(self.halo.send_mut(side), face.map(|k| src[k]));
        }
    }

    /// Write the received columns into the exchanged x halos of the current buffer.
    pub(crate) fn unpack_halo(&mut self) {
        let (nx, stride, rows) = (self.nx, self.stride, self.ny + 2);
        let acc = self.access();
        let dst = &mut self.buf[self.cur];
        for (side, xp, dirs) in [(Side::Left, 0, EASTWARD), (Side::Right, nx + 1, WESTWARD)] {
            if self.halo.peer(side).is_none() {
                continue;
            }
            let face = dirs
                .into_iter()
                .flat_map(|i| (0..rows).map(move |yp| acc.own(i, yp * stride + xp)));
            for (k, v) in face.zip(unpack_words::<T>(self.halo.recv(side))) {
                dst[k] = v;
            }
        }
    }

    /// One parallel pass over the rows, for the cells of `part` (and the moving-surface
    /// cells of those rows).
    fn sweep_part(&mut self, part: Part, moving: Option<&MovingRun<'_>>) {
        with_collider!(self.collision, self.smagorinsky, self.params, |c| self
            .sweep(c, part, moving));
    }

    /// One parallel pass over all rows for the cells of `part`.
    fn sweep<C: Collider<T>>(&mut self, c: &C, part: Part, moving: Option<&MovingRun<'_>>) {
        let mut dst = std::mem::take(&mut self.buf[self.cur ^ 1]);
        let writer = RowWriter(dst.as_mut_ptr());
        let ns = self.forces.solids();
        let mut slot_values = std::mem::take(&mut self.forces.values);
        let slots = RowWriter(slot_values.as_mut_ptr());
        let mut row_bad = std::mem::take(&mut self.row_bad);
        let this = &*self;
        let src = &this.buf[this.cur];
        let min_len = if part == Part::Inner { 4 } else { 64 };
        let bulk = bulk_kernel::<T, C>();
        row_bad
            .par_iter_mut()
            .enumerate()
            .with_min_len(min_len)
            .for_each(|(y, bad)| {
                let yp = y + 1;
                let row = &this.plan[y];
                let mut b = false;
                let (cells, first_slot) = match part {
                    Part::Inner => {
                        for &(x0, x1) in &row.bulk {
                            // SAFETY: row yp of the destination is written by this task only.
                            // 8 lanes: one AVX register of f32, one 64-byte line of f64 (streamed).
                            b |= unsafe {
                                bulk(
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
                        (&row.special, this.forces.row_start[y])
                    }
                    Part::Edge => (&row.edge, this.forces.row_start[y] + row.special.len()),
                };
                for (j, &x) in cells.iter().enumerate() {
                    // SAFETY: the slots of this row's cells belong to this task only.
                    let f = unsafe {
                        std::slice::from_raw_parts_mut(slots.ptr().add((first_slot + j) * ns), ns)
                    };
                    f.fill([0.0; 2]);
                    let mut h = this.gather_special(
                        super::boundary::Src::of(src),
                        super::boundary::Access::new(Layout::TwoArray, this.plane, this.stride),
                        x as usize,
                        y,
                        Some(f),
                    );
                    let m = c.collide(&mut h);
                    let k = yp * this.stride + x as usize + 1;
                    for (i, hi) in h.iter().enumerate() {
                        // SAFETY: as above, a cell of this task's own row.
                        unsafe { *writer.0.add(i * this.plane + k) = *hi };
                    }
                    b |= !(m.rho > T::default());
                }
                store_fence();
                if let Some(run) = moving {
                    // SAFETY: row yp of the destination belongs to this task; plan cells are
                    // listed once.
                    unsafe { run.row(this, c, src, writer.ptr(), y, part == Part::Edge) };
                }
                match part {
                    Part::Inner => *bad = b as u8,
                    Part::Edge => *bad |= b as u8,
                }
            });
        self.row_bad = row_bad;
        self.forces.values = slot_values;
        self.buf[self.cur ^ 1] = dst;
    }

    /// After a sweep: the first cell whose density went bad, over all ranks, unless a cell
    /// of the moving surfaces in `run` went bad on any rank. That one is the coupling's to
    /// report, since it names the surface, so the step then goes on and the coupling stops
    /// the run. Collective (one agreement over the ranks per call with a run, one more
    /// when a row went bad).
    pub(crate) fn check_sweep(
        &self,
        comm: &dyn Comm,
        run: Option<&MovingRun<'_>>,
    ) -> Result<(), StepError> {
        let moving_bad = match run {
            Some(r) if comm.size() > 1 => comm.any(r.first_bad().is_some()),
            Some(r) => r.first_bad().is_some(),
            None => false,
        };
        let bad_row = self.row_bad.iter().position(|&b| b != 0);
        if moving_bad {
            Ok(())
        } else if comm.size() > 1 {
            match comm.any(bad_row.is_some()) {
                true => Err(self.agree_on_instability(comm, bad_row)),
                false => Ok(()),
            }
        } else {
            bad_row.map_or(Ok(()), |y| Err(self.locate_instability(y)))
        }
    }

    /// The first bad cell over all ranks (rank order), known to every rank. Collective.
    pub(crate) fn agree_on_instability(
        &self,
        comm: &dyn Comm,
        bad_row: Option<usize>,
    ) -> StepError {
        let mine = match bad_row.map(|y| self.locate_instability(y)) {
            Some(e) => vec![e.x as f64, e.y as f64, e.density],
            None => Vec::new(),
        };
        let all = comm.all_gather_f64(&mine);
        StepError {
            // The sweep under way is step self.step + 1 (counted from 1, as the coupling's
            // errors and the progress count them).
            step: self.step + 1,
            x: all[0] as usize,
            y: all[1] as usize,
            density: all[2],
        }
    }

    /// Find the first bad cell of row `y` in the freshly written state.
    pub(crate) fn locate_instability(&self, y: usize) -> StepError {
        // In place, the layout already says where the new values are; two arrays, they are
        // in the other buffer, in the cells' own slots.
        let (dst, acc) = if self.in_place() {
            (&self.buf[0], self.access())
        } else {
            (
                &self.buf[self.cur ^ 1],
                super::boundary::Access::new(Layout::TwoArray, self.plane, self.stride),
            )
        };
        let mut worst = (0, f64::NAN);
        for x in 0..self.nx {
            if !self.is_fluid(x, y) {
                continue;
            }
            let k = self.idx(x as isize, y as isize);
            let rho = 1.0 + (0..Q).map(|i| dst[acc.own(i, k)].to_f64()).sum::<f64>();
            if !(rho > 0.0) {
                worst = (x, rho);
                break;
            }
        }
        StepError {
            // The sweep under way is step self.step + 1 (counted from 1, as the coupling's
            // errors and the progress count them).
            step: self.step + 1,
            x: self.x0 + worst.0,
            y,
            density: worst.1,
        }
    }
}

/// A bulk row kernel, as [`bulk_run`] with 8 lanes.
type BulkFn<T, C> = unsafe fn(&C, &[T], RowWriter<T>, usize, usize, usize, usize, usize) -> bool;

/// The bulk row kernel for this CPU: an AVX-512 build (32 vector registers) where the CPU
/// has AVX-512F/VL, else the build target's; same operations in the same order, same bits.
fn bulk_kernel<T: Real, C: Collider<T>>() -> BulkFn<T, C> {
    #[cfg(target_arch = "x86_64")]
    if has_avx512() {
        return bulk_run_avx512::<T, C>;
    }
    bulk_run::<T, C, 8>
}

/// [`bulk_run`] (8 lanes) compiled with AVX-512.
///
/// # Safety
/// As [`bulk_run`]; the CPU has AVX-512F and AVX-512VL.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl")]
#[allow(clippy::too_many_arguments)]
unsafe fn bulk_run_avx512<T: Real, C: Collider<T>>(
    c: &C,
    src: &[T],
    dst: RowWriter<T>,
    plane: usize,
    stride: usize,
    yp: usize,
    x0: usize,
    x1: usize,
) -> bool {
    bulk_run::<T, C, 8>(c, src, dst, plane, stride, yp, x0, x1)
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
    let ahead: [*const T; Q] = s.map(|r| r.as_ptr());
    while k + LANES <= n {
        prefetch_ahead(&ahead, k);
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
