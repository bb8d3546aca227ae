//! The bounce-back schemes' side of the [`Interface`]: a cell is solid when its centre lies
//! inside a grain (the cover map, `owner`), the fluid cells next to the solid ones carry
//! links to it (`links.rs`), and cells that change hands are handed over (`handover.rs`).
//! Half-way ([`HalfWay`], Ladd 1994) and interpolated ([`Bouzidi`], Bouzidi, Firdaouss &
//! Lallemand 2001) bounce-back differ only in the links' wall fractions.

use super::boundary_lists::BoundaryLists;
use super::cover_update::{Change, CoverUpdate};
use super::exchange::rigid_velocity;
use super::interface::{Cells, Common, Interface};
use super::map::{cover, for_owned, set_cells, GrainView, SlabFrame, NONE};
use super::{Refill, Scheme};
use decomposition::Comm;
use lbm::moving::{BodyColumns, LinkPlan, MovingCells, PlanKind};
use lbm::{FluidBackend, Lattice, Real};
use rayon::prelude::*;
use std::marker::PhantomData;

/// Where a link's wall sits.
pub(super) trait LinkRule: Send + Sync {
    /// The scheme these links make.
    const SCHEME: Scheme;
    /// Whether each link carries the exact fraction q of the curved surface (otherwise
    /// the wall is half-way, q = ½).
    const INTERPOLATED: bool;
    /// The coupler's cells holding `cells`.
    fn wrap(cells: LinkCells<Self>) -> Cells
    where
        Self: Sized;
    /// The link cells `cells` holds, if they follow this rule (tests).
    #[cfg(test)]
    fn of(cells: &mut Cells) -> &mut LinkCells<Self>
    where
        Self: Sized;
}

/// Half-way bounce-back: the wall half-way along every link (Ladd 1994).
pub(super) struct HalfWay;

impl LinkRule for HalfWay {
    const SCHEME: Scheme = Scheme::BounceBack;
    const INTERPOLATED: bool = false;
    fn wrap(cells: LinkCells<Self>) -> Cells {
        Cells::BounceBack(cells)
    }
    #[cfg(test)]
    fn of(cells: &mut Cells) -> &mut LinkCells<Self> {
        match cells {
            Cells::BounceBack(c) => c,
            _ => panic!("not half-way bounce-back"),
        }
    }
}

/// Linear interpolated bounce-back at the link's exact fraction q (Bouzidi, Firdaouss &
/// Lallemand 2001, eq. 5; seed eqs. 5.50–5.52).
pub(super) struct Bouzidi;

impl LinkRule for Bouzidi {
    const SCHEME: Scheme = Scheme::Interpolated;
    const INTERPOLATED: bool = true;
    fn wrap(cells: LinkCells<Self>) -> Cells {
        Cells::Interpolated(cells)
    }
    #[cfg(test)]
    fn of(cells: &mut Cells) -> &mut LinkCells<Self> {
        match cells {
            Cells::Interpolated(c) => c,
            _ => panic!("not interpolated bounce-back"),
        }
    }
}

/// The cells of a bounce-back scheme on one slab.
pub(super) struct LinkCells<R> {
    pub(super) refill: Refill,
    /// Covering grain per padded cell: an index into `Common::owner_ids`.
    pub(super) owner: Vec<u32>,
    /// A map built afresh when the grains in view change (all [`NONE`] between remaps;
    /// empty until the first such remap).
    pub(super) next_owner: Vec<u32>,
    /// Updates `owner` in place when the same grains stay in view (`cover_update.rs`).
    pub(super) update: CoverUpdate,
    /// Remaps done in place and remaps that mapped afresh.
    pub(super) in_place_remaps: u64,
    pub(super) fresh_remaps: u64,
    /// Cells whose owner changes in the current remap.
    pub(super) changes: Vec<Change>,
    /// Scratch cell lists of a remap done afresh: cells set in the old map and the new.
    pub(super) old_cells: Vec<u32>,
    pub(super) new_cells: Vec<u32>,
    pub(super) scratch: Vec<u32>,
    /// Scratch of the link plan's parallel build: where each thread's range of grains
    /// starts, and each range's cell and link counts (then slots) per row.
    pub(super) part_grains: Vec<usize>,
    pub(super) part_counts: Vec<u32>,
    /// Each grain's boundary cells, kept between remaps (`boundary_lists.rs`).
    pub(super) lists: BoundaryLists,
    /// Scratch marks per padded cell (all false between uses).
    pub(super) mark: Vec<bool>,
    /// The plan of the last exchange.
    pub(super) links: LinkPlan,
    /// The grain (view) of each of the link plan's bodies, and each view's first body.
    pub(super) body_grain: Vec<u32>,
    pub(super) body_start: Vec<u32>,
    /// Momentum per link of the last exchange.
    pub(super) link_momentum: Vec<f64>,
    /// The covered cells (padded) of the last `fill_rest`, and their rest velocities.
    pub(super) rest_cells: Vec<u32>,
    pub(super) rest: Vec<[f64; 2]>,
    /// Cells changing hands in the last remap, and their refills and momenta.
    pub(super) refills: Vec<lbm::moving::Refill>,
    pub(super) newly: Vec<u32>,
    pub(super) cell_momentum: Vec<[f64; 2]>,
    pub(super) refill_momentum: Vec<[f64; 2]>,
    /// Cells changing hands: (cell, grain view, newly covered).
    pub(super) events: Vec<(u32, u32, bool)>,
    rule: PhantomData<R>,
}

