//! The plans a fluid backend executes for moving solid surfaces (see [`super::moving`]):
//! plain data in lattice units, grouped by row. Nothing here knows about grains.
//!
//! * [`LinkPlan`]: fluid cells next to a moving surface, each with its links to it and the
//!   rigid motions the links' wall terms come from.
//! * [`PsmPlan`]: partially saturated cells, each with its solid shares.
//! * [`Refill`]: a cell a surface has just uncovered, to be rebuilt.

use super::d2q9::{CX, CY, Q};

/// One link of a fluid cell to a moving surface: population `dir` enters the cell from its
/// solid neighbour at x − c_dir, which belongs to the rigid body `body` of the plan. Packed
/// in four bytes (the plan is rewritten every step, so its size is its cost).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MovingLink(u32);

impl MovingLink {
    /// The link of direction `dir` (1..=8) to body `body` (< 2²⁸).
    #[inline]
    pub fn new(dir: usize, body: u32) -> Self {
        debug_assert!((1..Q).contains(&dir) && body < 1 << 28);
        Self(body << 4 | dir as u32)
    }

    /// The incoming population (1..=8).
    #[inline]
    pub fn dir(self) -> usize {
        (self.0 & 15) as usize
    }

    /// Index of the body in [`LinkPlan::bodies`].
    #[inline]
    pub fn body(self) -> usize {
        (self.0 >> 4) as usize
    }

    /// The packed word: body · 16 + dir (a device kernel unpacks it).
    #[inline]
    pub fn bits(self) -> u32 {
        self.0
    }
}

/// The rigid motion of one moving surface, lattice units: the wall's velocity at a point p
/// is u + ω × (p − c) (seed eq. 5.46).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RigidMotion {
    /// Velocity u of the centre (cells per step).
    pub velocity: [f64; 2],
    /// Angular velocity ω (radians per step, counter-clockwise).
    pub omega: f64,
    /// Centre c (global lattice coordinates: cell (x, y) spans [x, x+1) × [y, y+1)).
    pub centre: [f64; 2],
}

impl RigidMotion {
    /// The body's velocity at point `p` (global lattice coordinates): u + ω × (p − c)
    /// (seed eq. 5.46).
    #[inline]
    pub fn velocity_at(&self, p: [f64; 2]) -> [f64; 2] {
        let r = [p[0] - self.centre[0], p[1] - self.centre[1]];
        [
            self.velocity[0] - self.omega * r[1],
            self.velocity[1] + self.omega * r[0],
        ]
    }
}

/// Centre (global lattice coordinates) of the cell at padded index `k` in local row `y` of a
/// slab with row stride `stride` whose local column 0 is global column `x0`.
#[inline]
pub fn cell_centre(stride: usize, x0: i64, k: usize, y: usize) -> [f64; 2] {
    let x = k as i64 - ((y + 1) * stride) as i64 - 1;
    [(x + x0) as f64 + 0.5, y as f64 + 0.5]
}

/// Fluid cells next to moving surfaces with their links, compressed by cell: the links of
/// `cells[c]` are `links[start[c]..start[c + 1]]`. Cells are padded indices of interior
/// plain-fluid cells, each at most once, grouped by row: row y's are
/// `cells[rows[y]..rows[y + 1]]` (any order within a row).
///
/// The moving-wall term of each link is computed by the executing sweep from its body's
/// rigid motion at the link's midpoint ([`LinkPlan::wall`]), so the plan holds four bytes
/// per link (twelve with interpolation).
#[derive(Debug, Clone, Default)]
pub struct LinkPlan {
    /// Offsets of each row's cells (ny + 1 values; empty for an empty plan).
    pub rows: Vec<u32>,
    /// Padded cell indices.
    pub cells: Vec<u32>,
    /// Offsets into `links`, one more than `cells`.
    pub start: Vec<u32>,
    /// The links, cell by cell.
    pub links: Vec<MovingLink>,
    /// Where each link meets the surface, as a fraction q of the link from the cell centre,
    /// one per link; empty when every link is half-way (q = ½). Below ½ the post-collision
    /// value of the fluid neighbour at x + c_dir is interpolated, so the planner must give
    /// ½ where that neighbour is not plain fluid outside every surface.
    pub fractions: Vec<f64>,
    /// The rigid motions the links refer to.
    pub bodies: Vec<RigidMotion>,
    /// Global x of local column 0 (a cell's centre is (x0 + x + ½, y + ½)).
    pub x0: i64,
}

impl LinkPlan {
    /// Empty the plan, keeping its allocations.
    pub fn clear(&mut self) {
        self.rows.clear();
        self.cells.clear();
        self.start.clear();
        self.start.push(0);
        self.links.clear();
        self.fractions.clear();
        self.bodies.clear();
    }

