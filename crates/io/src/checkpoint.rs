//! Checkpoint and restart: the whole state of a run in one HDF5 file, written by every
//! rank collectively into a temporary file that is renamed into place only when complete.
//!
//! Layout (format version 1):
//! * root attributes: `format` = "grainflow-checkpoint", `format_version`, `grainflow_version`,
//!   `step`, `time_s`, `precision`, `nx`, `ny`;
//! * `/lbm/populations`: shifted distributions h = f − w, shape `[9, ny, nx]`, in the run's
//!   precision;
//! * `/run/totals_initial`: mass, momentum x/y, kinetic energy, max speed at step 0;
//! * `/run/probes/NNN`: one probe series each, rows `[step, time_s, values…]`, with the
//!   probe's `name` as an attribute.
//!
//! Later physics add their own groups (`/dem`, `/mpm`) beside `/lbm`; a reader ignores
//! groups it does not know and refuses a file that lacks one it needs.

use super::h5par::{self, Access, Block};
use super::probes::Series;
use super::OutputError;
use decomposition::Comm;
use hdf5::types::{H5Type, VarLenUnicode};
use std::path::{Path, PathBuf};

/// Value of the root `format` attribute.
pub const FORMAT: &str = "grainflow-checkpoint";
/// Current format version.
pub const FORMAT_VERSION: u32 = 1;

/// The lattice part of a checkpoint, as this rank holds it.
pub struct LatticeState<'a, T> {
    /// Global cells along x and y.
    pub global: [usize; 2],
    /// This rank's first global column and width.
    pub slab: (usize, usize),
    /// This rank's interior populations, `[9][ny][width]` row-major.
    pub populations: &'a [T],
}

/// Everything besides the lattice that a restarted run needs to continue bit-identically.
#[derive(Debug, Clone)]
pub struct RunState {
    /// Steps completed.
    pub step: u64,
    /// Simulated time (s).
    pub time_s: f64,
    /// "f32" or "f64".
    pub precision: String,
    /// Totals at step 0 (mass, momentum x, momentum y, kinetic energy, max speed).
    pub totals_initial: [f64; 5],
    /// Probe series recorded so far.
    pub series: Vec<Series>,
}

fn err(path: &Path, message: impl Into<String>) -> OutputError {
    OutputError::Checkpoint {
        path: path.to_owned(),
        message: message.into(),
    }
}

fn vlu(s: &str) -> VarLenUnicode {
    s.parse().expect("ASCII attribute")
}

/// Write `path` atomically on every rank of `comm`: a temporary file next to it first,
/// renamed over `path` by rank 0 once every rank has closed it. A crash at any point
/// leaves the previous complete checkpoint in place. Collective.
pub fn write<T: H5Type + Copy>(
    path: &Path,
    comm: &dyn Comm,
    lattice: &LatticeState<'_, T>,
    run: &RunState,
) -> Result<(), OutputError> {
    write_with(path, comm, lattice, run, &|_, _| Ok(()))
}

/// [`write()`] plus the groups `more` adds (another physics' state). Collective.
pub fn write_with<T: H5Type + Copy>(
    path: &Path,
    comm: &dyn Comm,
    lattice: &LatticeState<'_, T>,
    run: &RunState,
    more: &dyn Fn(&hdf5::File, Access) -> hdf5::Result<()>,
) -> Result<(), OutputError> {
    write_atomically(path, comm, &|file, access| {
        fill(file, access, lattice, run)?;
        more(file, access)
    })
}

/// Create `path.tmp` on every rank, let `fill` write it (collectively), then fsync it and
/// rename it over `path` on rank 0 once every rank has closed it: the new name appears only
/// for a complete file. Collective.
pub fn write_atomically(
    path: &Path,
    comm: &dyn Comm,
    fill: &dyn Fn(&hdf5::File, Access) -> hdf5::Result<()>,
) -> Result<(), OutputError> {
    let tmp = PathBuf::from(format!("{}.tmp", path.display()));
    let h5 = |source| OutputError::Hdf5 {
        path: tmp.clone(),
        source,
    };
    {
        let (file, access) =
            h5par::create_with_user_block(&tmp, comm, super::digest::USER_BLOCK).map_err(h5)?;
        fill(&file, access).map_err(h5)?;
        file.flush().map_err(h5)?;
        // Every group and dataset is closed by now: MPI-IO files refuse to close otherwise.
        drop(file);
    }
    comm.barrier();
    let mut status = Ok(());
    if comm.is_root() {
        // Seal it with the digest of its bytes, fsync, then rename: the new name appears
        // only for a complete file that a restart can verify.
        status = super::digest::seal(&tmp)
            .and_then(|_| std::fs::File::open(&tmp))
            .and_then(|f| f.sync_all())
            .and_then(|_| std::fs::rename(&tmp, path))
            .map_err(|source| OutputError::Io {
                path: path.to_owned(),
                source,
            });
    }
    comm.barrier();
    status
}

