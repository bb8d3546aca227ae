//! The fluid side of the coupling: after each stream–collide sweep, the cells next to
//! grains (bounce-back schemes) or inside them (partially saturated method) are recomputed
//! with the grains' surfaces applied, and the momentum each grain receives is summed per
//! lattice column (`sums.rs`). Between steps, cells that a moving grain covers or uncovers
//! are handed over with their momentum (`handover.rs`).
//!
//! The coupler only plans: which cells, which links, which velocities (`links.rs`,
//! `psm.rs`). The fluid backend executes the plan (`lbm::moving`) on its own device and
//! returns one momentum per link or share, in plan order, or (a device backend, and the CPU's
//! in-place sweep for some PSM bodies) those momenta already summed per grain and column in
//! the same order (`body_sums.rs`).
//!
//! **Order, and so the bits, do not depend on the partition.** The grains are seen in id
//! order (owned and ghosts alike), each grain's cells in the order of its bounding box, so
//! every list a slab builds is the restriction of one global list to the slab's cells;
//! summed per column, the partial sums are the same on any number of ranks.
//!
//! Momentum is counted on the shifted populations (h = f − w). The rest state's part
//! (ρ₀ c_s² on the surface) integrates to zero over a closed surface, and leaving it out is
//! what makes fluid + grain momentum conserved to round-off (tested).

use super::cover_update::{Change, CoverUpdate};
use super::map::{cover, for_owned, set_cells, GrainView, SlabFrame, NONE};
use super::sums::ColumnSums;
use super::{Refill, Scheme};
use lbm::moving::{BodyColumns, LinkPlan, MovingCells, PsmPlan};
use lbm::{FluidBackend, Lattice, Real};
use rayon::prelude::*;
use thiserror::Error;

/// A coupled step that cannot go on.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CouplingError {
    /// A cell next to or inside a grain went NaN or non-positive.
    #[error("unstable at step {step}: cell ({x}, {y}) next to grain {grain} has density {density} (NaN or ≤ 0); lower the grains' speed in lattice units (smaller time step), raise τ, or refine the lattice")]
    Unstable {
        /// Fluid step.
        step: u64,
        /// Global cell x.
        x: usize,
        /// Cell y.
        y: usize,
        /// Grain id.
        grain: u64,
        /// The offending density.
        density: f64,
    },
    /// A grain moves faster than the lattice's speed of sound: the fluid cannot carry the
    /// disturbance it makes, and the coupling's results are meaningless.
    #[error("unstable at step {step}: grain {grain} moves at {speed_lattice:.3} cells per step ({speed_m_s:.4e} m/s), faster than the lattice's speed of sound 1/√3 ≈ 0.577; lower the grains' speed in lattice units (smaller time step), or refine the lattice")]
    TooFast {
        /// Fluid step.
        step: u64,
        /// Grain id.
        grain: u64,
        /// Its speed in lattice units (cells per step).
        speed_lattice: f64,
        /// Its speed (m/s).
        speed_m_s: f64,
    },
    /// A grain left the fluid domain (through an open or periodic face).
    #[error("at step {step}: grain {grain} left the fluid domain at {position:?} m; grains cannot cross open or periodic faces yet: close the domain with walls or keep the grains away from them")]
    Left {
        /// Fluid step.
        step: u64,
        /// Grain id.
        grain: u64,
        /// Its centre (m).
        position: [f64; 2],
    },
}

/// A recomputed cell that went bad: padded cell, the grain (view) it belongs to, density.
pub type Unstable = (usize, u32, f64);

