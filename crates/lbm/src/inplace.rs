//! The in-place sweep (the AA pattern, Bailey et al. 2009): one buffer instead of two. Steps
//! alternate between a *push* step, which pulls each cell's populations from its neighbours'
//! slots and pushes the results back into them, and a *local* step, which reads and writes
//! only the cell's own slots (see [`Layout`]). Each cell reads and writes the same nine slots
//! in a step, so the rayon tasks never race, and no line is written that was not just read
//! (no write-allocate traffic).
//!
//! The collision, the wall and open-face rules are the two-array kernel's, through
//! [`Access`]; the values a cell pulls are the same, so the results have the same bits (tested
//! for every boundary on 1–4 ranks). What differs is the halo: before a push step the halos
//! hold the neighbours' results as the two-array kernel's do (same fills, same exchange);
//! after it, the results the boundary cells pushed out are brought back in ("drained"): each
//! halo value the two-array kernel would have pulled is evaluated by the same face rules and
//! written into the slot of the cell that pulls it, and across rank faces the neighbours
//! exchange them.

use super::aligned::AlignedBuf;
use super::boundary::{Access, Src};
use super::bulk_aa::{bulk_kernels, sweep_run, BULK_LANES};
use super::collision::{with_collider, Collider};
use super::d2q9::{CX, CY, MIRROR_X, MIRROR_Y, OPP, Q};
use super::lattice::{Face, FaceCondition, Lattice, Layout, StepError, FLUID, HALO_DIRS};
use super::moving::{MovingCells, MovingRun};
use super::real::Real;
use super::rows::{block_tasks, DrainPlan};
use super::wall_runs::sweep_wall_run;
use decomposition::{pack_words, unpack_words, Comm, Side};
use rayon::prelude::*;

use std::sync::atomic::{AtomicUsize, Ordering};

/// Populations that leave through the west face (c_x = −1) and the east face (c_x = +1).
const WESTWARD: [usize; HALO_DIRS] = [3, 6, 7];
const EASTWARD: [usize; HALO_DIRS] = [1, 5, 8];
/// "No slot": the halo value is zero (faces whose halo the two-array kernel leaves empty).
pub(crate) const NONE: usize = usize::MAX;

/// A pointer into the one buffer that row tasks share (each touches only its cells' slots).
#[derive(Clone, Copy)]
struct Shared<T>(*mut T);
// SAFETY: tasks write disjoint slots (see the module docs).
unsafe impl<T> Send for Shared<T> {}
unsafe impl<T> Sync for Shared<T> {}

impl<T> Shared<T> {
    /// The pointer (a method, so closures capture the whole `Send` wrapper).
    #[inline(always)]
    fn ptr(&self) -> *mut T {
        self.0
    }
}

impl<T: Real> Lattice<T> {
    /// The access of the step about to be taken (see [`Access`]).
    pub(crate) fn access(&self) -> Access {
        Access::new(self.layout, self.plane, self.stride)
    }

    /// Whether the populations are held in one buffer (the AA pattern).
    pub fn in_place(&self) -> bool {
        self.layout != Layout::TwoArray
    }

    /// Whether an x face is exchanged with a neighbouring slab (its edge column is then
    /// swept after the halo arrives, row by row in parallel).
    pub(crate) fn exchanges_x(&self) -> bool {
        self.faces[..2].contains(&FaceCondition::Exchange)
    }

    /// Rows per block of a sweep that sums partially saturated loads per body: about four
    /// blocks per thread, so that tasks balance, and as tall as that allows (a body whose
    /// box crosses a block's edge is collected by the host instead), 4 to 256 rows.
    fn sum_block_rows(&self) -> usize {
        (self.ny / (4 * rayon::current_num_threads())).clamp(4, 256)
    }

    /// Hold the populations in one buffer from now on: half the memory, and no
    /// write-allocate traffic. The state is kept (the current buffer's post-collision values
    /// move to the slots of the opposite direction, halos included).
    pub fn make_in_place(&mut self) {
        if self.in_place() {
            return;
        }
        let mut b = std::mem::take(&mut self.buf[self.cur]);
        let plane = self.plane;
        for j in [1, 2, 5, 6] {
            let o = OPP[j];
            let (lo, hi) = b.split_at_mut(o * plane);
            lo[j * plane..(j + 1) * plane].swap_with_slice(&mut hi[..plane]);
        }
        self.buf = [b, AlignedBuf::default()];
        self.cur = 0;
        self.layout = Layout::Local;
    }