    /// The fraction q of link `l` (see [`LinkPlan::fractions`]).
    #[inline]
    pub fn q(&self, l: usize) -> f64 {
        if self.fractions.is_empty() {
            0.5
        } else {
            self.fractions[l]
        }
    }

    /// Ladd's moving-wall term 2 w_i ρ_w (c_i·u_w)/c_s², ρ_w = 1, of `link` from the cell at
    /// padded index `k` in local row `y` of a lattice with row stride `stride` (Ladd 1994,
    /// eq. 3.3; seed eq. 5.45): u_w is the body's velocity at the link's midpoint.
    #[inline]
    pub fn wall(&self, stride: usize, k: usize, y: usize, link: MovingLink) -> f64 {
        let i = link.dir();
        let centre = cell_centre(stride, self.x0, k, y);
        let mid = [
            centre[0] - 0.5 * CX[i] as f64,
            centre[1] - 0.5 * CY[i] as f64,
        ];
        let u = self.bodies[link.body()].velocity_at(mid);
        super::boundary::moving_wall_term(i, u)
    }
}

/// One solid's share of a partially saturated cell.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SolidShare {
    /// Its weight B_s in the collision (the cell's B split by solid fraction).
    pub b: f64,
    /// Index of the solid's rigid motion in [`PsmPlan::bodies`].
    pub body: u32,
}

/// Partially saturated cells with their solid shares, compressed and grouped by row like
/// [`LinkPlan`].
///
/// The solid's velocity at a cell is computed by the executing sweep from its body's rigid
/// motion at the cell centre ([`PsmPlan::velocity`]), so the plan holds sixteen bytes per
/// share.
#[derive(Debug, Clone, Default)]
pub struct PsmPlan {
    /// Offsets of each row's cells (ny + 1 values; empty for an empty plan).
    pub rows: Vec<u32>,
    /// Padded cell indices (interior fluid cells, each at most once), increasing within
    /// each row (the in-place sweep walks them beside its runs, and checks this).
    pub cells: Vec<u32>,
    /// Offsets into `shares`, one more than `cells`.
    pub start: Vec<u32>,
    /// Total weight B of each cell (Noble & Torczynski 1998, eq. 9).
    pub total: Vec<f64>,
    /// The shares, cell by cell.
    pub shares: Vec<SolidShare>,
    /// The rigid motions the shares refer to.
    pub bodies: Vec<RigidMotion>,
    /// Global x of local column 0 (a cell's centre is (x0 + x + ½, y + ½)).
    pub x0: i64,
}

impl PsmPlan {
    /// Empty the plan, keeping its allocations.
    pub fn clear(&mut self) {
        self.rows.clear();
        self.cells.clear();
        self.start.clear();
        self.start.push(0);
        self.total.clear();
        self.shares.clear();
        self.bodies.clear();
    }

    /// Velocity (lattice units) of `share`'s body at the centre of the cell at padded index
    /// `k` in local row `y` of a lattice with row stride `stride`: u + ω × (p − c) (seed
    /// eq. 5.46).
    #[inline]
    pub fn velocity(&self, stride: usize, k: usize, y: usize, share: SolidShare) -> [f64; 2] {
        self.bodies[share.body as usize].velocity_at(cell_centre(stride, self.x0, k, y))
    }

    /// Local row of padded cell `k` in a lattice with row stride `stride`.
    #[inline]
    pub fn row_of(stride: usize, k: usize) -> usize {
        k / stride - 1
    }
}

