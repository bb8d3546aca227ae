//! One interface for the three coupling schemes. A scheme decides how grains cover cells
//! (map), what the fluid's sweep does at their surfaces (plan), how the momenta it reports
//! become loads per grain and column (collect), and what happens to the cells a moving
//! grain covers or uncovers (hand-over). [`Interface`] names those steps; half-way and
//! interpolated bounce-back ([`LinkCells`] with [`HalfWay`] or [`Bouzidi`] links) and the
//! partially saturated method ([`PartialCells`]) implement them. [`Cells`] holds the one a
//! scene chose: the only place that branches on the scheme.

use super::link_cells::{Bouzidi, HalfWay, LinkCells, LinkRule};
use super::map::{GrainView, SlabFrame};
use super::partial_cells::PartialCells;
use super::sums::{ColumnSums, Window};
use super::{Refill, Scheme};
use decomposition::Comm;
use lbm::moving::{BodyColumns, MovingCells, PlanKind};
use lbm::{FluidBackend, Lattice, Real};

/// What every scheme's coupler keeps: its slab, the grains of the last map and their ids,
/// the loads of the last exchange and hand-over, the pass timers, and the per-body sums a
/// fluid backend may make.
pub(super) struct Common {
    pub(super) frame: SlabFrame,
    /// The grain views and ids of the last map.
    pub(super) mapped: Vec<GrainView>,
    pub(super) owner_ids: Vec<u64>,
    /// The plan's boxes per body, and the fluid backend's sums in them when it makes them
    /// (`body_sums.rs`).
    pub(super) body_columns: BodyColumns,
    /// Per body of the plan: its window of the column sums (scratch of the collect).
    pub(super) body_windows: Vec<Window>,
    /// Seconds spent in each of [`super::PASSES`] on this rank.
    pub(super) passes: [f64; 6],
    /// Loads of the last exchange and of the last remap's hand-over, per grain and column.
    pub(super) sums: ColumnSums,
    pub(super) handover: ColumnSums,
}

impl Common {
    pub(super) fn new(frame: SlabFrame) -> Self {
        Self {
            frame,
            mapped: Vec::new(),
            owner_ids: Vec::new(),
            body_columns: BodyColumns::default(),
            body_windows: Vec::new(),
            passes: [0.0; 6],
            sums: ColumnSums::default(),
            handover: ColumnSums::default(),
        }
    }

    /// Global column of padded cell `k`.
    #[inline]
    pub(super) fn column(&self, k: usize) -> usize {
        (self.frame.local(k).0 + self.frame.x0 as i64) as usize
    }
}

/// A coupling scheme, in the order of a coupled step. `views` are the grains in view of the
/// slab (owned and ghosts) in increasing id, `ids` their ids.
pub(super) trait Interface {
    /// The scheme, as scenes name it.
    fn scheme(&self) -> Scheme;

    /// Map the grains onto the cells before the first step (no hand-over). `c.mapped` still
    /// holds the grains of an earlier start, if any.
    fn start<T: Real>(
        &mut self,
        c: &mut Common,
        lat: &Lattice<T>,
        views: &[GrainView],
        ids: &[u64],
    );

    /// Map the grains again after they moved, hand the cells that changed hands over (loads
    /// into `c.handover`, which the caller has reset), and record `views` and `ids` in `c`.
    fn remap<T: Real>(
        &mut self,
        c: &mut Common,
        fluid: &mut dyn FluidBackend<T>,
        views: &[GrainView],
        ids: &[u64],
        comm: &dyn Comm,
    );

    /// Whether [`Interface::remap`] hands loads over (the owners must then sum them).
    fn hands_over(&self) -> bool;

    /// Plan the cells at the grains' surfaces for the sweep, from the last map.
    fn plan<T: Real>(&mut self, c: &Common, lat: &Lattice<T>, views: &[GrainView]);

    /// The kind of plan, for a fluid backend deciding whether to sum per body.
    fn plan_kind(&self) -> PlanKind;

    /// The planned cells for the fluid's sweep, with where their momenta go.
    fn moving<'a>(&'a mut self, body_columns: &'a mut BodyColumns) -> MovingCells<'a>;

    /// The plan's bodies: how many, each one's grain (view) and centre, and how many links
    /// or shares the plan holds.
    fn bodies(&self) -> usize;
    fn body(&self, b: usize) -> (usize, [f64; 2]);
    fn planned(&self) -> usize;

    /// Add each link's or share's momentum, as the sweep reported it, to its grain's column
    /// sums (`c.sums`, reset by the caller).
    fn collect(&mut self, c: &mut Common, views: &[GrainView]);

    /// [`Interface::collect`] for the bodies a backend's per-body sums did not hold
    /// (`BodyColumns::body_slot`); returns how many links or shares it added.
    fn collect_unslotted(&mut self, c: &mut Common, views: &[GrainView]) -> usize;

    /// Plan cell `n`'s padded cell and the grain (view) of its first link or share.
    fn bad_cell(&self, n: usize) -> (usize, u32);