/// The coupling state of one slab.
pub struct Coupler {
    pub(super) scheme: Scheme,
    pub(super) refill: Refill,
    pub(super) frame: SlabFrame,
    /// Covering grain per padded cell (bounce-back schemes; empty with PSM): an index into
    /// `owner_ids`.
    pub(super) owner: Vec<u32>,
    /// A map built afresh when the grains in view change (all [`NONE`] between remaps;
    /// empty until the first such remap).
    pub(super) next_owner: Vec<u32>,
    /// Ids and views of the grains `owner` refers to (the views of the last map).
    pub(super) owner_ids: Vec<u64>,
    pub(super) mapped: Vec<GrainView>,
    /// Updates `owner` in place when the same grains stay in view (`cover_update.rs`).
    pub(super) update: CoverUpdate,
    /// Remaps done in place and remaps that mapped afresh (bounce-back schemes).
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
    pub(super) lists: super::boundary_lists::BoundaryLists,
    /// Solid fractions (partially saturated method) by row, each row sorted by cell.
    pub(super) share_rows: Vec<super::map::ShareRow>,
    /// The grain images that reach the slab (grain, image centre), with the line tables of
    /// their exact cell areas (`geometry::CellAreas`: image i's vertical lines are
    /// `column_lines[column_start[i]..column_start[i + 1]]`, its horizontal lines likewise).
    pub(super) disk_images: Vec<(u32, [f64; 2])>,
    pub(super) column_start: Vec<u32>,
    pub(super) column_lines: Vec<super::geometry::ColumnLine>,
    pub(super) row_start: Vec<u32>,
    pub(super) row_lines: Vec<super::geometry::RowLine>,
    /// Each grain image's rows (index into `disk_images`, row), and their order by row
    /// with where each row starts.
    pub(super) row_images: Vec<(u32, u32)>,
    pub(super) image_order: Vec<u32>,
    pub(super) image_rows: Vec<u32>,
    /// Scratch marks per padded cell (all false between uses; bounce-back schemes).
    pub(super) mark: Vec<bool>,
    /// The plans of the last exchange and where each link or share belongs.
    pub(super) links: LinkPlan,
    /// The grain (view) of each of the link plan's bodies, and each view's first body.
    pub(super) body_grain: Vec<u32>,
    pub(super) body_start: Vec<u32>,
    /// Per body of the link plan (per grain image with PSM): its window of the column
    /// sums (scratch of the collect).
    pub(super) body_windows: Vec<super::sums::Window>,
    /// Rows that hold shares of bodies the fluid backend did not sum (a PSM collect's
    /// scratch).
    pub(super) rest_rows: Vec<bool>,
    pub(super) psm: PsmPlan,
    /// Momentum per link or share of the last exchange, and scratch lists.
    pub(super) link_momentum: Vec<f64>,
    pub(super) share_momentum: Vec<[f64; 2]>,
    /// The plan's boxes per body, and the fluid backend's sums in them when it makes
    /// them (`body_sums.rs`).
    pub(super) body_columns: BodyColumns,
    pub(super) rest: Vec<[f64; 2]>,
    /// PSM: where each row's shares start in the plan (scratch of the plan).
    pub(super) offsets: Vec<u32>,
    /// Cells changing hands in the last remap, and their refills and momenta.
    pub(super) refills: Vec<lbm::moving::Refill>,
    pub(super) newly: Vec<u32>,
    pub(super) cell_momentum: Vec<[f64; 2]>,
    pub(super) refill_momentum: Vec<[f64; 2]>,
    /// Cells changing hands: (cell, grain view, newly covered).
    pub(super) events: Vec<(u32, u32, bool)>,
    /// Seconds spent in each of [`super::PASSES`] on this rank.
    pub(super) passes: [f64; 6],
    /// Loads of the last exchange and of the last remap's hand-over, per grain and column.
    pub(super) sums: ColumnSums,
    pub(super) handover: ColumnSums,
}

impl Coupler {
    /// A coupler on the slab `frame`. Place the grains with [`Coupler::start`].
    pub fn new(scheme: Scheme, refill: Refill, frame: SlabFrame) -> Self {
        // Per-cell maps for the bounce-back schemes only; the second map only once a remap
        // needs it (`handover.rs`).
        let cells = match scheme {
            Scheme::Psm => 0,
            _ => frame.stride * (frame.ny + 2),
        };
        Self {
            scheme,
            refill,
            frame,
            owner: vec![NONE; cells],
            next_owner: Vec::new(),
            owner_ids: Vec::new(),
            mapped: Vec::new(),
            update: CoverUpdate::default(),
            in_place_remaps: 0,
            fresh_remaps: 0,
            changes: Vec::new(),
            old_cells: Vec::new(),
            new_cells: Vec::new(),
            scratch: Vec::new(),
            part_grains: Vec::new(),
            part_counts: Vec::new(),
            lists: Default::default(),
            share_rows: Vec::new(),
            disk_images: Vec::new(),
            column_start: Vec::new(),
            column_lines: Vec::new(),
            row_start: Vec::new(),
            row_lines: Vec::new(),
            row_images: Vec::new(),
            image_order: Vec::new(),
            image_rows: Vec::new(),
            mark: vec![false; cells],
            links: LinkPlan::default(),
            body_grain: Vec::new(),
            body_windows: Vec::new(),
            rest_rows: Vec::new(),
            body_start: Vec::new(),
            psm: PsmPlan::default(),
            link_momentum: Vec::new(),
            share_momentum: Vec::new(),
            body_columns: BodyColumns::default(),
            rest: Vec::new(),
            offsets: Vec::new(),
            refills: Vec::new(),
            newly: Vec::new(),
            cell_momentum: Vec::new(),
            refill_momentum: Vec::new(),
            events: Vec::new(),
            passes: [0.0; 6],
            sums: ColumnSums::default(),
            handover: ColumnSums::default(),
        }
    }

