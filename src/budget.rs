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

/// This process's peak resident memory so far (bytes): the kernel's high-water mark,
/// `VmHWM` in `/proc/self/status`; `None` where it cannot be read (not Linux).
pub fn peak_resident_bytes() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = text.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
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
/// buffers of `bytes`-byte reals: the populations, the cell types and the fields the run
/// keeps ([`CELL_BYTES`]), and `snapshot` bytes per cell while a snapshot is taken
/// ([`snapshot_bytes_per_cell`]).
pub fn fluid_bytes(cells: [usize; 2], buffers: f64, bytes: f64, snapshot: f64) -> f64 {
    let n = (cells[0] as f64 + 2.0) * (cells[1] as f64 + 2.0);
    n * (buffers * 9.0 * bytes + CELL_BYTES + snapshot)
}

/// What a snapshot or a checkpoint of a fluid scene with `output` adds per cell of the
/// whole lattice, all ranks together, in a run of `bytes`-byte reals (bytes): the fields in
/// f64 and their conversions for the HDF5 file ([`SNAPSHOT_BYTES_PER_CELL`], each rank its
/// slab) and the pictured fields ([`PICTURE_BYTES_PER_CELL`] beside them on one rank,
/// [`GATHERED_PICTURE_BYTES_PER_CELL`] gathered on rank 0 of several); or, when the scene
/// writes checkpoints, the copy of the populations a checkpoint writes from (9 reals per
/// cell), whichever is larger: a box that snapshots and checkpoints at its end peaks at the
/// larger of the two, not their sum.
pub fn snapshot_bytes_per_cell(output: &scene::Output, ranks: usize, bytes: f64) -> f64 {
    let (fields, pictures) = (!output.fields().is_empty(), output.pictures());
    let one = |b: bool| f64::from(u8::from(b));
    let snapshot = match (ranks <= 1, fields, pictures) {
        (_, false, false) => 0.0,
        (true, _, p) => SNAPSHOT_BYTES_PER_CELL + one(p) * PICTURE_BYTES_PER_CELL,
        (false, f, p) => {
            one(f) * SNAPSHOT_BYTES_PER_CELL + one(p) * GATHERED_PICTURE_BYTES_PER_CELL
        }
    };
    let checkpoints = output.checkpoint_at_end()
        || output.checkpoint_every_steps() > 0
        || output.checkpoint_every_minutes() > 0.0;
    snapshot.max(one(checkpoints) * 9.0 * bytes)
}

/// What a fluid run holds per cell beyond its populations (bytes): the cell types, the
/// totals' fields and the row plans, as the peak resident memory of 1024² and 2048² boxes
/// without snapshots measured it in f32 and f64 (`tests/memory_estimate.rs`). A coupled
/// run's per-cell maps fit in it; its per-grain tables are [`COUPLED_GRAIN_BYTES`].
pub const CELL_BYTES: f64 = 27.0;

/// What a snapshot adds per cell while it is taken (bytes): the fields in f64 (ρ, u_x,
/// u_y) and each one's conversion for the HDF5 file in turn, as the peak resident memory of
/// 1024² and 2048² boxes measured it in f32 and f64, and the medium landslide.
pub const SNAPSHOT_BYTES_PER_CELL: f64 = 24.0;

/// What the pictures add per cell on one rank beside the snapshot's fields (bytes): the
/// drawn speed and vorticity and the fluid mask, as the same boxes and the medium landslide
/// measured it (9.4 in the boxes, 8 in the landslide).
pub const PICTURE_BYTES_PER_CELL: f64 = 10.0;

/// What the pictures add on rank 0 of several per cell of the whole lattice (bytes): the
/// gathered fields and their colours, as a 1024² box on two ranks measured it.
pub const GATHERED_PICTURE_BYTES_PER_CELL: f64 = 60.0;

/// What the one process of a run without MPI holds whatever its scene (bytes): the
/// program and its libraries (MPI, HDF5, the GPU loader), thread stacks and the
/// allocator's pools, as the peak resident memory of the smallest runs measured it.
pub const PROCESS_BYTES: f64 = 24.0 * 1048576.0;
/// What each rank of an MPI run holds whatever its scene (bytes): [`PROCESS_BYTES`] and
/// Open MPI's own buffers, as a 1024² box on two ranks measured it.
pub const RANK_BYTES: f64 = 30.0 * 1048576.0;

