//! Lattice storage, cell types and the per-row execution plan.

use super::aligned::AlignedBuf;
use super::collision::{equilibrium, Collision, CollisionParams, Moments};
use super::d2q9::{CX, CY, Q};
use super::real::Real;
use thiserror::Error;

/// Cell type code for fluid (including halo cells filled by copies: periodic, free-slip, outflow).
pub const FLUID: u16 = 0;
/// First type code of the open-boundary halo cells (west, east, south, north, corner).
pub const OPEN_WEST: u16 = 0xFFF0;
/// Open east halo.
pub const OPEN_EAST: u16 = 0xFFF1;
/// Open south halo.
pub const OPEN_SOUTH: u16 = 0xFFF2;
/// Open north halo.
pub const OPEN_NORTH: u16 = 0xFFF3;
/// Halo corner between two open faces.
pub const OPEN_CORNER: u16 = 0xFFF4;
/// Largest solid id (solid ids are `1..=MAX_SOLID`).
pub const MAX_SOLID: u16 = 0xFFEF;

/// The four faces of the lattice, in the order boundary arrays use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Face {
    /// x = 0.
    West = 0,
    /// x = nx − 1.
    East = 1,
    /// y = 0.
    South = 2,
    /// y = ny − 1.
    North = 3,
}

impl Face {
    /// All faces.
    pub const ALL: [Face; 4] = [Face::West, Face::East, Face::South, Face::North];
    /// Quarter turns that map the west-face frame onto this face (inward normals: W +x, S +y, E −x, N −y).
    pub fn quarter_turns(self) -> usize {
        match self {
            Face::West => 0,
            Face::South => 1,
            Face::East => 2,
            Face::North => 3,
        }
    }
    /// The halo type code of this face when it is open.
    pub fn open_code(self) -> u16 {
        OPEN_WEST + self as u16
    }
}

/// A face's boundary condition in lattice units.
#[derive(Debug, Clone, PartialEq)]
pub enum FaceCondition {
    /// Wraps to the opposite face (which must be periodic too).
    Periodic,
    /// Half-way bounce-back wall; `solid` indexes [`LatticeSetup::solids`] (its velocity
    /// makes it a moving wall, Ladd 1994).
    Wall {
        /// Solid id (≥ 1).
        solid: u16,
    },
    /// Specular reflection (free slip).
    FreeSlip,
    /// Zero-gradient outflow: the halo copies the last interior column/row.
    Outflow,
    /// Zou–He velocity; one velocity (lattice units) per cell along the face.
    Velocity(Vec<[f64; 2]>),
    /// Zou–He pressure, as density deviation ρ − 1.
    Pressure(f64),
}

impl FaceCondition {
    /// True for Zou–He faces (velocity or pressure).
    pub fn is_open(&self) -> bool {
        matches!(
            self,
            FaceCondition::Velocity(_) | FaceCondition::Pressure(_)
        )
    }
}

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
    /// Step that produced the bad value.
    pub step: u64,
    /// Cell x.
    pub x: usize,
    /// Cell y.
    pub y: usize,
    /// The offending density.
    pub density: f64,
}

/// Per-row plan: runs of bulk cells and the special cells between them.
#[derive(Debug, Clone, Default)]
pub(crate) struct RowPlan {
    /// Half-open `[x0, x1)` runs of cells whose 8 neighbours are all plain fluid.
    pub bulk: Vec<(u32, u32)>,
    /// Fluid cells needing bounce-back or open-boundary reconstruction.
    pub special: Vec<u32>,
}

/// The D2Q9 lattice of one rank: two SoA buffers of shifted populations plus geometry.
pub struct Lattice<T: Real> {
    pub(crate) nx: usize,
    pub(crate) ny: usize,
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
    /// Per-row momentum-exchange force on each solid (rows × solids), reduced in row order.
    pub(crate) row_force: Vec<[f64; 2]>,
    pub(crate) row_bad: Vec<u8>,
    pub(crate) force_on: Vec<[f64; 2]>,
    pub(crate) step: u64,
    /// Factor applied to every Zou–He velocity face (start-up ramps).
    pub(crate) inlet_scale: f64,
}

