//! Access for boundary rules that live outside the fluid core (moving grains, see
//! `coupling/`): after a sweep, such a rule recomputes a few cells of the fresh buffer from
//! the previous one with some incoming links replaced, using the lattice's own gather
//! (walls, obstacles, open faces) and its own collision operator. Nothing here knows about
//! grains.

use super::collision::{with_collider, Collider, Moments};
use super::d2q9::Q;
use super::lattice::{Lattice, FLUID};
use super::moving::{MovingCells, MovingRun};
use super::real::Real;
use rayon::prelude::*;

/// A destination pointer shared by row tasks that write disjoint rows.
#[derive(Clone, Copy)]
struct RowPtr<T>(*mut T);
// SAFETY: tasks write disjoint rows (see `run_rows`).
unsafe impl<T> Send for RowPtr<T> {}
unsafe impl<T> Sync for RowPtr<T> {}

impl<T> RowPtr<T> {
    /// The pointer (a method, so closures capture the whole `Send` wrapper).
    fn get(&self) -> *mut T {
        self.0
    }
}

impl<T: Real> Lattice<T> {
    /// Padded linear index of interior cell (x, y) (x, y may be −1 or nx, ny: the halo).
    /// Plane `i` of a buffer holds population i of that cell at `i * plane() + index`.
    pub fn padded_index(&self, x: isize, y: isize) -> usize {
        self.idx(x, y)
    }
    /// Values per population plane of a buffer.
    pub fn plane(&self) -> usize {
        self.plane
    }
    /// Padded row length (nx + 2).
    pub fn stride(&self) -> usize {
        self.stride
    }
    /// Whether padded cell `k` is plain fluid (not a wall, obstacle or open face).
    pub fn is_fluid_at(&self, k: usize) -> bool {
        self.types[k] == FLUID
    }
    /// The buffer the last step read: post-collision populations of the step before
    /// (shifted, h = f − w), halos included.
    ///
    /// # Panics
    /// On a lattice in place, or built with one buffer ([`Lattice::new_slab_one_buffer`]):
    /// it has no previous buffer.
    pub fn previous_buffer(&self) -> &[T] {
        assert!(
            !self.buf[self.cur ^ 1].is_empty(),
            "no previous buffer: the lattice is in place, or was built with one buffer"
        );
        &self.buf[self.cur ^ 1]
    }
    /// The buffer the last step wrote (the current state), for rules that overwrite cells.
    /// Call [`Lattice::update_boundaries`] afterwards so halo copies see the new values.
    pub fn current_buffer_mut(&mut self) -> &mut [T] {
        &mut self.buf[self.cur]
    }
    /// The current state (read only).
    pub fn current_buffer(&self) -> &[T] {
        &self.buf[self.cur]
    }
    /// Both buffers: (previous, current), for rules that read one and write the other.
    ///
    /// # Panics
    /// As [`Lattice::previous_buffer`].
    pub fn buffers_mut(&mut self) -> (&[T], &mut [T]) {
        assert!(
            !self.buf[self.cur ^ 1].is_empty(),
            "no previous buffer: the lattice is in place, or was built with one buffer"
        );
        let (a, b) = self.buf.split_at_mut(1);
        if self.cur == 0 {
            (&b[0], &mut a[0])
        } else {
            (&a[0], &mut b[0])
        }
    }

    /// Pre-collision populations of interior fluid cell (x, y) for the step just taken,
    /// pulled from the previous buffer with the lattice's own walls, obstacles and open
    /// faces applied (no force bookkeeping: the sweep already recorded it).
    pub fn gather_previous(&self, x: usize, y: usize) -> [T; Q] {
        let acc =
            super::boundary::Access::new(super::lattice::Layout::TwoArray, self.plane, self.stride);
        self.gather_special(
            super::boundary::Src::of(self.previous_buffer()),
            acc,
            x,
            y,
            None,
        )
    }

    /// Collide one cell's pre-collision populations in place with the lattice's operator
    /// (BGK, TRT or MRT, Smagorinsky and body force as configured); returns the
    /// pre-collision moments.
    pub fn collide_one(&self, h: &mut [T; Q]) -> Moments<T> {
        with_collider!(self.collision, self.smagorinsky, self.params, |c| c
            .collide(h))
    }

    /// Recompute the cells of `moving` from the previous buffer into the current one with
    /// the lattice's operator, as a sweep would have (for a backend that swept elsewhere).
    /// Returns the plan index and density of the first cell that went bad.
    pub fn apply_moving(&mut self, moving: &mut MovingCells<'_>) -> Option<(usize, f64)> {
        let run = MovingRun::new(moving, [None, None], None)?;
        with_collider!(self.collision, self.smagorinsky, self.params, |c| self
            .run_rows(c, &run));
        let n = run.first_bad()?;
        Some((n, self.density_at(run.cells()[n] as usize)))
    }

    /// Every row of `run`, in parallel, from the previous buffer into the current one.
    fn run_rows<C: Collider<T>>(&mut self, c: &C, run: &MovingRun<'_>) {
        let mut cur = std::mem::take(&mut self.buf[self.cur]);
        let dst = RowPtr(cur.as_mut_ptr());
        {
            let this = &*self;
            let src = this.previous_buffer();
            (0..this.ny).into_par_iter().for_each(|y| {
                // SAFETY: each task owns its row of the current buffer; plan cells are
                // listed once.
                unsafe { run.row(this, c, src, dst.get(), y, false) };
            });
        }
        self.buf[self.cur] = cur;
    }

    /// Face conditions (west, east, south, north) of this slab.
    pub fn faces(&self) -> &[super::lattice::FaceCondition; 4] {
        &self.faces
    }

    /// Molecular relaxation time τ₀ = 3ν + ½ (lattice units).
    pub fn tau0(&self) -> f64 {
        self.params.tau0.to_f64()
    }

    /// Body force per cell (lattice units).
    pub fn body_force(&self) -> [f64; 2] {
        [self.params.force[0].to_f64(), self.params.force[1].to_f64()]
    }
}
