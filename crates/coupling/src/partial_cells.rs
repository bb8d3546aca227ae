//! The partially saturated method's side of the [`Interface`]: every cell a grain overlaps
//! carries a share of it, weighted by the exact solid fraction (`psm.rs`). Nothing is
//! handed over when grains move: the shares are mapped afresh.

use super::geometry::{ColumnLine, RowLine};
use super::interface::{Common, Interface};
use super::map::{GrainView, ShareRow};
use super::Scheme;
use decomposition::Comm;
use lbm::moving::{BodyColumns, MovingCells, PlanKind, PsmPlan};
use lbm::{FluidBackend, Lattice, Real};

/// A grain image (the grain or a periodic copy) that reaches the slab's rows.
#[derive(Debug, Clone, Copy)]
pub(super) struct DiskImage {
    /// The grain: its index among the views.
    pub(super) grain: u32,
    /// The image's centre (lattice units).
    pub(super) centre: [f64; 2],
    /// The first and last row of the slab it reaches.
    pub(super) rows: [u32; 2],
}

/// The partially saturated cells of one slab.
#[derive(Default)]
pub(super) struct PartialCells {
    /// Solid fractions by row, each row sorted by cell.
    pub(super) share_rows: Vec<ShareRow>,
    /// The grain images that reach the slab's rows, as the map finds them, with the line
    /// tables of their exact cell areas (`geometry::CellAreas`: image i's vertical lines are
    /// `column_lines[column_start[i]..column_start[i + 1]]`, its horizontal lines likewise).
    pub(super) disk_images: Vec<DiskImage>,
    pub(super) column_start: Vec<u32>,
    pub(super) column_lines: Vec<ColumnLine>,
    pub(super) row_start: Vec<u32>,
    pub(super) row_lines: Vec<RowLine>,
    /// The images (indices into `disk_images`) by row, with where each row starts.
    pub(super) image_order: Vec<u32>,
    pub(super) image_rows: Vec<u32>,
    /// The plan of the last exchange.
    pub(super) psm: PsmPlan,
    /// Momentum per share of the last exchange.
    pub(super) share_momentum: Vec<[f64; 2]>,
    /// Where each row's shares start in the plan (scratch of the plan).
    pub(super) offsets: Vec<u32>,
    /// Rows that hold shares of bodies the fluid backend did not sum (a collect's
    /// scratch).
    pub(super) rest_rows: Vec<bool>,
}

impl Interface for PartialCells {
    fn scheme(&self) -> Scheme {
        Scheme::Psm
    }

    fn start<T: Real>(
        &mut self,
        c: &mut Common,
        lat: &Lattice<T>,
        views: &[GrainView],
        _ids: &[u64],
    ) {
        self.map_shares(&c.frame, lat, views);
    }

    fn remap<T: Real>(
        &mut self,
        c: &mut Common,
        fluid: &mut dyn FluidBackend<T>,
        views: &[GrainView],
        ids: &[u64],
        _comm: &dyn Comm,
    ) {
        let t = std::time::Instant::now();
        self.map_shares(&c.frame, fluid.lattice(), views);
        c.owner_ids.clear();
        c.owner_ids.extend_from_slice(ids);
        c.passes[super::pass::MAP] += t.elapsed().as_secs_f64();
    }

    fn hands_over(&self) -> bool {
        false
    }

    fn plan<T: Real>(&mut self, c: &Common, lat: &Lattice<T>, views: &[GrainView]) {
        self.plan_psm(&c.frame, lat, views);
    }

    fn plan_kind(&self) -> PlanKind {
        PlanKind::Partial
    }

    fn moving<'a>(&'a mut self, body_columns: &'a mut BodyColumns) -> MovingCells<'a> {
        MovingCells::Partial(&self.psm, &mut self.share_momentum, body_columns)
    }

    fn bodies(&self) -> usize {
        self.disk_images.len()
    }

    fn body(&self, b: usize) -> (usize, [f64; 2]) {
        let d = self.disk_images[b];
        (d.grain as usize, d.centre)
    }

    fn planned(&self) -> usize {
        self.psm.shares.len()
    }

    fn collect(&mut self, c: &mut Common, views: &[GrainView]) {
        self.collect_psm(c, views);
    }

    fn collect_unslotted(&mut self, c: &mut Common, views: &[GrainView]) -> usize {
        self.collect_psm_unslotted(c, views)
    }

    fn bad_cell(&self, n: usize) -> (usize, u32) {
        let s = self.psm.start[n] as usize;
        let image = self.psm.shares[s].body as usize;
        (self.psm.cells[n] as usize, self.disk_images[image].grain)
    }

    fn fill_rest<T: Real>(
        &mut self,
        _c: &Common,
        _fluid: &mut dyn FluidBackend<T>,
        _views: &[GrainView],
    ) {
        // The fluid inside a grain is the method's own state: it stays.
    }

    fn solid_fraction(&self, _c: &Common, out: &mut [f64]) {
        for s in self.share_rows.iter().flat_map(|r| &r.shares) {
            let e = &mut out[s.cell as usize];
            *e = (*e + s.fraction).min(1.0);
        }
    }

    fn counts(&self) -> [u64; 6] {
        [0; 6]
    }

    fn is_open(&self, _k: usize) -> bool {
        true
    }
}
