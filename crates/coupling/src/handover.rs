//! Between fluid steps: the grains have moved, so the cells they cover change hands. A cell a
//! grain newly covers gives its fluid momentum to the grain (Aidun, Lu & Ding 1998); a cell it
//! uncovers is refilled and its momentum is taken from the grain. Also the fluid half of the
//! momentum balance.

use super::cover_update::Change;
use super::exchange::{rigid_velocity, Coupler};
use super::interface::{Common, Interface};
use super::link_cells::{LinkCells, LinkRule};
use super::map::neighbour;
use super::map::{cover, nearest_image, set_cells, GrainView, SlabFrame, NONE};
use super::Refill;
use decomposition::Comm;
use lbm::d2q9::{CX, CY, Q};
use lbm::moving::Refill as CellRefill;
use lbm::{FluidBackend, Lattice, Real};

impl Coupler {
    /// Stage "coupling", after the grains moved to `views` (ids `ids`, increasing): map them
    /// again. A fluid cell that a grain now covers hands its momentum to the grain; a cell a
    /// grain uncovers is refilled (equilibrium at the surface velocity with its fluid
    /// neighbours' mean density, plus their non-equilibrium part with
    /// [`Refill::Extrapolation`]) and its momentum is taken from the grain. Both go to
    /// [`Coupler::handover_loads`]. Call before the fluid's halo refill.
    pub fn remap<T: Real>(
        &mut self,
        fluid: &mut dyn FluidBackend<T>,
        views: &[GrainView],
        ids: &[u64],
        comm: &dyn Comm,
    ) {
        let c = &mut self.common;
        c.handover.reset(views, c.frame.global_nx);
        self.cells.remap(&mut self.common, fluid, views, ids, comm);
    }

    /// Momentum of the fluid in this slab's interior cells that no grain covers (lattice
    /// units), one partial sum per column (y increasing): the fluid half of the momentum
    /// balance, to be added in column order over all ranks.
    pub fn fluid_momentum_columns<T: Real>(
        &self,
        fluid: &mut dyn FluidBackend<T>,
    ) -> Vec<[f64; 2]> {
        let f = self.common.frame;
        let lat = fluid.lattice();
        let mut cells = Vec::new();
        for x in 0..f.nx as i64 {
            for y in 0..f.ny as i64 {
                let k = f.padded(x, y);
                if lat.is_fluid_at(k) && self.cells.is_open(k) {
                    cells.push(k as u32);
                }
            }
        }
        let mut j = Vec::new();
        fluid.momentum_of_cells(&cells, &mut j);
        let mut columns = vec![[0.0; 2]; f.nx];
        for (&k, m) in cells.iter().zip(&j) {
            let c = &mut columns[(f.local(k as usize).0) as usize];
            c[0] += m[0];
            c[1] += m[1];
        }
        columns
    }
}

impl<R: LinkRule> LinkCells<R> {
    /// [`Coupler::remap`] for the bounce-back schemes: the cover map follows the grains,
    /// and the cells that change hands are handed over into `c.handover`.
    pub(super) fn remap_links<T: Real>(
        &mut self,
        c: &mut Common,
        fluid: &mut dyn FluidBackend<T>,
        views: &[GrainView],
        ids: &[u64],
        comm: &dyn Comm,
    ) {
        let t = std::time::Instant::now();
        let f = c.frame;
        // The same grains in view: update the map in place (`cover_update.rs`); otherwise
        // map afresh into `next_owner` and compare.
        let in_place = {
            let lat = fluid.lattice();
            c.owner_ids == ids
                && self.update.changes(
                    &f,
                    views,
                    &|k| lat.is_fluid_at(k),
                    &self.owner,
                    &mut self.mark,
                    &mut self.changes,
                )
        };
        if in_place {
            self.in_place_remaps += 1;
        } else {
            self.fresh_remaps += 1;
            self.changes_afresh(c, fluid.lattice(), views, ids);
            self.update.reset(views);
        }
        c.passes[super::pass::MAP] += t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        // Refills average whole neighbour cells, across faces too: the halos must hold
        // them now, as one rank would see them.
        fluid.refresh_halos_full(comm);
        // The interior cells changing hands, uncovered ones first, each kind grain by grain
        // (id order) and row by row: every per-grain, per-column sum below is then added in
        // increasing row, whatever the partition.
        let new_index = |id: u64| ids.binary_search(&id).ok();
        let mut events: Vec<(u32, u32, bool)> = std::mem::take(&mut self.events);
        events.clear();
        let (nx, ny) = (f.nx as i64, f.ny as i64);
        for ch in &self.changes {
            let (x, y) = f.local(ch.cell as usize);
            if x < 0 || y < 0 || x >= nx || y >= ny {
                continue;
            }
            if ch.old == NONE {
                // Covered: the grain takes the cell's momentum (Aidun, Lu & Ding 1998).
                events.push((ch.cell, ch.new, true));
            } else if ch.new == NONE {
                // Uncovered, by a grain that is still in view (it moved less than a cell).
                if let Some(g) = new_index(c.owner_ids[ch.old as usize]) {
                    events.push((ch.cell, g as u32, false));
                }
            }
        }
        events.sort_unstable_by_key(|&(k, g, covered)| (covered, g, k));
        // From here on a cell counts as covered when it is covered before or after the
        // move: the newly covered ones are written now, the uncovered ones cleared last.
        for ch in &self.changes {
            if ch.old == NONE {
                self.owner[ch.cell as usize] = ch.new;
            }
        }
        self.newly.clear();
        self.refills.clear();
        let lat = fluid.lattice();
        for &(k, g, covered) in &events {
            if covered {
                self.newly.push(k);
            } else {
                let r = self.refill_for(&f, k as usize, &views[g as usize], |m| lat.is_fluid_at(m));
                self.refills.push(r);
            }
        }
        fluid.momentum_of_cells(&self.newly, &mut self.cell_momentum);
        fluid.apply_refills(&self.refills, &mut self.refill_momentum);
        let (mut a, mut b) = (0, 0);
        for &(k, g, covered) in &events {
            let (j, sign) = if covered {
                a += 1;
                (self.cell_momentum[a - 1], 1.0)
            } else {
                b += 1;
                (self.refill_momentum[b - 1], -1.0)
            };
            let p = f.centre(k as usize);
            let grain = &views[g as usize];
            let image = nearest_image(&f, grain, p);
            let r = [p[0] - image[0], p[1] - image[1]];
            let load = [sign * j[0], sign * j[1], sign * (r[0] * j[1] - r[1] * j[0])];
            let col = c.column(k as usize);
            c.handover
                .add(g as usize, grain.centre[0], image[0], col, load);
        }
        self.events = events;
        self.lists.follow(ids);
        if in_place {
            self.lists.mark_near(&f, &self.changes, &self.owner);
            for ch in &self.changes {
                self.owner[ch.cell as usize] = ch.new;
            }
        } else {
            self.lists.mark_all();
            std::mem::swap(&mut self.owner, &mut self.next_owner);
            // `next_owner` now holds the old map and the newly covered cells: clear them
            // (it is all NONE between remaps).
            for &k in self.old_cells.iter() {
                self.next_owner[k as usize] = NONE;
            }
            for ch in &self.changes {
                self.next_owner[ch.cell as usize] = NONE;
            }
        }
        c.mapped.clear();
        c.mapped.extend_from_slice(views);
        c.owner_ids.clear();
        c.owner_ids.extend_from_slice(ids);
        c.passes[super::pass::HANDOVER] += t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        self.rebuild_lists(&f, fluid.lattice(), views);
        c.passes[super::pass::LISTS] += t.elapsed().as_secs_f64();
    }

