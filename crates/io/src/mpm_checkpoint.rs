//! Checkpoints of MPM runs: every material point's full state and the run's counters.
//! Written atomically and collectively (each rank its own rows); read by any rank count.
//! The grid holds nothing between steps, so the points and the clock are the whole state
//! and a restarted run continues bit for bit.

use super::checkpoint::{open_checked, write_atomically, write_header};
use super::h5par::{write_rows, Access};
use super::OutputError;
use decomposition::Comm;
use decomposition::PackRows;
use mpm::{MpmSystem, Points};
use std::path::Path;

/// `format` attribute of an MPM checkpoint.
pub const FORMAT: &str = "grainflow-mpm-checkpoint";
/// Version of the layout below (2: points carry the APIC affine velocity, 25 words).
pub const FORMAT_VERSION: u32 = 2;

/// Counters of an MPM run that a restart needs besides the points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MpmRunState {
    /// Steps taken.
    pub step: u64,
    /// Simulated time (s).
    pub time_s: f64,
    /// Time of the next snapshot (s).
    pub next_output_s: f64,
    /// Points migrated so far, all ranks.
    pub migrated: u64,
    /// Column-collapse analysis: initial length and height of the column (m); NaN without.
    pub initial_shape_m: [f64; 2],
}

/// What a restart reads.
pub struct RestoredMpm {
    /// Counters.
    pub run: MpmRunState,
    /// Every point, sorted by id.
    pub points: Points,
}

/// Write the checkpoint of `sys` to `path` (collective, atomic).
pub fn write(
    path: &Path,
    comm: &dyn Comm,
    sys: &MpmSystem,
    run: &MpmRunState,
) -> Result<(), OutputError> {
    let p = &sys.points;
    let mut rows = Vec::with_capacity(p.len() * Points::WORDS);
    for i in 0..p.len() {
        p.pack_row(i, &mut rows);
    }
    let fill = |file: &hdf5::File, access: Access| -> hdf5::Result<()> {
        write_header(
            file,
            (FORMAT, FORMAT_VERSION),
            &[("step", run.step), ("migrated", run.migrated)],
            &[
                ("time_s", run.time_s),
                ("next_output_s", run.next_output_s),
                ("initial_length_m", run.initial_shape_m[0]),
                ("initial_height_m", run.initial_shape_m[1]),
            ],
        )?;
        let g = file.create_group("mpm")?;
        write_rows(&g, "points", &rows, Points::WORDS, comm, access)?;
        Ok(())
    };
    write_atomically(path, comm, &fill)
}

/// Read an MPM checkpoint (every rank reads every point). Collective.
pub fn read(path: &Path, comm: &dyn Comm) -> Result<RestoredMpm, OutputError> {
    let c = open_checked(path, comm, (FORMAT, FORMAT_VERSION), "an MPM")?;
    let (u, f) = (|n: &str| c.u64(n), |n: &str| c.f64(n));
    let rows = c.rows("mpm/points", Points::WORDS)?;
    let mut sorted: Vec<&[f64]> = rows.chunks_exact(Points::WORDS).collect();
    sorted.sort_by_key(|r| r[0].to_bits());
    let mut points = Points::default();
    for r in sorted {
        points.push_row(r);
    }
    Ok(RestoredMpm {
        run: MpmRunState {
            step: u("step")?,
            time_s: f("time_s")?,
            next_output_s: f("next_output_s")?,
            migrated: u("migrated")?,
            initial_shape_m: [f("initial_length_m")?, f("initial_height_m")?],
        },
        points,
    })
}
