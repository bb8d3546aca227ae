//! Each grain's boundary cells (bounce-back schemes), kept from step to step and rescanned
//! only for grains near a cell that changed hands.
//!
//! A grain's list (the interior fluid cells no grain covers that neighbour one of its
//! cells, each with its link masks) depends only on the cover map within two cells of the
//! cells it owns. So when a remap changes the owner of cell e, only the grains owning a
//! cell within two cells of e (before or after) can see their list change; the others keep
//! theirs. Grains whose box comes within three cells of the slab's edge are always
//! rescanned (their lists also read the halo, whose changes are not listed), as are grains
//! new to this slab. The kept lists are the very lists a rescan would give, so the
//! boundary list, and every bit after it, is unchanged (tested against a full rescan).

use super::cover_update::Change;
use super::map::{GrainView, SlabFrame, NONE};
use lbm::d2q9::Q;
use rayon::prelude::*;

/// One boundary cell of a grain's list, with what the cover map decides about its links
/// (so the plan reads the map only for foreign links). Bit i − 1 of each mask is about
/// direction i.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(super) struct Entry {
    /// Padded cell.
    pub cell: u32,
    /// Local row.
    pub row: u32,
    /// Links: the neighbour at x − c_i is covered by a grain.
    pub links: u8,
    /// Links whose covering grain is not the one the entry is listed with (the lowest
    /// index among the cell's neighbours' owners).
    pub foreign: u8,
    /// The neighbour at x + c_i is fluid and covered by no grain (interpolated
    /// bounce-back below ½ reads it).
    pub plain: u8,
}

/// The grains' boundary lists and which must be rescanned.
#[derive(Debug, Default)]
pub(super) struct BoundaryLists {
    /// Per grain view: its entries, in scan order.
    lists: Vec<Vec<Entry>>,
    /// Ids of the views the lists belong to (increasing).
    ids: Vec<u64>,
    /// Per grain view: rescan it.
    dirty: Vec<bool>,
    /// Grains rescanned and grains kept, summed over all rebuilds (the tests check that
    /// lists are kept at all).
    pub rescanned: u64,
    /// See `rescanned`.
    pub kept: u64,
}

impl BoundaryLists {
    /// Per grain view: its entries, in scan order.
    pub fn per_grain(&self) -> &[Vec<Entry>] {
        &self.lists
    }

    /// Forget every list (the next rebuild rescans all grains).
    pub fn clear(&mut self) {
        self.ids.clear();
        self.lists.clear();
        self.dirty.clear();
    }

    /// Before a rebuild for the grains `ids` (increasing): carry the kept lists over to
    /// the new views by id and mark the grains new to the slab dirty.
    pub fn follow(&mut self, ids: &[u64]) {
        if self.ids != ids {
            let mut old = std::mem::take(&mut self.lists);
            let mut lists = Vec::with_capacity(ids.len());
            self.dirty.clear();
            let mut j = 0;
            for &id in ids {
                while j < self.ids.len() && self.ids[j] < id {
                    j += 1;
                }
                if j < self.ids.len() && self.ids[j] == id {
                    lists.push(std::mem::take(&mut old[j]));
                    self.dirty.push(false);
                } else {
                    lists.push(Vec::new());
                    self.dirty.push(true);
                }
            }
            self.lists = lists;
            self.ids.clear();
            self.ids.extend_from_slice(ids);
        }
        self.dirty.resize(ids.len(), true);
    }

    /// After a remap that kept the same grains in view (call after
    /// [`BoundaryLists::follow`]): `changes` lists the cells whose owner changed, with both
    /// owners, and `owner` holds at every other cell its owner (the same before and after).
    /// Mark every grain that owns, before or after, a cell within two cells of a changed
    /// one.
    pub fn mark_near(&mut self, f: &SlabFrame, changes: &[Change], owner: &[u32]) {
        for c in changes {
            for g in [c.old, c.new] {
                if g != NONE {
                    self.dirty[g as usize] = true;
                }
            }
            let (ex, ey) = f.local(c.cell as usize);
            for y in (ey - 2).max(-1)..=(ey + 2).min(f.ny as i64) {
                for x in (ex - 2).max(-1)..=(ex + 2).min(f.nx as i64) {
                    let k = f.padded(x, y);
                    if owner[k] != NONE {
                        self.dirty[owner[k] as usize] = true;
                    }
                }
            }
        }
    }

    /// Mark every grain (a remap that mapped afresh: rescan all).
    pub fn mark_all(&mut self) {
        self.dirty.iter_mut().for_each(|d| *d = true);
    }

