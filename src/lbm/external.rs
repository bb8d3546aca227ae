//! Access for boundary rules that live outside the fluid core (moving grains, see
//! `coupling/`): after a sweep, such a rule recomputes a few cells of the fresh buffer from
//! the previous one with some incoming links replaced, using the lattice's own gather
//! (walls, obstacles, open faces) and its own collision operator. Nothing here knows about
//! grains.

use super::collision::{family, Collider, Collision, MomentCollider, Moments};
use super::d2q9::Q;
use super::lattice::{Lattice, FLUID};
use super::real::Real;

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
    pub fn previous_buffer(&self) -> &[T] {
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
    pub fn buffers_mut(&mut self) -> (&[T], &mut [T]) {
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
        self.gather_special(self.previous_buffer(), x, y, None)
    }

    /// Collide one cell's pre-collision populations in place with the lattice's operator
    /// (BGK, TRT or MRT, Smagorinsky and body force as configured); returns the
    /// pre-collision moments.
    pub fn collide_one(&self, h: &mut [T; Q]) -> Moments<T> {
        let p = self.params;
        let forced = p.force[0] != T::default() || p.force[1] != T::default();
        macro_rules! go {
            ($fam:expr) => {
                match (self.smagorinsky, forced) {
                    (false, false) => MomentCollider::<T, false, { $fam }, false>(p).collide(h),
                    (false, true) => MomentCollider::<T, false, { $fam }, true>(p).collide(h),
                    (true, false) => MomentCollider::<T, true, { $fam }, false>(p).collide(h),
                    (true, true) => MomentCollider::<T, true, { $fam }, true>(p).collide(h),
                }
            };
        }
        match self.collision {
            Collision::Bgk => go!(family::BGK),
            Collision::Trt { .. } => go!(family::TRT),
            Collision::Mrt { .. } => go!(family::MRT),
        }
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