    /// The interface scheme.
    pub fn scheme(&self) -> Scheme {
        self.scheme
    }

    /// Place the grains (`views` with their `ids`, in increasing id) on the lattice before
    /// the first step: build the maps and, unless the populations come from a checkpoint
    /// (`fill_rest = false`), fill the covered cells with equilibrium at the grain velocity
    /// (bounce-back schemes).
    pub fn start<T: Real>(
        &mut self,
        fluid: &mut dyn FluidBackend<T>,
        views: &[GrainView],
        ids: &[u64],
        fill_rest: bool,
    ) {
        let f = self.frame;
        match self.scheme {
            Scheme::Psm => self.map_shares(fluid.lattice(), views),
            _ => {
                // Clear what an earlier start left, then map.
                set_cells(
                    &f,
                    &self.mapped,
                    &self.owner,
                    &mut self.mark,
                    &mut self.scratch,
                );
                for &k in &self.scratch {
                    self.owner[k as usize] = NONE;
                }
                let lat = fluid.lattice();
                self.scratch.clear();
                cover(
                    &f,
                    views,
                    |k| lat.is_fluid_at(k),
                    &mut self.owner,
                    &mut self.scratch,
                    &mut self.new_cells,
                );
            }
        }
        self.mapped.clear();
        self.mapped.extend_from_slice(views);
        self.update.reset(views);
        self.owner_ids.clear();
        self.owner_ids.extend_from_slice(ids);
        self.handover.reset(views, self.frame.global_nx);
        self.lists.clear();
        self.lists.follow(ids);
        self.rebuild_lists(fluid.lattice(), views);
        if fill_rest {
            self.fill_rest(fluid, views);
        }
    }

    /// The interior cells covered by a grain now (bounce-back schemes), padded indices,
    /// into `out`, grain by grain.
    fn covered_cells(&mut self, out: &mut Vec<u32>) {
        let f = self.frame;
        set_cells(&f, &self.mapped, &self.owner, &mut self.mark, out);
        out.retain(|&k| {
            let (x, y) = f.local(k as usize);
            x >= 0 && y >= 0 && x < f.nx as i64 && y < f.ny as i64
        });
    }

    /// This rank's counts of [`super::COUNTS`]: remaps done in place and afresh, grains
    /// whose cells an update in place decided and skipped, grains whose boundary lists
    /// were kept and rescanned (bounce-back schemes; all zero with PSM).
    pub fn counts(&self) -> [u64; 6] {
        [
            self.in_place_remaps,
            self.fresh_remaps,
            self.update.decided,
            self.update.skipped,
            self.lists.kept,
            self.lists.rescanned,
        ]
    }

    /// Solid fraction of every interior cell (padded index → Σ ε, capped at 1).
    pub fn solid_fraction(&self, out: &mut [f64]) {
        out.fill(0.0);
        match self.scheme {
            Scheme::Psm => {
                for s in self.share_rows.iter().flat_map(|r| &r.shares) {
                    let e = &mut out[s.cell as usize];
                    *e = (*e + s.fraction).min(1.0);
                }
            }
            _ => {
                let f = self.frame;
                for_owned(&f, &self.mapped, &self.owner, |k, x, y| {
                    if x >= 0 && y >= 0 && x < f.nx as i64 && y < f.ny as i64 {
                        out[k] = 1.0;
                    }
                });
            }
        }
    }

