//! Snapshot output of a fluid run: the HDF5 series (every rank its block), the grains of a
//! coupled run beside it, and the pictures (rank 0).

use crate::simulation::Simulation;
use decomposition::Comm;
use io::hdf5_out::{FieldSpec, Layout, SnapshotWriter};
use io::picture::{robust_limit, write_field_png, Scale};
use io::OutputError;
use lbm::fields::Fields;
use lbm::Real;
use scene::{FieldName, Units, ValidScene};
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Snapshot output of one run: HDF5 series (every rank its block), pictures (rank 0).
pub(super) struct Output {
    dir: PathBuf,
    h5: SnapshotWriter,
    fields: Vec<FieldName>,
    pictures: bool,
    /// Bytes of field data in the file (global), and seconds this rank spent writing them.
    pub(super) bytes: u64,
    pub(super) write_s: f64,
    /// `grains.h5` + `grains.xdmf` of a coupled run.
    grains: Option<io::grains_out::GrainWriter>,
}

impl Output {
    pub(super) fn new(
        dir: &Path,
        scene: &ValidScene,
        layout: Layout,
        comm: &dyn Comm,
        resume_after: Option<u64>,
    ) -> Result<Self, OutputError> {
        if scene.scene.output.pictures() && comm.is_root() {
            let pics = dir.join("pictures");
            std::fs::create_dir_all(&pics)
                .map_err(|source| OutputError::Io { path: pics, source })?;
        }
        Ok(Self {
            dir: dir.to_owned(),
            h5: SnapshotWriter::open(
                dir,
                comm,
                layout,
                scene.scene.output.compression(),
                resume_after,
            )?,
            fields: scene.scene.output.fields(),
            pictures: scene.scene.output.pictures(),
            bytes: 0,
            write_s: 0.0,
            grains: match scene.scene.grains {
                Some(_) => Some(io::grains_out::GrainWriter::open(
                    dir,
                    comm,
                    resume_after,
                    true,
                )?),
                None => None,
            },
        })
    }

    /// Write this slab's fields `f` (lattice units) of `step` to HDF5 and, if enabled, the
    /// whole lattice as pictures (gathered on rank 0). Collective.
    pub(super) fn snapshot<T: Real>(
        &mut self,
        step: u64,
        u: &Units,
        sim: &mut Simulation<T>,
        comm: &dyn Comm,
        f: &Fields,
    ) -> Result<(), OutputError> {
        // Each field is converted to SI when it is written, so that only one of them
        // exists at a time beside `f`. The pictures need the vorticity: it is kept then.
        let vorticity: Vec<f64> = if self.pictures {
            si_vorticity(sim, comm, f, u)
        } else {
            Vec::new()
        };
        let specs: Vec<FieldSpec> = self
            .fields
            .iter()
            .map(|name| {
                let (units, components) = match name {
                    FieldName::Density => ("kg/m^3", 1),
                    FieldName::Velocity => ("m/s", 2),
                    FieldName::Vorticity => ("1/s", 1),
                };
                FieldSpec {
                    name: name.as_str(),
                    units,
                    components,
                }
            })
            .collect();
        let t = Instant::now();
        let (names, pictures) = (&self.fields, self.pictures);
        self.h5.write(step, u.time_si(step), &specs, |i| {
            Ok(match names[i] {
                FieldName::Density => {
                    Cow::Owned(f.rho.iter().map(|r| r * u.density_kg_m3).collect())
                }
                FieldName::Velocity => Cow::Owned(
                    f.ux.iter()
                        .zip(&f.uy)
                        .flat_map(|(a, b)| [u.velocity_to_si(*a), u.velocity_to_si(*b)])
                        .collect(),
                ),
                FieldName::Vorticity if pictures => Cow::Borrowed(&vorticity),
                FieldName::Vorticity => Cow::Owned(si_vorticity(sim, comm, f, u)),
            })
        })?;
        if let (Some(w), Some(c)) = (&mut self.grains, &sim.grains) {
            let hydro: Vec<[f64; 3]> = (0..c.system().owned()).map(|i| c.hydrodynamic(i)).collect();
            w.write_at(c.system(), comm, step, &hydro)?;
        }
        self.write_s += t.elapsed().as_secs_f64();
        let cells = (sim.partition.columns() * f.ny) as u64;
        self.bytes += specs
            .iter()
            .map(|d| cells * d.components as u64 * 8)
            .sum::<u64>();
        if let (true, Some(c)) = (self.pictures, &sim.grains) {
            // The grains alone, coloured by speed (the fluid pictures draw them grey).
            let cells = [sim.partition.columns(), f.ny];
            let region = (
                [0.0, 0.0],
                [cells[0] as f64 * u.dx_m, cells[1] as f64 * u.dx_m],
            );
            io::grains_out::write_grains_png(
                &self.dir.join(format!("pictures/grains_{step:08}.png")),
                c.system(),
                region,
                0.0,
                comm,
            )?;
        }
        if self.pictures {
            // Pictures are one image of the whole lattice: gathered on every rank, drawn by rank 0.
            let speed_local: Vec<f64> =
                f.ux.iter()
                    .zip(&f.uy)
                    .map(|(a, b)| u.velocity_to_si(*a).hypot(u.velocity_to_si(*b)))
                    .collect();
            // Speed and vorticity travel in the velocity's places; the density is not drawn.
            let mut slab = Fields {
                nx: f.nx,
                ny: f.ny,
                rho: Vec::new(),
                ux: speed_local,
                uy: vorticity,
                fluid: f.fluid.clone(),
            };
            if let Some(c) = &sim.grains {
                // Grains drawn as solid where they cover at least half a cell.
                let lat = sim.fluid.lattice();
                let mut frac = vec![0.0; lat.plane()];
                c.coupler().solid_fraction(&mut frac);
                let (nx, ny) = (lat.nx(), lat.ny());
                for k in 0..ny * nx {
                    let (x, y) = ((k % nx) as isize, (k / nx) as isize);
                    slab.fluid[k] &= frac[lat.padded_index(x, y)] < 0.5;
                }
            }
            if let Some(g) = sim.gather_fields_at_root(comm, slab) {
                let solid: Vec<bool> = g.fluid.iter().map(|b| !b).collect();
                let (speed, vort) = (&g.ux, &g.uy);
                let pics = self.dir.join("pictures");
                let vmax = speed.iter().copied().fold(0.0, f64::max);
                write_field_png(
                    &pics.join(format!("speed_{step:08}.png")),
                    g.nx,
                    g.ny,
                    speed,
                    &solid,
                    Scale::Magnitude(vmax),
                )?;
                let wlim = robust_limit(vort, &solid);
                write_field_png(
                    &pics.join(format!("vorticity_{step:08}.png")),
                    g.nx,
                    g.ny,
                    vort,
                    &solid,
                    Scale::Signed(wlim),
                )?;
            }
        }
        Ok(())
    }
}

/// The vorticity of this slab's `f` in SI units (1/s). Collective.
fn si_vorticity<T: Real>(
    sim: &mut Simulation<T>,
    comm: &dyn Comm,
    f: &Fields,
    u: &Units,
) -> Vec<f64> {
    let mut w = sim.vorticity(comm, f);
    w.iter_mut().for_each(|w| *w /= u.dt_s);
    w
}