    /// One in-place step (see the module docs) with the cells of moving surfaces in
    /// `moving` (see [`super::moving`]): link cells are prepared from the step's start state
    /// just before the sweep reaches them, partially saturated cells are computed by the
    /// sweep itself. Returns the plan index and density of the first such cell that went
    /// bad. Collective when the slab has neighbours.
    pub(crate) fn stream_collide_in_place(
        &mut self,
        comm: &dyn Comm,
        moving: &mut MovingCells<'_>,
    ) -> Result<Option<(usize, f64)>, StepError> {
        if self.step == 0 {
            self.fill_halo();
        }
        let push = self.layout == Layout::Local;
        if !push && self.redrain {
            // Cells refilled since the last push step (a surface uncovered them): their
            // values go to the slots their neighbours pull, as the last drain did.
            self.drain(comm);
        }
        self.redrain = false;
        let exchanged = |f: &FaceCondition| *f == FaceCondition::Exchange;
        let edge = [
            exchanged(&self.faces[0]).then_some(0),
            exchanged(&self.faces[1]).then_some(self.nx - 1),
        ];
        // With no exchanged face (no edge pass), partially saturated cells sum the loads of
        // the bodies inside one block of rows in the sweep, which then goes by those blocks.
        let block = (!self.exchanges_x()).then(|| self.sum_block_rows());
        let run = MovingRun::new(moving, edge, block);
        let summed = run.as_ref().is_some_and(|r| r.sum_block().is_some());
        let peers = self.halo.peer(Side::Left).is_some() || self.halo.peer(Side::Right).is_some();
        // Open corners read their diagonal neighbour's values of the step's start, which the
        // sweep overwrites in place: taken first (the two-array kernel reads them untouched).
        self.corner_drho = Some(self.corner_drhos(self.access()));
        if push {
            // The neighbours' results into the halos, as the two-array kernel's, while the
            // cells that do not read them are swept (partially saturated cells among them:
            // they read only their own slots). With link cells the sweep waits: those next
            // to the faces read both the halo and slots the sweep rewrites.
            self.pack_halo();
            let waits = run.as_ref().is_some_and(|r| r.precomputes());
            let mut halo = std::mem::take(&mut self.halo);
            let waited = halo.exchange(comm, &mut || {
                if !waits {
                    self.sweep_in_place(true, run.as_ref())
                }
            });
            self.halo = halo;
            self.halo_wait_s += waited;
            if peers {
                self.unpack_halo();
            }
            if let Some(r) = run.as_ref().filter(|_| waits) {
                self.precompute_edge(r);
                self.sweep_in_place(true, Some(r));
            }
            if peers {
                self.sweep_in_place(false, run.as_ref());
            }
        } else {
            if let Some(r) = &run {
                self.precompute_edge(r);
            }
            self.sweep_in_place(true, run.as_ref());
            self.sweep_in_place(false, run.as_ref());
        }
        self.corner_drho = None;
        self.layout = if push { Layout::Pushed } else { Layout::Local };
        // A moving-surface cell that went bad is the coupling's to report (it names the
        // surface), before the sweep's rows that hold it.
        self.check_sweep(comm, run.as_ref())?;
        if push {
            self.drain(comm);
            self.redrain = run.is_some();
        }
        self.step += 1;
        let bad = run.and_then(|r| {
            let n = r.first_bad()?;
            Some((n, self.density_at(r.cells()[n] as usize)))
        });
        if let MovingCells::Partial(_, _, sums) = moving {
            sums.made = summed;
        }
        Ok(bad)
    }

