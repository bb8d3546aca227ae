//! Lattice storage: the populations of a slab, its cell types and its row plans.

use super::aligned::AlignedBuf;
pub(crate) use super::cells::{is_plain, HALO_DIRS};
pub use super::cells::{
    Face, FaceCondition, FLUID, MAX_SOLID, OPEN_CORNER, OPEN_EAST, OPEN_NORTH, OPEN_SOUTH,
    OPEN_WEST,
};
use super::collision::{equilibrium, Collision, CollisionParams, Moments};
use super::d2q9::Q;
use super::forces::ForceSlots;
use super::real::Real;
use super::rows::{row_plan, DrainPlan, RowPlan};
use decomposition::{Comm, Side, SlabHalo, SlabPartition};
use thiserror::Error;

/// A solid body known to the lattice (walls and obstacles).
#[derive(Debug, Clone, PartialEq)]
pub struct SolidInfo {
    /// Name for reports.
    pub name: String,
    /// Wall velocity, lattice units (zero for fixed obstacles).
    pub velocity: [f64; 2],
}

/// Everything needed to build a [`Lattice`], in lattice units.
#[derive(Debug, Clone)]
pub struct LatticeSetup {
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
    /// Interior cell types, row-major `y * nx + x`: [`FLUID`] or a solid id.
    pub cells: Vec<u16>,
    /// Conditions on west, east, south, north.
    pub faces: [FaceCondition; 4],
    /// Solids; id `k` is `solids[k - 1]`.
    pub solids: Vec<SolidInfo>,
    /// Collision model.
    pub collision: Collision,
    /// τ₀ = 3ν + ½.
    pub tau0: f64,
    /// Smagorinsky constant, if the closure is on.
    pub smagorinsky: Option<f64>,
    /// Body force per cell.
    pub force: [f64; 2],
}

/// A run that went unstable.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("unstable at step {step}: cell ({x}, {y}) has density {density} (NaN or ≤ 0); reduce the velocity, raise τ or refine the lattice")]
pub struct StepError {
    /// Step that produced the bad value, counted from 1 (the first step is step 1; the
    /// state after step − 1 steps was the last good one).
    pub step: u64,
    /// Cell x.
    pub x: usize,
    /// Cell y.
    pub y: usize,
    /// The offending density.
    pub density: f64,
}

/// How a lattice holds its populations between steps.
///
/// * `TwoArray`: two buffers; the current one holds each cell's post-collision values in its
///   own slots (`h_j(x)` at plane j, cell x); a step pulls from it into the other.
/// * In place (one buffer, the AA pattern of Bailey et al. 2009), alternating:
///   `Local` holds `h_j(x)` at plane `OPP[j]`, cell x (the next step pulls from the
///   neighbours and pushes its results to them); `Pushed` holds `h_j(x)` at plane j, cell
///   x + c_j, already streamed (the next step reads and writes only the cell's own slots).
///   Each cell reads and writes the same nine slots in a step, so cells never race.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// Two buffers, post-collision values in place.
    TwoArray,
    /// One buffer, post-collision values in the opposite direction's slot.
    Local,
    /// One buffer, post-collision values streamed to the neighbours.
    Pushed,
}

/// The D2Q9 lattice of one rank: two SoA buffers of shifted populations (one in place, or
/// when built to go in place) plus geometry.
pub struct Lattice<T: Real> {
    /// Local columns (the slab width).
    pub(crate) nx: usize,
    pub(crate) ny: usize,
    /// Global column of local column 0.
    pub(crate) x0: usize,
    /// Global columns.
    pub(crate) global_nx: usize,
    pub(crate) stride: usize,
    pub(crate) plane: usize,
    pub(crate) buf: [AlignedBuf<T>; 2],
    pub(crate) cur: usize,
    pub(crate) types: Vec<u16>,
    pub(crate) plan: Vec<RowPlan>,
    pub(crate) faces: [FaceCondition; 4],
    pub(crate) solids: Vec<SolidInfo>,
    pub(crate) collision: Collision,
    pub(crate) smagorinsky: bool,
    pub(crate) params: CollisionParams<T>,
    /// Momentum exchanged by each special cell with each solid during the last step.
    pub(crate) forces: ForceSlots,
    pub(crate) row_bad: Vec<u8>,
    /// The tasks of the last in-place sweep by blocks (kept for their allocation).
    pub(crate) block_tasks: Vec<std::ops::Range<usize>>,
    pub(crate) step: u64,
    /// Factor applied to every Zou–He velocity face (start-up ramps).
    pub(crate) inlet_scale: f64,
    /// Neighbours and buffers of the x-face halo exchange (no peers on one rank).
    pub(crate) halo: SlabHalo,
    /// Seconds spent waiting for halos, accumulated.
    pub(crate) halo_wait_s: f64,
    /// How the populations are held (two buffers, or one in place).
    pub(crate) layout: Layout,
    /// The in-place kernel's halo gather, built at its first use.
    pub(crate) drain_plan: Option<DrainPlan>,
    /// During an in-place sweep: δρ of each open corner's diagonal neighbour from the step's
    /// start (W–S, E–S, E–N, W–N), read before the sweep overwrites its slots. None otherwise
    /// (the two-array kernel reads the untouched source buffer).
    pub(crate) corner_drho: Option<[T; 4]>,
    /// In place: the last push step ran with moving surfaces, whose refills the next step
    /// must drain again.
    pub(crate) redrain: bool,
    /// In place: all nine post-collision values of the neighbours' edge columns (west,
    /// east; direction-major over the padded rows), from the last
    /// [`Lattice::refresh_exchange_full`].
    pub(crate) full_halo: [Vec<T>; 2],
}

