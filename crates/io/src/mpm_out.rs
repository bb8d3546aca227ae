//! MPM snapshots: `mpm.h5` with one group per snapshot holding the material points (each
//! rank writing its block of rows collectively) and the grid's node fields (each rank its
//! node columns), an XDMF sidecar that ParaView opens as points plus a rectilinear grid,
//! and PNG pictures of the points coloured by speed or plastic strain.
//!
//! Point rows are in rank order, then storage order, so they differ between rank counts;
//! the `id` dataset identifies each point (sort by it to compare runs).

use super::atomic::write_atomic;
use super::figure::{write_figure, Frame, Image, Legend, PictureStyle};
use super::h5par::{self, write_rows, Access, Block};
use super::picture::Scale;
use super::OutputError;
use decomposition::Comm;
use mpm::MpmSystem;
use scene::PictureField;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Point datasets of a snapshot: name, components, units. Each snapshot also holds `id`
/// and the grid group `grid` (`mass`, `velocity` on the (ny+3) × (nx+3) nodes, padding
/// included, from (−h, −h)).
const POINT_DATASETS: [(&str, usize, &str); 6] = [
    ("position", 3, "m"),
    ("velocity", 3, "m/s"),
    (
        "stress",
        9,
        "Pa (3 x 3 row-major: xx xy xz yx yy yz zx zy zz; tension positive; plane strain)",
    ),
    ("plastic_strain", 1, "1 (equivalent plastic strain)"),
    ("speed", 1, "m/s"),
    ("volume", 1, "m^2 (per metre of depth)"),
];

/// Writer of `mpm.h5` and `mpm.xdmf`.
pub struct MpmWriter {
    path: PathBuf,
    file: hdf5::File,
    access: Access,
    root: bool,
    /// (group, time, point count) of every snapshot written.
    written: Vec<(String, f64, u64)>,
    /// Node columns and rows, origin and spacing of the grid.
    grid: ([usize; 2], f64),
}

impl MpmWriter {
    /// Open `dir/mpm.h5` on every rank (collective). `resume_after` as for
    /// [`h5par::open_series`]: a restart keeps the snapshots up to its step.
    pub fn open(
        dir: &Path,
        sys: &MpmSystem,
        comm: &dyn Comm,
        resume_after: Option<u64>,
    ) -> Result<Self, OutputError> {
        let path = dir.join("mpm.h5");
        let h5 = |source| OutputError::Hdf5 {
            path: path.clone(),
            source,
        };
        let (file, access, kept) = h5par::open_series(&path, comm, resume_after).map_err(h5)?;
        let spec = sys.setup.spec;
        let mut w = MpmWriter {
            path: path.clone(),
            file,
            access,
            root: comm.is_root(),
            written: Vec::new(),
            grid: ([spec.cols(), spec.rows()], spec.h),
        };
        w.written = h5par::kept_snapshots(&w.file, kept).map_err(h5)?;
        if w.root && !w.written.is_empty() {
            w.write_xdmf()?;
        }
        Ok(w)
    }

