//! The cover map updated in place after the grains moved (bounce-back schemes).
//!
//! Between two fluid steps a grain moves a small fraction of a cell, so all but a few of
//! the cells it covers keep their owner. Mapping every grain afresh (`map::cover`) rewrites
//! every covered cell of the slab to find the few hundred that change hands. This module
//! finds them directly:
//! - an *isolated* grain (no other grain's disk, before or after the move, can reach its
//!   own before or after) owns exactly the plain-fluid cells whose centres its disk holds,
//!   so its cells change only in the difference of its old and new disk, which is at most
//!   two runs of cells per row, found from the disk's chord in that row;
//! - for a grain with neighbours, every cell of its old and new disk is decided again from
//!   the rule of `map::cover` (nearest centre among the grains covering it, the lower
//!   index on a tie) over the grain and its neighbours, which include every grain that can
//!   cover such a cell.
//!
//! An isolated grain that moved less than its *slack* (how far it may move before a cell
//! centre crosses its circle) since its cells were last decided is skipped.
//!
//! The result is the list of cells whose owner changes; applied to the old map it gives
//! the very map `cover` would build for the new positions (tested over many random moves).

use super::geometry::covers;
use super::grain_neighbours::{moved, GrainNeighbours};
use super::map::{GrainView, SlabFrame, NONE};
use rayon::prelude::*;

/// The farthest a grain may move in one remap (cells) for the map to be updated in place;
/// beyond it (a grain crossing a periodic seam, a violent step) the caller maps afresh.
pub const MAX_MOVE: f64 = 1.0;

/// A cell whose owner changes: padded index, owner before and after (view indices, or
/// [`NONE`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Change {
    /// Padded cell index.
    pub cell: u32,
    /// Owner before the move.
    pub old: u32,
    /// Owner after the move.
    pub new: u32,
}

/// Where each grain's cells were last decided, and scratch kept between updates.
#[derive(Debug, Default)]
pub struct CoverUpdate {
    /// Per grain: the view its cells in the map were decided for, and how far it may move
    /// from there before a cell centre crosses its circle (0 for grains with neighbours,
    /// whose cells are decided every time).
    anchor: Vec<GrainView>,
    slack: Vec<f64>,
    /// Grains whose cells were decided and grains skipped, over all updates (the tests
    /// check that grains are skipped at all).
    pub decided: u64,
    /// See `decided`.
    pub skipped: u64,
    /// The grains that may overlap each grain.
    near: GrainNeighbours,
    /// Cells already decided in this update (cleared on exit).
    seen: Vec<u32>,
    /// Whole-lattice shifts of a grain's periodic images.
    shifts: Vec<[f64; 2]>,
    /// Per range of grains: the changes its isolated grains make.
    part_changes: Vec<Vec<Change>>,
}

impl CoverUpdate {
    /// The map was built afresh (by [`super::map::cover`]) for the grains `views`.
    pub fn reset(&mut self, views: &[GrainView]) {
        self.anchor.clear();
        self.anchor.extend_from_slice(views);
        self.slack.clear();
        self.slack.resize(views.len(), 0.0);
    }

