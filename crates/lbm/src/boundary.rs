//! Boundary conditions: halo fills (periodic, free-slip, outflow) and the link
//! reconstruction of special cells (half-way bounce-back with Ladd's moving-wall term,
//! Zou–He velocity and pressure faces and corners).

use super::cells::is_plain;
use super::d2q9::{rotate, CX, CY, MIRROR_X, MIRROR_Y, OPP, Q, W};
use super::lattice::{
    Face, FaceCondition, Lattice, Layout, FLUID, MAX_SOLID, OPEN_CORNER, OPEN_WEST,
};
use super::real::Real;

/// Where a step finds and puts populations in a buffer, for the layout the lattice holds
/// before the step (see [`Layout`]). `pulled(i, k)`: the value population i of cell k pulls
/// (the post-collision value of k − c_i in direction i); `own(j, k)`: cell k's own
/// post-collision value in direction j; `store(j, k)`: where the step writes k's new one
/// (in the other buffer for two arrays, in the same one in place).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Access {
    layout: Layout,
    plane: usize,
    stride: isize,
}

impl Access {
    /// The access of a step taken from `layout`.
    pub(crate) fn new(layout: Layout, plane: usize, stride: usize) -> Self {
        Self {
            layout,
            plane,
            stride: stride as isize,
        }
    }

    #[inline(always)]
    fn off(&self, i: usize) -> isize {
        CX[i] as isize + CY[i] as isize * self.stride
    }

    /// Index of the population `i` that cell `k` pulls.
    #[inline(always)]
    pub(crate) fn pulled(&self, i: usize, k: usize) -> usize {
        let at = match self.layout {
            Layout::TwoArray => (i * self.plane) as isize + k as isize - self.off(i),
            Layout::Local => (OPP[i] * self.plane) as isize + k as isize - self.off(i),
            Layout::Pushed => (i * self.plane + k) as isize,
        };
        at as usize
    }

    /// Index of cell `k`'s own post-collision value in direction `j`.
    #[inline(always)]
    pub(crate) fn own(&self, j: usize, k: usize) -> usize {
        let at = match self.layout {
            Layout::TwoArray => (j * self.plane + k) as isize,
            Layout::Local => (OPP[j] * self.plane + k) as isize,
            Layout::Pushed => (j * self.plane) as isize + k as isize + self.off(j),
        };
        at as usize
    }

    /// Index where the step stores cell `k`'s new post-collision value in direction `j`.
    #[inline(always)]
    pub(crate) fn store(&self, j: usize, k: usize) -> usize {
        let at = match self.layout {
            Layout::TwoArray => (j * self.plane + k) as isize,
            Layout::Local => (j * self.plane) as isize + k as isize + self.off(j),
            Layout::Pushed => (OPP[j] * self.plane + k) as isize,
        };
        at as usize
    }
}

/// A buffer read through a raw pointer: an in-place sweep reads slots that other tasks
/// write (never the same slot in one step), which a shared slice may not see.
#[derive(Clone, Copy)]
pub(crate) struct Src<T>(pub(crate) *const T);
// SAFETY: read-only access to slots no task writes during the pass that reads them.
unsafe impl<T> Send for Src<T> {}
unsafe impl<T> Sync for Src<T> {}

impl<T: Copy> Src<T> {
    /// The reader of a whole buffer.
    pub(crate) fn of(buf: &[T]) -> Self {
        Self(buf.as_ptr())
    }
    /// The value at `i`.
    #[inline(always)]
    pub(crate) fn get(&self, i: usize) -> T {
        // SAFETY: indices come from `Access` on padded cells of the buffer the pointer
        // belongs to, which outlives the pass.
        unsafe { *self.0.add(i) }
    }
}

/// The moving-wall term of half-way bounce-back along direction `i` off a wall moving at
/// `u` (lattice units), ρ_w = 1: 2 w_i ρ_w (c_i · u)/c_s² = 6 w_i c_i · u (Ladd 1994, eq. 3.3;
/// seed eq. 5.45).
#[inline(always)]
pub(crate) fn moving_wall_term(i: usize, u: [f64; 2]) -> f64 {
    6.0 * W[i] * (CX[i] as f64 * u[0] + CY[i] as f64 * u[1])
}