    /// Write group `/step_NNNNNNNN`: every point of every rank and the grid's node mass and
    /// velocity of the last step; then flush and rewrite the XDMF. Collective.
    pub fn write(&mut self, sys: &MpmSystem, comm: &dyn Comm) -> Result<(), OutputError> {
        let h5 = |source| OutputError::Hdf5 {
            path: self.path.clone(),
            source,
        };
        let group = format!("step_{:08}", sys.steps);
        if self.written.iter().any(|w| w.0 == group) {
            return Ok(());
        }
        let p = &sys.points;
        let n = p.len();
        let grp = self.file.create_group(&group).map_err(h5)?;
        grp.new_attr::<f64>()
            .create("time_s")
            .and_then(|a| a.write_scalar(&sys.time))
            .and_then(|_| grp.new_attr::<u64>().create("step"))
            .and_then(|a| a.write_scalar(&sys.steps))
            .map_err(h5)?;
        for (name, comps, units) in POINT_DATASETS {
            let mut v = Vec::with_capacity(n * comps);
            for i in 0..n {
                match name {
                    "position" => v.extend_from_slice(&[p.pos[i][0], p.pos[i][1], 0.0]),
                    "velocity" => v.extend_from_slice(&[p.vel[i][0], p.vel[i][1], 0.0]),
                    "stress" => {
                        let [xx, yy, xy, zz] = p.stress[i];
                        v.extend_from_slice(&[xx, xy, 0.0, xy, yy, 0.0, 0.0, 0.0, zz]);
                    }
                    "plastic_strain" => v.push(p.eps_p[i]),
                    "speed" => v.push(p.vel[i][0].hypot(p.vel[i][1])),
                    _ => v.push(p.volume(i)),
                }
            }
            let ds = write_rows(&grp, name, &v, comps, comm, self.access).map_err(h5)?;
            unit(&ds, units).map_err(h5)?;
        }
        let counts = comm.all_gather_f64(&[n as f64]);
        let offset: f64 = counts[..comm.rank()].iter().sum();
        let total = counts.iter().sum::<f64>() as u64;
        let ds = grp
            .new_dataset::<u64>()
            .shape([total as usize])
            .create("id")
            .map_err(h5)?;
        let block = Block {
            start: vec![offset as u64],
            count: vec![n as u64],
        };
        h5par::write_block(&ds, &block, &p.id, self.access).map_err(h5)?;
        self.write_grid(&grp, sys).map_err(h5)?;
        self.file.flush().map_err(h5)?;
        self.written.push((group, sys.time, total));
        if self.root {
            self.write_xdmf()?;
        }
        Ok(())
    }

    /// Node mass and velocity on every node, the padding layer included (so the nodes hold
    /// exactly the points' mass): `[ny+3, nx+3(, 3)]`, node (I, J) at ((I, J)) h, I, J from
    /// −1. Each rank writes the node columns of its cell columns (the outer ones at the ends).
    fn write_grid(&self, grp: &hdf5::Group, sys: &MpmSystem) -> hdf5::Result<()> {
        let spec = sys.setup.spec;
        let g = grp.create_group("grid")?;
        let own = sys.own_columns();
        // Storage column k holds node column I = k − 1.
        let k0 = if own.start == 0 { 0 } else { own.start + 1 };
        let k1 = if own.end == spec.nx {
            spec.cols()
        } else {
            own.end + 1
        };
        let (rows, width) = (spec.rows(), k1 - k0);
        let (mass, vel) = sys.nodes.snapshot(&spec);
        let mut m = Vec::with_capacity(width * rows);
        let mut v = Vec::with_capacity(width * rows * 3);
        for r in 0..rows {
            for k in k0..k1 {
                let n = k * rows + r;
                m.push(mass[n]);
                v.extend_from_slice(&[vel[n][0], vel[n][1], 0.0]);
            }
        }
        let dm = g
            .new_dataset::<f64>()
            .shape([rows, spec.cols()])
            .create("mass")?;
        let b = Block {
            start: vec![0, k0 as u64],
            count: vec![rows as u64, width as u64],
        };
        h5par::write_block(&dm, &b, &m, self.access)?;
        unit(&dm, "kg/m")?;
        let dv = g
            .new_dataset::<f64>()
            .shape([rows, spec.cols(), 3])
            .create("velocity")?;
        let b = Block {
            start: vec![0, k0 as u64, 0],
            count: vec![rows as u64, width as u64, 3],
        };
        h5par::write_block(&dv, &b, &v, self.access)?;
        unit(&dv, "m/s")?;
        g.new_attr::<f64>()
            .create("origin_m")
            .and_then(|a| a.write_scalar(&-spec.h))
    }

    /// Snapshots written so far.
    pub fn snapshots(&self) -> usize {
        self.written.len()
    }