impl<R: LinkRule> LinkCells<R> {
    /// The cells of slab `frame`, no grain mapped; `refill` fills uncovered cells.
    pub(super) fn new(refill: Refill, frame: SlabFrame) -> Self {
        let cells = frame.stride * (frame.ny + 2);
        Self {
            refill,
            owner: vec![NONE; cells],
            next_owner: Vec::new(),
            update: CoverUpdate::default(),
            in_place_remaps: 0,
            fresh_remaps: 0,
            changes: Vec::new(),
            old_cells: Vec::new(),
            new_cells: Vec::new(),
            scratch: Vec::new(),
            part_grains: Vec::new(),
            part_counts: Vec::new(),
            lists: BoundaryLists::default(),
            mark: vec![false; cells],
            links: LinkPlan::default(),
            body_grain: Vec::new(),
            body_start: Vec::new(),
            link_momentum: Vec::new(),
            rest_cells: Vec::new(),
            rest: Vec::new(),
            refills: Vec::new(),
            newly: Vec::new(),
            cell_momentum: Vec::new(),
            refill_momentum: Vec::new(),
            events: Vec::new(),
            rule: PhantomData,
        }
    }

    /// The interior cells covered by a grain of `mapped` now, padded indices, into `out`,
    /// grain by grain.
    fn covered_cells(&mut self, f: &SlabFrame, mapped: &[GrainView], out: &mut Vec<u32>) {
        set_cells(f, mapped, &self.owner, &mut self.mark, out);
        out.retain(|&k| {
            let (x, y) = f.local(k as usize);
            x >= 0 && y >= 0 && x < f.nx as i64 && y < f.ny as i64
        });
    }
}

impl<R: LinkRule> Interface for LinkCells<R> {
    fn scheme(&self) -> Scheme {
        R::SCHEME
    }

    fn start<T: Real>(
        &mut self,
        c: &mut Common,
        lat: &Lattice<T>,
        views: &[GrainView],
        ids: &[u64],
    ) {
        let f = c.frame;
        // Clear what an earlier start left, then map.
        set_cells(
            &f,
            &c.mapped,
            &self.owner,
            &mut self.mark,
            &mut self.scratch,
        );
        for &k in &self.scratch {
            self.owner[k as usize] = NONE;
        }
        self.scratch.clear();
        cover(
            &f,
            views,
            |k| lat.is_fluid_at(k),
            &mut self.owner,
            &mut self.scratch,
            &mut self.new_cells,
        );
        self.update.reset(views);
        self.lists.clear();
        self.lists.follow(ids);
        self.rebuild_lists(&f, lat, views);
    }

    fn remap<T: Real>(
        &mut self,
        c: &mut Common,
        fluid: &mut dyn FluidBackend<T>,
        views: &[GrainView],
        ids: &[u64],
        comm: &dyn Comm,
    ) {
        self.remap_links(c, fluid, views, ids, comm);
    }

    fn hands_over(&self) -> bool {
        true
    }

    fn plan<T: Real>(&mut self, c: &Common, _lat: &Lattice<T>, views: &[GrainView]) {
        self.plan_links(&c.frame, views);
    }

    fn plan_kind(&self) -> PlanKind {
        PlanKind::Links
    }

    fn moving<'a>(&'a mut self, body_columns: &'a mut BodyColumns) -> MovingCells<'a> {
        MovingCells::Links(&self.links, &mut self.link_momentum, body_columns)
    }

    fn bodies(&self) -> usize {
        self.links.bodies.len()
    }

    fn body(&self, b: usize) -> (usize, [f64; 2]) {
        (self.body_grain[b] as usize, self.links.bodies[b].centre)
    }

    fn planned(&self) -> usize {
        self.links.links.len()
    }

    fn collect(&mut self, c: &mut Common, views: &[GrainView]) {
        self.collect_links(c, views);
    }

    fn collect_unslotted(&mut self, _c: &mut Common, _views: &[GrainView]) -> usize {
        // No backend sums some link bodies and not others (`sums_per_body`).
        0
    }

    fn bad_cell(&self, n: usize) -> (usize, u32) {
        let l = self.links.start[n] as usize;
        let body = self.links.links[l].body();
        (self.links.cells[n] as usize, self.body_grain[body])
    }

    fn fill_rest<T: Real>(
        &mut self,
        c: &Common,
        fluid: &mut dyn FluidBackend<T>,
        views: &[GrainView],
    ) {
        let f = c.frame;
        let mut covered = std::mem::take(&mut self.rest_cells);
        self.covered_cells(&f, &c.mapped, &mut covered);
        let owner = &self.owner;
        covered
            .par_iter()
            .with_min_len(1024)
            .map(|&k| rigid_velocity(&f, &views[owner[k as usize] as usize], f.centre(k as usize)))
            .collect_into_vec(&mut self.rest);
        fluid.set_rest(&covered, &self.rest);
        self.rest_cells = covered;
    }

    fn solid_fraction(&self, c: &Common, out: &mut [f64]) {
        let f = c.frame;
        for_owned(&f, &c.mapped, &self.owner, |k, x, y| {
            if x >= 0 && y >= 0 && x < f.nx as i64 && y < f.ny as i64 {
                out[k] = 1.0;
            }
        });
    }

    fn counts(&self) -> [u64; 6] {
        [
            self.in_place_remaps,
            self.fresh_remaps,
            self.update.decided,
            self.update.skipped,
            self.lists.kept,
            self.lists.rescanned,
        ]
    }

    fn is_open(&self, k: usize) -> bool {
        self.owner[k] == NONE
    }
}
