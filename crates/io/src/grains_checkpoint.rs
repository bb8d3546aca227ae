//! Checkpoints of grains runs: every grain's full state including the forces of the last
//! evaluation, the tangential history of every contact, the walls, and the run's counters.
//! Written atomically and collectively (each rank its own rows); read by any rank count.
//!
//! Forces are stored rather than recomputed on restart because evaluating them advances the
//! tangential springs and uses the half-step velocities, which are gone: with the stored
//! forces a restarted run continues bit for bit.

use super::checkpoint::{open_checked, write_atomically, write_header, CheckedFile};
use super::h5par::{write_rows, Access};
use super::OutputError;
use decomposition::Comm;
use decomposition::PackRows;
use dem::system::HistoryMap;
use dem::walls::WallStates;
use dem::{Grains, SlabDem};
use std::path::Path;

/// `format` attribute of a grains checkpoint.
pub const FORMAT: &str = "grainflow-grains-checkpoint";
/// Version of the layout below.
pub const FORMAT_VERSION: u32 = 1;
/// Values per grain row: [`Grains::pack`] then fx, fy, torque.
const ROW: usize = Grains::WORDS + 3;

/// Counters of a grains run that a restart needs besides the grains.
#[derive(Debug, Clone, PartialEq)]
pub struct GrainRunState {
    /// Steps taken.
    pub step: u64,
    /// Simulated time (s).
    pub time_s: f64,
    /// Time of the next snapshot (s).
    pub next_output_s: f64,
    /// Steps spent settling the sample.
    pub settle_steps: u64,
    /// Grains migrated so far (this rank's, summed on write).
    pub migrated: u64,
    /// (x, y, r) of every grain when the run started, by id (for the analyses).
    pub initial: Vec<f64>,
}

/// What a restart reads: the run state, every grain (with forces), the contact history,
/// and each wall's ends and removal flag.
pub struct RestoredGrains {
    /// Counters.
    pub run: GrainRunState,
    /// Every grain, sorted by id.
    pub grains: Grains,
    /// Pair and wall contact history.
    pub history: HistoryMap,
    /// Per wall: a, b, removed.
    pub walls: WallStates,
}

fn err(path: &Path, message: impl Into<String>) -> OutputError {
    OutputError::Checkpoint {
        path: path.to_owned(),
        message: message.into(),
    }
}

/// Write the checkpoint of `d` to `path` (collective, atomic).
pub fn write(
    path: &Path,
    comm: &dyn Comm,
    d: &SlabDem,
    run: &GrainRunState,
) -> Result<(), OutputError> {
    let mut migrated = [run.migrated as f64];
    comm.sum_f64(&mut migrated);
    let fill = |file: &hdf5::File, access: Access| -> hdf5::Result<()> {
        write_header(
            file,
            (FORMAT, FORMAT_VERSION),
            &[("step", run.step), ("settle_steps", run.settle_steps)],
            &[
                ("time_s", run.time_s),
                ("next_output_s", run.next_output_s),
                ("migrated", migrated[0]),
            ],
        )?;
        write_dem(file, access, d, &run.initial, comm)
    };
    write_atomically(path, comm, &fill)
}

/// The `/dem` group: every owned grain with the forces of its last evaluation (each rank
/// its rows), each live contact's history once, the walls and `initial` (rank 0's rows).
/// Collective.
pub fn write_dem(
    file: &hdf5::File,
    access: Access,
    d: &SlabDem,
    initial: &[f64],
    comm: &dyn Comm,
) -> hdf5::Result<()> {
    let sys = &d.system;
    let g = &sys.grains;
    let mut rows = Vec::with_capacity(sys.owned() * ROW);
    for i in 0..sys.owned() {
        g.pack_row(i, &mut rows);
        rows.extend_from_slice(&[g.fx[i], g.fy[i], g.torque[i]]);
    }
    // Each contact once: a pair by the owner of its smaller-id grain, a wall contact by the
    // grain's owner.
    let mut history = Vec::new();
    for ((a, b), s) in sys.owned_history() {
        history.extend_from_slice(&[f64::from_bits(a), f64::from_bits(b), s]);
    }
    let mut walls = Vec::new();
    for w in &sys.walls {
        walls.extend_from_slice(&[w.a[0], w.a[1], w.b[0], w.b[1], w.removed as u8 as f64]);
    }
    let dem = file.create_group("dem")?;
    write_rows(&dem, "grains", &rows, ROW, comm, access)?;
    write_rows(&dem, "history", &history, 3, comm, access)?;
    // Identical on every rank: rank 0's rows only.
    let root_only = |v: &[f64]| {
        if comm.is_root() {
            v.to_vec()
        } else {
            Vec::new()
        }
    };
    write_rows(&dem, "walls", &root_only(&walls), 5, comm, access)?;
    write_rows(&dem, "initial", &root_only(initial), 3, comm, access)?;
    Ok(())
}

/// Read a grains checkpoint (every rank reads everything). `walls` is the scene's wall
/// count, which the file must match. Collective.
pub fn read(path: &Path, comm: &dyn Comm, walls: usize) -> Result<RestoredGrains, OutputError> {
    let c = open_checked(path, comm, (FORMAT, FORMAT_VERSION), "a grains")?;
    let (u, f) = (|n: &str| c.u64(n), |n: &str| c.f64(n));
    let (grains, history, walls) = read_dem(&c, path, walls)?;
    Ok(RestoredGrains {
        run: GrainRunState {
            step: u("step")?,
            time_s: f("time_s")?,
            next_output_s: f("next_output_s")?,
            settle_steps: u("settle_steps")?,
            migrated: f("migrated")? as u64,
            initial: c.rows("dem/initial", 3)?,
        },
        grains,
        history,
        walls,
    })
}

/// The `/dem` group of an open checkpoint: every grain sorted by id (with its forces), the
/// contact history and the walls, which must be `walls` many.
pub fn read_dem(
    c: &CheckedFile<'_>,
    path: &Path,
    walls: usize,
) -> Result<(Grains, HistoryMap, WallStates), OutputError> {
    let data = |n: &str, cols: usize| c.rows(&format!("dem/{n}"), cols);
    let rows = data("grains", ROW)?;
    let mut sorted: Vec<&[f64]> = rows.chunks_exact(ROW).collect();
    sorted.sort_by_key(|r| r[9].to_bits());
    let mut grains = Grains::default();
    for r in sorted {
        grains.push_row(&r[..Grains::WORDS]);
        let i = grains.len() - 1;
        grains.fx[i] = r[10];
        grains.fy[i] = r[11];
        grains.torque[i] = r[12];
    }
    let history = data("history", 3)?
        .chunks_exact(3)
        .map(|h| ((h[0].to_bits(), h[1].to_bits()), h[2]))
        .collect();
    let wall_rows = data("walls", 5)?;
    if wall_rows.len() / 5 != walls {
        return Err(err(
            path,
            format!(
                "holds {} walls, the scene {walls}; restart with the scene that wrote it",
                wall_rows.len() / 5
            ),
        ));
    }
    let walls = wall_rows
        .chunks_exact(5)
        .map(|w| ([w[0], w[1]], [w[2], w[3]], w[4] != 0.0))
        .collect();
    Ok((grains, history, walls))
}