    /// Prepare the link cells of `run` on the exchanged edge columns before the sweep (the
    /// others are prepared by the sweep, just ahead of it).
    fn precompute_edge(&mut self, run: &MovingRun<'_>) {
        if !run.precomputes() || !self.exchanged_faces().contains(&true) {
            return;
        }
        let (base, acc) = (Shared(self.buf[0].as_mut_ptr()), self.access());
        let this = &*self;
        (0..this.ny).into_par_iter().with_min_len(64).for_each(|y| {
            // SAFETY: no cell has been swept yet.
            unsafe { run.precompute_row(this, base.ptr(), acc, y, true) }
        });
    }

    /// One parallel pass over the rows: bulk and special cells (`inner`), or the cells next
    /// to exchanged faces, with the moving-surface cells of `moving`: link cells prepared
    /// ahead of the sweep (in the inner pass), partially saturated cells computed by it.
    fn sweep_in_place(&mut self, inner: bool, moving: Option<&MovingRun<'_>>) {
        with_collider!(self.collision, self.smagorinsky, self.params, |c| self
            .sweep_aa(c, inner, moving));
    }

    fn sweep_aa<C: Collider<T>>(&mut self, c: &C, inner: bool, moving: Option<&MovingRun<'_>>) {
        let acc = self.access();
        let base = Shared(self.buf[0].as_mut_ptr());
        let partial = moving.and_then(|r| r.partial_sweep(self.stride));
        let ns = self.forces.solids();
        let mut slot_values = std::mem::take(&mut self.forces.values);
        let slots = Shared(slot_values.as_mut_ptr());
        let mut row_bad = std::mem::take(&mut self.row_bad);
        let mut tasks = std::mem::take(&mut self.block_tasks);
        let this = &*self;
        let kernels = bulk_kernels::<T, C>();
        let sweep_row = |y: usize, bad: &mut u8| {
            let row = &this.plan[y];
            let mut b = false;
            let yp = y + 1;
            // This row's partially saturated cells (increasing padded index).
            let psm = partial.as_ref().map(|p| (p, p.row(y)));
            let (cells, first_slot) = if inner {
                let mut next = psm.as_ref().map_or(0, |(_, r)| r.start);
                for &(x0, x1) in &row.bulk {
                    let k0 = yp * this.stride + x0 as usize + 1;
                    let n = (x1 - x0) as usize;
                    // The plan cells inside this run (the others are special cells).
                    let run_cells = psm.as_ref().map(|(p, r)| {
                        while next < r.end && p.cell(next) < k0 {
                            next += 1;
                        }
                        let first = next;
                        while next < r.end && p.cell(next) < k0 + n {
                            next += 1;
                        }
                        (*p, first..next)
                    });
                    // SAFETY: the run's cells are this task's; each reads and writes only
                    // its own nine slots; so are the plan cells' momentum slots.
                    b |= unsafe { sweep_run(c, kernels, base.ptr(), acc, k0, n, run_cells) };
                }
                (&row.special, this.forces.row_start[y])
            } else {
                // Loads summed per body come only from a sweep with no exchanged face (no
                // edge cells): the edge pass goes row by row in parallel.
                assert!(
                    row.edge.is_empty() || !partial.as_ref().is_some_and(|p| p.sums_bodies()),
                    "edge cells in a sweep that sums per body"
                );
                (&row.edge, this.forces.row_start[y] + row.special.len())
            };
            // Wall runs (inner rows only) go in lanes where no partially saturated cell lies
            // in them; the rest of the cells one by one.
            let runs: &[(u32, u32)] = if inner { &row.wall_runs } else { &[] };
            let mut runs = runs.iter().peekable();
            let mut j = 0;
            while j < cells.len() {
                let x = cells[j];
                if let Some(&(_, count)) = runs.next_if(|r| r.0 as usize == j) {
                    let n = count as usize / BULK_LANES * BULK_LANES;
                    let k = yp * this.stride + x as usize + 1;
                    if psm
                        .as_ref()
                        .is_none_or(|(p, r)| !p.any_in(r.clone(), k..k + n))
                    {
                        // SAFETY: the run's cells and their force slots are this task's.
                        b |= unsafe {
                            sweep_wall_run(
                                this,
                                c,
                                base.ptr(),
                                acc,
                                y,
                                x as usize,
                                n,
                                slots.ptr().add((first_slot + j) * ns),
                                ns,
                            )
                        };
                        j += n;
                        continue;
                    }
                }
                // SAFETY: the slots of this row's cells belong to this task only.
                let f = unsafe {
                    std::slice::from_raw_parts_mut(slots.ptr().add((first_slot + j) * ns), ns)
                };
                f.fill([0.0; 2]);
                let src = Src(base.ptr() as *const T);
                let mut h = this.gather_special(src, acc, x as usize, y, Some(f));
                let pre = h;
                let m = c.collide(&mut h);
                let k = yp * this.stride + x as usize + 1;
                if let Some(n) = psm.as_ref().and_then(|(p, r)| p.find(r.clone(), k)) {
                    let p = psm.as_ref().expect("found in it").0;
                    // SAFETY: the cell's shares are swept by this task only.
                    unsafe { p.blend(n, &pre, &mut h, &m) };
                }
                for (i, hi) in h.iter().enumerate() {
                    // SAFETY: the cell's own slots (see the module docs).
                    unsafe { *base.ptr().add(acc.store(i, k)) = *hi };
                }
                b |= !(m.rho > T::default());
                j += 1;
            }
            // Link cells are swept with the rest of the row, whose check (pre-collision
            // density ≤ 0 or NaN, as the two-array path checks link cells) covers them, so
            // they are looked at again only to name a bad one.
            if let Some(run) = moving.filter(|_| b) {
                // SAFETY: the slots of this row's cells belong to this task.
                unsafe { run.check_row(this, base.ptr(), acc, y, !inner) };
            }
            if inner {
                *bad = b as u8;
            } else {
                *bad |= b as u8;
            }
        };
        let block = moving.and_then(|r| r.sum_block()).filter(|_| inner);
        match moving.filter(|r| inner && r.precomputes()) {
            // Partially saturated cells that sum some loads per body: each task sweeps a
            // block of rows in increasing order (see `ShareSums`), adding the loads as it
            // blends the cells.
            None if block.is_some() => {
                let h = block.expect("tested");
                let p = partial.as_ref().expect("a sweep that sums has a plan");
                block_tasks(&mut tasks, this.ny, h, |y| !p.row(y).is_empty());
                let bads = Shared(row_bad.as_mut_ptr());
                let next = AtomicUsize::new(0);
                // Each worker takes the next task until none is left: the blocks that hold
                // plan cells first, the bands of plain rows last, so that the tasks that end
                // the sweep are short ones.
                let workers = rayon::current_num_threads().min(tasks.len());
                (0..workers).into_par_iter().with_max_len(1).for_each(|_| {
                    while let Some(rows) = tasks.get(next.fetch_add(1, Ordering::Relaxed)) {
                        for y in rows.clone() {
                            // SAFETY: the tasks' rows are disjoint, each taken once.
                            sweep_row(y, unsafe { &mut *bads.ptr().add(y) });
                        }
                    }
                });
            }
            None => row_bad
                .par_iter_mut()
                .enumerate()
                .with_min_len(if inner { 4 } else { 64 })
                .for_each(|(y, bad)| sweep_row(y, bad)),
            Some(run) => {
                // A link cell's preparation reads slots of the rows next to it that the
                // sweep rewrites, so it is done before them: each task sweeps a band of rows
                // in order and prepares row y + 1's cells just before sweeping row y (the
                // data then in cache); the bands' first and last rows are prepared first.
                // SAFETY (both closures): rows y − 1..=y + 1 are not yet swept when row y
                // is prepared, and each row's link cells are prepared by one task.
                let compute =
                    |y: usize| unsafe { run.precompute_row(this, base.ptr(), acc, y, false) };
                let ny = this.ny;
                let band = (ny / (4 * rayon::current_num_threads())).clamp(8, 64);
                (0..ny.div_ceil(band)).into_par_iter().for_each(|b| {
                    let (a, e) = (b * band, ((b + 1) * band).min(ny));
                    compute(a);
                    if e - 1 > a {
                        compute(e - 1);
                    }
                });
                row_bad
                    .par_chunks_mut(band)
                    .enumerate()
                    .for_each(|(b, bads)| {
                        let (a, e) = (b * band, b * band + bads.len());
                        for (j, bad) in bads.iter_mut().enumerate() {
                            let y = a + j;
                            run.prefetch_row(this, base.ptr() as *const T, y + 2);
                            if y + 2 < e {
                                compute(y + 1);
                            }
                            sweep_row(y, bad);
                        }
                    });
            }
        }
        self.row_bad = row_bad;
        self.block_tasks = tasks;
        self.forces.values = slot_values;
    }