/// Everything but the file itself: root attributes, `/lbm`, `/run`.
fn fill<T: H5Type + Copy>(
    file: &hdf5::File,
    access: Access,
    lattice: &LatticeState<'_, T>,
    run: &RunState,
) -> hdf5::Result<()> {
    let [nx, ny] = lattice.global;
    for (name, v) in [("step", run.step), ("nx", nx as u64), ("ny", ny as u64)] {
        file.new_attr::<u64>()
            .create(name)
            .and_then(|a| a.write_scalar(&v))?;
    }
    file.new_attr::<f64>()
        .create("time_s")
        .and_then(|a| a.write_scalar(&run.time_s))?;
    file.new_attr::<u32>()
        .create("format_version")
        .and_then(|a| a.write_scalar(&FORMAT_VERSION))?;
    for (name, v) in [
        ("format", FORMAT),
        ("grainflow_version", env!("CARGO_PKG_VERSION")),
        ("precision", run.precision.as_str()),
    ] {
        file.new_attr::<VarLenUnicode>()
            .create(name)
            .and_then(|a| a.write_scalar(&vlu(v)))?;
    }
    let lbm = file.create_group("lbm")?;
    let (x0, width) = lattice.slab;
    let ds = lbm
        .new_dataset::<T>()
        .shape([9, ny, nx])
        .create("populations")?;
    let block = Block {
        start: vec![0, 0, x0 as u64],
        count: vec![9, ny as u64, width as u64],
    };
    h5par::write_block(&ds, &block, lattice.populations, access)?;
    let rg = file.create_group("run")?;
    write_small(&rg, "totals_initial", &run.totals_initial, 1, access)?;
    let pg = rg.create_group("probes")?;
    for (k, s) in run.series.iter().enumerate() {
        let cols = 2 + s.columns.len();
        let mut rows = Vec::with_capacity(s.len() * cols);
        for j in 0..s.len() {
            rows.push(s.steps[j] as f64);
            rows.push(s.times[j]);
            rows.extend_from_slice(&s.values[j * s.columns.len()..(j + 1) * s.columns.len()]);
        }
        let name = format!("{k:03}");
        write_small(&pg, &name, &rows, cols, access)?;
        pg.dataset(&name).and_then(|d| {
            d.new_attr::<VarLenUnicode>()
                .create("name")
                .and_then(|a| a.write_scalar(&vlu(&s.name)))
        })?;
    }

    Ok(())
}

/// A small 2-D dataset `[len / cols, cols]` of f64, identical on every rank.
fn write_small(
    g: &hdf5::Group,
    name: &str,
    values: &[f64],
    cols: usize,
    access: Access,
) -> hdf5::Result<()> {
    let rows = values.len() / cols;
    let ds = g.new_dataset::<f64>().shape([rows, cols]).create(name)?;
    if rows > 0 {
        let block = Block {
            start: vec![0, 0],
            count: vec![rows as u64, cols as u64],
        };
        h5par::write_block(&ds, &block, values, access)?;
    }
    Ok(())
}

/// What [`read`] returns: the run state plus this rank's populations.
pub struct Restored<T> {
    /// Step, time, totals, probe series.
    pub run: RunState,
    /// This rank's interior populations, `[9][ny][width]`.
    pub populations: Vec<T>,
    /// Whether the file also holds grains (a coupled run's checkpoint).
    pub grains: bool,
}