    /// Stage "coupling", before the sweep: plan the cells at the grains' surfaces (links
    /// for the bounce-back schemes, solid shares for PSM) from the maps of the last remap,
    /// built for the grains `views` (the same views: the link plan took their rigid motions
    /// then). With `per_body`, also the box of each body for a fluid backend that sums the
    /// momenta per body and column itself ([`BodyColumns`]). Then let the fluid sweep with
    /// [`Coupler::moving`] and collect the loads with [`Coupler::collect`].
    pub fn plan<T: Real>(&mut self, lat: &Lattice<T>, views: &[GrainView], per_body: bool) {
        let t = std::time::Instant::now();
        match self.scheme {
            Scheme::Psm => self.plan_psm(lat, views),
            _ => self.plan_links(views),
        }
        self.box_bodies(views, per_body);
        self.passes[super::pass::PLAN] += t.elapsed().as_secs_f64();
    }

    /// The planned cells for the fluid's sweep, with where their momenta go.
    pub fn moving(&mut self) -> MovingCells<'_> {
        match self.scheme {
            Scheme::Psm => {
                MovingCells::Partial(&self.psm, &mut self.share_momentum, &mut self.body_columns)
            }
            _ => MovingCells::Links(&self.links, &mut self.link_momentum, &mut self.body_columns),
        }
    }

    /// Stage "coupling", after the sweep: sum the momentum each grain received per column
    /// (see [`Coupler::loads`]). `bad` is what the sweep reported (plan index, density); it
    /// comes back as the first bad cell (padded cell, grain view, density).
    pub fn collect(&mut self, views: &[GrainView], bad: Option<(usize, f64)>) -> Option<Unstable> {
        let t = std::time::Instant::now();
        self.sums.reset(views, self.frame.global_nx);
        if self.body_columns.made {
            self.collect_bodies(views);
        } else if self.scheme == Scheme::Psm {
            self.collect_psm(views);
        } else {
            self.collect_links(views);
        }
        self.passes[super::pass::COLLECT] += t.elapsed().as_secs_f64();
        // The bad plan cell's grain: that of its first link or share.
        bad.map(|(c, rho)| match self.scheme {
            Scheme::Psm => {
                let s = self.psm.start[c] as usize;
                let image = self.psm.shares[s].body as usize;
                (self.psm.cells[c] as usize, self.disk_images[image].0, rho)
            }
            _ => {
                let l = self.links.start[c] as usize;
                let body = self.links.links[l].body();
                (self.links.cells[c] as usize, self.body_grain[body], rho)
            }
        })
    }

    /// Seconds this rank spent in each of [`super::PASSES`] so far.
    pub fn pass_seconds(&self) -> [f64; 6] {
        self.passes
    }

    /// The loads of the last exchange, per grain view and column.
    pub fn loads(&self) -> &ColumnSums {
        &self.sums
    }

    /// The loads of the last remap's hand-over of covered and uncovered cells.
    pub fn handover_loads(&self) -> &ColumnSums {
        &self.handover
    }

    /// Set the fluid under the grains (bounce-back schemes) to rest at the grains' velocity.
    /// Nothing reads it: the sweep's values there are overwritten where they would reach
    /// the fluid (boundary links) and ignored otherwise (refills read fluid neighbours), so
    /// this is done at the start and before output only, for fields that show the grains.
    pub fn fill_rest<T: Real>(&mut self, fluid: &mut dyn FluidBackend<T>, views: &[GrainView]) {
        if self.scheme == Scheme::Psm {
            return;
        }
        let mut covered = std::mem::take(&mut self.scratch);
        self.covered_cells(&mut covered);
        let (f, owner) = (self.frame, &self.owner);
        covered
            .par_iter()
            .with_min_len(1024)
            .map(|&k| rigid_velocity(&f, &views[owner[k as usize] as usize], f.centre(k as usize)))
            .collect_into_vec(&mut self.rest);
        fluid.set_rest(&covered, &self.rest);
        self.scratch = covered;
    }

    /// Global column of padded cell `k`.
    #[inline]
    pub(super) fn column(&self, k: usize) -> usize {
        (self.frame.local(k).0 + self.frame.x0 as i64) as usize
    }
}

/// Velocity of grain `g`'s rigid motion at point `p`, about its image nearest to `p`.
#[inline]
pub(super) fn rigid_velocity(f: &SlabFrame, g: &GrainView, p: [f64; 2]) -> [f64; 2] {
    let c = super::map::nearest_image(f, g, p);
    GrainView { centre: c, ..*g }.surface_velocity(p)
}
