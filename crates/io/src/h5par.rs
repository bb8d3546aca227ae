//! Parallel HDF5 plumbing: open a file through MPI-IO when the run has several ranks, and
//! read or write one rank's hyperslab of a global dataset — collectively on MPI-IO files
//! (every rank calls, each with its own block), so no rank funnels another's data.

use decomposition::Comm;
use hdf5::types::H5Type;
use hdf5_sys::h5d::{H5Dread, H5Dwrite};
use hdf5_sys::h5i::hid_t;
use hdf5_sys::h5p::H5FD_mpio_xfer_t;
use hdf5_sys::h5p::{H5Pclose, H5Pcreate, H5Pset_dxpl_mpio};
use hdf5_sys::h5s::{H5S_seloper_t, H5Sclose, H5Screate_simple, H5Sselect_hyperslab};
use std::path::Path;

/// How a file is accessed: serially (one rank) or through MPI-IO (collective transfers).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// One process, the default sec2 driver.
    Serial,
    /// Every rank of the communicator opens the file; transfers are collective.
    Mpio,
}

fn access_of(comm: &dyn Comm) -> Option<(Access, Option<decomposition::RawComm>)> {
    match (comm.size(), comm.raw_mpi()) {
        (1, _) => Some((Access::Serial, None)),
        (_, Some(raw)) => Some((Access::Mpio, Some(raw))),
        (_, None) => None,
    }
}

/// Create (truncate) `path` for every rank of `comm`. Collective.
pub fn create(path: &Path, comm: &dyn Comm) -> hdf5::Result<(hdf5::File, Access)> {
    match access_of(comm).ok_or("several ranks without an MPI communicator")? {
        (Access::Serial, _) => Ok((hdf5::File::create(path)?, Access::Serial)),
        (Access::Mpio, raw) => {
            let raw = raw.expect("MPI-IO access has a communicator");
            let f = hdf5::File::with_options()
                .with_fapl(|p| p.mpio(raw, None))
                .create(path)?;
            Ok((f, Access::Mpio))
        }
    }
}

/// Create (truncate) `path` for every rank of `comm`, its first `user_block` bytes left to
/// the application (a power of two ≥ 512). Collective.
pub fn create_with_user_block(
    path: &Path,
    comm: &dyn Comm,
    user_block: u64,
) -> hdf5::Result<(hdf5::File, Access)> {
    match access_of(comm).ok_or("several ranks without an MPI communicator")? {
        (Access::Serial, _) => {
            let f = hdf5::File::with_options()
                .with_fcpl(|p| p.userblock(user_block))
                .create(path)?;
            Ok((f, Access::Serial))
        }
        (Access::Mpio, raw) => {
            let raw = raw.expect("MPI-IO access has a communicator");
            let f = hdf5::File::with_options()
                .with_fcpl(|p| p.userblock(user_block))
                .with_fapl(|p| p.mpio(raw, None))
                .create(path)?;
            Ok((f, Access::Mpio))
        }
    }
}

/// Open `path` read-only (`write = false`) or read-write on every rank of `comm`. Collective.
pub fn open(path: &Path, comm: &dyn Comm, write: bool) -> hdf5::Result<(hdf5::File, Access)> {
    let mode = if write {
        hdf5::file::OpenMode::ReadWrite
    } else {
        hdf5::file::OpenMode::Read
    };
    match access_of(comm).ok_or("several ranks without an MPI communicator")? {
        (Access::Serial, _) => Ok((hdf5::File::open_as(path, mode)?, Access::Serial)),
        (Access::Mpio, raw) => {
            let raw = raw.expect("MPI-IO access has a communicator");
            let f = hdf5::File::with_options()
                .with_fapl(|p| p.mpio(raw, None))
                .open_as(path, mode)?;
            Ok((f, Access::Mpio))
        }
    }
}

/// The snapshot groups a restart keeps: (name, step), in order.
pub type KeptGroups = Vec<(String, u64)>;

/// Open the snapshot series `path` of a run on every rank of `comm`. Collective.
///
/// With `resume_after = None`, or when the file does not exist, it is created (truncating
/// an old one) and no groups are returned. With `Some(step)` (a restart) the file is kept:
/// its `step_NNNNNNNN` groups up to `step` stay and are returned in order as (name, step);
/// later ones, written after the checkpoint by the run being redone, are unlinked.
pub fn open_series(
    path: &Path,
    comm: &dyn Comm,
    resume_after: Option<u64>,
) -> hdf5::Result<(hdf5::File, Access, Option<KeptGroups>)> {
    let Some(last) = resume_after.filter(|_| path.exists()) else {
        let (file, access) = create(path, comm)?;
        return Ok((file, access, None));
    };
    let (file, access) = open(path, comm, true)?;
    let mut names = file.member_names()?;
    names.sort();
    let mut kept = Vec::new();
    for group in names {
        let Some(step) = group
            .strip_prefix("step_")
            .and_then(|s| s.parse::<u64>().ok())
        else {
            continue;
        };
        if step > last {
            file.unlink(&group)?;
        } else {
            kept.push((group, step));
        }
    }
    Ok((file, access, Some(kept)))
}

/// A hyperslab: `start` and `count` per dimension of the dataset.
#[derive(Debug, Clone)]
pub struct Block {
    /// First index per dimension.
    pub start: Vec<u64>,
    /// Extent per dimension.
    pub count: Vec<u64>,
}