impl<T: Real> Lattice<T> {
    /// Build a lattice at rest (ρ = 1, u = 0). Precondition: `setup` was validated by the
    /// scene layer (sizes match, periodic faces paired, solid ids in range).
    pub fn new(setup: LatticeSetup) -> Self {
        let (nx, ny) = (setup.nx, setup.ny);
        assert_eq!(setup.cells.len(), nx * ny, "cell array size");
        let stride = nx + 2;
        // Planes padded to 16 values: every plane then has the same 64-byte alignment phase,
        // which the non-temporal stores of the bulk kernel rely on.
        let plane = (stride * (ny + 2)).div_ceil(16) * 16;
        let mut types = vec![FLUID; plane];
        for y in 0..ny {
            for x in 0..nx {
                types[(y + 1) * stride + x + 1] = setup.cells[y * nx + x];
            }
        }
        let halo_code = |f: &FaceCondition, face: Face| match f {
            FaceCondition::Wall { solid } => *solid,
            f if f.is_open() => face.open_code(),
            _ => FLUID,
        };
        let [w, e, s, n] = &setup.faces;
        for yp in 1..=ny {
            types[yp * stride] = halo_code(w, Face::West);
            types[yp * stride + nx + 1] = halo_code(e, Face::East);
        }
        for xp in 1..=nx {
            types[xp] = halo_code(s, Face::South);
            types[(ny + 1) * stride + xp] = halo_code(n, Face::North);
        }
        for (xp, yp, fx, fy) in [
            (0, 0, (w, Face::West), (s, Face::South)),
            (nx + 1, 0, (e, Face::East), (s, Face::South)),
            (0, ny + 1, (w, Face::West), (n, Face::North)),
            (nx + 1, ny + 1, (e, Face::East), (n, Face::North)),
        ] {
            let code = match (fx.0, fy.0) {
                (_, FaceCondition::Wall { solid }) | (FaceCondition::Wall { solid }, _) => *solid,
                (a, b) if a.is_open() && b.is_open() => OPEN_CORNER,
                (a, _) if a.is_open() => fx.1.open_code(),
                (_, b) if b.is_open() => fy.1.open_code(),
                _ => FLUID,
            };
            types[yp * stride + xp] = code;
        }
        let plan = (0..ny).map(|y| row_plan(&types, stride, nx, y)).collect();
        // Rest state: h = f − w = 0 everywhere.
        let buf = [AlignedBuf::zeros(Q * plane), AlignedBuf::zeros(Q * plane)];
        let ns = setup.solids.len();
        Self {
            nx,
            ny,
            stride,
            plane,
            buf,
            cur: 0,
            types,
            plan,
            faces: setup.faces,
            solids: setup.solids,
            collision: setup.collision,
            smagorinsky: setup.smagorinsky.is_some(),
            params: CollisionParams::new(
                setup.collision,
                setup.tau0,
                setup.smagorinsky,
                setup.force,
            ),
            row_force: vec![[0.0; 2]; ny * ns.max(1)],
            row_bad: vec![0; ny],
            force_on: vec![[0.0; 2]; ns],
            step: 0,
            inlet_scale: 1.0,
        }
    }

    /// Cells along x.
    pub fn nx(&self) -> usize {
        self.nx
    }
    /// Cells along y.
    pub fn ny(&self) -> usize {
        self.ny
    }
    /// Steps taken so far.
    pub fn steps_done(&self) -> u64 {
        self.step
    }
    /// Bytes of distribution storage (both buffers, halo included).
    pub fn storage_bytes(&self) -> usize {
        2 * Q * self.plane * T::BYTES
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
    /// Momentum-exchange force (lattice units) on solid `id` during the last step.
    pub fn force_on(&self, id: u16) -> [f64; 2] {
        self.force_on[id as usize - 1]
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

    /// Overwrite interior cell (x, y) with the equilibrium of (ρ, u) in both buffers.
    /// Used for initial conditions.
    pub fn set_equilibrium(&mut self, x: usize, y: usize, rho: f64, u: [f64; 2]) {
        let k = self.idx(x as isize, y as isize);
        let eq = equilibrium(&Moments {
            drho: rho - 1.0,
            rho,
            ux: u[0],
            uy: u[1],
        });
        for (i, h) in eq.iter().enumerate() {
            for b in 0..2 {
                self.buf[b][i * self.plane + k] = T::from_f64(*h);
            }
        }
    }
}

/// Whether every neighbour of padded cell `k` is plain fluid (the bulk kernel may pull it
/// without boundary handling).
pub(crate) fn is_plain(types: &[u16], stride: usize, k: usize) -> bool {
    (1..Q).all(|i| {
        types[(k as isize - CX[i] as isize - CY[i] as isize * stride as isize) as usize] == FLUID
    })
}

/// Classify one interior row into bulk runs and special cells.
fn row_plan(types: &[u16], stride: usize, nx: usize, y: usize) -> RowPlan {
    let yp = y + 1;
    let mut plan = RowPlan::default();
    let mut run_start: Option<u32> = None;
    for x in 0..nx {
        let k = yp * stride + x + 1;
        let fluid = types[k] == FLUID;
        let plain = fluid && is_plain(types, stride, k);
        match (plain, run_start) {
            (true, None) => run_start = Some(x as u32),
            (false, Some(s)) => {
                plan.bulk.push((s, x as u32));
                run_start = None;
            }
            _ => {}
        }
        if fluid && !plain {
            plan.special.push(x as u32);
        }
    }
    if let Some(s) = run_start {
        plan.bulk.push((s, nx as u32));
    }
    plan
}
