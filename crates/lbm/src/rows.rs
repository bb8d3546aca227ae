//! Row plans, fixed by the geometry and built once: each interior row split into runs of
//! plain cells, special cells (next to a solid or an open face) with their wall runs, and
//! edge cells (next to an exchanged face); the in-place sweep's tasks and halo drain.

use super::cells::{is_plain, FLUID, MAX_SOLID};
use super::d2q9::{CX, CY, Q};
use super::lanes::BULK_LANES;
use std::ops::Range;

/// Per-row plan: runs of bulk cells and the special cells between them.
#[derive(Debug, Clone, Default)]
pub(crate) struct RowPlan {
    /// Half-open `[x0, x1)` runs of cells whose 8 neighbours are all plain fluid.
    pub bulk: Vec<(u32, u32)>,
    /// Fluid cells needing bounce-back or open-boundary reconstruction.
    pub special: Vec<u32>,
    /// Runs `(first, count)` of `special` along a straight wall, which the in-place sweep
    /// takes in lanes (see `wall_runs`).
    pub wall_runs: Vec<(u32, u32)>,
    /// Fluid cells next to an exchanged face: computed after the halo has arrived.
    pub edge: Vec<u32>,
}

/// Classify one interior row into bulk runs, special cells and edge cells (those next to
/// a face in `exchange` = [west, east]).
pub(crate) fn row_plan(
    types: &[u16],
    stride: usize,
    nx: usize,
    y: usize,
    exchange: [bool; 2],
) -> RowPlan {
    let yp = y + 1;
    let mut plan = RowPlan::default();
    let mut run_start: Option<u32> = None;
    for x in 0..nx {
        let k = yp * stride + x + 1;
        let edge = (x == 0 && exchange[0]) || (x + 1 == nx && exchange[1]);
        if types[k] == FLUID && edge {
            plan.edge.push(x as u32);
        }
        let fluid = types[k] == FLUID && !edge;
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
    plan.wall_runs = wall_runs(types, stride, yp, &plan.special);
    plan
}

/// The types of the nine cells padded cell `k` pulls from (its own first), if none is an
/// open face.
pub(crate) fn neighbour_types(types: &[u16], stride: usize, k: usize) -> Option<[u16; Q]> {
    let t: [u16; Q] = std::array::from_fn(|i| {
        types[(k as isize - CX[i] as isize - CY[i] as isize * stride as isize) as usize]
    });
    t.iter().all(|&t| t <= MAX_SOLID).then_some(t)
}

/// The wall runs among `special` (the special cells of padded row `yp`, in increasing x):
/// `(first, count)` for each stretch of at least `BULK_LANES` consecutive cells whose
/// neighbours' types agree direction by direction and include no open face.
pub(crate) fn wall_runs(
    types: &[u16],
    stride: usize,
    yp: usize,
    special: &[u32],
) -> Vec<(u32, u32)> {
    let of = |x: u32| neighbour_types(types, stride, yp * stride + x as usize + 1);
    let mut runs = Vec::new();
    let mut j = 0;
    while j < special.len() {
        let Some(first) = of(special[j]) else {
            j += 1;
            continue;
        };
        let mut e = j + 1;
        while e < special.len() && special[e] == special[e - 1] + 1 && of(special[e]) == Some(first)
        {
            e += 1;
        }
        if e - j >= BULK_LANES {
            runs.push((j as u32, (e - j) as u32));
        }
        j = e;
    }
    runs
}

/// Rows per task of the plain rows of a sweep by blocks ([`block_tasks`]).
pub(crate) const PLAIN_BAND: usize = 16;

/// What `Lattice::drain` copies after every push step: the indices are fixed by the
/// geometry, so they are found once (the first drain) and the step only gathers.
#[derive(Debug, Clone, Default)]
pub(crate) struct DrainPlan {
    /// Per x side (left, right): the slot each value sent to that neighbour comes from.
    pub(crate) send: [Vec<usize>; 2],
    /// (slot a fluid cell pulls, slot its value comes from).
    pub(crate) fill: Vec<(usize, usize)>,
}

/// The tasks of a sweep by blocks of `h` rows that sums loads per body (see
/// `partial::ShareSums`), into `tasks`: within each block, the rows from its first to its
/// last row that holds partially saturated cells (`planned(y)`) are one task, to be swept in
/// increasing order (every body summed in the sweep lies there); the other rows go in bands
/// of [`PLAIN_BAND`] rows. The blocks come first, the most rows first, then the bands, so
/// that a pool that takes them in order ends the sweep on short tasks (the cost of a sweep
/// by blocks sits where the grains are).
pub(crate) fn block_tasks(
    tasks: &mut Vec<Range<usize>>,
    ny: usize,
    h: usize,
    planned: impl Fn(usize) -> bool,
) {
    tasks.clear();
    for b0 in (0..ny).step_by(h.max(1)) {
        let b1 = (b0 + h).min(ny);
        // The block's planned rows, first to last (none: the block ends them).
        let (a, e) = match (b0..b1).find(|&y| planned(y)) {
            Some(first) => {
                let last = (first..b1).rev().find(|&y| planned(y)).expect("first is");
                (first, last + 1)
            }
            None => (b1, b1),
        };
        if a < e {
            tasks.push(a..e);
        }
        for (from, to) in [(b0, a), (e, b1)] {
            tasks.extend(
                (from..to)
                    .step_by(PLAIN_BAND)
                    .map(|y| y..(y + PLAIN_BAND).min(to)),
            );
        }
    }
    // The blocks (each starts on a planned row) first, longest first; then the bands, in
    // row order (the sort is stable).
    tasks.sort_by_key(|r| {
        let block = planned(r.start);
        (!block, std::cmp::Reverse(if block { r.len() } else { 0 }))
    });
}
