//! What a run will cost, judged before its big allocations: the steps it will take and the
//! memory its ranks will hold on one node, against sane limits and this machine's memory.
//! `check` prints the same figures `run` judges; `--force` overrides the refusal.

use crate::error::RunError;
use decomposition::Comm;

pub mod walltime;

/// Most steps a run may take without `--force`: 10⁹ steps are weeks of cluster time even
/// on a small grid; more is almost always a unit slip (an end time in ms given as s, a
/// stiffness in Pa given as GPa).
pub const MAX_STEPS: u64 = 1_000_000_000;

/// The estimated cost of a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cost {
    /// Steps to the end.
    pub steps: u64,
    /// Memory of the whole run, all ranks together (bytes).
    pub memory_bytes: f64,
}

/// This machine's memory (bytes), from `/proc/meminfo`; `None` where it cannot be read.
pub fn machine_memory_bytes() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}

/// Why `cost` on `ranks` ranks, `here` of them on this node, should not start, with the
/// figures and the fix; `None` when it may. `memory` is this node's memory (bytes), when
/// known.
pub fn objection(cost: Cost, ranks: usize, here: usize, memory: Option<f64>) -> Option<String> {
    if cost.steps > MAX_STEPS {
        return Some(format!(
            "the run would take {} steps, more than {MAX_STEPS:.0e}: check the end time and the \
             time step (units?), or pass --force",
            cost.steps
        ));
    }
    let ranks = ranks.max(1);
    let here = here.clamp(1, ranks);
    let on_node = cost.memory_bytes / ranks as f64 * here as f64;
    match memory {
        Some(m) if !(on_node <= m) => Some(format!(
            "the run needs about {:.1} GiB on this node ({here} rank(s) here of {ranks}), more \
             than its {:.1} GiB: run on more nodes, coarsen the grid, or pass --force",
            on_node / GIB,
            m / GIB
        )),
        _ => None,
    }
}

/// Refuse `cost` on the ranks of `comm` unless it fits (or `force`).
pub fn admit(cost: Cost, comm: &dyn Comm, force: bool) -> Result<(), RunError> {
    let memory = machine_memory_bytes();
    match objection(cost, comm.size(), comm.ranks_on_node(), memory) {
        Some(why) if !force => Err(RunError::TooLarge(why)),
        _ => Ok(()),
    }
}

const GIB: f64 = 1024.0 * 1024.0 * 1024.0;

/// Bytes of a fluid lattice of `cells` (with the one-cell halo) in `buffers` distribution
/// buffers of `bytes`-byte reals: the populations, the cell types, the fields a snapshot
/// computes (density, velocity, vorticity in f64) and, coupled, the coupling's per-cell
/// state ([`COUPLING_BYTES_PER_CELL`]).
pub fn fluid_bytes(cells: [usize; 2], buffers: f64, bytes: f64, coupled: bool) -> f64 {
    let n = (cells[0] as f64 + 2.0) * (cells[1] as f64 + 2.0);
    let coupling = if coupled {
        COUPLING_BYTES_PER_CELL
    } else {
        0.0
    };
    n * (buffers * 9.0 * bytes + 2.0 + 4.0 * 8.0 + coupling)
}

/// What a coupled run holds per lattice cell beyond the fluid's (bytes): the covering-grain
/// maps and marks, the partially saturated cells' shares and the snapshot's conversions, as
/// the resident memory of a 50.9 M-cell coupled run measured it.
pub const COUPLING_BYTES_PER_CELL: f64 = 43.0;

/// Bytes per grain: its state, its contacts' history and its neighbour lists (about).
pub const GRAIN_BYTES: f64 = 1024.0;
/// Bytes per material point (25 words) and per background-grid node (about 12 words).
pub const POINT_BYTES: f64 = 200.0;
/// See [`POINT_BYTES`].
pub const NODE_BYTES: f64 = 96.0;

/// The cost of a fluid (or coupled) run of `steps` steps in `bytes`-byte reals, in one
/// distribution buffer (`in_place`) or two.
pub fn fluid_cost(scene: &scene::ValidScene, steps: u64, bytes: f64, in_place: bool) -> Cost {
    let buffers = if in_place { 1.0 } else { 2.0 };
    let coupled = scene.scene.grains.is_some();
    Cost {
        steps,
        memory_bytes: fluid_bytes(scene.scene.domain.cells, buffers, bytes, coupled),
    }
}

/// The cost of an MPM run of `steps` steps.
pub fn mpm_cost(scene: &scene::ValidMpmScene, steps: u64) -> Cost {
    let g = scene.setup.spec;
    let nodes = (g.nx as f64 + 1.0) * (g.ny as f64 + 1.0);
    Cost {
        steps,
        memory_bytes: scene.points.len() as f64 * POINT_BYTES + nodes * NODE_BYTES,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_beyond_the_limit_and_memory_beyond_the_node_are_refused() {
        let gib = GIB;
        let fits = Cost {
            steps: 1000,
            memory_bytes: 2.0 * gib,
        };
        assert_eq!(objection(fits, 1, 1, Some(4.0 * gib)), None);
        let long = Cost {
            steps: MAX_STEPS + 1,
            ..fits
        };
        assert!(objection(long, 1, 1, Some(4.0 * gib))
            .unwrap()
            .contains("steps"));
        let big = Cost {
            memory_bytes: 16.0 * gib,
            ..fits
        };
        let why = objection(big, 1, 1, Some(4.0 * gib)).unwrap();
        assert!(why.contains("16.0 GiB") && why.contains("--force"), "{why}");
        // Spread over 8 nodes of 4 GiB, one rank each, it fits.
        assert_eq!(objection(big, 8, 1, Some(4.0 * gib)), None);
        // Unknown memory: only the steps are judged.
        assert_eq!(objection(big, 1, 1, None), None);
        // A NaN estimate is refused, not waved through.
        let nan = Cost {
            memory_bytes: f64::NAN,
            ..fits
        };
        assert!(objection(nan, 1, 1, Some(4.0 * gib)).is_some());
    }
}
