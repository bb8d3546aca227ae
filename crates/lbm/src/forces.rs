//! Momentum-exchange forces on solids, stored per boundary cell and reduced in a fixed
//! global order (column by column, south to north within a column), so the total has the
//! same bits on any number of ranks and threads.

use super::rows::RowPlan;
use decomposition::Comm;

/// Per-cell force slots of one slab: each special or edge cell has one `[fx, fy]` per solid.
#[derive(Debug, Clone, Default)]
pub(crate) struct ForceSlots {
    /// Solids.
    ns: usize,
    /// First cell slot of each row (row y: its special cells, then its edge cells); ny + 1 entries.
    pub(crate) row_start: Vec<usize>,
    /// `values[cell * ns + solid]`, lattice units, from the last step.
    pub(crate) values: Vec<[f64; 2]>,
    /// Cell slots grouped by local column: column x holds `col_cells[col_start[x]..col_start[x + 1]]`,
    /// in increasing y.
    col_start: Vec<usize>,
    col_cells: Vec<u32>,
}

impl ForceSlots {
    /// Slots for the special and edge cells of `plan` (rows of a slab `nx` wide), `ns` solids.
    pub(crate) fn new(plan: &[RowPlan], nx: usize, ns: usize) -> Self {
        let mut row_start = Vec::with_capacity(plan.len() + 1);
        let mut by_column: Vec<Vec<u32>> = vec![Vec::new(); nx];
        let mut next = 0usize;
        for row in plan {
            row_start.push(next);
            for &x in row.special.iter().chain(&row.edge) {
                by_column[x as usize].push(next as u32);
                next += 1;
            }
        }
        row_start.push(next);
        let mut col_start = Vec::with_capacity(nx + 1);
        let mut col_cells = Vec::with_capacity(next);
        for cells in by_column {
            col_start.push(col_cells.len());
            col_cells.extend(cells);
        }
        col_start.push(col_cells.len());
        Self {
            ns,
            row_start,
            values: vec![[0.0; 2]; next * ns],
            col_start,
            col_cells,
        }
    }

    /// Solids.
    pub(crate) fn solids(&self) -> usize {
        self.ns
    }

    /// This slab's contribution, self-delimiting so that ranks' contributions can be
    /// concatenated: for each solid, the count n of non-zero column sums, then n pairs
    /// (fx, fy) in column order. Adding an exact zero never changes a sum, so skipping
    /// zero columns keeps the result independent of the partition.
    pub(crate) fn column_partials(&self) -> Vec<f64> {
        let mut out = Vec::new();
        for s in 0..self.ns {
            let count_at = out.len();
            out.push(0.0);
            let mut n = 0usize;
            for x in 0..self.col_start.len() - 1 {
                let mut acc = [0.0f64; 2];
                for &c in &self.col_cells[self.col_start[x]..self.col_start[x + 1]] {
                    let f = self.values[c as usize * self.ns + s];
                    acc[0] += f[0];
                    acc[1] += f[1];
                }
                if acc != [0.0, 0.0] {
                    out.extend(acc);
                    n += 1;
                }
            }
            out[count_at] = n as f64;
        }
        out
    }
}

/// Total force on every solid (lattice units) from every rank's
/// [`ForceSlots::column_partials`], folded in global column order. Collective.
pub(crate) fn reduce_forces(comm: &dyn Comm, slots: &ForceSlots) -> Vec<[f64; 2]> {
    let ns = slots.solids();
    let all = comm.all_gather_f64(&slots.column_partials());
    let mut total = vec![[0.0f64; 2]; ns];
    let mut at = 0;
    for _rank in 0..comm.size() {
        for t in total.iter_mut() {
            let n = all[at] as usize;
            at += 1;
            for _ in 0..n {
                t[0] += all[at];
                t[1] += all[at + 1];
                at += 2;
            }
        }
    }
    total
}
