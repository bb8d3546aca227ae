//! Running a scene end to end: the time loop, output, analyses, checks and `summary.json`.

use crate::analysis::checks::{evaluate, CheckOutcome};
use crate::analysis::{self, Results};
use crate::io::atomic::{ensure_writable_dir, write_atomic};
use crate::io::hdf5_out::{FieldData, SnapshotWriter};
use crate::io::picture::{robust_limit, write_field_png, Scale};
use crate::io::OutputError;
use crate::lbm::fields::{Fields, Totals};
use crate::lbm::Real;
use crate::progress::Progress;
use crate::scene::{FieldName, SceneError, Units, ValidScene};
use crate::simulation::{Simulation, STAGES};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;
use thiserror::Error;

pub use crate::scene::Precision;

/// Options from the command line that override or complement the scene.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Output folder.
    pub out_dir: PathBuf,
    /// Precision override.
    pub precision: Option<Precision>,
    /// Step count override.
    pub steps: Option<u64>,
    /// Show progress (bar on a terminal, log lines otherwise).
    pub progress: bool,
}

/// Why a run could not start or finish writing.
#[derive(Debug, Error)]
pub enum RunError {
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Output could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// An analysis failed.
    #[error(transparent)]
    Analysis(#[from] analysis::AnalysisError),
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// Ran to the end and every check passed.
    Ok,
    /// Ran to the end; at least one check failed.
    ChecksFailed,
    /// Stopped early: NaN or non-positive density.
    Unstable,
}

/// Everything `summary.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// grainflow version.
    pub version: &'static str,
    /// Scene file.
    pub scene_path: PathBuf,
    /// Scene title.
    pub title: String,
    /// The scene as parsed (defaults filled in).
    pub scene: crate::scene::Scene,
    /// Outcome.
    pub status: Status,
    /// Instability report, if any.
    pub error: Option<String>,
    /// Warnings from validation.
    pub warnings: Vec<String>,
    /// Precision used.
    pub precision: Precision,
    /// Rayon threads.
    pub threads: usize,
    /// Derived lattice parameters.
    pub units: Units,
    /// Lattice size.
    pub cells: [usize; 2],
    /// Fluid cells.
    pub fluid_cells: usize,
    /// Distribution storage (bytes).
    pub memory_bytes: usize,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time (s).
    pub simulated_time_s: f64,
    /// Wall time of the time loop (s).
    pub wall_time_s: f64,
    /// Million lattice-cell updates per second over the whole loop (all cells).
    pub mlups: f64,
    /// MLUPS of the collide–stream stage alone.
    pub kernel_mlups: f64,
    /// Seconds per stage.
    pub stage_seconds: BTreeMap<&'static str, f64>,
    /// Totals at the start and the end (lattice units).
    pub totals_initial: Totals,
    /// See `totals_initial`.
    pub totals_final: Totals,
    /// Last sample of each probe (SI).
    pub probes: BTreeMap<String, BTreeMap<String, f64>>,
    /// Results of the analyses.
    pub results: Results,
    /// Checks with their outcome.
    pub checks: Vec<CheckOutcome>,
}

/// Validate, run and summarise a scene. Writes into `opts.out_dir`. An instability is not
/// an `Err`: the summary says `unstable` and the output so far is kept.
pub fn run(scene: &ValidScene, opts: &RunOptions) -> Result<Summary, RunError> {
    let names = analysis::result_names(scene);
    for c in &scene.scene.checks {
        if !names.contains(&c.quantity) {
            return Err(SceneError::Invalid {
                path: scene.path.clone(),
                line: None,
                key: "quantity".into(),
                message: format!(
                    "check on unknown quantity `{}`; this scene produces: {}",
                    c.quantity,
                    names.join(", ")
                ),
            }
            .into());
        }
    }
    ensure_writable_dir(&opts.out_dir)?;
    let precision = opts.precision.unwrap_or(scene.scene.run.precision);
    match precision {
        Precision::F32 => run_typed::<f32>(scene, opts, precision),
        Precision::F64 => run_typed::<f64>(scene, opts, precision),
    }
}

/// Number of steps a run will take.
pub fn step_count(scene: &ValidScene, override_steps: Option<u64>) -> u64 {
    override_steps.or(scene.scene.run.steps).unwrap_or_else(|| {
        (scene.scene.run.end_time_s.unwrap_or(0.0) / scene.units.dt_s)
            .round()
            .max(1.0) as u64
    })
}

