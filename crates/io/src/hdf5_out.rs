//! HDF5 field snapshots (`fields.h5`, one group per output step) and an XDMF sidecar
//! (`fields.xdmf`) so ParaView opens the series directly. Every rank writes its own block
//! of each global dataset, collectively through MPI-IO when there are several ranks; every
//! dataset carries its units, the lattice spacing and the time as attributes.

use super::atomic::write_atomic;
use super::h5par::{self, Access, Block};
use super::OutputError;
use decomposition::Comm;
use hdf5::types::VarLenUnicode;
use std::borrow::Cow;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One scalar or vector field of a snapshot (its values come from
/// [`SnapshotWriter::write`]'s producer).
pub struct FieldSpec<'a> {
    /// Dataset name.
    pub name: &'a str,
    /// Units string (SI).
    pub units: &'a str,
    /// Components per cell (1 or 2).
    pub components: usize,
}

/// A snapshot already in the file: group name, time and (field, components).
struct Written {
    group: String,
    step: u64,
    time_s: f64,
    fields: Vec<(String, usize)>,
}

/// Where this rank's block lies in the global lattice.
#[derive(Debug, Clone, Copy)]
pub struct Layout {
    /// Global cells along x.
    pub nx: usize,
    /// Global cells along y.
    pub ny: usize,
    /// First global column of this rank's block.
    pub x0: usize,
    /// Columns of this rank's block.
    pub width: usize,
    /// Lattice spacing (m).
    pub dx: f64,
}

/// An open snapshot series, written collectively by every rank.
pub struct SnapshotWriter {
    path: PathBuf,
    file: hdf5::File,
    access: Access,
    layout: Layout,
    compression: u8,
    root: bool,
    written: Vec<Written>,
}

impl SnapshotWriter {
    /// Open `dir/fields.h5` for a run on every rank of `comm`. Collective.
    ///
    /// With `resume_after = None` the file is created (truncating an old one). With
    /// `Some(step)` (a restart) an existing file is kept: snapshots up to `step` stay,
    /// later ones (written after the checkpoint by the run that is being redone) are removed.
    pub fn open(
        dir: &Path,
        comm: &dyn Comm,
        layout: Layout,
        compression: u8,
        resume_after: Option<u64>,
    ) -> Result<Self, OutputError> {
        let path = dir.join("fields.h5");
        let h5 = |source| OutputError::Hdf5 {
            path: path.clone(),
            source,
        };
        let (file, access, kept) = h5par::open_series(&path, comm, resume_after).map_err(h5)?;
        let mut w = Self {
            path: path.clone(),
            file,
            access,
            layout,
            compression,
            root: comm.is_root(),
            written: Vec::new(),
        };
        if let Some(kept) = kept {
            w.adopt_existing(kept).map_err(h5)?;
            if w.root {
                w.write_xdmf()?;
            }
        }
        Ok(w)
    }

    /// This rank's block from now on (its slabs moved: a load balance): first global
    /// column and width.
    pub fn set_block(&mut self, x0: usize, width: usize) {
        self.layout.x0 = x0;
        self.layout.width = width;
    }

    /// Record the snapshots kept on a restart (their time and fields).
    fn adopt_existing(&mut self, kept: Vec<(String, u64)>) -> hdf5::Result<()> {
        for (group, step) in kept {
            let g = self.file.group(&group)?;
            let time_s = g.attr("time_s")?.read_scalar::<f64>()?;
            let mut fields = Vec::new();
            for name in g.member_names()? {
                let ds = g.dataset(&name)?;
                fields.push((name, if ds.ndim() == 3 { ds.shape()[2] } else { 1 }));
            }
            self.written.push(Written {
                group,
                step,
                time_s,
                fields,
            });
        }
        Ok(())
    }

