//! Running a grains-only scene: prepare the sample (pack, settle, trim, or load), then the
//! time loop of named, timed stages — walls (removals), DEM step (with migration and
//! ghost exchange inside), output — and the analyses, checks and `summary.json`.

use crate::driver::{RunHeader, Signals, StageClock};
use crate::progress::Progress;
use crate::run::{RunError, RunOptions, Status};
use analysis::checks::evaluate;
use analysis::collapse::{collapse_results, pile_shape, QUANTITIES};
use analysis::Results;
use decomposition::Comm;
use dem::walls::apply_walls;
use dem::{Grains, SlabDem};
use io::atomic::{ensure_writable_dir, write_atomic};
use io::grains_checkpoint::{self, GrainRunState};
use io::grains_out::{write_grains_png, GrainWriter};
use scene::{GrainAnalysis, GrainScene, ValidGrainScene};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

pub(crate) mod sample;

pub use sample::gather_grains;
use sample::{bounds_for, global_state, prepare, start};

/// Stages of a grains step, in order.
pub const GRAIN_STAGES: [&str; 3] = ["walls", "dem", "output"];

/// Everything a grains run's `summary.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct GrainSummary {
    /// The keys every summary starts with (see [`RunHeader`]).
    #[serde(flatten)]
    pub run: RunHeader,
    /// The scene as parsed.
    pub scene: GrainScene,
    /// x-boundaries of the ranks' slabs at the end (m).
    pub slab_bounds_m: Vec<f64>,
    /// Grains in the run.
    pub grains: usize,
    /// Time step (s) and the λ it satisfies.
    pub time_step_s: f64,
    /// See `time_step_s`.
    pub lambda: f64,
    /// Steps spent settling the sample (0 when it was not settled).
    pub settle_steps: u64,
    /// Grain-steps per second over the loop (all ranks).
    pub grain_steps_per_s: f64,
    /// Grains handed to another rank, all ranks together.
    pub migrated: u64,
    /// Times the slab boundaries moved to rebalance the grain counts.
    pub rebalances: u64,
    /// Seconds waiting for ghost and migration messages, slowest rank.
    pub comm_wait_s: f64,
    /// Contacts at the end.
    pub contacts: usize,
    /// Verlet-list rebuilds.
    pub list_rebuilds: u64,
    /// Kinetic energy at the end (J/m).
    pub kinetic_energy_j_m: f64,
    /// Total momentum at the end (kg m/s per m).
    pub momentum: [f64; 2],
    /// Snapshots written.
    pub snapshots: usize,
}