/// The momenta of a plan summed per group of bodies and column by the backend that executes
/// it, instead of reported one per link or share: a device backend then sends back one load
/// per group and column (about a dozen per grain) rather than one momentum per link or share.
///
/// A group is one body, or the images of one body across a periodic y face (they share
/// their columns, and the host sums them into the same column sums). The caller fills the
/// boxes and groups before the sweep; a backend that can (see
/// [`crate::FluidBackend::sums_per_body`]) fills `sums` and `counts` and sets `made`; a
/// device backend leaves the per-link or per-share momenta empty, the CPU's in-place sweep
/// sums only some bodies (see `body_slot`) and reports the momenta of the others' shares
/// (a summed body's entries may be left as they were). Each slot is
/// summed over the cells of its column in increasing row (the group's bodies in turn, in
/// increasing first row), each cell's links or shares in plan order: the order of a serial
/// walk of the plan restricted to the slot, so it does not depend on how the lattice is
/// split into slabs of columns.
#[derive(Debug, Clone, Default)]
pub struct BodyColumns {
    /// Per body of the plan: `[first local column, columns, first local row, rows]` of the
    /// box that holds every plan cell with a link or share of that body (clipped to the
    /// slab's interior). Empty when no sums are wanted.
    pub boxes: Vec<[u32; 4]>,
    /// The bodies, group by group, each group's in increasing first row of their boxes
    /// (which span the same columns).
    pub members: Vec<u32>,
    /// Where each group starts in `members`; one more value than groups.
    pub groups: Vec<u32>,
    /// Each group's first slot (one slot per column of its boxes); one more value than
    /// groups.
    pub first: Vec<u32>,
    /// Out, per slot: the momentum the group receives, [p_x, p_y, torque about the centre
    /// of the body each term belongs to], lattice units: −(f*_ī + f_i) c_i at the link's
    /// midpoint (seed eqs. 5.47–5.48) or a share's momentum at its cell's centre (seed eq.
    /// 5.54).
    pub sums: Vec<[f64; 3]>,
    /// Out, per slot: how many links or shares it sums (0: the column has none).
    pub counts: Vec<u32>,
    /// Out: the backend made the sums.
    pub made: bool,
    /// Out, from a backend that sums only some bodies (the CPU's in-place sweep, which
    /// reports the momenta of the others' shares): per body, the slot of its group's local
    /// column 0 (a cell of local column x added to slot `body_slot[b] + x`), or [`NO_SLOT`] for a body
    /// it did not sum, whose shares the host collects from their momenta. Empty when every
    /// body was summed (a device backend).
    pub body_slot: Vec<i64>,
}

/// [`BodyColumns::body_slot`] of a body the backend did not sum.
pub const NO_SLOT: i64 = i64::MIN;

/// Which kind of plan a step will execute (see [`crate::FluidBackend::sums_per_body`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlanKind {
    /// A [`LinkPlan`].
    Links,
    /// A [`PsmPlan`].
    Partial,
}

impl BodyColumns {
    /// No sums wanted.
    pub fn clear(&mut self) {
        self.boxes.clear();
        self.members.clear();
        self.groups.clear();
        self.first.clear();
        self.sums.clear();
        self.counts.clear();
        self.made = false;
        self.body_slot.clear();
    }

    /// Whether sums are wanted (boxes given).
    pub fn wanted(&self) -> bool {
        !self.boxes.is_empty()
    }

    /// Slots of all groups.
    pub fn slots(&self) -> usize {
        self.first.last().map_or(0, |&n| n as usize)
    }

    /// Bodies of group `j`.
    pub fn group(&self, j: usize) -> &[u32] {
        &self.members[self.groups[j] as usize..self.groups[j + 1] as usize]
    }

    /// The columns `[first local column, columns]` of group `j`: those of its bodies whose
    /// boxes are not empty (they agree), or none.
    pub fn columns(&self, j: usize) -> [u32; 2] {
        self.group(j)
            .iter()
            .map(|&b| self.boxes[b as usize])
            .find(|bx| bx[1] > 0)
            .map_or([0, 0], |bx| [bx[0], bx[1]])
    }
}

/// A cell that a moving surface has just uncovered, to be rebuilt.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Refill {
    /// Padded cell index.
    pub cell: u32,
    /// Bit i set: the neighbour at x + c_i is fluid to average the density from.
    pub neighbours: u16,
    /// Direction of the neighbour whose non-equilibrium part is copied (Caiazzo 2005), or 0
    /// for the equilibrium alone.
    pub extrapolate: u8,
    /// Velocity of the surface at the cell (lattice units).
    pub velocity: [f64; 2],
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A share's solid velocity is its body's u + ω × (p − c) at the centre p of its cell,
    /// in global coordinates, for a slab that starts at global column x0.
    #[test]
    fn share_velocity_is_the_body_motion_at_the_cell_centre() {
        let (stride, x0) = (12, 40);
        let plan = PsmPlan {
            bodies: vec![
                RigidMotion::default(),
                RigidMotion {
                    velocity: [0.01, -0.02],
                    omega: 0.003,
                    centre: [45.25, 2.75],
                },
            ],
            x0,
            ..PsmPlan::default()
        };
        // Local cell (3, 4): padded index (4 + 1) · stride + 3 + 1, centre (43.5, 4.5).
        let k = 5 * stride + 4;
        assert_eq!(PsmPlan::row_of(stride, k), 4);
        let share = SolidShare { b: 0.5, body: 1 };
        let u = plan.velocity(stride, k, 4, share);
        let r = [43.5 - 45.25, 4.5 - 2.75];
        let want = [0.01 - 0.003 * r[1], -0.02 + 0.003 * r[0]];
        assert_eq!(u, want);
        // The other body stands still.
        assert_eq!(
            plan.velocity(stride, k, 4, SolidShare { body: 0, ..share }),
            [0.0; 2]
        );
    }
}
