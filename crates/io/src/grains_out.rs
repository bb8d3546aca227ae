//! Grain snapshots: `grains.h5` (one group per snapshot, every rank writing its block of
//! each dataset collectively), an XDMF sidecar that ParaView opens as points, and PNG
//! pictures of the grains coloured by speed (`grains_picture`).
//!
//! Rows are in rank order, then local order, so they differ between rank counts; the `id`
//! dataset identifies each grain (sort by it to compare runs).

use super::atomic::write_atomic;
use super::h5par::{self, Access, Block};
use super::OutputError;
use decomposition::Comm;
use dem::DemSystem;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Writer of `grains.h5` and `grains.xdmf`.
pub struct GrainWriter {
    path: PathBuf,
    file: hdf5::File,
    access: Access,
    root: bool,
    /// (group, time, grain count) of every snapshot written.
    written: Vec<(String, f64, u64)>,
    /// The grains of a coupled run: snapshots also hold `hydrodynamic_force`.
    coupled: bool,
}

/// Per-grain datasets of a snapshot: name, components, units. Each snapshot also holds
/// `id` and `contacts` (the contact network, one row per touching pair); a coupled run's
/// also `hydrodynamic_force` (the last entry).
const DATASETS: [(&str, usize, &str); 7] = [
    ("position", 3, "m"),
    ("velocity", 3, "m/s"),
    ("radius", 1, "m"),
    ("angular_velocity", 1, "rad/s"),
    ("contact_force", 3, "N/m"),
    ("speed", 1, "m/s"),
    ("hydrodynamic_force", 3, "N/m"),
];

impl GrainWriter {
    /// Open `dir/grains.h5` on every rank of `comm`; `coupled` for the grains of a fluid
    /// run. Collective.
    ///
    /// With `resume_after = None` the file is created (truncating an old one). With
    /// `Some(step)` (a restart) an existing file is kept: its snapshots up to `step` stay and
    /// later ones (written after the checkpoint by the run being redone) are removed.
    pub fn open(
        dir: &Path,
        comm: &dyn Comm,
        resume_after: Option<u64>,
        coupled: bool,
    ) -> Result<Self, OutputError> {
        let path = dir.join("grains.h5");
        let h5 = |source| OutputError::Hdf5 {
            path: path.clone(),
            source,
        };
        let (file, access, kept) = h5par::open_series(&path, comm, resume_after).map_err(h5)?;
        let mut w = Self {
            path: path.clone(),
            file,
            access,
            root: comm.is_root(),
            written: Vec::new(),
            coupled,
        };
        if kept.is_some() {
            w.written = h5par::kept_snapshots(&w.file, kept).map_err(h5)?;
            if w.root {
                w.write_xdmf()?;
            }
        }
        Ok(w)
    }

    /// Write group `/step_NNNNNNNN` (the DEM's step) with every owned grain of every rank:
    /// position and velocity (3 components, z = 0, as ParaView expects), radius, angular
    /// velocity, contact force (the net force minus gravity, global damping and any force
    /// held from outside) and speed, plus `id`. Then flush and rewrite the XDMF. Collective.
    pub fn write(&mut self, sys: &DemSystem, comm: &dyn Comm) -> Result<(), OutputError> {
        self.write_at(sys, comm, sys.steps, &[])
    }