fn run_typed<T: Real>(
    scene: &ValidScene,
    opts: &RunOptions,
    precision: Precision,
) -> Result<Summary, RunError> {
    let run = &scene.scene.run;
    let n = step_count(scene, opts.steps);
    let mut sim = Simulation::<T>::new(scene)?;
    let (nx, ny) = (sim.lattice.nx(), sim.lattice.ny());
    let mut out = Output::new(&opts.out_dir, scene, nx, ny)?;
    // Fields are computed once per output step and shared by snapshot, totals and analyses.
    let initial = sim.lattice.fields();
    let totals_initial = initial.totals();
    if run.output_every > 0 {
        out.snapshot(0, &scene.units, &initial)?;
    }
    let mut latest = (0, initial);
    sim.record_probes();
    let mut progress = Progress::new(n, (nx * ny) as f64, scene.units.dt_s, opts.progress);
    let start = Instant::now();
    let mut error = None;
    for step in 1..=n {
        if let Err(e) = sim.step() {
            error = Some(e.to_string());
            break;
        }
        if step % run.probe_every == 0 {
            sim.record_probes();
        }
        if (run.output_every > 0 && step % run.output_every == 0) || step == n {
            let t = Instant::now();
            latest = (step, sim.lattice.fields());
            out.snapshot(step, &scene.units, &latest.1)?;
            sim.times.seconds[3] += t.elapsed().as_secs_f64();
        }
        progress.update(step);
    }
    let wall = start.elapsed().as_secs_f64();
    progress.finish();
    let steps = sim.lattice.steps_done();
    let fields = if latest.0 == steps {
        latest.1
    } else {
        sim.lattice.fields()
    };
    if error.is_some() {
        // Keep the last good state for diagnosis; earlier snapshots stay untouched.
        out.snapshot(steps, &scene.units, &fields)?;
    }
    let totals_final = fields.totals();
    let results = if error.is_none() {
        analysis::run_all(&analysis::Inputs {
            scene,
            fields: &fields,
            steps,
            series: &sim.series,
            totals: (totals_initial, totals_final),
        })?
    } else {
        Results::new()
    };
    let checks = evaluate(&scene.scene.checks, &results);
    let status = match (&error, checks.iter().all(|c| c.passed)) {
        (Some(_), _) => Status::Unstable,
        (None, true) => Status::Ok,
        (None, false) => Status::ChecksFailed,
    };
    let updates = (nx * ny) as f64 * steps as f64;
    let probes = sim
        .series
        .iter()
        .filter(|s| !s.is_empty())
        .map(|s| {
            let last = s.len() - 1;
            let row = s
                .columns
                .iter()
                .enumerate()
                .map(|(c, name)| (name.to_string(), s.values[last * s.columns.len() + c]))
                .collect();
            (s.name.clone(), row)
        })
        .collect();
    let summary = Summary {
        version: env!("CARGO_PKG_VERSION"),
        scene_path: scene.path.clone(),
        title: scene.scene.title.clone(),
        scene: scene.scene.clone(),
        status,
        error,
        warnings: scene.warnings.clone(),
        precision,
        threads: rayon::current_num_threads(),
        units: scene.units,
        cells: [nx, ny],
        fluid_cells: sim.lattice.fluid_cells(),
        memory_bytes: sim.lattice.storage_bytes(),
        steps,
        simulated_time_s: scene.units.time_si(steps),
        wall_time_s: wall,
        mlups: updates / wall.max(1e-12) / 1e6,
        kernel_mlups: updates / sim.times.seconds[0].max(1e-12) / 1e6,
        stage_seconds: STAGES.iter().copied().zip(sim.times.seconds).collect(),
        totals_initial,
        totals_final,
        probes,
        results,
        checks,
    };
    for s in &sim.series {
        s.write_csv(&opts.out_dir)?;
    }
    let json = serde_json::to_vec_pretty(&summary).expect("summary serialises");
    write_atomic(&opts.out_dir.join("summary.json"), &json)?;
    Ok(summary)
}

/// Snapshot output of one run: HDF5 series, pictures, probe CSVs.
struct Output {
    dir: PathBuf,
    h5: SnapshotWriter,
    fields: Vec<FieldName>,
    pictures: bool,
}

impl Output {
    fn new(dir: &Path, scene: &ValidScene, nx: usize, ny: usize) -> Result<Self, OutputError> {
        if scene.scene.run.pictures {
            let pics = dir.join("pictures");
            std::fs::create_dir_all(&pics)
                .map_err(|source| OutputError::Io { path: pics, source })?;
        }
        Ok(Self {
            dir: dir.to_owned(),
            h5: SnapshotWriter::create(dir, nx, ny, scene.units.dx_m)?,
            fields: scene.scene.run.fields.clone(),
            pictures: scene.scene.run.pictures,
        })
    }

    /// Write the fields `f` (lattice units) of `step` to HDF5 and, if enabled, as pictures.
    fn snapshot(&mut self, step: u64, u: &Units, f: &Fields) -> Result<(), OutputError> {
        let density: Vec<f64> = f.rho.iter().map(|r| r * u.density_kg_m3).collect();
        let velocity: Vec<f64> =
            f.ux.iter()
                .zip(&f.uy)
                .flat_map(|(a, b)| [u.velocity_to_si(*a), u.velocity_to_si(*b)])
                .collect();
        let vorticity: Vec<f64> = f.vorticity().iter().map(|w| w / u.dt_s).collect();
        let mut data = Vec::new();
        for name in &self.fields {
            let (units, components, values) = match name {
                FieldName::Density => ("kg/m^3", 1, &density),
                FieldName::Velocity => ("m/s", 2, &velocity),
                FieldName::Vorticity => ("1/s", 1, &vorticity),
            };
            data.push(FieldData {
                name: name.as_str(),
                units,
                components,
                values,
            });
        }
        self.h5.write(step, u.time_si(step), &data)?;
        if self.pictures {
            let solid: Vec<bool> = f.fluid.iter().map(|b| !b).collect();
            let speed: Vec<f64> = velocity.chunks(2).map(|v| v[0].hypot(v[1])).collect();
            let pics = self.dir.join("pictures");
            let vmax = speed.iter().copied().fold(0.0, f64::max);
            write_field_png(
                &pics.join(format!("speed_{step:08}.png")),
                f.nx,
                f.ny,
                &speed,
                &solid,
                Scale::Magnitude(vmax),
            )?;
            let wlim = robust_limit(&vorticity, &solid);
            write_field_png(
                &pics.join(format!("vorticity_{step:08}.png")),
                f.nx,
                f.ny,
                &vorticity,
                &solid,
                Scale::Signed(wlim),
            )?;
        }
        Ok(())
    }
}