/// Cell types of the global lattice with its one-cell halo, row-major over the padded
/// `(nx + 2) × (ny + 2)` grid. Periodic halos take the type of the cell they wrap to
/// (so a solid touching a periodic face is bounced back from across it); walls take
/// their solid id, open faces their code; a corner next to a periodic face wraps too.
pub(crate) fn padded_types(setup: &LatticeSetup) -> Vec<u16> {
    let (nx, ny) = (setup.nx, setup.ny);
    let stride = nx + 2;
    let mut types = vec![FLUID; stride * (ny + 2)];
    for y in 0..ny {
        types[(y + 1) * stride + 1..(y + 1) * stride + 1 + nx]
            .copy_from_slice(&setup.cells[y * nx..(y + 1) * nx]);
    }
    let [w, e, s, n] = &setup.faces;
    let code = |f: &FaceCondition, face: Face| match f {
        FaceCondition::Wall { solid } => Some(*solid),
        f if f.is_open() => Some(face.open_code()),
        FaceCondition::Periodic => None,
        _ => Some(FLUID),
    };
    for yp in 1..=ny {
        types[yp * stride] = code(w, Face::West).unwrap_or(types[yp * stride + nx]);
        types[yp * stride + nx + 1] = code(e, Face::East).unwrap_or(types[yp * stride + 1]);
    }
    for xp in 1..=nx {
        types[xp] = code(s, Face::South).unwrap_or(types[ny * stride + xp]);
        types[(ny + 1) * stride + xp] = code(n, Face::North).unwrap_or(types[stride + xp]);
    }
    for (xp, yp, fx, fy) in [
        (0, 0, (w, Face::West), (s, Face::South)),
        (nx + 1, 0, (e, Face::East), (s, Face::South)),
        (0, ny + 1, (w, Face::West), (n, Face::North)),
        (nx + 1, ny + 1, (e, Face::East), (n, Face::North)),
    ] {
        let wrap_y = if yp == 0 { ny } else { 1 };
        let wrap_x = if xp == 0 { nx } else { 1 };
        types[yp * stride + xp] = match (fx.0, fy.0) {
            (_, FaceCondition::Periodic) => types[wrap_y * stride + xp],
            (FaceCondition::Periodic, _) => types[yp * stride + wrap_x],
            (_, FaceCondition::Wall { solid }) | (FaceCondition::Wall { solid }, _) => *solid,
            (a, b) if a.is_open() && b.is_open() => OPEN_CORNER,
            (a, _) if a.is_open() => fx.1.open_code(),
            (_, b) if b.is_open() => fy.1.open_code(),
            _ => FLUID,
        };
    }
    types
}

impl<T: Real> Lattice<T> {
    /// The cell types of this slab with its halo, row-major over the padded lattice
    /// (`(y + 1) * stride + x + 1`): [`FLUID`], a solid id or an open face's code.
    #[inline]
    pub fn padded_cell_types(&self) -> &[u16] {
        &self.types
    }

    /// Build a one-rank lattice at rest (ρ = 1, u = 0). Precondition: `setup` was validated
    /// by the scene layer (sizes match, periodic faces paired, solid ids in range).
    pub fn new(setup: LatticeSetup) -> Self {
        let partition = SlabPartition::uniform(setup.nx, 1).expect("nx ≥ 1");
        Self::new_slab(&setup, &partition, 0)
    }

    /// Build the slab of `rank` in `partition` of the global lattice `setup`, at rest.
    /// Its x halo columns hold the neighbours' cell types, so bounce-back against a solid
    /// on the other side of a rank face is the same as on one rank; faces shared with
    /// another rank become [`FaceCondition::Exchange`].
    pub fn new_slab(setup: &LatticeSetup, partition: &SlabPartition, rank: usize) -> Self {
        Self::build(setup, partition, rank, 2)
    }