    /// XDMF 2: a temporal collection of spatial collections, each holding the points
    /// (Polyvertex) and the grid (2DCoRectMesh, node-centred fields).
    fn write_xdmf(&self) -> Result<(), OutputError> {
        let ([nxn, nyn], h) = self.grid;
        let mut s = String::from("<?xml version=\"1.0\" ?>\n<Xdmf Version=\"2.0\">\n <Domain>\n  <Grid Name=\"mpm\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
        for (group, t, n) in &self.written {
            let _ = write!(
                s,
                "   <Grid Name=\"{group}\" GridType=\"Collection\" CollectionType=\"Spatial\">\n    <Time Value=\"{t:e}\"/>\n"
            );
            super::xdmf::open_points_grid(
                &mut s,
                "    ",
                "points",
                ("mpm.h5", group, *n),
                &POINT_DATASETS,
            );
            let _ = write!(
                s,
                "    </Grid>\n    <Grid Name=\"grid\" GridType=\"Uniform\">\n     <Topology TopologyType=\"2DCoRectMesh\" Dimensions=\"{nyn} {nxn}\"/>\n     <Geometry GeometryType=\"ORIGIN_DXDY\">\n      <DataItem Dimensions=\"2\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">{o:e} {o:e}</DataItem>\n      <DataItem Dimensions=\"2\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">{h:e} {h:e}</DataItem>\n     </Geometry>\n     <Attribute Name=\"node_mass\" AttributeType=\"Scalar\" Center=\"Node\">\n      <DataItem Dimensions=\"{nyn} {nxn}\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">mpm.h5:/{group}/grid/mass</DataItem>\n     </Attribute>\n     <Attribute Name=\"node_velocity\" AttributeType=\"Vector\" Center=\"Node\">\n      <DataItem Dimensions=\"{nyn} {nxn} 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">mpm.h5:/{group}/grid/velocity</DataItem>\n     </Attribute>\n    </Grid>\n   </Grid>\n",
                o = -h
            );
        }
        s.push_str("  </Grid>\n </Domain>\n</Xdmf>\n");
        write_atomic(&self.path.with_extension("xdmf"), s.as_bytes())
    }
}

fn unit(ds: &hdf5::Dataset, units: &str) -> hdf5::Result<()> {
    let u: hdf5::types::VarLenUnicode = units.parse().expect("ASCII units");
    ds.new_attr::<hdf5::types::VarLenUnicode>()
        .create("units")
        .and_then(|a| a.write_scalar(&u))
}

/// Draw the points of every rank into `path` (rank 0 writes; collective): each point as
/// a filled square of its current area (at least its initial domain), on white framing the
/// grid, coloured by `field` from 0 to `style.limit`, the sides that are not open drawn
/// black, with a legend giving the time `time_s`.
pub fn write_mpm_png(
    path: &Path,
    sys: &MpmSystem,
    field: PictureField,
    style: PictureStyle,
    time_s: f64,
    comm: &dyn Comm,
) -> Result<(), OutputError> {
    let p = &sys.points;
    let mut local = Vec::with_capacity(p.len() * 4);
    for i in 0..p.len() {
        let value = match field {
            PictureField::PlasticStrain => p.eps_p[i],
            // Validation leaves speed or plastic strain to MPM scenes.
            _ => p.vel[i][0].hypot(p.vel[i][1]),
        };
        // Each point covers its current volume, so a stretched body shows no gaps.
        let half = 0.5 * p.volume(i).sqrt();
        local.extend_from_slice(&[p.pos[i][0], p.pos[i][1], half.max(p.half0[i]), value]);
    }
    let all = comm.all_gather_f64(&local);
    if !comm.is_root() {
        return Ok(());
    }
    let spec = sys.setup.spec;
    let frame = Frame::new(([0.0, 0.0], [spec.width(), spec.height()]), style.size_px);
    let (width, height) = frame.size();
    let mut panel = Image::new(width, height, [255, 255, 255]);
    let vmax = style.limit.max(1e-300);
    for c in all.chunks_exact(4) {
        let colour = super::colormap::sequential(c[3] / vmax);
        let half = (c[2] * frame.scale).max(0.5);
        let [cx, cy] = frame.pixel([c[0], c[1]]);
        let (x0, x1) = ((cx - half).floor() as isize, (cx + half).ceil() as isize);
        let (y0, y1) = ((cy - half).floor() as isize, (cy + half).ceil() as isize);
        panel.fill((x0, y0), (x1, y1), colour);
    }
    let b = &sys.setup.boundaries;
    let wall = |s: mpm::grid::Side| s != mpm::grid::Side::Open;
    super::picture::draw_walls(
        &mut panel,
        [wall(b.left), wall(b.right), wall(b.bottom), wall(b.top)],
    );
    let title = match field {
        PictureField::PlasticStrain => "equivalent plastic strain",
        _ => "speed (m/s)",
    };
    let legend = Legend {
        title: title.into(),
        scale: Scale::Magnitude(style.limit),
        time_s,
        metres_per_pixel: 1.0 / frame.scale,
    };
    write_figure(path, &panel, &legend)
}
