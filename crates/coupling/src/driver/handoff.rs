//! Handing the coupled grains to a new slab partition: their whole state gathered on every
//! rank, as a checkpoint holds it (so that [`LbmDem::new`] continues from it bit for bit,
//! as a restart does), the work they put on each lattice column, the narrowest slab they
//! allow, and the counters a run reports over its whole length.

use super::{LbmDem, RestoredCoupling};
use decomposition::{Comm, PackRows};
use dem::Grains;

/// Values per gathered grain: its row ([`Grains::WORDS`]), its force and torque of the last
/// evaluation, then the coupling's 9 of [`LbmDem::per_grain_state`].
const ROW: usize = Grains::WORDS + 3 + 9;

/// What a run counts over its whole length, kept across a hand-over.
#[derive(Debug, Clone, Copy, Default)]
pub struct CouplingCounters {
    /// Seconds in each coupling pass.
    pub passes: [f64; 6],
    /// Counts of [`crate::COUNTS`].
    pub counts: [u64; 6],
}

impl LbmDem {
    /// Every grain's state, sorted by id, on every rank: what a coupled checkpoint holds.
    /// Errors with the id of a grain that two ranks hold. Collective.
    pub fn gather_state(&self, comm: &dyn Comm) -> Result<RestoredCoupling, u64> {
        let sys = &self.dem.system;
        let g = &sys.grains;
        let per_grain = self.per_grain_state();
        let mut rows = Vec::with_capacity(sys.owned() * ROW);
        for (i, p) in per_grain.iter().enumerate() {
            g.pack_row(i, &mut rows);
            rows.extend_from_slice(&[g.fx[i], g.fy[i], g.torque[i]]);
            rows.extend_from_slice(p);
        }
        let all = comm.all_gather_f64(&rows);
        let mut sorted: Vec<&[f64]> = all.chunks_exact(ROW).collect();
        // The id is the row's last word.
        let id = |r: &[f64]| r[Grains::WORDS - 1].to_bits();
        sorted.sort_by_key(|r| id(r));
        if let Some(w) = sorted.windows(2).find(|w| id(w[0]) == id(w[1])) {
            return Err(id(w[0]));
        }
        let mut grains = Grains::default();
        let mut state = Vec::with_capacity(sorted.len());
        for r in &sorted {
            grains.push_row(&r[..Grains::WORDS]);
            let i = grains.len() - 1;
            let f = &r[Grains::WORDS..];
            (grains.fx[i], grains.fy[i], grains.torque[i]) = (f[0], f[1], f[2]);
            state.push((id(r), std::array::from_fn(|k| f[3 + k])));
        }
        let mut history = Vec::new();
        for ((a, b), s) in sys.owned_history() {
            history.extend_from_slice(&[f64::from_bits(a), f64::from_bits(b), s]);
        }
        let history = comm
            .all_gather_f64(&history)
            .chunks_exact(3)
            .map(|h| ((h[0].to_bits(), h[1].to_bits()), h[2]))
            .collect();
        let walls = sys.walls.iter().map(|w| (w.a, w.b, w.removed)).collect();
        Ok(RestoredCoupling {
            grains,
            history,
            walls,
            clock: (sys.time, sys.steps),
            per_grain: state,
        })
    }

    /// The least width of a slab (columns): a grain's reach into its neighbours' cells.
    pub fn min_slab_columns(&self) -> usize {
        // The setup's own test is `width · Δx ≥ reach`: the least width that passes it.
        let mut w = (self.reach_m / self.units.dx_m).ceil() as usize;
        while (w as f64) * self.units.dx_m < self.reach_m {
            w += 1;
        }
        w
    }

    /// How many owned grains have their centre in each global lattice column (`columns`
    /// of them).
    pub fn grains_per_column(&self, columns: usize) -> Vec<f64> {
        let mut n = vec![0.0; columns];
        let g = &self.dem.system.grains;
        for &x in &g.x[..self.dem.system.owned()] {
            let c = (x / self.units.dx_m)
                .floor()
                .clamp(0.0, (columns - 1) as f64);
            n[c as usize] += 1.0;
        }
        n
    }

    /// This rank's run-long counters, to carry to the coupling that replaces this one.
    pub fn counters(&self) -> CouplingCounters {
        CouplingCounters {
            passes: self.pass_seconds(),
            counts: self.counts(),
        }
    }

    /// Continue the counters of the coupling this one replaces.
    pub fn continue_counters(&mut self, earlier: CouplingCounters) {
        self.earlier = earlier;
    }
}