/// The momentum a solid exchanges along direction `i` with a fluid cell that bounced the
/// shifted population `back` (h*_ī) back into `bounced` (h_i): f*_ī + f_i = h*_ī + h_i + 2 w_i,
/// of which the solid receives the negative times c_i (Ladd 1994).
#[inline(always)]
pub(crate) fn exchanged_momentum(i: usize, back: f64, bounced: f64) -> f64 {
    back + bounced + 2.0 * W[i]
}

impl<T: Real> Lattice<T> {
    /// Fill the halo of the current buffer from the interior: periodic wrap, specular
    /// mirror (free slip) or zero-gradient copy (outflow). Wall and open halos are never
    /// read as populations, so they are left alone. x faces first (interior rows), then y
    /// faces over the full padded width, so corners are consistent.
    pub(crate) fn fill_halo(&mut self) {
        let (nx, ny, stride, plane) = (self.nx, self.ny, self.stride, self.plane);
        let buf = &mut self.buf[self.cur];
        for (face, halo_x, inner_x, wrap_x) in [(Face::West, 0, 1, nx), (Face::East, nx + 1, nx, 1)]
        {
            let map: Option<(&[usize; Q], usize)> = match self.faces[face as usize] {
                FaceCondition::Periodic => Some((&IDENTITY, wrap_x)),
                FaceCondition::FreeSlip => Some((&MIRROR_X, inner_x)),
                FaceCondition::Outflow => Some((&IDENTITY, inner_x)),
                _ => None,
            };
            if let Some((dirs, from_x)) = map {
                for yp in 1..=ny {
                    for i in 0..Q {
                        buf[i * plane + yp * stride + halo_x] =
                            buf[dirs[i] * plane + yp * stride + from_x];
                    }
                }
            }
        }
        for (face, halo_y, inner_y, wrap_y) in
            [(Face::South, 0, 1, ny), (Face::North, ny + 1, ny, 1)]
        {
            let map: Option<(&[usize; Q], usize)> = match self.faces[face as usize] {
                FaceCondition::Periodic => Some((&IDENTITY, wrap_y)),
                FaceCondition::FreeSlip => Some((&MIRROR_Y, inner_y)),
                FaceCondition::Outflow => Some((&IDENTITY, inner_y)),
                _ => None,
            };
            if let Some((dirs, from_y)) = map {
                for i in 0..Q {
                    let (dst, src) = (
                        i * plane + halo_y * stride,
                        dirs[i] * plane + from_y * stride,
                    );
                    buf.copy_within(src..src + stride, dst);
                }
            }
        }
    }

    /// Pre-collision shifted populations of fluid cell (x, y) read from `src` as `acc`
    /// says, with links from solids bounced back (Ladd 1994 moving-wall term) and links
    /// from open faces reconstructed (Zou & He 1997). Momentum handed to each solid is
    /// added to `force` (indexed by solid id − 1) when given.
    #[inline]
    pub(crate) fn gather_special(
        &self,
        src: Src<T>,
        acc: Access,
        x: usize,
        y: usize,
        mut force: Option<&mut [[f64; 2]]>,
    ) -> [T; Q] {
        let k = self.idx(x as isize, y as isize);
        let mut h = [T::default(); Q];
        let mut unknown = false;
        for i in 0..Q {
            let n = (k as isize - CX[i] as isize - CY[i] as isize * self.stride as isize) as usize;
            let t = self.types[n];
            if t == FLUID {
                h[i] = src.get(acc.pulled(i, k));
            } else if t <= MAX_SOLID {
                let solid = &self.solids[t as usize - 1];
                let back = src.get(acc.own(OPP[i], k));
                // Half-way bounce-back with wall velocity, ρ_w = 1 (Ladd 1994, eq. 3.3).
                h[i] = back + T::from_f64(moving_wall_term(i, solid.velocity));
                if let Some(f) = force.as_deref_mut() {
                    let m = exchanged_momentum(i, back.to_f64(), h[i].to_f64());
                    f[t as usize - 1][0] -= m * CX[i] as f64;
                    f[t as usize - 1][1] -= m * CY[i] as f64;
                }
            } else {
                debug_assert!((OPEN_WEST..=OPEN_CORNER).contains(&t));
                unknown = true;
            }
        }
        if unknown {
            self.reconstruct_open(src, acc, x, y, &mut h);
        }
        h
    }