    /// After a push step: every halo value a cell will pull is written into that cell's
    /// slot (the two-array kernel's halo rules, evaluated on the pushed results), the values
    /// across rank faces exchanged first. Collective when the slab has neighbours.
    pub(crate) fn drain(&mut self, comm: &dyn Comm) {
        if self.drain_plan.is_none() {
            self.drain_plan = Some(self.build_drain_plan());
        }
        let plan = self.drain_plan.take().expect("built above");
        let (ny, stride, plane) = (self.ny, self.stride, self.plane);
        let rows = ny + 2;
        let value = |buf: &[T], src: usize| if src == NONE { T::default() } else { buf[src] };
        if self.halo.peer(Side::Left).is_some() || self.halo.peer(Side::Right).is_some() {
            // What each boundary column pushed towards a neighbour, on every padded row.
            for (n, side) in [Side::Left, Side::Right].into_iter().enumerate() {
                if self.halo.peer(side).is_none() {
                    continue;
                }
                let buf = &self.buf[0];
                let out = self.halo.send_mut(side);
                pack_words(out, plan.send[n].iter().map(|&src| value(buf, src)));
            }
            let mut halo = std::mem::take(&mut self.halo);
            self.halo_wait_s += halo.exchange(comm, &mut || {});
            self.halo = halo;
            // Into the halo cells' own slots of the inward directions (free in this layout).
            let nx = self.nx;
            for (side, xp, dirs) in [(Side::Left, 0, EASTWARD), (Side::Right, nx + 1, WESTWARD)] {
                if self.halo.peer(side).is_none() {
                    continue;
                }
                let mut data = unpack_words::<T>(self.halo.recv(side));
                let buf = &mut self.buf[0];
                for s in dirs {
                    for yp in 0..rows {
                        buf[s * plane + yp * stride + xp] = data.next().expect("a whole face");
                    }
                }
            }
        }
        // Every slot a fluid cell pulls from a halo cell. Sources and targets never overlap
        // (checked when the plan is built), so the copy needs no staging.
        let buf = &mut self.buf[0];
        for &(dst, src) in &plan.fill {
            buf[dst] = value(buf, src);
        }
        self.drain_plan = Some(plan);
    }

