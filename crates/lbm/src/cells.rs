//! Cell types and faces: the codes of the padded cell-type array (fluid, solid ids, open
//! faces) and the conditions a face of the lattice can carry.

use super::d2q9::{CX, CY, Q};

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
    /// Half-way bounce-back wall; `solid` indexes [`crate::lattice::LatticeSetup::solids`] (its velocity
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
    /// A face shared with another rank (or with oneself across a periodic wrap on several
    /// ranks): its halo is filled by the halo exchange, never by the lattice itself.
    Exchange,
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

/// Populations that cross one x face: 3 of the 9.
pub(crate) const HALO_DIRS: usize = 3;

/// Whether every neighbour of padded cell `k` is plain fluid (the bulk kernel may pull it
/// without boundary handling).
pub(crate) fn is_plain(types: &[u16], stride: usize, k: usize) -> bool {
    (1..Q).all(|i| {
        types[(k as isize - CX[i] as isize - CY[i] as isize * stride as isize) as usize] == FLUID
    })
}
