//! Snapshot output of a fluid run: the HDF5 series (every rank its block), the grains of a
//! coupled run beside it, and the pictures (rank 0).

use crate::simulation::Simulation;
use decomposition::Comm;
use io::figure::{remove_stale, write_figure, write_movies, Frame, Legend};
use io::hdf5_out::{FieldSpec, Layout, SnapshotWriter};
use io::picture::{draw_walls, field_panel, Scale, WallFaces};
use io::OutputError;
use lbm::fields::Fields;
use lbm::Real;
use scene::{BoundarySpec, FieldName, PictureField, Units, ValidScene};
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Snapshot output of one run: HDF5 series (every rank its block), pictures (rank 0).
pub(super) struct Output {
    dir: PathBuf,
    h5: SnapshotWriter,
    fields: Vec<FieldName>,
    pictures: Option<Pictures>,
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
        let pictures = scene.scene.output.pictures().then(|| Pictures::new(scene));
        if comm.is_root() {
            // An earlier run's pictures go, whether or not this run draws any.
            let pics = dir.join("pictures");
            let made = match pictures {
                Some(_) => std::fs::create_dir_all(&pics),
                None => Ok(()),
            };
            made.and_then(|_| remove_stale(&pics, resume_after))
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
            pictures,
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

    /// This rank's block of the lattice from now on (after a load balance).
    pub(super) fn set_block(&mut self, x0: usize, width: usize) {
        self.h5.set_block(x0, width);
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
        let drawn = |field| self.pictures.as_ref().is_some_and(|p| p.draws(field));
        let vorticity: Vec<f64> = if drawn(PictureField::Vorticity) {
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
                    FieldName::Velocity => ("m/s", 3),
                    FieldName::Vorticity => ("1/s", 1),
                    FieldName::Pressure => ("Pa", 1),
                };
                FieldSpec {
                    name: name.as_str(),
                    units,
                    components,
                }
            })
            .collect();
        let t = Instant::now();
        let (names, pictures) = (&self.fields, drawn(PictureField::Vorticity));
        self.h5.write(step, u.time_si(step), &specs, |i| {
            Ok(match names[i] {
                FieldName::Density => {
                    Cow::Owned(f.rho.iter().map(|r| r * u.density_kg_m3).collect())
                }
                FieldName::Velocity => {
                    // Sized up front: a flattening iterator would grow the vector by
                    // doubling, holding up to twice the field while it copies.
                    let mut v = Vec::with_capacity(3 * f.ux.len());
                    for (a, b) in f.ux.iter().zip(&f.uy) {
                        v.extend_from_slice(&[u.velocity_to_si(*a), u.velocity_to_si(*b), 0.0]);
                    }
                    Cow::Owned(v)
                }
                FieldName::Pressure => {
                    Cow::Owned(f.rho.iter().map(|r| u.drho_to_pressure(r - 1.0)).collect())
                }
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
        if let Some(p) = &self.pictures {
            p.draw(&self.dir.join("pictures"), step, u, sim, comm, f, vorticity)?;
        }
        Ok(())
    }

    /// After the last snapshot: a movie of each picture series when ffmpeg is present
    /// (rank 0). The movies written.
    pub(super) fn finish(&self, comm: &dyn Comm) -> Vec<PathBuf> {
        match (&self.pictures, comm.is_root()) {
            (Some(p), true) => write_movies(&self.dir.join("pictures"), &p.prefixes()),
            _ => Vec::new(),
        }
    }
}

/// The pictures of a fluid (or coupled) run: the fields drawn, their colour limits fixed
/// for the run, the panel size and the wall faces.
struct Pictures {
    /// (field, colour scale, legend title).
    fields: Vec<(PictureField, Scale, &'static str)>,
    size_px: usize,
    walls: WallFaces,
    /// A coupled run also draws the grains alone, coloured by speed.
    grains: bool,
    /// The top of the speed scale (m/s), the grains' pictures' too.
    speed: f64,
}

impl Pictures {
    fn new(scene: &ValidScene) -> Self {
        let s = &scene.scene;
        let o = &s.output;
        let limits = o.picture_limits();
        let (rho, u_ref, l_ref) = (
            s.fluid.density_kg_m3,
            s.fluid.reference_velocity_m_s,
            s.fluid.reference_length_m,
        );
        let height = s.domain.cells[1] as f64 * scene.units.dx_m;
        let g = s.fluid.body_acceleration_m_s2[0].hypot(s.fluid.body_acceleration_m_s2[1]);
        // Defaults from the scene's own scales (docs/outputs.md): 1.5 U for the speed,
        // 10 U/L for the vorticity, the larger of ρU² and the hydrostatic ρ g H for the
        // pressure.
        let round = io::figure::round_up;
        let speed = limits.speed_m_s.unwrap_or(round(1.5 * u_ref));
        let vorticity = limits.vorticity_1_s.unwrap_or(round(10.0 * u_ref / l_ref));
        let pressure = limits
            .pressure_pa
            .unwrap_or(round((rho * u_ref * u_ref).max(rho * g * height)));
        let chosen = match o.picture_field {
            Some(f) => vec![f],
            None => vec![PictureField::Speed, PictureField::Vorticity],
        };
        let fields = chosen
            .into_iter()
            .map(|f| match f {
                PictureField::Vorticity => (f, Scale::Signed(vorticity), "vorticity (1/s)"),
                PictureField::Pressure => (f, Scale::Signed(pressure), "pressure (Pa)"),
                _ => (f, Scale::Magnitude(speed), "speed (m/s)"),
            })
            .collect();
        let wall = |b: &BoundarySpec| {
            matches!(
                b,
                BoundarySpec::Wall | BoundarySpec::MovingWall { .. } | BoundarySpec::FreeSlip
            )
        };
        let b = &s.boundaries;
        Self {
            fields,
            size_px: o.picture_size_px(),
            walls: [wall(&b.west), wall(&b.east), wall(&b.south), wall(&b.north)],
            grains: s.grains.is_some(),
            speed,
        }
    }

    fn draws(&self, field: PictureField) -> bool {
        self.fields.iter().any(|(f, _, _)| *f == field)
    }

    /// The file-name prefixes of the series.
    fn prefixes(&self) -> Vec<&'static str> {
        let mut p: Vec<&'static str> = self
            .fields
            .iter()
            .map(|(f, _, _)| match f {
                PictureField::Vorticity => "vorticity_",
                PictureField::Pressure => "pressure_",
                _ => "speed_",
            })
            .collect();
        if self.grains {
            p.push("grains_");
        }
        p
    }

    /// Draw this snapshot's pictures into `pics` (gathered on rank 0). Collective.
    #[allow(clippy::too_many_arguments)]
    fn draw<T: Real>(
        &self,
        pics: &Path,
        step: u64,
        u: &Units,
        sim: &mut Simulation<T>,
        comm: &dyn Comm,
        f: &Fields,
        vorticity: Vec<f64>,
    ) -> Result<(), OutputError> {
        let time_s = u.time_si(step);
        let grains = match &sim.grains {
            Some(c) => {
                if self.grains {
                    // The grains alone, coloured by speed on the fluid's speed scale.
                    let cells = [sim.partition.columns(), f.ny];
                    let region = (
                        [0.0, 0.0],
                        [cells[0] as f64 * u.dx_m, cells[1] as f64 * u.dx_m],
                    );
                    let style = io::figure::PictureStyle {
                        size_px: self.size_px,
                        limit: self.speed,
                    };
                    io::grains_picture::write_grains_png(
                        &pics.join(format!("grains_{step:08}.png")),
                        c.system(),
                        region,
                        style,
                        time_s,
                        comm,
                    )?;
                }
                io::grains_picture::gather_grains(c.system(), comm)
            }
            None => None,
        };
        // The fields drawn travel in the three places of a `Fields`, gathered on rank 0.
        let si = |v: &f64| u.velocity_to_si(*v);
        let speed: Vec<f64> = if self.draws(PictureField::Speed) {
            f.ux.iter()
                .zip(&f.uy)
                .map(|(a, b)| si(a).hypot(si(b)))
                .collect()
        } else {
            Vec::new()
        };
        let pressure: Vec<f64> = if self.draws(PictureField::Pressure) {
            f.rho.iter().map(|r| u.drho_to_pressure(r - 1.0)).collect()
        } else {
            Vec::new()
        };
        let slab = Fields {
            nx: f.nx,
            ny: f.ny,
            rho: pressure,
            ux: speed,
            uy: vorticity,
            fluid: f.fluid.clone(),
        };
        let Some(g) = sim.gather_fields_at_root(comm, slab) else {
            return Ok(());
        };
        let solid: Vec<bool> = g.fluid.iter().map(|b| !b).collect();
        let frame = Frame::new(
            ([0.0, 0.0], [g.nx as f64 * u.dx_m, g.ny as f64 * u.dx_m]),
            self.size_px,
        );
        for (field, scale, title) in &self.fields {
            let (values, prefix) = match field {
                PictureField::Vorticity => (&g.uy, "vorticity_"),
                PictureField::Pressure => (&g.rho, "pressure_"),
                _ => (&g.ux, "speed_"),
            };
            let mut panel = field_panel(
                (g.nx, g.ny),
                values,
                &solid,
                *scale,
                self.walls,
                self.size_px,
            );
            if let Some(grains) = &grains {
                io::grains_picture::draw_grains_over(&mut panel, &frame, grains);
                draw_walls(&mut panel, self.walls);
            }
            let legend = Legend {
                title: (*title).into(),
                scale: *scale,
                time_s,
                metres_per_pixel: 1.0 / frame.scale,
            };
            write_figure(
                &pics.join(format!("{prefix}{step:08}.png")),
                &panel,
                &legend,
            )?;
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
