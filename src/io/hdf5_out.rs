//! HDF5 field snapshots (`fields.h5`, one group per output step) and an XDMF sidecar
//! (`fields.xdmf`) so ParaView opens the series directly. Serial for now; every dataset
//! carries its units, the lattice spacing and the time as attributes.

use super::atomic::write_atomic;
use super::OutputError;
use hdf5::types::VarLenUnicode;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One scalar or vector field of a snapshot.
pub struct FieldData<'a> {
    /// Dataset name.
    pub name: &'a str,
    /// Units string (SI).
    pub units: &'a str,
    /// Components per cell (1 or 2).
    pub components: usize,
    /// Values, row-major from the south row, components interleaved.
    pub values: &'a [f64],
}

/// A snapshot already in the file: group name, time and (field, components).
struct Written {
    group: String,
    time_s: f64,
    fields: Vec<(String, usize)>,
}

/// An open snapshot series.
pub struct SnapshotWriter {
    path: PathBuf,
    file: hdf5::File,
    nx: usize,
    ny: usize,
    dx: f64,
    written: Vec<Written>,
}

impl SnapshotWriter {
    /// Create `dir/fields.h5` (truncating an old one) for an `nx` × `ny` lattice of spacing `dx` metres.
    pub fn create(dir: &Path, nx: usize, ny: usize, dx: f64) -> Result<Self, OutputError> {
        let path = dir.join("fields.h5");
        let file = hdf5::File::create(&path).map_err(|source| OutputError::Hdf5 {
            path: path.clone(),
            source,
        })?;
        Ok(Self {
            path,
            file,
            nx,
            ny,
            dx,
            written: Vec::new(),
        })
    }

    /// Write the group `/step_NNNNNNNN` with the given fields, then flush the file and
    /// rewrite the XDMF sidecar, so a crash later still leaves every earlier snapshot readable.
    pub fn write(
        &mut self,
        step: u64,
        time_s: f64,
        fields: &[FieldData],
    ) -> Result<(), OutputError> {
        let h5 = |source| OutputError::Hdf5 {
            path: self.path.clone(),
            source,
        };
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
        for f in fields {
            let shape: Vec<usize> = if f.components == 1 {
                vec![self.ny, self.nx]
            } else {
                vec![self.ny, self.nx, f.components]
            };
            let mut chunk = shape.clone();
            chunk[0] = chunk[0].min(256);
            chunk[1] = chunk[1].min(256);
            let ds = g
                .new_dataset::<f64>()
                .shape(shape.as_slice())
                .chunk(chunk.as_slice())
                .deflate(1)
                .create(f.name)
                .map_err(h5)?;
            ds.write_raw(f.values).map_err(h5)?;
            let units: VarLenUnicode = f.units.parse().expect("ASCII units");
            ds.new_attr::<VarLenUnicode>()
                .create("units")
                .and_then(|a| a.write_scalar(&units))
                .map_err(h5)?;
            ds.new_attr::<f64>()
                .create("spacing_m")
                .and_then(|a| a.write_scalar(&self.dx))
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
            time_s,
            fields: names,
        });
        self.write_xdmf()
    }

    /// XDMF 2 temporal collection over a 2DCoRectMesh with cell-centred attributes.
    fn write_xdmf(&self) -> Result<(), OutputError> {
        let (nx, ny, dx) = (self.nx, self.ny, self.dx);
        let mut s = String::from("<?xml version=\"1.0\" ?>\n<Xdmf Version=\"2.0\">\n <Domain>\n  <Grid Name=\"fields\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
        for Written {
            group,
            time_s: t,
            fields: names,
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