/// Read a checkpoint for a run of precision `precision` on a `global` lattice, this rank
/// holding columns `slab = (x0, width)`. Any rank count may read a checkpoint written on
/// any other. `series` gives the probes the scene defines (names and columns), which the
/// file must match. Collective.
pub fn read<T: H5Type + Copy + Default>(
    path: &Path,
    comm: &dyn Comm,
    precision: &str,
    global: [usize; 2],
    slab: (usize, usize),
    series: &[Series],
) -> Result<Restored<T>, OutputError> {
    if !path.is_file() {
        return Err(err(
            path,
            "no such file; give the path of a checkpoint.h5 written by `grainflow run`",
        ));
    }
    super::digest::verify(path, comm)?;
    let unreadable = |e: hdf5::Error| {
        err(
            path,
            format!("unreadable (truncated, or not a grainflow checkpoint): {e}"),
        )
    };
    let (file, access) = h5par::open(path, comm, false).map_err(unreadable)?;
    let text = |name: &str| -> Result<String, OutputError> {
        let a = file.attr(name).map_err(unreadable)?;
        Ok(a.read_scalar::<VarLenUnicode>()
            .map_err(unreadable)?
            .to_string())
    };
    let int = |name: &str| -> Result<u64, OutputError> {
        file.attr(name)
            .and_then(|a| a.read_scalar::<u64>())
            .map_err(unreadable)
    };
    if text("format")? != FORMAT {
        return Err(err(
            path,
            "not a grainflow checkpoint (wrong `format` attribute)",
        ));
    }
    let version = file
        .attr("format_version")
        .and_then(|a| a.read_scalar::<u32>())
        .map_err(unreadable)?;
    if version != FORMAT_VERSION {
        return Err(err(
            path,
            format!("format version {version}, but this grainflow reads version {FORMAT_VERSION}"),
        ));
    }
    let file_precision = text("precision")?;
    if file_precision != precision {
        return Err(err(
            path,
            format!(
                "written in {file_precision}, but this run is {precision}; restart with --precision {file_precision}"
            ),
        ));
    }
    let (nx, ny) = (int("nx")? as usize, int("ny")? as usize);
    if [nx, ny] != global {
        return Err(err(
            path,
            format!(
                "lattice is {nx} × {ny}, but the scene's is {} × {}; restart with the scene that wrote it",
                global[0], global[1]
            ),
        ));
    }
    let step = int("step")?;
    let time_s = file
        .attr("time_s")
        .and_then(|a| a.read_scalar::<f64>())
        .map_err(unreadable)?;
    let ds = file.dataset("lbm/populations").map_err(unreadable)?;
    if ds.shape() != [9, ny, nx] {
        return Err(err(
            path,
            format!(
                "/lbm/populations has shape {:?}, expected [9, {ny}, {nx}]",
                ds.shape()
            ),
        ));
    }
    let (x0, width) = slab;
    let block = Block {
        start: vec![0, 0, x0 as u64],
        count: vec![9, ny as u64, width as u64],
    };
    let mut populations = vec![T::default(); block.len()];
    h5par::read_block(&ds, &block, &mut populations, access).map_err(unreadable)?;
    let totals: Vec<f64> = file
        .dataset("run/totals_initial")
        .and_then(|d| d.read_raw::<f64>())
        .map_err(unreadable)?;
    let totals_initial: [f64; 5] = totals
        .try_into()
        .map_err(|_| err(path, "/run/totals_initial must hold 5 values"))?;
    let mut restored = Vec::with_capacity(series.len());
    for (k, want) in series.iter().enumerate() {
        let d = file.dataset(&format!("run/probes/{k:03}")).map_err(|_| {
            err(
                path,
                format!(
                    "has no series for probe `{}`; restart with the scene that wrote it",
                    want.name
                ),
            )
        })?;
        let name = d
            .attr("name")
            .and_then(|a| a.read_scalar::<VarLenUnicode>())
            .map_err(unreadable)?
            .to_string();
        let cols = 2 + want.columns.len();
        if name != want.name || d.ndim() != 2 || d.shape()[1] != cols {
            return Err(err(
                path,
                format!("probe {k} is `{name}`, but the scene's is `{}`; restart with the scene that wrote it", want.name),
            ));
        }
        let rows = d.read_raw::<f64>().map_err(unreadable)?;
        let mut s = Series::new(&want.name, want.columns.clone());
        for r in rows.chunks_exact(cols) {
            s.push(r[0] as u64, r[1], &r[2..]);
        }
        restored.push(s);
    }
    Ok(Restored {
        run: RunState {
            step,
            time_s,
            precision: file_precision,
            totals_initial,
            series: restored,
        },
        populations,
        grains: file.group("dem").is_ok(),
    })
}