    /// The index lists of [`Lattice::drain`], from the faces and cell types (fixed for the
    /// lattice's life). Built in the pushed layout.
    fn build_drain_plan(&self) -> DrainPlan {
        debug_assert_eq!(self.layout, Layout::Pushed);
        let (nx, ny) = (self.nx, self.ny);
        let send = [(0i64, WESTWARD), (nx as i64 - 1, EASTWARD)].map(|(x, dirs)| {
            dirs.iter()
                .flat_map(|&s| (-1..=ny as i64).map(move |y| (s, y)))
                .map(|(s, y)| self.halo_index(x, y, s))
                .collect()
        });
        let mut border: Vec<(i64, i64)> = Vec::with_capacity(2 * (nx + ny) + 4);
        for y in -1..=ny as i64 {
            border.push((-1, y));
            border.push((nx as i64, y));
        }
        for x in 0..nx as i64 {
            border.push((x, -1));
            border.push((x, ny as i64));
        }
        let mut fill = Vec::with_capacity(border.len() * 3);
        for &(x, y) in &border {
            let h = self.idx(x as isize, y as isize);
            if self.types[h] != FLUID {
                continue;
            }
            for i in 1..Q {
                let (tx, ty) = (x + CX[i] as i64, y + CY[i] as i64);
                if tx < 0 || ty < 0 || tx >= nx as i64 || ty >= ny as i64 {
                    continue;
                }
                let t = self.idx(tx as isize, ty as isize);
                if self.types[t] == FLUID {
                    fill.push((i * self.plane + t, self.halo_index(x, y, i)));
                }
            }
        }
        let targets: std::collections::HashSet<usize> = fill.iter().map(|f| f.0).collect();
        assert!(
            fill.iter().all(|f| !targets.contains(&f.1)),
            "in-place halo plan reads a slot it writes"
        );
        DrainPlan { send, fill }
    }