    /// Rescan the dirty grains and those near the slab's edge (in parallel). All grains are
    /// clean afterwards.
    pub fn rebuild(
        &mut self,
        f: &SlabFrame,
        owner: &[u32],
        fluid: &(impl Fn(usize) -> bool + Sync),
        views: &[GrainView],
    ) {
        debug_assert_eq!(self.lists.len(), views.len(), "call follow first");
        let dirty = &self.dirty;
        let rescanned: u64 = self
            .lists
            .par_iter_mut()
            .enumerate()
            .with_min_len(16)
            .map(|(g, out)| {
                if !dirty[g] && !near_edge(f, &views[g]) {
                    return 0;
                }
                out.clear();
                boundary_of(f, owner, fluid, views, g, |e| out.push(e));
                1
            })
            .sum();
        self.rescanned += rescanned;
        self.kept += views.len() as u64 - rescanned;
        self.dirty.iter_mut().for_each(|d| *d = false);
    }

    /// Every grain's entries in grain order, each with the grain's index.
    #[cfg(test)]
    pub fn entries(&self) -> impl Iterator<Item = (u32, &Entry)> {
        self.lists
            .iter()
            .enumerate()
            .flat_map(|(g, list)| list.iter().map(move |e| (g as u32, e)))
    }
}

/// Whether grain `g`'s box, widened by three cells, leaves the slab's interior (its list
/// then reads halo cells, or a periodic image).
fn near_edge(f: &SlabFrame, g: &GrainView) -> bool {
    let r = g.radius + 3.0;
    let x = g.centre[0] - f.x0 as f64;
    let y = g.centre[1];
    (x - r).floor() < 0.0
        || (x + r).floor() >= f.nx as f64
        || (y - r).floor() < 0.0
        || (y + r).floor() >= f.ny as f64
}