    /// [`Lattice::new_slab`] for a lattice that goes in place ([`Lattice::make_in_place`])
    /// before its first step: the two-array kernel's second buffer is never allocated, so
    /// the populations' peak memory (and the kernel's zeroing of fresh pages at start) is
    /// one buffer, not two. Initial conditions, boundary updates and checkpoint imports work
    /// as on a two-array lattice until then; a two-array step, [`Lattice::previous_buffer`]
    /// and [`Lattice::buffers_mut`] panic (and so does anything that reads the previous
    /// buffer, such as `gather_previous`).
    pub fn new_slab_one_buffer(
        setup: &LatticeSetup,
        partition: &SlabPartition,
        rank: usize,
    ) -> Self {
        Self::build(setup, partition, rank, 1)
    }

    /// [`Lattice::new_slab`] with `buffers` (1 or 2) population buffers allocated.
    fn build(setup: &LatticeSetup, partition: &SlabPartition, rank: usize, buffers: usize) -> Self {
        let (gnx, ny) = (setup.nx, setup.ny);
        assert_eq!(setup.cells.len(), gnx * ny, "cell array size");
        let slab = partition.slab(rank);
        let (x0, nx) = (slab.x_begin, slab.width());
        let ranks = partition.ranks();
        let periodic_x = setup.faces[Face::West as usize] == FaceCondition::Periodic;
        let halo = SlabHalo::new(partition, rank, periodic_x && ranks > 1);
        let stride = nx + 2;
        // Planes padded to 16 values: every plane then has the same 64-byte alignment phase,
        // which the non-temporal stores of the bulk kernel rely on.
        let plane = (stride * (ny + 2)).div_ceil(16) * 16;
        let global = padded_types(setup);
        let mut types = vec![FLUID; plane];
        for yp in 0..ny + 2 {
            let src = yp * (gnx + 2) + x0;
            types[yp * stride..(yp + 1) * stride].copy_from_slice(&global[src..src + stride]);
        }
        let mut faces = setup.faces.clone();
        for (side, face) in [(Side::Left, Face::West), (Side::Right, Face::East)] {
            if halo.peer(side).is_some() {
                faces[face as usize] = FaceCondition::Exchange;
            }
        }
        for face in [Face::South, Face::North] {
            if let FaceCondition::Velocity(v) = &mut faces[face as usize] {
                *v = v[x0..x0 + nx].to_vec();
            }
        }
        let exchange =
            [Face::West, Face::East].map(|f| faces[f as usize] == FaceCondition::Exchange);
        let plan: Vec<RowPlan> = (0..ny)
            .map(|y| row_plan(&types, stride, nx, y, exchange))
            .collect();
        let ns = setup.solids.len();
        let forces = ForceSlots::new(&plan, nx, ns);
        // Rest state: h = f − w = 0 everywhere.
        let buf = [
            AlignedBuf::zeros_in_planes(Q, plane),
            if buffers == 2 {
                AlignedBuf::zeros_in_planes(Q, plane)
            } else {
                AlignedBuf::default()
            },
        ];
        let mut halo = halo;
        halo.set_message_bytes(HALO_DIRS * (ny + 2) * T::BYTES);
        Self {
            nx,
            ny,
            x0,
            global_nx: gnx,
            stride,
            plane,
            buf,
            cur: 0,
            types,
            plan,
            faces,
            solids: setup.solids.clone(),
            collision: setup.collision,
            smagorinsky: setup.smagorinsky.is_some(),
            params: CollisionParams::new(
                setup.collision,
                setup.tau0,
                setup.smagorinsky,
                setup.force,
            ),
            forces,
            row_bad: vec![0; ny],
            block_tasks: Vec::new(),
            step: 0,
            inlet_scale: 1.0,
            halo,
            halo_wait_s: 0.0,
            layout: Layout::TwoArray,
            drain_plan: None,
            corner_drho: None,
            redrain: false,
            full_halo: [Vec::new(), Vec::new()],
        }
    }