/// Bytes per grain of a grains run: its state, its contacts' history, its neighbour
/// lists, the packing's working copies and a snapshot's conversions, as the peak resident
/// memory of a 113 000-grain run measured it (`tests/memory_estimate.rs`).
pub const GRAIN_BYTES: f64 = 560.0;
/// Bytes per (estimated) grain of a coupled run: a grains run's and the coupling's
/// per-grain state (its views, hand-over loads, carried forces), and the per-step tables of
/// the cells it covers (the partially saturated plan, the moving cells' momentum slots, the
/// two column sums, the map's line tables: 3 KB per grain of 3.7–5.5 cells across in the
/// heap profiles of the landslides), as the peak resident memory of the medium landslide
/// measured it; the large one's peak lies within 2 %.
pub const COUPLED_GRAIN_BYTES: f64 = 4608.0;
/// Bytes per grain that every rank holds while a coupled run rebalances: the grains'
/// state gathered from all ranks (22 words, sent and received, then sorted and unpacked)
/// and their contacts' history.
pub const GATHERED_GRAIN_BYTES: f64 = 400.0;
/// Bytes per material point: its 25 words, the step's working arrays (next positions,
/// gradients, the sorting scratch), the scene's generated copy and a snapshot's
/// conversions, as the peak resident memory of a 0.64 million-point run measured it.
pub const POINT_BYTES: f64 = 580.0;
/// Bytes per background-grid node (about 12 words). See [`POINT_BYTES`].
pub const NODE_BYTES: f64 = 32.0;

/// The cost of a fluid (or coupled) run of `steps` steps in `bytes`-byte reals, in one
/// distribution buffer (`in_place`) or two, on `ranks` processes: the lattice, a coupled
/// scene's estimated grains and each process's own memory.
pub fn fluid_cost(
    scene: &scene::ValidScene,
    steps: u64,
    bytes: f64,
    in_place: bool,
    ranks: usize,
) -> Cost {
    let buffers = if in_place { 1.0 } else { 2.0 };
    let grains = scene.scene.grains.as_ref();
    let rebalances = scene
        .scene
        .coupling
        .as_ref()
        .is_some_and(|c| grains.is_some() && ranks > 1 && c.rebalance_every_steps() > 0);
    let per_grain =
        COUPLED_GRAIN_BYTES + f64::from(u8::from(rebalances)) * ranks as f64 * GATHERED_GRAIN_BYTES;
    let grain_bytes = grains
        .and_then(|g| scene::estimated_grains(&g.sample))
        .map_or(0.0, |n| n * per_grain);
    // A snapshot and a rebalance are never taken together. While the populations move, a
    // rank holds its old block, what it sends and what it receives (two more copies when
    // the whole slab changes hands), then the received block beside the new lattice.
    let moving = f64::from(u8::from(rebalances)) * 2.0 * 9.0 * bytes;
    Cost {
        steps,
        memory_bytes: fluid_bytes(
            scene.scene.domain.cells,
            buffers,
            bytes,
            snapshot_bytes_per_cell(&scene.scene.output, ranks, bytes).max(moving),
        ) + grain_bytes
            + processes(ranks),
    }
}

/// The cost of a grains run of `steps` steps holding about `grains` grains on `ranks`
/// processes.
pub fn grain_cost(grains: f64, steps: u64, ranks: usize) -> Cost {
    Cost {
        steps,
        memory_bytes: grains * GRAIN_BYTES + processes(ranks),
    }
}

/// The cost of an MPM run of `steps` steps on `ranks` processes.
pub fn mpm_cost(scene: &scene::ValidMpmScene, steps: u64, ranks: usize) -> Cost {
    let g = scene.setup.spec;
    let nodes = (g.nx as f64 + 1.0) * (g.ny as f64 + 1.0);
    Cost {
        steps,
        memory_bytes: scene.points.len() as f64 * POINT_BYTES
            + nodes * NODE_BYTES
            + processes(ranks),
    }
}

/// What `ranks` processes hold whatever their scene: [`PROCESS_BYTES`] alone, or
/// [`RANK_BYTES`] each under MPI.
fn processes(ranks: usize) -> f64 {
    match ranks {
        0 | 1 => PROCESS_BYTES,
        n => n as f64 * RANK_BYTES,
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