    /// Write the group `/step_NNNNNNNN` with the given fields (this rank's block of
    /// each), then flush the file and rewrite the XDMF sidecar, so a crash later still
    /// leaves every earlier snapshot readable. `values(i)` gives field i's values
    /// (row-major from the south row, components interleaved) when it is written, so only
    /// one field's values need exist at a time. Collective, and so is `values`.
    pub fn write<'v>(
        &mut self,
        step: u64,
        time_s: f64,
        fields: &[FieldSpec],
        mut values: impl FnMut(usize) -> Result<Cow<'v, [f64]>, OutputError>,
    ) -> Result<(), OutputError> {
        let h5 = |source| OutputError::Hdf5 {
            path: self.path.clone(),
            source,
        };
        let Layout {
            nx,
            ny,
            x0,
            width,
            dx,
        } = self.layout;
        let group_name = format!("step_{step:08}");
        let g = self.file.create_group(&group_name).map_err(h5)?;
        g.new_attr::<f64>()
            .create("time_s")
            .and_then(|a| a.write_scalar(&time_s))
            .map_err(h5)?;
        g.new_attr::<u64>()
            .create("step")
            .and_then(|a| a.write_scalar(&step))
            .map_err(h5)?;
        let mut names = Vec::new();
        for (i, f) in fields.iter().enumerate() {
            let (shape, block) = if f.components == 1 {
                (
                    vec![ny, nx],
                    Block {
                        start: vec![0, x0 as u64],
                        count: vec![ny as u64, width as u64],
                    },
                )
            } else {
                (
                    vec![ny, nx, f.components],
                    Block {
                        start: vec![0, x0 as u64, 0],
                        count: vec![ny as u64, width as u64, f.components as u64],
                    },
                )
            };
            let builder = g.new_dataset::<f64>();
            let mut builder = builder.shape(shape.as_slice());
            if self.compression > 0 {
                let mut chunk = shape.clone();
                chunk[0] = chunk[0].min(256);
                chunk[1] = chunk[1].min(256);
                builder = builder.chunk(chunk.as_slice()).deflate(self.compression);
            }
            let ds = builder.create(f.name).map_err(h5)?;
            let v = values(i)?;
            h5par::write_block(&ds, &block, &v, self.access).map_err(h5)?;
            drop(v);
            let units: VarLenUnicode = f.units.parse().expect("ASCII units");
            ds.new_attr::<VarLenUnicode>()
                .create("units")
                .and_then(|a| a.write_scalar(&units))
                .map_err(h5)?;
            ds.new_attr::<f64>()
                .create("spacing_m")
                .and_then(|a| a.write_scalar(&dx))
                .map_err(h5)?;
            ds.new_attr::<f64>()
                .create("time_s")
                .and_then(|a| a.write_scalar(&time_s))
                .map_err(h5)?;
            names.push((f.name.to_string(), f.components));
        }
        self.file.flush().map_err(h5)?;
        self.written.push(Written {
            group: group_name,
            step,
            time_s,
            fields: names,
        });
        if self.root {
            self.write_xdmf()?;
        }
        Ok(())
    }

    /// Steps of the snapshots in the file, in order.
    pub fn steps(&self) -> Vec<u64> {
        self.written.iter().map(|w| w.step).collect()
    }

    /// XDMF 2 temporal collection over a 2DCoRectMesh with cell-centred attributes.
    fn write_xdmf(&self) -> Result<(), OutputError> {
        let (nx, ny, dx) = (self.layout.nx, self.layout.ny, self.layout.dx);
        let mut s = String::from("<?xml version=\"1.0\" ?>\n<Xdmf Version=\"2.0\">\n <Domain>\n  <Grid Name=\"fields\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
        for Written {
            group,
            time_s: t,
            fields: names,
            ..
        } in &self.written
        {
            let _ = write!(
                s,
                "   <Grid Name=\"{group}\" GridType=\"Uniform\">\n    <Time Value=\"{t:e}\"/>\n    <Topology TopologyType=\"2DCoRectMesh\" Dimensions=\"{} {}\"/>\n    <Geometry GeometryType=\"ORIGIN_DXDY\">\n     <DataItem Dimensions=\"2\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">0 0</DataItem>\n     <DataItem Dimensions=\"2\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">{dx:e} {dx:e}</DataItem>\n    </Geometry>\n",
                ny + 1,
                nx + 1
            );
            for (name, comps) in names {
                let (kind, dims) = if *comps == 1 {
                    ("Scalar", format!("{ny} {nx}"))
                } else {
                    ("Vector", format!("{ny} {nx} {comps}"))
                };
                // ParaView wants 3-component vectors; 2-component data are shown as such by
                // readers that accept them (h5py, VisIt); ParaView reads them as "Vector" too.
                let _ = write!(
                    s,
                    "    <Attribute Name=\"{name}\" AttributeType=\"{kind}\" Center=\"Cell\">\n     <DataItem Dimensions=\"{dims}\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">fields.h5:/{group}/{name}</DataItem>\n    </Attribute>\n"
                );
            }
            s.push_str("   </Grid>\n");
        }
        s.push_str("  </Grid>\n </Domain>\n</Xdmf>\n");
        write_atomic(&self.path.with_extension("xdmf"), s.as_bytes())
    }
}