    /// Set the fluid under the grains to rest at their velocity, where the scheme leaves
    /// it unused (for fields that show the grains).
    fn fill_rest<T: Real>(
        &mut self,
        c: &Common,
        fluid: &mut dyn FluidBackend<T>,
        views: &[GrainView],
    );

    /// Solid fraction of every interior cell (padded index → Σ ε, capped at 1).
    fn solid_fraction(&self, c: &Common, out: &mut [f64]);

    /// This rank's counts of [`super::COUNTS`].
    fn counts(&self) -> [u64; 6];

    /// Whether the fluid in fluid cell `k` counts as fluid in the momentum balance (not
    /// covered by a grain).
    fn is_open(&self, k: usize) -> bool;
}

/// The scheme a scene chose.
pub(super) enum Cells {
    BounceBack(LinkCells<HalfWay>),
    Interpolated(LinkCells<Bouzidi>),
    Partial(PartialCells),
}

impl Cells {
    /// The link plan's cells (padded) of the last exchange; none with partially saturated
    /// cells.
    pub(crate) fn link_cells(&self) -> &[u32] {
        match self {
            Cells::BounceBack(l) => &l.links.cells,
            Cells::Interpolated(l) => &l.links.cells,
            Cells::Partial(_) => &[],
        }
    }

    /// The cells under bounce-back grains (padded) and their rest velocities (lattice
    /// units), as the last `fill_rest` set them; none with partially saturated cells.
    pub(crate) fn rest_cells(&self) -> (&[u32], &[[f64; 2]]) {
        match self {
            Cells::BounceBack(l) => (&l.rest_cells, &l.rest),
            Cells::Interpolated(l) => (&l.rest_cells, &l.rest),
            Cells::Partial(_) => (&[], &[]),
        }
    }

    /// The scheme's cells on slab `frame`.
    pub(super) fn new(scheme: Scheme, refill: Refill, frame: SlabFrame) -> Self {
        match scheme {
            Scheme::BounceBack => HalfWay::wrap(LinkCells::new(refill, frame)),
            Scheme::Interpolated => Bouzidi::wrap(LinkCells::new(refill, frame)),
            Scheme::Psm => Cells::Partial(PartialCells::default()),
        }
    }
}

/// `$body` with `$i` bound to the chosen scheme's cells.
macro_rules! dispatch {
    ($cells:expr, $i:ident => $body:expr) => {
        match $cells {
            Cells::BounceBack($i) => $body,
            Cells::Interpolated($i) => $body,
            Cells::Partial($i) => $body,
        }
    };
}

impl Interface for Cells {
    fn scheme(&self) -> Scheme {
        dispatch!(self, i => i.scheme())
    }
    fn start<T: Real>(
        &mut self,
        c: &mut Common,
        lat: &Lattice<T>,
        views: &[GrainView],
        ids: &[u64],
    ) {
        dispatch!(self, i => i.start(c, lat, views, ids))
    }
    fn remap<T: Real>(
        &mut self,
        c: &mut Common,
        fluid: &mut dyn FluidBackend<T>,
        views: &[GrainView],
        ids: &[u64],
        comm: &dyn Comm,
    ) {
        dispatch!(self, i => i.remap(c, fluid, views, ids, comm))
    }
    fn hands_over(&self) -> bool {
        dispatch!(self, i => i.hands_over())
    }
    fn plan<T: Real>(&mut self, c: &Common, lat: &Lattice<T>, views: &[GrainView]) {
        dispatch!(self, i => i.plan(c, lat, views))
    }
    fn plan_kind(&self) -> PlanKind {
        dispatch!(self, i => i.plan_kind())
    }
    fn moving<'a>(&'a mut self, body_columns: &'a mut BodyColumns) -> MovingCells<'a> {
        dispatch!(self, i => i.moving(body_columns))
    }
    fn bodies(&self) -> usize {
        dispatch!(self, i => i.bodies())
    }
    fn body(&self, b: usize) -> (usize, [f64; 2]) {
        dispatch!(self, i => i.body(b))
    }
    fn planned(&self) -> usize {
        dispatch!(self, i => i.planned())
    }
    fn collect(&mut self, c: &mut Common, views: &[GrainView]) {
        dispatch!(self, i => i.collect(c, views))
    }
    fn collect_unslotted(&mut self, c: &mut Common, views: &[GrainView]) -> usize {
        dispatch!(self, i => i.collect_unslotted(c, views))
    }
    fn bad_cell(&self, n: usize) -> (usize, u32) {
        dispatch!(self, i => i.bad_cell(n))
    }
    fn fill_rest<T: Real>(
        &mut self,
        c: &Common,
        fluid: &mut dyn FluidBackend<T>,
        views: &[GrainView],
    ) {
        dispatch!(self, i => i.fill_rest(c, fluid, views))
    }
    fn solid_fraction(&self, c: &Common, out: &mut [f64]) {
        dispatch!(self, i => i.solid_fraction(c, out))
    }
    fn counts(&self) -> [u64; 6] {
        dispatch!(self, i => i.counts())
    }
    fn is_open(&self, k: usize) -> bool {
        dispatch!(self, i => i.is_open(k))
    }
}