/// The header of a particle checkpoint: `format`, `grainflow_version` and `format_version`
/// attributes, then the named u64 and f64 counters, on the file's root.
pub fn write_header(
    file: &hdf5::File,
    (format, version): (&str, u32),
    ints: &[(&str, u64)],
    reals: &[(&str, f64)],
) -> hdf5::Result<()> {
    for (name, v) in [
        ("format", format),
        ("grainflow_version", env!("CARGO_PKG_VERSION")),
    ] {
        file.new_attr::<VarLenUnicode>()
            .create(name)
            .and_then(|a| a.write_scalar(&vlu(v)))?;
    }
    file.new_attr::<u32>()
        .create("format_version")
        .and_then(|a| a.write_scalar(&version))?;
    for (name, v) in ints {
        file.new_attr::<u64>()
            .create(*name)
            .and_then(|a| a.write_scalar(v))?;
    }
    for (name, v) in reals {
        file.new_attr::<f64>()
            .create(*name)
            .and_then(|a| a.write_scalar(v))?;
    }
    Ok(())
}

/// A particle checkpoint opened for reading, its `format` and `format_version` checked.
pub struct CheckedFile<'a> {
    /// The open file (every rank).
    pub file: hdf5::File,
    path: &'a Path,
}

impl CheckedFile<'_> {
    /// The error for an HDF5 failure while reading this file.
    pub fn bad(&self, e: hdf5::Error) -> OutputError {
        err(
            self.path,
            format!("unreadable (truncated, or not a grainflow checkpoint): {e}"),
        )
    }
    /// A u64 attribute of the root.
    pub fn u64(&self, name: &str) -> Result<u64, OutputError> {
        self.file
            .attr(name)
            .and_then(|a| a.read_scalar::<u64>())
            .map_err(|e| self.bad(e))
    }
    /// An f64 attribute of the root.
    pub fn f64(&self, name: &str) -> Result<f64, OutputError> {
        self.file
            .attr(name)
            .and_then(|a| a.read_scalar::<f64>())
            .map_err(|e| self.bad(e))
    }
    /// A `[rows, cols]` f64 dataset, its width checked.
    pub fn rows(&self, name: &str, cols: usize) -> Result<Vec<f64>, OutputError> {
        let ds = self.file.dataset(name).map_err(|e| self.bad(e))?;
        if ds.ndim() != 2 || ds.shape()[1] != cols {
            return Err(err(self.path, format!("/{name} must have {cols} columns")));
        }
        ds.read_raw::<f64>().map_err(|e| self.bad(e))
    }
}

/// Open the particle checkpoint `path` written by [`write_header`] with `(format,
/// version)`, on every rank (collective). `run` names the kind of run in messages
/// ("a grains", "an MPM").
pub fn open_checked<'a>(
    path: &'a Path,
    comm: &dyn Comm,
    (format, version): (&str, u32),
    run: &str,
) -> Result<CheckedFile<'a>, OutputError> {
    if !path.is_file() {
        return Err(err(
            path,
            format!("no such file; give the checkpoint.h5 of {run} run"),
        ));
    }
    super::digest::verify(path, comm)?;
    let bad = |e: hdf5::Error| {
        err(
            path,
            format!("unreadable (truncated, or not a grainflow checkpoint): {e}"),
        )
    };
    let (file, _) = h5par::open(path, comm, false).map_err(bad)?;
    let found = file
        .attr("format")
        .and_then(|a| a.read_scalar::<VarLenUnicode>())
        .map_err(bad)?
        .to_string();
    if found != format {
        return Err(err(
            path,
            format!("a `{found}` file, not {run} checkpoint; restart {run} scene from the checkpoint.h5 its run wrote"),
        ));
    }
    let v = file
        .attr("format_version")
        .and_then(|a| a.read_scalar::<u32>())
        .map_err(bad)?;
    if v != version {
        return Err(err(
            path,
            format!("format version {v}, this grainflow reads {version}"),
        ));
    }
    Ok(CheckedFile { file, path })
}