/// Run a grains scene on every rank of `comm` (collective). Writes `grains.h5` +
/// `grains.xdmf`, `pictures/grains_*.png` and (rank 0) `summary.json` into `opts.out_dir`.
pub fn run_grains(
    scene: &ValidGrainScene,
    opts: &RunOptions,
    comm: &dyn Comm,
) -> Result<GrainSummary, RunError> {
    let s = &scene.scene;
    if comm.is_root() {
        ensure_writable_dir(&opts.out_dir)?;
        ensure_writable_dir(&opts.out_dir.join("pictures"))?;
    }
    comm.barrier();
    let restored = match &opts.restart {
        Some(p) => Some(grains_checkpoint::read(p, comm, s.grains.walls.len())?),
        None => None,
    };
    let (mut d, settle_steps, initial, resume) = match restored {
        None => {
            let (grains, settle_steps) = prepare(scene, comm)?;
            let allow = s.grains.allow_overlap || settle_steps > 0;
            let d = start(scene, grains, allow, comm)?;
            let initial = gather_grains(&d.system, comm);
            (d, settle_steps, initial, None)
        }
        Some(r) => {
            let bounds = bounds_for(scene, &r.grains, comm);
            let mut setup = scene.dem_setup(&r.grains);
            apply_walls(&mut setup.walls, &r.walls);
            let clock = (r.run.time_s, r.run.step);
            let mut d = SlabDem::restore(r.grains, r.history, &bounds, setup, clock, comm)?;
            d.system.global_damping = s.grains.global_damping_1_s;
            if comm.is_root() {
                d.migrated = r.run.migrated;
            }
            let mut initial = Grains::default();
            for p in r.run.initial.chunks_exact(3) {
                initial.push([p[0], p[1]], p[2], s.grains.density_kg_m3, false);
            }
            (d, r.run.settle_steps, initial, Some(r.run))
        }
    };
    let n_total = d.global_count(comm);
    let region = (s.region.min_m, s.region.max_m);
    let mut writer =
        GrainWriter::open(&opts.out_dir, comm, resume.as_ref().map(|r| r.step), false)?;
    let mut clock = StageClock::new(&GRAIN_STAGES);
    let picture = |d: &SlabDem, vmax: f64| -> Result<(), RunError> {
        let name = format!("grains_step_{:08}.png", d.system.steps);
        write_grains_png(
            &opts.out_dir.join("pictures").join(name),
            &d.system,
            region,
            vmax,
            comm,
        )?;
        Ok(())
    };
    if resume.is_none() {
        writer.write(&d.system, comm)?;
        if s.run.pictures {
            picture(&d, 0.0)?;
        }
    }
    // Speed scale of the pictures: free fall over the sample height, so frames compare.
    let height = initial.y.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - initial.y.iter().cloned().fold(f64::INFINITY, f64::min);
    let g_abs = s.grains.gravity_m_s2[0].hypot(s.grains.gravity_m_s2[1]);
    let vmax = (2.0 * g_abs * height.max(1e-9)).sqrt();
    let dt = d.system.dt;
    let end_time = opts.end_time_s.unwrap_or(s.run.end_time_s);
    let total_steps = opts.steps.unwrap_or((end_time / dt).ceil() as u64);
    let mut progress = Progress::new(
        total_steps,
        n_total as f64,
        dt,
        opts.progress && comm.is_root(),
    )
    .with_unit("M grain-steps/s");
    let last_removal = s
        .grains
        .walls
        .iter()
        .filter_map(|w| w.remove_at_s)
        .fold(0.0, f64::max);
    let mut next_output = resume
        .as_ref()
        .map_or(s.run.output_every_s, |r| r.next_output_s);
    let start_step = resume.as_ref().map_or(0, |r| r.step);
    let mut stop_time = None;
    // The deposit's front every 1000 steps (column collapses), for the time it reaches 95 %
    // of its run-out.
    let collapse_at = s
        .analyses
        .iter()
        .map(|a| match a {
            GrainAnalysis::ColumnCollapse {
                wall_x_m,
                floor_y_m,
                ..
            } => (*wall_x_m, *floor_y_m),
        })
        .next();
    let mut fronts: Vec<(f64, f64)> = Vec::new();
    let mut status = Status::Ok;
    let mut error = None;
    let signals = Signals::install();
    let checkpoint_path = opts.out_dir.join("checkpoint.h5");
    let mut checkpoints = Vec::new();
    let initial_rows: Vec<f64> = (0..initial.len())
        .flat_map(|i| [initial.x[i], initial.y[i], initial.r[i]])
        .collect();
    let write_checkpoint = |d: &SlabDem, next_output: f64, list: &mut Vec<PathBuf>| {
        let state = GrainRunState {
            step: d.system.steps,
            time_s: d.system.time,
            next_output_s: next_output,
            settle_steps,
            migrated: d.migrated,
            initial: initial_rows.clone(),
        };
        grains_checkpoint::write(&checkpoint_path, comm, d, &state)?;
        list.push(checkpoint_path.clone());
        Ok::<(), RunError>(())
    };
    let t0 = Instant::now();
    let mut step = start_step;
    while step < total_steps {
        let t = Instant::now();
        for (w, spec) in s.grains.walls.iter().enumerate() {
            if spec.remove_at_s.is_some_and(|r| d.system.time >= r) && !d.system.walls[w].removed {
                d.system.remove_wall(w);
            }
        }
        clock.add("walls", t);
        let t = Instant::now();
        d.step(comm);
        step += 1;
        clock.add("dem", t);
        let t = Instant::now();
        if let (Some((wx, fy)), true) = (collapse_at, step % 1000 == 0 && start_step == 0) {
            let g = gather_grains(&d.system, comm);
            fronts.push((d.system.time, pile_shape(&g.x, &g.y, &g.r, wx, fy).length_m));
        }
        if step % 100 == 0 || step == total_steps {
            let (ke, _, _) = global_state(&d, comm);
            if !ke.is_finite() {
                status = Status::Unstable;
                error = Some(format!(
                    "the grains' kinetic energy is not finite at step {step} (t = {:.6e} s): \
                     the time step is too large for these contacts; lower lambda",
                    d.system.time
                ));
                break;
            }
            let quiet = s.run.stop_below_kinetic_energy_j_m > 0.0
                && d.system.time > last_removal
                && ke / (n_total as f64) < s.run.stop_below_kinetic_energy_j_m;
            if quiet {
                stop_time = Some(d.system.time);
                break;
            }
        }
        if s.run.output_every_s > 0.0 && d.system.time >= next_output {
            next_output += s.run.output_every_s;
            writer.write(&d.system, comm)?;
            if s.run.pictures {
                picture(&d, vmax)?;
            }
        }
        // After the snapshot, so a restart does not write it again. Signals are agreed on
        // by all ranks after every step, so all ranks checkpoint (and stop) together.
        let agreed = signals.agree(comm, false);
        let every = s.run.checkpoint_every > 0 && step % s.run.checkpoint_every == 0;
        if agreed.checkpoint || every {
            write_checkpoint(&d, next_output, &mut checkpoints)?;
        }
        if agreed.stop {
            status = Status::Interrupted;
            clock.add("output", t);
            break;
        }
        clock.add("output", t);
        progress.update(step);
    }
    progress.finish();
    let wall = t0.elapsed().as_secs_f64();
    if status == Status::Ok && s.run.checkpoint_at_end {
        write_checkpoint(&d, next_output, &mut checkpoints)?;
    }
    if status == Status::Ok {
        let t = Instant::now();
        writer.write(&d.system, comm)?;
        if s.run.pictures {
            picture(&d, vmax)?;
        }
        clock.add("output", t);
    }
    // Analyses on the gathered deposit.
    let mut results = Results::new();
    let fin = gather_grains(&d.system, comm);
    for a in &s.analyses {
        match a {
            GrainAnalysis::ColumnCollapse {
                wall_x_m,
                floor_y_m,
                ..
            } => {
                let before = pile_shape(&initial.x, &initial.y, &initial.r, *wall_x_m, *floor_y_m);
                let after = pile_shape(&fin.x, &fin.y, &fin.r, *wall_x_m, *floor_y_m);
                let flow_time = stop_time.unwrap_or(d.system.time) - last_removal;
                let values = collapse_results(before, after, g_abs, flow_time);
                for (k, v) in QUANTITIES.iter().zip(values) {
                    results.insert(format!("collapse.{k}"), v);
                }
                // When the front first reached 95 % of its run-out, in τ_c (not after a
                // restart: the series before it is gone).
                let target = before.length_m + 0.95 * (after.length_m - before.length_m);
                let t95 = fronts.iter().find(|f| f.1 >= target).map_or(f64::NAN, |f| {
                    (f.0 - last_removal) / (before.height_m / g_abs).sqrt()
                });
                results.insert("collapse.front_t95".into(), t95);
            }
        }
    }
    let checks = evaluate(&s.checks, &results);
    if status == Status::Ok && checks.iter().any(|c| !c.passed) {
        status = Status::ChecksFailed;
    }
    let (ke, momentum, _) = global_state(&d, comm);
    let mut counts = [
        d.migrated as f64,
        d.system.contacts() as f64,
        d.comm_seconds,
    ];
    let comm_wait = comm.max_f64(d.comm_seconds);
    comm.sum_f64(&mut counts);
    let mut header = RunHeader::new(
        "grains",
        scene.path.clone(),
        s.title.clone(),
        scene.warnings.clone(),
        comm,
    );
    header.status = status;
    header.error = error;
    header.restarted_from_step = start_step;
    header.steps = step;
    header.simulated_time_s = d.system.time;
    header.wall_time_s = wall;
    header.set_stages(&clock, comm);
    header.checkpoints = checkpoints;
    header.results = results;
    header.checks = checks;
    let summary = GrainSummary {
        run: header,
        scene: s.clone(),
        slab_bounds_m: d.bounds().to_vec(),
        grains: n_total,
        time_step_s: dt,
        lambda: scene.lambda(),
        settle_steps,
        grain_steps_per_s: n_total as f64 * (step - start_step) as f64 / wall.max(1e-12),
        migrated: counts[0] as u64,
        rebalances: d.rebalances,
        comm_wait_s: comm_wait,
        contacts: counts[1] as usize,
        list_rebuilds: d.system.list_rebuilds(),
        kinetic_energy_j_m: ke,
        momentum,
        snapshots: writer.snapshots(),
    };
    if comm.is_root() {
        let json = serde_json::to_vec_pretty(&summary).expect("summary serialises");
        write_atomic(&opts.out_dir.join("summary.json"), &json)?;
    }
    Ok(summary)
}
