//! Checkpoints of coupled fluid–grain runs: the fluid checkpoint (`/lbm`, `/run`) plus the
//! grains (`/dem`, as a grains run writes them) and the coupling's per-grain state
//! (`/coupling`): the force held on each grain, the previous step's hydrodynamic force (for
//! the two-step average) and the pending hand-over of covered and uncovered cells. With
//! these a restart continues bit for bit, on any rank count. Written atomically.

use super::checkpoint::{self, open_checked, LatticeState, RunState, FORMAT, FORMAT_VERSION};
use super::grains_checkpoint::{read_dem, write_dem};
use super::h5par::{write_rows, Access};
use super::OutputError;
use coupling::RestoredCoupling;
use decomposition::Comm;
use dem::SlabDem;
use hdf5::types::H5Type;
use std::path::Path;

/// Values per `/coupling/grains` row: id (bits), then the 9 of
/// [`coupling::LbmDem::per_grain_state`].
const ROW: usize = 10;

/// Fluid and grain momentum (kg m/s per m), x and y of each.
pub type MomentumPair = [[f64; 2]; 2];

/// The grains' part of a coupled checkpoint, as this rank holds it.
pub struct CoupledState<'a> {
    /// The distributed DEM.
    pub dem: &'a SlabDem,
    /// Per owned grain, in owned order: the coupling's state.
    pub per_grain: Vec<[f64; 9]>,
    /// Fluid and grain momentum at step 0 (kg m/s per m), when the run tracks it.
    pub momentum_initial: Option<MomentumPair>,
    /// (x, y, r) of every grain at step 0 (m), by id (the same on every rank).
    pub initial: &'a [[f64; 3]],
}

/// Write the checkpoint of a coupled run (collective, atomic).
pub fn write<T: H5Type + Copy>(
    path: &Path,
    comm: &dyn Comm,
    lattice: &LatticeState<'_, T>,
    run: &RunState,
    grains: &CoupledState<'_>,
) -> Result<(), OutputError> {
    let sys = &grains.dem.system;
    let mut rows = Vec::with_capacity(grains.per_grain.len() * ROW);
    for (i, p) in grains.per_grain.iter().enumerate() {
        rows.push(f64::from_bits(sys.grains.id[i]));
        rows.extend_from_slice(p);
    }
    let momentum: Vec<f64> = match (comm.is_root(), grains.momentum_initial) {
        (true, Some(m)) => vec![m[0][0], m[0][1], m[1][0], m[1][1]],
        _ => Vec::new(),
    };
    let initial: Vec<f64> = grains.initial.iter().flatten().copied().collect();
    let more = |file: &hdf5::File, access: Access| -> hdf5::Result<()> {
        write_dem(file, access, grains.dem, &initial, comm)?;
        let c = file.create_group("coupling")?;
        for (name, v) in [("dem_time_s", sys.time), ("dem_steps", sys.steps as f64)] {
            c.new_attr::<f64>()
                .create(name)
                .and_then(|a| a.write_scalar(&v))?;
        }
        write_rows(&c, "grains", &rows, ROW, comm, access)?;
        write_rows(&c, "momentum_initial", &momentum, 4, comm, access)?;
        Ok(())
    };
    checkpoint::write_with(path, comm, lattice, run, &more)
}

/// What a coupled checkpoint holds besides the fluid.
pub struct CoupledRestart {
    /// The grains' state to restart from.
    pub grains: RestoredCoupling,
    /// Fluid and grain momentum at step 0, if recorded.
    pub momentum_initial: Option<MomentumPair>,
    /// (x, y, r) of every grain at step 0 (m), by id.
    pub initial: Vec<[f64; 3]>,
}

/// The grains of a coupled checkpoint (every rank reads everything); `walls` is the
/// scene's wall count (its own and the fluid's wall faces). Collective.
pub fn read(path: &Path, comm: &dyn Comm, walls: usize) -> Result<CoupledRestart, OutputError> {
    let c = open_checked(path, comm, (FORMAT, FORMAT_VERSION), "a coupled")?;
    if c.file.group("dem").is_err() {
        return Err(OutputError::Checkpoint {
            path: path.to_owned(),
            message: "holds no grains (a fluid-only run wrote it); restart a coupled scene \
                      from a checkpoint its own run wrote"
                .into(),
        });
    }
    let (grains, history, walls) = read_dem(&c, path, walls)?;
    let group = c.file.group("coupling").map_err(|e| c.bad(e))?;
    let attr = |n: &str| {
        group
            .attr(n)
            .and_then(|a| a.read_scalar::<f64>())
            .map_err(|e| c.bad(e))
    };
    let clock = (attr("dem_time_s")?, attr("dem_steps")? as u64);
    let mut per_grain: Vec<(u64, [f64; 9])> = c
        .rows("coupling/grains", ROW)?
        .chunks_exact(ROW)
        .map(|r| (r[0].to_bits(), std::array::from_fn(|k| r[k + 1])))
        .collect();
    per_grain.sort_by_key(|r| r.0);
    let m = c.rows("coupling/momentum_initial", 4)?;
    let initial = c
        .rows("dem/initial", 3)?
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    Ok(CoupledRestart {
        grains: RestoredCoupling {
            grains,
            history,
            walls,
            clock,
            per_grain,
        },
        momentum_initial: (m.len() == 4).then(|| [[m[0], m[1]], [m[2], m[3]]]),
        initial,
    })
}
