//! Test scaffolding shared by the coupling's map tests: a small deterministic generator
//! and the slabs the tests move grains over.

use super::exchange::Coupler;
use super::interface::{Cells, Common};
use super::link_cells::{LinkCells, LinkRule};
use super::map::{cover, GrainView, SlabFrame};
use super::Refill;

pub use lbm::test_rng::next;

/// Test slab `case`: 70 + case columns starting at global column 23 (case mod 3) of a
/// 160-column lattice, 60 rows, periodic on both axes for even cases; with its solid
/// cells (every 89th padded cell).
pub fn slab(case: usize) -> (SlabFrame, Vec<bool>) {
    let periodic = case.is_multiple_of(2);
    let f = SlabFrame {
        nx: 70 + case,
        ny: 60,
        x0: 23 * (case % 3),
        global_nx: 160,
        stride: 70 + case + 2,
        periodic_x: periodic,
        periodic_y: periodic,
    };
    let cells = f.stride * (f.ny + 2);
    let solid = (0..cells).map(|k| k % 89 == 7).collect();
    (f, solid)
}

/// `n` grains at rest scattered over slab `f` and 6 cells beyond its x edges (some cross
/// them, and the periodic faces), rows −3 to 63, radii 2 to 6 cells.
pub fn grains_at_rest(f: &SlabFrame, n: usize, seed: &mut u64) -> Vec<GrainView> {
    (0..n)
        .map(|_| GrainView {
            centre: [
                f.x0 as f64 - 6.0 + next(seed) * (f.nx as f64 + 12.0),
                -3.0 + next(seed) * 66.0,
            ],
            radius: 2.0 + 4.0 * next(seed),
            velocity: [0.0; 2],
            omega: 0.0,
        })
        .collect()
}

/// The link cells of rule `R` on slab `f` with the cover map and the link plan of `views`
/// (ids 0, 1, …), `fluid(k)` telling whether padded cell k is fluid.
pub fn planned_links<R: LinkRule>(
    f: SlabFrame,
    views: &[GrainView],
    fluid: &(impl Fn(usize) -> bool + Sync),
) -> LinkCells<R> {
    let ids: Vec<u64> = (0..views.len() as u64).collect();
    let mut c = LinkCells::<R>::new(Refill::default(), f);
    let (mut touched, mut inner) = (Vec::new(), Vec::new());
    cover(&f, views, fluid, &mut c.owner, &mut touched, &mut inner);
    c.lists.clear();
    c.lists.follow(&ids);
    c.group_lists(&f, fluid, views);
    c.plan_links(&f, views);
    c
}

/// [`planned_links`] in a coupler.
pub fn planned<R: LinkRule>(
    f: SlabFrame,
    views: &[GrainView],
    fluid: &(impl Fn(usize) -> bool + Sync),
) -> Coupler {
    let cells: Cells = R::wrap(planned_links::<R>(f, views, fluid));
    Coupler {
        common: Common::new(f),
        cells,
    }
}