    /// Zou–He reconstruction of the unknown links of a cell on one open face, or on the
    /// corner of two. Works on the shifted populations h = f − w in the kernel's precision:
    /// forming f = h + w in f32 would cost two digits of the small deviations.
    fn reconstruct_open(&self, src: Src<T>, acc: Access, x: usize, y: usize, h: &mut [T; Q]) {
        let open = |f: Face| self.faces[f as usize].is_open();
        let xf = if x == 0 && open(Face::West) {
            Some(Face::West)
        } else if x + 1 == self.nx && open(Face::East) {
            Some(Face::East)
        } else {
            None
        };
        let yf = if y == 0 && open(Face::South) {
            Some(Face::South)
        } else if y + 1 == self.ny && open(Face::North) {
            Some(Face::North)
        } else {
            None
        };
        match (xf, yf) {
            (Some(a), Some(b)) => self.zou_he_corner(src, acc, x, y, a, b, h),
            (Some(face), None) => self.zou_he_face(face, y, h),
            (None, Some(face)) => self.zou_he_face(face, x, h),
            (None, None) => unreachable!("open link without an open face at ({x}, {y})"),
        }
    }

    /// Prescribed velocity of an open face at position `s` along it (None for pressure faces).
    fn face_velocity(&self, face: Face, s: usize) -> Option<[T; 2]> {
        match &self.faces[face as usize] {
            FaceCondition::Velocity(v) => Some([
                T::from_f64(v[s][0] * self.inlet_scale),
                T::from_f64(v[s][1] * self.inlet_scale),
            ]),
            _ => None,
        }
    }

    /// Zou & He (1997) on one face, written for the west face (eqs. 19–23 there) and
    /// rotated onto the others, in shifted populations (the weights cancel in eqs. 20–22;
    /// the known weights in eq. 19 sum to 1).
    fn zou_he_face(&self, face: Face, s: usize, h: &mut [T; Q]) {
        let k = face.quarter_turns();
        let r = |i: usize| rotate(i, k);
        let (n, t) = (r(1), r(2));
        let c = T::from_f64;
        let one = c(1.0);
        let known = h[0] + h[r(2)] + h[r(4)] + c(2.0) * (h[r(3)] + h[r(6)] + h[r(7)]);
        let (rho, un, ut) = match &self.faces[face as usize] {
            FaceCondition::Velocity(_) => {
                let u = self.face_velocity(face, s).expect("velocity face");
                let un = c(CX[n] as f64) * u[0] + c(CY[n] as f64) * u[1];
                let ut = c(CX[t] as f64) * u[0] + c(CY[t] as f64) * u[1];
                // ρ − 1 = (Σ_known h + u_n) / (1 − u_n) (Zou & He 1997, eq. 19, shifted).
                (one + (known + un) / (one - un), un, ut)
            }
            FaceCondition::Pressure(drho) => {
                let d = c(*drho);
                let rho = one + d;
                // u_n = 1 − Σ_known f / ρ = (δρ − Σ_known h) / ρ (Zou & He 1997, shifted).
                (rho, (d - known) / rho, c(0.0))
            }
            _ => unreachable!("zou_he_face on a closed face"),
        };
        let half_diff = c(0.5) * (h[r(2)] - h[r(4)]);
        let (two_thirds, sixth, half) = (c(2.0 / 3.0), c(6.0), c(0.5));
        // Zou & He 1997, eqs. 20–22 (tangential term keeps u_t).
        h[r(1)] = h[r(3)] + two_thirds * rho * un;
        h[r(5)] = h[r(7)] - half_diff + rho * un / sixth + half * rho * ut;
        h[r(8)] = h[r(6)] + half_diff + rho * un / sixth - half * rho * ut;
    }