impl Block {
    /// Values in the block.
    pub fn len(&self) -> usize {
        self.count.iter().product::<u64>() as usize
    }
    /// True for an empty block.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Spaces and transfer list of one hyperslab transfer, closed on drop.
struct Transfer {
    mem: hid_t,
    file: hid_t,
    xfer: hid_t,
}

impl Transfer {
    fn new(ds: &hdf5::Dataset, block: &Block, access: Access) -> hdf5::Result<Self> {
        // HDF5 is not thread-safe: raw calls hold the crate's library lock like its own
        // calls do (tests and callers may write files from several threads).
        // SAFETY: plain HDF5 C calls on valid ids; every id made here is closed in Drop.
        hdf5::sync::sync(|| unsafe {
            let mem = H5Screate_simple(
                block.count.len() as i32,
                block.count.as_ptr(),
                std::ptr::null(),
            );
            let file = hdf5_sys::h5d::H5Dget_space(ds.id());
            let xfer = H5Pcreate(*hdf5::globals::H5P_DATASET_XFER);
            let t = Self { mem, file, xfer };
            if mem < 0 || file < 0 || xfer < 0 {
                return Err("cannot create HDF5 dataspaces for a hyperslab".into());
            }
            if H5Sselect_hyperslab(
                file,
                H5S_seloper_t::H5S_SELECT_SET,
                block.start.as_ptr(),
                std::ptr::null(),
                block.count.as_ptr(),
                std::ptr::null(),
            ) < 0
            {
                return Err("hyperslab outside the dataset".into());
            }
            if access == Access::Mpio
                && H5Pset_dxpl_mpio(xfer, H5FD_mpio_xfer_t::H5FD_MPIO_COLLECTIVE) < 0
            {
                return Err("cannot request collective MPI-IO transfers".into());
            }
            Ok(t)
        })
    }
}

impl Drop for Transfer {
    fn drop(&mut self) {
        // SAFETY: ids created in `new`; under the library lock (see `new`).
        hdf5::sync::sync(|| unsafe {
            H5Sclose(self.mem);
            H5Sclose(self.file);
            H5Pclose(self.xfer);
        });
    }
}

/// Write `data` (row-major, `block.len()` values) into `block` of `ds`. Collective on
/// MPI-IO files: every rank must call it for the same dataset.
pub fn write_block<T: H5Type>(
    ds: &hdf5::Dataset,
    block: &Block,
    data: &[T],
    access: Access,
) -> hdf5::Result<()> {
    assert_eq!(data.len(), block.len(), "hyperslab size");
    let t = Transfer::new(ds, block, access)?;
    let mem_type = hdf5::Datatype::from_type::<T>()?;
    // SAFETY: `data` holds exactly the selected number of values of the memory type;
    // under the library lock (see `Transfer::new`).
    let status = hdf5::sync::sync(|| unsafe {
        H5Dwrite(
            ds.id(),
            mem_type.id(),
            t.mem,
            t.file,
            t.xfer,
            data.as_ptr().cast(),
        )
    });
    if status < 0 {
        return Err(format!("H5Dwrite of a hyperslab of {} failed", ds.name()).into());
    }
    Ok(())
}

/// Read `block` of `ds` into `out` (row-major, `block.len()` values). Collective on
/// MPI-IO files.
pub fn read_block<T: H5Type>(
    ds: &hdf5::Dataset,
    block: &Block,
    out: &mut [T],
    access: Access,
) -> hdf5::Result<()> {
    assert_eq!(out.len(), block.len(), "hyperslab size");
    let t = Transfer::new(ds, block, access)?;
    let mem_type = hdf5::Datatype::from_type::<T>()?;
    // SAFETY: `out` has room for exactly the selected number of values; under the
    // library lock (see `Transfer::new`).
    let status = hdf5::sync::sync(|| unsafe {
        H5Dread(
            ds.id(),
            mem_type.id(),
            t.mem,
            t.file,
            t.xfer,
            out.as_mut_ptr().cast(),
        )
    });
    if status < 0 {
        return Err(format!("H5Dread of a hyperslab of {} failed", ds.name()).into());
    }
    Ok(())
}

/// This rank's rows of a global `[rows, cols]` f64 dataset `name` in `g`, placed after the
/// rows of the lower ranks and written collectively. Collective.
pub fn write_rows(
    g: &hdf5::Group,
    name: &str,
    local: &[f64],
    cols: usize,
    comm: &dyn Comm,
    access: Access,
) -> hdf5::Result<hdf5::Dataset> {
    let rows = (local.len() / cols) as f64;
    let all = comm.all_gather_f64(&[rows]);
    let offset: f64 = all[..comm.rank()].iter().sum();
    let total = all.iter().sum::<f64>() as usize;
    let ds = g.new_dataset::<f64>().shape([total, cols]).create(name)?;
    let block = Block {
        start: vec![offset as u64, 0],
        count: vec![rows as u64, cols as u64],
    };
    write_block(&ds, &block, local, access)?;
    Ok(ds)
}

/// (group, time, rows of its `id` dataset) of the snapshot groups a restart keeps (see
/// [`open_series`]), in order; each group carries a `time_s` attribute.
pub fn kept_snapshots(
    file: &hdf5::File,
    kept: Option<KeptGroups>,
) -> hdf5::Result<Vec<(String, f64, u64)>> {
    let mut out = Vec::new();
    for (group, _) in kept.unwrap_or_default() {
        let g = file.group(&group)?;
        let time = g.attr("time_s").and_then(|a| a.read_scalar::<f64>())?;
        let n = g.dataset("id")?.shape()[0] as u64;
        out.push((group, time, n));
    }
    Ok(out)
}