    /// Where the value is that the two-array kernel's halo cell (x, y) (local, −1 ≤ x ≤ nx, −1 ≤ y ≤ ny)
    /// would hold in direction `s` before the next step, in the pushed layout ([`NONE`]: zero): a cell's own
    /// result, or the face rules applied to one (x faces for the interior rows, y faces over
    /// the full padded width, as `fill_halo` orders them; exchanged faces from the halo slots
    /// the neighbour filled).
    pub(crate) fn halo_index(&self, x: i64, y: i64, s: usize) -> usize {
        let (nx, ny) = (self.nx as i64, self.ny as i64);
        let inside_x = (0..nx).contains(&x);
        let inside_y = (0..ny).contains(&y);
        if inside_x && inside_y {
            let k = self.idx(x as isize, y as isize);
            return self.access().own(s, k);
        }
        let x_face = if x < 0 { Face::West } else { Face::East };
        let exchanged = !inside_x && self.faces[x_face as usize] == FaceCondition::Exchange;
        if exchanged {
            // Filled by the neighbour (only the inward directions are ever asked for).
            return s * self.plane + self.idx(x as isize, y as isize);
        }
        if !inside_y {
            let (face, wrap, inner) = if y < 0 {
                (Face::South, ny - 1, 0)
            } else {
                (Face::North, 0, ny - 1)
            };
            return match self.faces[face as usize] {
                FaceCondition::Periodic => self.halo_index(x, wrap, s),
                FaceCondition::FreeSlip => self.halo_index(x, inner, MIRROR_Y[s]),
                FaceCondition::Outflow => self.halo_index(x, inner, s),
                _ => NONE,
            };
        }
        let (wrap, inner) = if x < 0 { (nx - 1, 0) } else { (0, nx - 1) };
        match self.faces[x_face as usize] {
            FaceCondition::Periodic => self.halo_index(wrap, y, s),
            FaceCondition::FreeSlip => self.halo_index(inner, y, MIRROR_X[s]),
            FaceCondition::Outflow => self.halo_index(inner, y, s),
            _ => NONE,
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::rows::{block_tasks, PLAIN_BAND};

    /// The tasks cover every row once; each block's rows that hold plan cells are one task
    /// (in order), the blocks come first, longest first, and the rest go in short bands.
    #[test]
    fn block_tasks_cover_the_rows_once_and_keep_each_blocks_cells_together() {
        let mut tasks = Vec::new();
        for (ny, h, planned) in [
            (100, 32, vec![40..45, 50..60, 97..100]),
            (64, 16, vec![]),
            (50, 64, vec![0..1, 49..50]),
            (33, 8, vec![3..4, 9..16, 17..18, 23..24, 24..25]),
        ] {
            let is_planned = |y: usize| planned.iter().any(|r| r.contains(&y));
            block_tasks(&mut tasks, ny, h, is_planned);
            let mut seen = vec![0; ny];
            for t in &tasks {
                assert!(!t.is_empty() && t.end <= ny, "{t:?}");
                t.clone().for_each(|y| seen[y] += 1);
            }
            assert!(seen.iter().all(|&n| n == 1), "rows covered once: {seen:?}");
            let blocks: Vec<_> = tasks.iter().take_while(|t| is_planned(t.start)).collect();
            for b0 in (0..ny).step_by(h) {
                let rows: Vec<_> = (b0..(b0 + h).min(ny)).filter(|&y| is_planned(y)).collect();
                if let (Some(&first), Some(&last)) = (rows.first(), rows.last()) {
                    assert!(
                        blocks.iter().any(|t| t.start == first && t.end == last + 1),
                        "block {b0}: rows {first}..={last} in one task of {tasks:?}"
                    );
                }
            }
            assert!(blocks.windows(2).all(|w| w[0].len() >= w[1].len()));
            assert!(tasks[blocks.len()..]
                .iter()
                .all(|t| t.len() <= PLAIN_BAND && !t.clone().any(is_planned)));
        }
    }
}
