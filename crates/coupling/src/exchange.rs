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

use super::interface::{Cells, Common, Interface};
use super::map::{GrainView, SlabFrame};
use super::sums::ColumnSums;
use super::{Refill, Scheme};
use lbm::moving::{MovingCells, PlanKind};
use lbm::{FluidBackend, Lattice, Real};
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

/// The coupling state of one slab: what every scheme shares, and the chosen scheme's cells
/// (`interface.rs`).
pub struct Coupler {
    pub(super) common: Common,
    pub(super) cells: Cells,
}

impl Coupler {
    /// A coupler on the slab `frame`. Place the grains with [`Coupler::start`].
    pub fn new(scheme: Scheme, refill: Refill, frame: SlabFrame) -> Self {
        Self {
            common: Common::new(frame),
            cells: Cells::new(scheme, refill, frame),
        }
    }

    /// The interface scheme.
    pub fn scheme(&self) -> Scheme {
        self.cells.scheme()
    }

    /// The slab.
    pub fn frame(&self) -> SlabFrame {
        self.common.frame
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
        self.cells
            .start(&mut self.common, fluid.lattice(), views, ids);
        let c = &mut self.common;
        c.mapped.clear();
        c.mapped.extend_from_slice(views);
        c.owner_ids.clear();
        c.owner_ids.extend_from_slice(ids);
        c.handover.reset(views, c.frame.global_nx);
        if fill_rest {
            self.fill_rest(fluid, views);
        }
    }

    /// This rank's counts of [`super::COUNTS`]: remaps done in place and afresh, grains
    /// whose cells an update in place decided and skipped, grains whose boundary lists
    /// were kept and rescanned (bounce-back schemes; all zero with PSM).
    pub fn counts(&self) -> [u64; 6] {
        self.cells.counts()
    }

    /// The fluid cells next to bounce-back grains (padded), as the last exchange planned
    /// them; none with partially saturated cells.
    pub fn link_cells(&self) -> &[u32] {
        self.cells.link_cells()
    }

    /// The cells under bounce-back grains (padded) and the rigid velocity (lattice units)
    /// the last [`Coupler::fill_rest`] set each to; none with partially saturated cells.
    pub fn rest_cells(&self) -> (&[u32], &[[f64; 2]]) {
        self.cells.rest_cells()
    }

    /// Solid fraction of every interior cell (padded index → Σ ε, capped at 1).
    pub fn solid_fraction(&self, out: &mut [f64]) {
        out.fill(0.0);
        self.cells.solid_fraction(&self.common, out);
    }

    /// The kind of plan the scheme makes (for a fluid backend deciding whether to sum
    /// the momenta per body itself).
    pub fn plan_kind(&self) -> PlanKind {
        self.cells.plan_kind()
    }

    /// Stage "coupling", before the sweep: plan the cells at the grains' surfaces (links
    /// for the bounce-back schemes, solid shares for PSM) from the maps of the last remap,
    /// built for the grains `views` (the same views: the link plan took their rigid motions
    /// then). With `per_body`, also the box of each body for a fluid backend that sums the
    /// momenta per body and column itself ([`lbm::moving::BodyColumns`]). Then let the fluid sweep with
    /// [`Coupler::moving`] and collect the loads with [`Coupler::collect`].
    pub fn plan<T: Real>(&mut self, lat: &Lattice<T>, views: &[GrainView], per_body: bool) {
        let t = std::time::Instant::now();
        self.cells.plan(&self.common, lat, views);
        self.box_bodies(views, per_body);
        self.common.passes[super::pass::PLAN] += t.elapsed().as_secs_f64();
    }

    /// The planned cells for the fluid's sweep, with where their momenta go.
    pub fn moving(&mut self) -> MovingCells<'_> {
        self.cells.moving(&mut self.common.body_columns)
    }

    /// Stage "coupling", after the sweep: sum the momentum each grain received per column
    /// (see [`Coupler::loads`]). `bad` is what the sweep reported (plan index, density); it
    /// comes back as the first bad cell (padded cell, grain view, density).
    pub fn collect(&mut self, views: &[GrainView], bad: Option<(usize, f64)>) -> Option<Unstable> {
        let t = std::time::Instant::now();
        let c = &mut self.common;
        c.sums.reset(views, c.frame.global_nx);
        if c.body_columns.made {
            self.collect_bodies(views);
        } else {
            self.cells.collect(&mut self.common, views);
        }
        self.common.passes[super::pass::COLLECT] += t.elapsed().as_secs_f64();
        // The bad plan cell's grain: that of its first link or share.
        bad.map(|(n, rho)| {
            let (k, g) = self.cells.bad_cell(n);
            (k, g, rho)
        })
    }

    /// Add `seconds` to pass `pass` of [`super::PASSES`].
    pub(super) fn add_pass(&mut self, pass: usize, seconds: f64) {
        self.common.passes[pass] += seconds;
    }

    /// Seconds this rank spent in each of [`super::PASSES`] so far.
    pub fn pass_seconds(&self) -> [f64; 6] {
        self.common.passes
    }

    /// The loads of the last exchange, per grain view and column.
    pub fn loads(&self) -> &ColumnSums {
        &self.common.sums
    }

    /// The loads of the last remap's hand-over of covered and uncovered cells.
    pub fn handover_loads(&self) -> &ColumnSums {
        &self.common.handover
    }

    /// Whether a remap hands loads over (bounce-back schemes).
    pub fn hands_over(&self) -> bool {
        self.cells.hands_over()
    }

    /// Set the fluid under the grains (bounce-back schemes) to rest at the grains' velocity.
    /// Nothing reads it: the sweep's values there are overwritten where they would reach
    /// the fluid (boundary links) and ignored otherwise (refills read fluid neighbours), so
    /// this is done at the start and before output only, for fields that show the grains.
    pub fn fill_rest<T: Real>(&mut self, fluid: &mut dyn FluidBackend<T>, views: &[GrainView]) {
        self.cells.fill_rest(&self.common, fluid, views);
    }
}

/// Velocity of grain `g`'s rigid motion at point `p`, about its image nearest to `p`.
#[inline]
pub(super) fn rigid_velocity(f: &SlabFrame, g: &GrainView, p: [f64; 2]) -> [f64; 2] {
    let c = super::map::nearest_image(f, g, p);
    GrainView { centre: c, ..*g }.surface_velocity(p)
}