    /// Corner between two open faces (Zou & He 1997, sec. 4; Hecht & Harting 2010, sec. 3.2):
    /// density from the diagonal interior neighbour, the buried pair split to conserve mass.
    /// Shifted populations: the buried pair gets ½(δρ − Σ_known h ± skew).
    #[allow(clippy::too_many_arguments)]
    fn zou_he_corner(
        &self,
        src: Src<T>,
        acc: Access,
        x: usize,
        y: usize,
        xf: Face,
        yf: Face,
        h: &mut [T; Q],
    ) {
        let k = match (xf, yf) {
            (Face::West, Face::South) => 0,
            (Face::East, Face::South) => 1,
            (Face::East, Face::North) => 2,
            _ => 3,
        };
        let r = |i: usize| rotate(i, k);
        let c = T::from_f64;
        let zero = c(0.0);
        let u = self
            .face_velocity(yf, x)
            .or_else(|| self.face_velocity(xf, y))
            .unwrap_or([zero, zero]);
        let (a, b) = (r(1), r(2));
        let ua = c(CX[a] as f64) * u[0] + c(CY[a] as f64) * u[1];
        let ub = c(CX[b] as f64) * u[0] + c(CY[b] as f64) * u[1];
        // Density of the interior neighbour along the inward diagonal (extrapolation), from
        // the step's start: in place, taken before the sweep overwrote the neighbour's slots.
        let drho = match &self.corner_drho {
            Some(d) => d[k],
            None => self.corner_neighbour_drho(src, acc, x, y, k),
        };
        let rho = c(1.0) + drho;
        let (two_thirds, sixth, half) = (c(2.0 / 3.0), c(6.0), c(0.5));
        h[a] = h[r(3)] + two_thirds * rho * ua;
        h[b] = h[r(4)] + two_thirds * rho * ub;
        h[r(5)] = h[r(7)] + rho * (ua + ub) / sixth;
        let known = h[0] + h[a] + h[b] + h[r(3)] + h[r(4)] + h[r(5)] + h[r(7)];
        let skew = rho * (ub - ua) / sixth;
        h[r(6)] = half * (drho - known + skew);
        h[r(8)] = half * (drho - known - skew);
    }
}

impl<T: Real> Lattice<T> {
    /// δρ = Σ_i h_i of the interior neighbour on the inward diagonal of corner `k` (0 W–S,
    /// 1 E–S, 2 E–N, 3 W–N) at cell (x, y): its post-collision values of the last step.
    pub(crate) fn corner_neighbour_drho(
        &self,
        src: Src<T>,
        acc: Access,
        x: usize,
        y: usize,
        k: usize,
    ) -> T {
        let dn = rotate(5, k);
        let nbr = self.idx(x as isize + CX[dn] as isize, y as isize + CY[dn] as isize);
        let mut drho = T::default();
        for i in 0..Q {
            drho += src.get(acc.own(i, nbr));
        }
        drho
    }

    /// The δρ of every open corner's neighbour (zero where there is no open corner), for the
    /// in-place sweeps, which overwrite the neighbour's slots while the corner still needs them.
    pub(crate) fn corner_drhos(&self, acc: Access) -> [T; 4] {
        let open = |f: Face| self.faces[f as usize].is_open();
        let (nx, ny) = (self.nx, self.ny);
        let src = Src(self.buf[self.cur].as_ptr());
        let mut out = [T::default(); 4];
        for (k, (xf, yf, x, y)) in [
            (Face::West, Face::South, 0, 0),
            (Face::East, Face::South, nx - 1, 0),
            (Face::East, Face::North, nx - 1, ny - 1),
            (Face::West, Face::North, 0, ny - 1),
        ]
        .into_iter()
        .enumerate()
        {
            if open(xf) && open(yf) && nx > 1 && ny > 1 {
                out[k] = self.corner_neighbour_drho(src, acc, x, y, k);
            }
        }
        out
    }
}

const IDENTITY: [usize; Q] = [0, 1, 2, 3, 4, 5, 6, 7, 8];

/// Pre-collision populations of interior fluid cell `k` (padded) pulled from `src` (read
/// through `acc`): a plain pull where every neighbour is plain fluid, the lattice's own wall
/// and open-face rules otherwise.
#[inline(always)]
pub(crate) fn pull<T: Real>(lat: &Lattice<T>, src: Src<T>, acc: Access, k: usize) -> [T; Q] {
    if is_plain(&lat.types, lat.stride, k) {
        std::array::from_fn(|i| src.get(acc.pulled(i, k)))
    } else {
        let (x, y) = (k % lat.stride - 1, k / lat.stride - 1);
        lat.gather_special(src, acc, x, y, None)
    }
}