    /// Cells along x in this slab (the whole lattice on one rank).
    pub fn nx(&self) -> usize {
        self.nx
    }
    /// Global column of this slab's column 0.
    pub fn x_offset(&self) -> usize {
        self.x0
    }
    /// Cells along x in the whole lattice.
    pub fn global_nx(&self) -> usize {
        self.global_nx
    }
    /// Seconds spent waiting for halos so far (exposed communication).
    pub fn halo_wait_seconds(&self) -> f64 {
        self.halo_wait_s
    }
    /// Halo bytes this rank sends per step.
    pub fn halo_bytes_per_step(&self) -> u64 {
        self.halo.bytes_per_exchange()
    }
    /// Cells along y.
    pub fn ny(&self) -> usize {
        self.ny
    }
    /// Steps taken so far.
    pub fn steps_done(&self) -> u64 {
        self.step
    }
    /// The population buffers allocated: 2, or 1 in place or built to go in place (the
    /// second is then empty).
    pub(crate) fn buffers(&self) -> usize {
        if self.buf[1].is_empty() {
            1
        } else {
            2
        }
    }
    /// Bytes of distribution storage (both buffers, or the one in place or built to go in
    /// place; halo included).
    pub fn storage_bytes(&self) -> usize {
        self.buf.iter().map(|b| b.len()).sum::<usize>() * T::BYTES
    }
    /// Whether interior cell (x, y) is fluid.
    pub fn is_fluid(&self, x: usize, y: usize) -> bool {
        self.types[(y + 1) * self.stride + x + 1] == FLUID
    }
    /// Number of fluid cells in the interior.
    pub fn fluid_cells(&self) -> usize {
        (0..self.ny)
            .map(|y| (0..self.nx).filter(|&x| self.is_fluid(x, y)).count())
            .sum()
    }
    /// Scale every velocity face by `factor` from the next step on (start-up ramps).
    pub fn set_inlet_scale(&mut self, factor: f64) {
        self.inlet_scale = factor;
    }
    /// Solids known to the lattice.
    pub fn solids(&self) -> &[SolidInfo] {
        &self.solids
    }

    /// Padded linear index of interior cell (x, y) offset by (dx, dy).
    #[inline(always)]
    pub(crate) fn idx(&self, x: isize, y: isize) -> usize {
        ((y + 1) as usize) * self.stride + (x + 1) as usize
    }

    /// This slab's interior populations (shifted, h = f − w), `[9][ny][nx]` row-major:
    /// the whole fluid state, for checkpoints.
    pub fn export_interior(&self) -> Vec<T> {
        let src = &self.buf[self.cur];
        let acc = self.access();
        let mut out = Vec::with_capacity(Q * self.ny * self.nx);
        for i in 0..Q {
            for y in 0..self.ny {
                let k = self.idx(0, y as isize);
                out.extend((k..k + self.nx).map(|c| src[acc.own(i, c)]));
            }
        }
        out
    }

    /// Replace the state with `data` (as from [`Lattice::export_interior`]) after `step`
    /// steps, in both buffers (the one of [`Lattice::new_slab_one_buffer`]), and refill the
    /// local halos. Exchanged halos are filled by
    /// the next step or [`Lattice::refresh_exchange`].
    ///
    /// In place, the state takes the layout a run that had gone on would hold after `step`
    /// steps (local after an even step, pushed after an odd one, as the first step starts
    /// local), so that a restart or a rebalance takes the same steps as the run would have,
    /// at every link cell and rank face; after an odd step the pushed values are drained
    /// across the faces as the step would have. Collective when the slab has neighbours.
    pub fn import_interior(&mut self, data: &[T], step: u64, comm: &dyn Comm) {
        assert_eq!(data.len(), Q * self.ny * self.nx, "checkpoint block size");
        if self.in_place() {
            let pushed = step % 2 == 1;
            self.layout = if pushed {
                Layout::Pushed
            } else {
                Layout::Local
            };
            let acc = self.access();
            for i in 0..Q {
                for y in 0..self.ny {
                    let k = self.idx(0, y as isize);
                    let from = (i * self.ny + y) * self.nx;
                    for x in 0..self.nx {
                        self.buf[0][acc.own(i, k + x)] = data[from + x];
                    }
                }
            }
            self.step = step;
            self.redrain = false;
            if pushed {
                self.drain(comm);
            } else {
                self.fill_halo();
            }
            return;
        }
        for b in 0..self.buffers() {
            for i in 0..Q {
                for y in 0..self.ny {
                    let k = i * self.plane + self.idx(0, y as isize);
                    let from = (i * self.ny + y) * self.nx;
                    self.buf[b][k..k + self.nx].copy_from_slice(&data[from..from + self.nx]);
                }
            }
        }
        self.step = step;
        self.fill_halo();
    }

    /// Overwrite interior cell (x, y) with the equilibrium of (ρ, u) in both buffers (the
    /// one of [`Lattice::new_slab_one_buffer`]).
    /// Used for initial conditions.
    pub fn set_equilibrium(&mut self, x: usize, y: usize, rho: f64, u: [f64; 2]) {
        let k = self.idx(x as isize, y as isize);
        let eq = equilibrium(&Moments {
            drho: rho - 1.0,
            rho,
            ux: u[0],
            uy: u[1],
        });
        assert!(
            !self.in_place(),
            "initial conditions are set before the lattice goes in place"
        );
        for (i, h) in eq.iter().enumerate() {
            for b in 0..self.buffers() {
                self.buf[b][i * self.plane + k] = T::from_f64(*h);
            }
        }
    }
}