    /// The cells of the padded slab `f` whose owner changes when the grains of the map
    /// `owner` (as last [`CoverUpdate::reset`] or updated here) move to `new` (the same
    /// grains, in the same order), appended to `out` in no particular order. `mark` is a
    /// per-cell scratch, all false on entry and on exit. Returns false, with `out` empty,
    /// when the update cannot be done in place: a grain moved more than [`MAX_MOVE`] or
    /// changed size, or a periodic lattice is too small for the grains' images to be told
    /// apart; map afresh then.
    pub fn changes(
        &mut self,
        f: &SlabFrame,
        new: &[GrainView],
        fluid: &(impl Fn(usize) -> bool + Sync),
        owner: &[u32],
        mark: &mut [bool],
        out: &mut Vec<Change>,
    ) -> bool {
        out.clear();
        // The anchors: where each grain's cells in `owner` were decided.
        let old = &mut self.anchor;
        if old.len() != new.len() {
            return false;
        }
        let mut rmax: f64 = 0.0;
        for (a, b) in old.iter().zip(new) {
            if a.radius != b.radius || moved(a, b) > MAX_MOVE {
                return false;
            }
            rmax = rmax.max(b.radius);
        }
        // Two grains are neighbours when their disks, before or after, may overlap: they
        // are never farther apart than this.
        let reach = 2.0 * (rmax + MAX_MOVE) + 1e-6;
        let lengths = [f.global_nx as f64, f.ny as f64];
        let periodic = [f.periodic_x, f.periodic_y];
        for a in 0..2 {
            // A periodic axis must hold two disjoint reaches, so that the nearest images
            // of two grains are the only ones that can meet.
            if periodic[a] && lengths[a] < 2.0 * reach + 2.0 {
                return false;
            }
        }
        self.shifts.clear();
        let sx: &[f64] = if f.periodic_x {
            &[0.0, 1.0, -1.0]
        } else {
            &[0.0]
        };
        let sy: &[f64] = if f.periodic_y {
            &[0.0, 1.0, -1.0]
        } else {
            &[0.0]
        };
        for &a in sx {
            for &b in sy {
                self.shifts.push([a * lengths[0], b * lengths[1]]);
            }
        }
        self.near.find(f, old, new, reach);
        // Isolated grains first, in parallel: their cells are no other grain's (before or
        // after the move), so no cell is decided twice and each range of grains lists its
        // own changes. The ranges' lists are joined in grain order, so the list holds the
        // isolated grains' changes by grain, then the others' (its consumers sort what they
        // take from it in any case).
        let (near, shifts) = (&self.near, &self.shifts);
        let parts = rayon::current_num_threads().clamp(1, 64);
        let chunk = new.len().div_ceil(parts).max(1);
        self.part_changes.resize_with(parts, Vec::new);
        // Ranges past the last grain run no task: nothing of theirs may stay.
        self.part_changes.iter_mut().for_each(Vec::clear);
        let counts: (u64, u64) = old
            .par_chunks_mut(chunk)
            .zip(self.slack.par_chunks_mut(chunk))
            .zip(self.part_changes.par_iter_mut())
            .enumerate()
            .map(|(t, ((old, slack), out))| {
                let (mut decided, mut skipped) = (0, 0);
                for (j, (old, slack)) in old.iter_mut().zip(slack.iter_mut()).enumerate() {
                    let g = t * chunk + j;
                    if !near.of(g).is_empty() {
                        continue;
                    }
                    // No cell centre can have crossed the circle of an isolated grain that
                    // moved less than its slack: its cells stay.
                    if moved(old, &new[g]) < *slack - 1e-9 {
                        skipped += 1;
                        continue;
                    }
                    decided += 1;
                    isolated_changes(f, shifts, old, &new[g], g as u32, fluid, owner, out);
                    *old = new[g];
                    *slack = slack_of(new[g].centre, new[g].radius);
                }
                (decided, skipped)
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        self.decided += counts.0;
        self.skipped += counts.1;
        for part in &self.part_changes {
            out.extend_from_slice(part);
        }
        // Then the grains with neighbours, one by one: a cell in several of their disks is
        // decided once (`mark`).
        for g in 0..new.len() {
            if self.near.of(g).is_empty() {
                continue;
            }
            self.decided += 1;
            for &s in &self.shifts {
                let co = [old[g].centre[0] + s[0], old[g].centre[1] + s[1]];
                let cn = [new[g].centre[0] + s[0], new[g].centre[1] + s[1]];
                let r = new[g].radius;
                let Some((ya, yb)) = rows_in_reach(f, co, cn, r) else {
                    continue;
                };
                for y in ya..=yb {
                    let o = chord(f, co, r, y);
                    let n = chord(f, cn, r, y);
                    let rest = minus(n, o);
                    for run in [o, rest[0], rest[1]] {
                        for x in run.0..=run.1 {
                            let k = f.padded(x - f.x0 as i64, y);
                            if mark[k] || !fluid(k) {
                                continue;
                            }
                            mark[k] = true;
                            self.seen.push(k as u32);
                            let to = decide(&self.near, &self.shifts, new, g, x, y);
                            if owner[k] != to {
                                out.push(Change {
                                    cell: k as u32,
                                    old: owner[k],
                                    new: to,
                                });
                            }
                        }
                    }
                }
            }
            old[g] = new[g];
            self.slack[g] = 0.0;
        }
        for &k in &self.seen {
            mark[k as usize] = false;
        }
        self.seen.clear();
        true
    }
}

/// The rows (first, last) that the disk of radius `r` at `co` (before) or `cn` (after)
/// can cover in the padded slab `f`, or `None` when it stays clear of the slab's columns.
fn rows_in_reach(f: &SlabFrame, co: [f64; 2], cn: [f64; 2], r: f64) -> Option<(i64, i64)> {
    let (xa, xb) = ((f.x0 as f64) - 1.0, (f.x0 + f.nx) as f64 + 1.0);
    if co[0].max(cn[0]) + r < xa || co[0].min(cn[0]) - r > xb {
        return None;
    }
    let ya = ((co[1].min(cn[1]) - r).floor() as i64).max(-1);
    let yb = ((co[1].max(cn[1]) + r).floor() as i64).min(f.ny as i64);
    Some((ya, yb))
}

/// The cells of the isolated grain `g` whose owner changes when it moves from `old` to
/// `new` (appended to `out`): only the difference of its old and new run in each row can
/// change, cells leaving the disk lose the grain and cells entering it gain it.
#[allow(clippy::too_many_arguments)]
fn isolated_changes(
    f: &SlabFrame,
    shifts: &[[f64; 2]],
    old: &GrainView,
    new: &GrainView,
    g: u32,
    fluid: &impl Fn(usize) -> bool,
    owner: &[u32],
    out: &mut Vec<Change>,
) {
    for s in shifts {
        let co = [old.centre[0] + s[0], old.centre[1] + s[1]];
        let cn = [new.centre[0] + s[0], new.centre[1] + s[1]];
        let r = new.radius;
        let Some((ya, yb)) = rows_in_reach(f, co, cn, r) else {
            continue;
        };
        for y in ya..=yb {
            let (o, n) = (chord(f, co, r, y), chord(f, cn, r, y));
            let (leave, enter) = (minus(o, n), minus(n, o));
            for (run, to) in [
                (leave[0], NONE),
                (leave[1], NONE),
                (enter[0], g),
                (enter[1], g),
            ] {
                for x in run.0..=run.1 {
                    let k = f.padded(x - f.x0 as i64, y);
                    if fluid(k) && owner[k] != to {
                        out.push(Change {
                            cell: k as u32,
                            old: owner[k],
                            new: to,
                        });
                    }
                }
            }
        }
    }
}

/// The owner of global cell (x, y) for the grains `views` under the rule of
/// `map::cover` (nearest centre, lower index on a tie), looked for among grain `g` and
/// its neighbours; the cell lies in g's disk before or after the move, so every grain
/// that covers it is among them.
fn decide(
    near: &GrainNeighbours,
    shifts: &[[f64; 2]],
    views: &[GrainView],
    g: usize,
    x: i64,
    y: i64,
) -> u32 {
    let near = near.of(g);
    let (mut best, mut bd) = (NONE, f64::INFINITY);
    for h in std::iter::once(g as u32).chain(near.iter().copied()) {
        let v = &views[h as usize];
        for s in shifts {
            let c = [v.centre[0] + s[0], v.centre[1] + s[1]];
            if !covers(c, v.radius, x, y) {
                continue;
            }
            // The same distance `cover` compares (cell centre minus image centre).
            let (dx, dy) = (x as f64 + 0.5 - c[0], y as f64 + 0.5 - c[1]);
            let d = dx * dx + dy * dy;
            if d < bd || (d == bd && h < best) {
                (best, bd) = (h, d);
            }
        }
    }
    best
}

/// The run of cells (global x, first and last; empty when first > last) of row `y` whose
/// centres a disk at `c` with radius `r` covers, by the very test of `map::cover`, clipped
/// to the padded slab's columns.
fn chord(f: &SlabFrame, c: [f64; 2], r: f64, y: i64) -> (i64, i64) {
    let (a, b) = run(c, r, y);
    let (xa, xb) = (f.x0 as i64 - 1, (f.x0 + f.nx) as i64);
    (a.max(xa), b.min(xb))
}

/// How far the disk at `c` with radius `r` can move before a cell centre crosses its
/// circle, at least (cells): |d − r| = |d² − r²| / (d + r) over the cells nearest the
/// circle in each row (the ends of the covered run and the cells just beyond, or the
/// cell nearest the centre's column in a row without one), where d + r < 2r + 2.
fn slack_of(c: [f64; 2], r: f64) -> f64 {
    let gap = |x: i64, y: i64| {
        let (dx, dy) = (x as f64 + 0.5 - c[0], y as f64 + 0.5 - c[1]);
        (dx * dx + dy * dy - r * r).abs()
    };
    let mut s = f64::INFINITY;
    for y in (c[1] - r).floor() as i64 - 1..=(c[1] + r).floor() as i64 + 1 {
        let (a, b) = run(c, r, y);
        if a <= b {
            s = s
                .min(gap(a - 1, y))
                .min(gap(a, y))
                .min(gap(b, y))
                .min(gap(b + 1, y));
        } else {
            s = s.min(gap((c[0] - 0.5).round() as i64, y));
        }
    }
    s / (2.0 * r + 2.0)
}

/// [`chord`] before clipping.
fn run(c: [f64; 2], r: f64, y: i64) -> (i64, i64) {
    let dy = y as f64 + 0.5 - c[1];
    let h2 = r * r - dy * dy;
    if h2 < 0.0 {
        return EMPTY;
    }
    let h = h2.sqrt();
    // First guesses from the chord's half-length, then nudged until `covers` agrees at
    // both ends (it decides, not the rounding of the square root).
    let mut a = (c[0] - 0.5 - h).ceil() as i64;
    let mut b = (c[0] - 0.5 + h).floor() as i64;
    while covers(c, r, a - 1, y) {
        a -= 1;
    }
    while a <= b && !covers(c, r, a, y) {
        a += 1;
    }
    while covers(c, r, b + 1, y) {
        b += 1;
    }
    while b >= a && !covers(c, r, b, y) {
        b -= 1;
    }
    if a > b {
        return EMPTY;
    }
    (a, b)
}

/// An empty run.
const EMPTY: (i64, i64) = (1, 0);

/// The cells of run `p` outside run `q`: at most two runs (either may be empty).
fn minus(p: (i64, i64), q: (i64, i64)) -> [(i64, i64); 2] {
    if p.0 > p.1 {
        return [EMPTY; 2];
    }
    if q.0 > q.1 || q.1 < p.0 || q.0 > p.1 {
        return [p, EMPTY];
    }
    let left = if p.0 < q.0 { (p.0, q.0 - 1) } else { EMPTY };
    let right = if q.1 < p.1 { (q.1 + 1, p.1) } else { EMPTY };
    [left, right]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::cover;
    use crate::test_slabs::{next, slab};

    /// Over many moves of crowded, overlapping grains (slabs with and without periodic
    /// faces, next to solid cells, grains crossing the slab's faces; in the last cases on
    /// quarter-cell positions, so that cell centres fall on circles and two grains are
    /// often equally near a cell), the map updated in place equals the map built afresh,
    /// cell for cell; every change is listed once, with the owner it had.
    #[test]
    fn updated_map_equals_a_fresh_cover() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let (mut isolated_changes, mut crowded_changes, mut refused) = (0, 0, 0);
        let (mut skipped, mut decided) = (0, 0);
        for case in 0..9 {
            // Round to quarter cells in the last three cases.
            let quarter = |v: f64| {
                if case >= 6 {
                    (v * 4.0).round() / 4.0
                } else {
                    v
                }
            };
            let (f, solid) = slab(case);
            let (cells, periodic) = (solid.len(), f.periodic_x);
            let fluid = |k: usize| !solid[k];
            // Half the grains in a cluster that overlaps, half spread out.
            let mut views: Vec<GrainView> = (0..40)
                .map(|n| {
                    let (cx, cy, span) = if n % 2 == 0 {
                        (f.x0 as f64 + 30.0, 30.0, 14.0)
                    } else {
                        (f.x0 as f64 - 6.0, -3.0, 80.0)
                    };
                    GrainView {
                        centre: [
                            quarter(cx + next(&mut seed) * span),
                            quarter(cy + next(&mut seed) * span),
                        ],
                        radius: if case >= 6 {
                            2.0 + (4.0 * next(&mut seed)).floor() * 0.5
                        } else {
                            2.0 + 4.0 * next(&mut seed)
                        },
                        velocity: [0.0; 2],
                        omega: 0.0,
                    }
                })
                .collect();
            let (mut owner, mut fresh) = (vec![NONE; cells], vec![NONE; cells]);
            let (mut touched, mut inner) = (Vec::new(), Vec::new());
            cover(&f, &views, fluid, &mut owner, &mut touched, &mut inner);
            let mut update = CoverUpdate::default();
            update.reset(&views);
            let mut mark = vec![false; cells];
            let mut changes = Vec::new();
            for round in 0..80 {
                // Small moves, a third of the grains creeping; now and then one grain
                // jumps more than MAX_MOVE.
                let jump = round % 17 == 16;
                let moved: Vec<GrainView> = views
                    .iter()
                    .enumerate()
                    .map(|(n, g)| {
                        let s = if jump && n == 5 {
                            3.0
                        } else if n % 3 == 0 {
                            0.01
                        } else {
                            0.3
                        };
                        let mut c = [
                            quarter(g.centre[0] + 2.0 * s * (next(&mut seed) - 0.5)),
                            quarter(g.centre[1] + 2.0 * s * (next(&mut seed) - 0.5)),
                        ];
                        if periodic {
                            c[0] = c[0].rem_euclid(f.global_nx as f64);
                            c[1] = c[1].rem_euclid(f.ny as f64);
                        }
                        GrainView { centre: c, ..*g }
                    })
                    .collect();
                // A grain wrapped across a periodic seam moves a lattice length: refused.
                let ok = update.changes(&f, &moved, &fluid, &owner, &mut mark, &mut changes);
                cover(&f, &moved, fluid, &mut fresh, &mut touched, &mut inner);
                assert!(mark.iter().all(|m| !m), "case {case}: marks left set");
                if !ok {
                    assert!(changes.is_empty());
                    refused += 1;
                    owner.clone_from(&fresh);
                    update.reset(&moved);
                } else {
                    let mut cells: Vec<u32> = changes.iter().map(|c| c.cell).collect();
                    cells.sort_unstable();
                    cells.dedup();
                    assert_eq!(
                        cells.len(),
                        changes.len(),
                        "case {case}: a cell listed twice"
                    );
                    for c in &changes {
                        assert_eq!(c.old, owner[c.cell as usize], "case {case}");
                        assert_ne!(c.old, c.new, "case {case}");
                        owner[c.cell as usize] = c.new;
                        let crowded = !update.near.of(c.new.min(c.old) as usize).is_empty();
                        if crowded {
                            crowded_changes += 1;
                        } else {
                            isolated_changes += 1;
                        }
                    }
                    assert!(owner == fresh, "case {case}, round {round}: maps differ");
                }
                views = moved;
            }
            (skipped, decided) = (skipped + update.skipped, decided + update.decided);
        }
        assert!(
            isolated_changes > 1000,
            "{isolated_changes} isolated changes"
        );
        assert!(crowded_changes > 1000, "{crowded_changes} crowded changes");
        assert!((36..360).contains(&refused), "{refused} refused of 720");
        // Isolated grains that moved less than their slack were skipped.
        assert!(
            skipped > decided / 20,
            "skipped {skipped}, decided {decided}"
        );
    }

    /// A periodic lattice too short to tell two grains' images apart is mapped afresh.
    #[test]
    fn small_periodic_lattices_are_refused() {
        let f = SlabFrame {
            nx: 20,
            ny: 20,
            x0: 0,
            global_nx: 20,
            stride: 22,
            periodic_x: true,
            periodic_y: false,
        };
        let g = GrainView {
            centre: [10.0, 10.0],
            radius: 4.0,
            velocity: [0.0; 2],
            omega: 0.0,
        };
        let moved = GrainView {
            centre: [10.1, 10.0],
            ..g
        };
        let cells = f.stride * (f.ny + 2);
        let (owner, mut mark, mut out) = (vec![NONE; cells], vec![false; cells], Vec::new());
        let mut u = CoverUpdate::default();
        u.reset(&[g]);
        assert!(!u.changes(&f, &[moved], &|_| true, &owner, &mut mark, &mut out));
    }
}