/// Visit the boundary cells of grain `g` in order (image by image, each image's box of
/// radius r + 1 row by row), each as an [`Entry`]. A cell is a boundary cell when it is
/// interior, `fluid`, uncovered (`owner` is [`NONE`]) and one of its eight neighbours is
/// covered; it is listed with the lowest-index grain among its neighbours' owners (which
/// the cell's neighbours alone decide, so a kept list stays right), and once.
pub(super) fn boundary_of(
    f: &SlabFrame,
    owner: &[u32],
    fluid: &impl Fn(usize) -> bool,
    views: &[GrainView],
    g: usize,
    mut visit: impl FnMut(Entry),
) {
    use super::map::neighbour;
    let grain = &views[g];
    let reach = grain.radius + 1.0;
    // Boxes of earlier images (global x, y ranges), where the lattice is so small that
    // two images' boxes can share a cell.
    let (mut earlier, mut images) = ([[0i64; 4]; 9], 0);
    for c in f.images(grain) {
        f.for_box(c, reach, |k, x, y| {
            let interior = x >= 0 && y >= 0 && x < f.nx as i64 && y < f.ny as i64;
            if !interior || owner[k] != NONE || !fluid(k) {
                return;
            }
            let (mut links, mut first) = (0u8, NONE);
            let mut owners = [NONE; Q];
            for i in 1..Q {
                owners[i] = owner[neighbour(f, k, i, -1)];
                links |= ((owners[i] != NONE) as u8) << (i - 1);
                first = first.min(owners[i]);
            }
            let gx = x + f.x0 as i64;
            let seen = earlier[..images]
                .iter()
                .any(|b| (b[0]..=b[1]).contains(&gx) && (b[2]..=b[3]).contains(&y));
            if first == g as u32 && !seen {
                let (mut foreign, mut plain) = (0u8, 0u8);
                for i in 1..Q {
                    let other = owners[i] != NONE && owners[i] != first;
                    foreign |= (other as u8) << (i - 1);
                    let ahead = neighbour(f, k, i, 1);
                    let open = owner[ahead] == NONE && fluid(ahead);
                    plain |= (open as u8) << (i - 1);
                }
                visit(Entry {
                    cell: k as u32,
                    row: y as u32,
                    links,
                    foreign,
                    plain,
                });
            }
        });
        earlier[images] = [
            (c[0] - reach).floor() as i64,
            (c[0] + reach).floor() as i64,
            (c[1] - reach).floor() as i64,
            (c[1] + reach).floor() as i64,
        ];
        images += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cover_update::CoverUpdate;
    use crate::map::cover;
    use crate::test_slabs::{grains_at_rest, next, slab};

    /// Over many remaps of crowded, touching, moving grains (some leaving and entering the
    /// view, some crossing the slab's faces and periodic seams, next to solid cells), the
    /// kept-and-rescanned lists equal a full rescan, entry for entry, and most grains are
    /// kept.
    #[test]
    fn kept_lists_equal_a_full_rescan() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        for case in 0..6 {
            let (f, solid) = slab(case);
            let cells = solid.len();
            let fluid = |k: usize| !solid[k];
            // Grains with ids 0..40; a few drift fast, the rest barely move.
            let mut all = grains_at_rest(&f, 40, &mut seed);
            let step: Vec<[f64; 2]> = (0..40)
                .map(|n| {
                    let s = if n % 5 == 0 { 0.4 } else { 0.02 };
                    [s * (next(&mut seed) - 0.5), s * (next(&mut seed) - 0.5)]
                })
                .collect();
            let (mut owner, mut fresh) = (vec![NONE; cells], vec![NONE; cells]);
            let (mut touched, mut inner) = (vec![], vec![]);
            let mut ids: Vec<u64> = Vec::new();
            let mut lists = BoundaryLists::default();
            let mut update = CoverUpdate::default();
            let (mut mark, mut changes) = (vec![false; cells], Vec::new());
            let (mut in_place, mut foreign, mut plain_below) = (0, 0, 0);
            for round in 0..60 {
                // Grain 3 leaves the view for rounds 20..30, grain 11 for 40..45.
                let hidden = |id: usize| {
                    (id == 3 && (20..30).contains(&round))
                        || (id == 11 && (40..45).contains(&round))
                };
                let new_ids: Vec<u64> = (0..40u64).filter(|&i| !hidden(i as usize)).collect();
                let views: Vec<GrainView> = new_ids.iter().map(|&i| all[i as usize]).collect();
                cover(&f, &views, fluid, &mut fresh, &mut touched, &mut inner);
                // As `Coupler::remap` does: in place when the same grains stay in view,
                // otherwise afresh with every grain rescanned.
                if round > 0
                    && ids == new_ids
                    && update.changes(&f, &views, &fluid, &owner, &mut mark, &mut changes)
                {
                    in_place += 1;
                    for c in &changes {
                        if c.old == NONE {
                            owner[c.cell as usize] = c.new;
                        }
                    }
                    lists.follow(&new_ids);
                    lists.mark_near(&f, &changes, &owner);
                    for c in &changes {
                        owner[c.cell as usize] = c.new;
                    }
                    assert!(owner == fresh, "case {case}, round {round}");
                } else {
                    if round == 0 {
                        lists.clear();
                    }
                    lists.follow(&new_ids);
                    if round > 0 {
                        lists.mark_all();
                    }
                    owner.clone_from(&fresh);
                    update.reset(&views);
                }
                ids = new_ids;
                let mut kept = Vec::new();
                lists.rebuild(&f, &owner, &fluid, &views);
                kept.extend(lists.entries().map(|(g, e)| (g, *e)));
                let mut full = Vec::new();
                for g in 0..views.len() {
                    boundary_of(&f, &owner, &fluid, &views, g, |e| full.push((g as u32, e)));
                }
                assert_eq!(kept, full, "case {case}, round {round}");
                // Every boundary cell is listed once, with one grain.
                let mut cells: Vec<u32> = full.iter().map(|e| e.1.cell).collect();
                cells.sort_unstable();
                cells.dedup();
                assert_eq!(cells.len(), full.len(), "case {case}, round {round}");
                assert!(full.len() > 200, "case {case}: {} entries", full.len());
                // Each entry's masks say what the map says around its cell.
                for &(g, e) in &full {
                    let k = e.cell as usize;
                    for i in 1..Q {
                        let bit = 1u8 << (i - 1);
                        let behind = owner[crate::map::neighbour(&f, k, i, -1)];
                        let ahead = crate::map::neighbour(&f, k, i, 1);
                        assert_eq!(e.links & bit != 0, behind != NONE);
                        assert_eq!(e.foreign & bit != 0, behind != NONE && behind != g);
                        assert_eq!(e.plain & bit != 0, owner[ahead] == NONE && fluid(ahead));
                    }
                    foreign += e.foreign.count_ones();
                    plain_below += (e.plain != 0xff) as u32;
                }
                for (g, d) in all.iter_mut().zip(&step) {
                    g.centre = [g.centre[0] + d[0], g.centre[1] + d[1]];
                }
            }
            assert!(in_place > 30, "case {case}: {in_place} remaps in place");
            // Crowded grains share boundary cells; solid cells or grains sit upstream.
            assert!(
                foreign > 0 && plain_below > 0,
                "case {case}: {foreign}, {plain_below}"
            );
            assert!(
                lists.kept > lists.rescanned / 4,
                "case {case}: kept {} rescanned {}",
                lists.kept,
                lists.rescanned
            );
        }
    }
}