    /// Map the grains `views` (ids `ids`) afresh into `next_owner` and list in `changes`
    /// every cell whose owner's id differs from `owner`'s (old owners as indices into
    /// `owner_ids`, new ones into `ids`). `old_cells` receives the cells set in `owner`.
    fn changes_afresh<T: Real>(
        &mut self,
        c: &Common,
        lat: &Lattice<T>,
        views: &[GrainView],
        ids: &[u64],
    ) {
        let f = c.frame;
        let fluid = |k: usize| lat.is_fluid_at(k);
        set_cells(
            &f,
            &c.mapped,
            &self.owner,
            &mut self.mark,
            &mut self.old_cells,
        );
        self.new_cells.clear();
        if self.next_owner.len() != self.owner.len() {
            self.next_owner = vec![NONE; self.owner.len()];
        }
        cover(
            &f,
            views,
            fluid,
            &mut self.next_owner,
            &mut self.new_cells,
            &mut self.scratch,
        );
        self.changes.clear();
        for &k in self.old_cells.iter().chain(self.new_cells.iter()) {
            let ku = k as usize;
            if self.mark[ku] {
                continue;
            }
            self.mark[ku] = true;
            let (old, new) = (self.owner[ku], self.next_owner[ku]);
            let old_id = (old != NONE).then(|| c.owner_ids[old as usize]);
            let new_id = (new != NONE).then(|| ids[new as usize]);
            if old_id != new_id {
                self.changes.push(Change { cell: k, old, new });
            }
        }
        for &k in self.old_cells.iter().chain(self.new_cells.iter()) {
            self.mark[k as usize] = false;
        }
    }

    /// How to refill padded cell `k` that grain `g` has just uncovered: its neighbours
    /// (halo ones too) that are fluid outside every grain (before and after the move), and
    /// the one most nearly along the surface normal for [`Refill::Extrapolation`].
    fn refill_for(
        &self,
        f: &SlabFrame,
        k: usize,
        g: &GrainView,
        fluid: impl Fn(usize) -> bool,
    ) -> CellRefill {
        let f = *f;
        let p = f.centre(k);
        let c = nearest_image(&f, g, p);
        let normal = [p[0] - c[0], p[1] - c[1]];
        let mut mask = 0u16;
        let mut along: Option<(f64, usize)> = None;
        for i in 1..Q {
            let m = neighbour(&f, k, i, 1);
            if !fluid(m) || self.owner[m] != NONE {
                continue;
            }
            mask |= 1 << i;
            let dot = (CX[i] as f64 * normal[0] + CY[i] as f64 * normal[1])
                / ((CX[i] * CX[i] + CY[i] * CY[i]) as f64).sqrt();
            if along.is_none_or(|(d, _)| dot > d) {
                along = Some((dot, i));
            }
        }
        let extrapolate = match (self.refill, along) {
            (Refill::Extrapolation, Some((_, i))) => i as u8,
            _ => 0,
        };
        CellRefill {
            cell: k as u32,
            neighbours: mask,
            extrapolate,
            velocity: rigid_velocity(&f, g, p),
        }
    }
}
