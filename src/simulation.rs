//! A simulation: the state of the physics a scene asked for, and `step()` as an ordered
//! list of named, timed stages. A fluid-only scene holds only a lattice.

use crate::analysis::flows::{taylor_green_pressure, taylor_green_velocity};
use crate::io::probes::Series;
use crate::lbm::lattice::StepError;
use crate::lbm::{Lattice, Real};
use crate::scene::{build_lattice, solid_id_of, Initial, Probe, SceneError, Units, ValidScene};
use std::time::Instant;

/// Names of the stages of one step, in execution order.
pub const STAGES: [&str; 4] = ["collide-stream", "boundaries", "probes", "output"];

/// Accumulated wall time per stage.
#[derive(Debug, Clone, Default)]
pub struct StageTimes {
    /// Seconds per entry of [`STAGES`].
    pub seconds: [f64; STAGES.len()],
}

impl StageTimes {
    /// Run `f` and add its duration to stage `i`.
    pub fn time<R>(&mut self, i: usize, f: impl FnOnce() -> R) -> R {
        let t = Instant::now();
        let r = f();
        self.seconds[i] += t.elapsed().as_secs_f64();
        r
    }
}

/// Where a probe samples.
enum ProbeTarget {
    Cell(usize, usize),
    Solid(u16),
}

/// The fluid state of a run plus its probes.
pub struct Simulation<T: Real> {
    /// The lattice.
    pub lattice: Lattice<T>,
    /// Derived units.
    pub units: Units,
    /// Recorded probe series, in scene order.
    pub series: Vec<Series>,
    targets: Vec<ProbeTarget>,
    /// Longest inlet ramp (s); 0 when none.
    ramp_s: f64,
    /// Stage timers.
    pub times: StageTimes,
}

impl<T: Real> Simulation<T> {
    /// Allocate the lattice, rasterise obstacles, apply the initial condition, place probes.
    pub fn new(scene: &ValidScene) -> Result<Self, SceneError> {
        let built = build_lattice(scene)?;
        let units = scene.units;
        let invalid = |key: &str, message: String| SceneError::Invalid {
            path: scene.path.clone(),
            line: None,
            key: key.into(),
            message,
        };
        let mut targets = Vec::new();
        let mut series = Vec::new();
        for p in &scene.scene.probes {
            match p {
                Probe::Point { name, position_m } => {
                    let x = (position_m[0] / units.dx_m) as usize;
                    let y = (position_m[1] / units.dx_m) as usize;
                    if built.setup.cells[y * built.setup.nx + x] != 0 {
                        return Err(invalid(
                            "position_m",
                            format!(
                                "probe `{name}` lies inside an obstacle; move it into the fluid"
                            ),
                        ));
                    }
                    targets.push(ProbeTarget::Cell(x, y));
                    series.push(Series::new(name, vec!["ux_m_s", "uy_m_s", "pressure_pa"]));
                }
                Probe::Force { name, obstacle } => {
                    let id = solid_id_of(&built.setup, obstacle).expect("validated");
                    targets.push(ProbeTarget::Solid(id));
                    series.push(Series::new(name, vec!["fx_n_per_m", "fy_n_per_m"]));
                }
            }
        }
        let (nx, ny) = (built.setup.nx, built.setup.ny);
        let mut lattice = Lattice::<T>::new(built.setup);
        match scene.scene.fluid.initial {
            Initial::Rest => {}
            Initial::Uniform { velocity_m_s } => {
                let u = [
                    units.velocity_to_lattice(velocity_m_s[0]),
                    units.velocity_to_lattice(velocity_m_s[1]),
                ];
                for y in 0..ny {
                    for x in 0..nx {
                        lattice.set_equilibrium(x, y, 1.0, u);
                    }
                }
            }
            Initial::TaylorGreen { amplitude_m_s } => {
                let u0 = units.velocity_to_lattice(amplitude_m_s);
                for y in 0..ny {
                    for x in 0..nx {
                        let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                        let u = taylor_green_velocity(nx, ny, u0, units.nu_lattice, 0.0, px, py);
                        // ρ = 1 + p/c_s² (lattice units).
                        let rho = 1.0 + 3.0 * taylor_green_pressure(nx, ny, u0, px, py);
                        lattice.set_equilibrium(x, y, rho, u);
                    }
                }
            }
        }
        lattice.update_boundaries();
        let b = &scene.scene.boundaries;
        let ramp_s = [&b.west, &b.east, &b.south, &b.north]
            .iter()
            .map(|f| match f {
                crate::scene::BoundarySpec::Velocity { ramp_time_s, .. } => *ramp_time_s,
                _ => 0.0,
            })
            .fold(0.0, f64::max);
        let mut sim = Self {
            lattice,
            units,
            series,
            targets,
            ramp_s,
            times: StageTimes::default(),
        };
        sim.apply_ramp();
        Ok(sim)
    }

    /// Inlet factor sin²(π t / 2T) for t < T, for the step about to be taken.
    fn apply_ramp(&mut self) {
        if self.ramp_s > 0.0 {
            let t = self.units.time_si(self.lattice.steps_done() + 1);
            let r = if t >= self.ramp_s {
                1.0
            } else {
                (0.5 * std::f64::consts::PI * t / self.ramp_s).sin().powi(2)
            };
            self.lattice.set_inlet_scale(r);
        }
    }

    /// The fluid stages of one step: collide–stream (with bounce-back and Zou–He links),
    /// then the halo boundaries. Probes and output are driven by the caller.
    pub fn step(&mut self) -> Result<(), StepError> {
        let lat = &mut self.lattice;
        self.times.time(0, || lat.stream_collide())?;
        self.times.time(1, || lat.update_boundaries());
        self.apply_ramp();
        Ok(())
    }

    /// Stage "probes": record every probe at the current step.
    pub fn record_probes(&mut self) {
        let step = self.lattice.steps_done();
        let t = self.units.time_si(step);
        let (lat, units, series, targets) =
            (&self.lattice, &self.units, &mut self.series, &self.targets);
        self.times.time(2, || {
            for (s, target) in series.iter_mut().zip(targets) {
                match *target {
                    ProbeTarget::Cell(x, y) => {
                        let (rho, u) = lat.sample(x, y);
                        s.push(
                            step,
                            t,
                            &[
                                units.velocity_to_si(u[0]),
                                units.velocity_to_si(u[1]),
                                units.drho_to_pressure(rho - 1.0),
                            ],
                        );
                    }
                    ProbeTarget::Solid(id) => {
                        let f = lat.force_on(id);
                        s.push(step, t, &[units.force_to_si(f[0]), units.force_to_si(f[1])]);
                    }
                }
            }
        });
    }
}