    /// [`GrainWriter::write`] as `/step_NNNNNNNN` of `step` (a coupled run's fluid step, so
    /// that grains and fields pair up), with each owned grain's `hydrodynamic` force (N/m;
    /// written when the writer is `coupled`). Collective.
    pub fn write_at(
        &mut self,
        sys: &DemSystem,
        comm: &dyn Comm,
        step: u64,
        hydrodynamic: &[[f64; 3]],
    ) -> Result<(), OutputError> {
        let h5 = |source| OutputError::Hdf5 {
            path: self.path.clone(),
            source,
        };
        let n = sys.owned();
        let counts = comm.all_gather_f64(&[n as f64]);
        let offset: f64 = counts[..comm.rank()].iter().sum();
        let total = counts.iter().sum::<f64>() as u64;
        let offset = offset as u64;
        let g = &sys.grains;
        let group = format!("step_{step:08}");
        if self.written.iter().any(|w| w.0 == group) {
            return Ok(());
        }
        let grp = self.file.create_group(&group).map_err(h5)?;
        grp.new_attr::<f64>()
            .create("time_s")
            .and_then(|a| a.write_scalar(&sys.time))
            .and_then(|_| grp.new_attr::<u64>().create("step"))
            .and_then(|a| a.write_scalar(&step))
            .map_err(h5)?;
        let external = sys.external();
        for (name, comps, units) in self.datasets().iter().copied() {
            let mut v = Vec::with_capacity(n * comps);
            for i in 0..n {
                match name {
                    "position" => v.extend_from_slice(&[g.x[i], g.y[i], 0.0]),
                    "velocity" => v.extend_from_slice(&[g.vx[i], g.vy[i], 0.0]),
                    "radius" => v.push(g.r[i]),
                    "angular_velocity" => v.push(g.omega[i]),
                    "contact_force" => {
                        let body = |v: f64, gr: f64| g.m[i] * (gr - sys.global_damping * v);
                        let e = external.get(i).copied().unwrap_or([0.0; 3]);
                        v.extend_from_slice(&[
                            g.fx[i] - body(g.vx[i], sys.gravity[0]) - e[0],
                            g.fy[i] - body(g.vy[i], sys.gravity[1]) - e[1],
                            0.0,
                        ]);
                    }
                    "hydrodynamic_force" => {
                        let h = hydrodynamic.get(i).copied().unwrap_or([0.0; 3]);
                        v.extend_from_slice(&[h[0], h[1], 0.0]);
                    }
                    _ => v.push(g.vx[i].hypot(g.vy[i])),
                }
            }
            let (shape, block) = if comps == 1 {
                (
                    vec![total as usize],
                    Block {
                        start: vec![offset],
                        count: vec![n as u64],
                    },
                )
            } else {
                (
                    vec![total as usize, comps],
                    Block {
                        start: vec![offset, 0],
                        count: vec![n as u64, comps as u64],
                    },
                )
            };
            let ds = grp
                .new_dataset::<f64>()
                .shape(shape.as_slice())
                .create(name)
                .map_err(h5)?;
            h5par::write_block(&ds, &block, &v, self.access).map_err(h5)?;
            let units: hdf5::types::VarLenUnicode = units.parse().expect("ASCII units");
            ds.new_attr::<hdf5::types::VarLenUnicode>()
                .create("units")
                .and_then(|a| a.write_scalar(&units))
                .map_err(h5)?;
        }
        let ds = grp
            .new_dataset::<u64>()
            .shape([total as usize])
            .create("id")
            .map_err(h5)?;
        let block = Block {
            start: vec![offset],
            count: vec![n as u64],
        };
        h5par::write_block(&ds, &block, &g.id[..n], self.access).map_err(h5)?;
        // The contact network: one row per touching pair, written by the owner of its
        // smaller-id grain.
        let list = sys.contact_list();
        let mut rows = Vec::with_capacity(list.len() * 6);
        for (a, b, p, f) in &list {
            rows.extend_from_slice(&[*a as f64, *b as f64, p[0], p[1], f[0], f[1]]);
        }
        let counts = comm.all_gather_f64(&[list.len() as f64]);
        let start: f64 = counts[..comm.rank()].iter().sum();
        let total_c: f64 = counts.iter().sum();
        let ds = grp
            .new_dataset::<f64>()
            .shape([total_c as usize, 6])
            .create("contacts")
            .map_err(h5)?;
        let block = Block {
            start: vec![start as u64, 0],
            count: vec![list.len() as u64, 6],
        };
        h5par::write_block(&ds, &block, &rows, self.access).map_err(h5)?;
        let what: hdf5::types::VarLenUnicode =
            "id_a, id_b, contact x (m), contact y (m), force on b x (N/m), force on b y (N/m)"
                .parse()
                .expect("ASCII");
        ds.new_attr::<hdf5::types::VarLenUnicode>()
            .create("columns")
            .and_then(|a| a.write_scalar(&what))
            .map_err(h5)?;
        self.file.flush().map_err(h5)?;
        self.written.push((group, sys.time, total));
        if self.root {
            self.write_xdmf()?;
        }
        Ok(())
    }

    /// Snapshots written so far.
    pub fn snapshots(&self) -> usize {
        self.written.len()
    }

    /// The per-grain datasets this writer writes.
    fn datasets(&self) -> &'static [(&'static str, usize, &'static str)] {
        if self.coupled {
            &DATASETS
        } else {
            &DATASETS[..DATASETS.len() - 1]
        }
    }

    /// XDMF 2 temporal collection of Polyvertex grids (points).
    fn write_xdmf(&self) -> Result<(), OutputError> {
        let mut s = String::from("<?xml version=\"1.0\" ?>\n<Xdmf Version=\"2.0\">\n <Domain>\n  <Grid Name=\"grains\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
        for (group, t, n) in &self.written {
            super::xdmf::open_points_grid(
                &mut s,
                "   ",
                group,
                ("grains.h5", group, *n),
                self.datasets(),
            );
            let _ = write!(s, "    <Time Value=\"{t:e}\"/>\n   </Grid>\n");
        }
        s.push_str("  </Grid>\n </Domain>\n</Xdmf>\n");
        write_atomic(&self.path.with_extension("xdmf"), s.as_bytes())
    }
}
