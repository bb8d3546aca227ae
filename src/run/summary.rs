//! What a fluid or coupled run reports: `summary.json`'s contents and the closing pass
//! that computes them (analyses, checks, the coupling's figures, probe CSVs).

use super::{analyse, FluidStepper};
use crate::driver::{stage_stats, RunHeader, StageClock, Status};
use crate::error::RunError;
use crate::simulation::{stage, Simulation, STAGES};
use crate::time_loop::{LoopEnd, Stepper};
use analysis::checks::evaluate;
use analysis::Results;
use decomposition::Comm;
use io::atomic::write_atomic;
use lbm::fields::Totals;
use lbm::Real;
use scene::{Backend, GpuStorage, Kernel, Precision, Units, ValidScene};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// Everything `summary.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// The keys every summary starts with (see [`RunHeader`]).
    #[serde(flatten)]
    pub run: RunHeader,
    /// The scene as parsed (defaults filled in).
    pub scene: scene::Scene,
    /// Precision used.
    pub precision: Precision,
    /// Backend used.
    pub backend: Backend,
    /// GPU population storage used.
    pub gpu_storage: GpuStorage,
    /// The device that ran the fluid solver (rank 0's).
    pub device: String,
    /// Columns `[x_begin, x_end)` of each rank.
    pub partition: Vec<[usize; 2]>,
    /// Halo bytes sent per step, all ranks together.
    pub halo_bytes_per_step: u64,
    /// Derived lattice parameters.
    pub units: Units,
    /// Lattice size.
    pub cells: [usize; 2],
    /// Fluid cells.
    pub fluid_cells: usize,
    /// Distribution storage (bytes).
    pub memory_bytes: usize,
    /// Million lattice-cell updates per second over the whole loop (all cells).
    pub mlups: f64,
    /// MLUPS of the collide–stream stage alone.
    pub kernel_mlups: f64,
    /// Coupled runs: the "coupling" stage's seconds per pass (`coupling::PASSES`), the
    /// slowest rank's. Absent without grains.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub coupling_pass_seconds: BTreeMap<&'static str, f64>,
    /// Coupled runs: `coupling::COUNTS` summed over ranks (remaps of the cover map done in
    /// place and afresh, grains decided and skipped in them, boundary lists kept and
    /// rescanned). Absent without grains.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub coupling_counts: BTreeMap<&'static str, u64>,
    /// Times the slabs moved to follow the work (coupled runs on several ranks), and the
    /// busiest rank's own work over the mean over the steps since the last check or move
    /// (1 on one rank).
    pub rebalances: u64,
    /// See `rebalances`.
    pub load_imbalance: f64,
    /// HDF5 snapshot data written (bytes, all ranks) and the slowest rank's seconds in
    /// the HDF5 write calls: their ratio is the parallel write bandwidth.
    pub snapshot_bytes: u64,
    /// See `snapshot_bytes`.
    pub snapshot_write_s: f64,
    /// Totals at the start and the end (lattice units).
    pub totals_initial: Totals,
    /// See `totals_initial`.
    pub totals_final: Totals,
    /// Last sample of each probe (SI).
    pub probes: BTreeMap<String, BTreeMap<String, f64>>,
}

/// The last sample of every probe series (SI).
fn last_probe_samples<T: Real>(sim: &Simulation<T>) -> BTreeMap<String, BTreeMap<String, f64>> {
    sim.series
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
        .collect()
}

/// The coupling's seconds per pass (slowest rank) and its counters (summed), when there
/// are grains. Collective.
#[allow(clippy::type_complexity)]
fn coupling_figures<T: Real>(
    sim: &Simulation<T>,
    comm: &dyn Comm,
) -> (BTreeMap<&'static str, f64>, BTreeMap<&'static str, u64>) {
    let Some(g) = &sim.grains else {
        return (BTreeMap::new(), BTreeMap::new());
    };
    // Every rank of a coupled run holds grains (maybe none in view), so this is collective.
    let seconds = stage_stats(
        &coupling::PASSES,
        &g.pass_seconds(),
        &[f64::NAN; coupling::PASSES.len()],
        comm,
    )
    .1;
    let mut v: Vec<f64> = g.counts().iter().map(|&c| c as f64).collect();
    comm.sum_f64(&mut v);
    let counts = coupling::COUNTS
        .iter()
        .zip(v)
        .map(|(n, c)| (*n, c as u64))
        .collect();
    (seconds, counts)
}

/// Analyses, checks, probe series and `summary.json` (rank 0) of a finished loop
/// (collective).
pub(super) fn summarise<T: Real + hdf5::H5Type>(
    scene: &ValidScene,
    mut st: FluidStepper<T>,
    end: LoopEnd,
    (precision, (backend, storage, _)): (Precision, (Backend, GpuStorage, Kernel)),
    comm: &dyn Comm,
    out_dir: &Path,
) -> Result<Summary, RunError> {
    let steps = st.steps_done();
    // The final fields are kept only when they are the state the loop ended in.
    let fields = match st.final_fields.take() {
        Some(f) if steps == st.last_step => f,
        _ => st.sim.fields(comm),
    };
    let totals_final = st.sim.totals(comm, &fields);
    let (results, skipped) = if end.status == Status::Ok {
        analyse(&mut st, fields, totals_final, comm)?
    } else {
        let mut r = Results::new();
        if let Some(c) = &st.sim.grains {
            r.insert("coupling.substeps".into(), c.substeps() as f64);
            r.insert("coupling.grains".into(), c.radii(comm).len() as f64);
        }
        (r, Vec::new())
    };
    let checks = evaluate(&scene.scene.checks, &results);
    let sim = &st.sim;
    let (nx, ny) = (sim.partition.columns(), sim.fluid.lattice().ny());
    let updates = (nx * ny) as f64 * (steps - end.start_step) as f64;
    let (coupling_pass_seconds, coupling_counts) = coupling_figures(sim, comm);
    let load_imbalance = match &mut st.balance {
        Some(b) => b.final_imbalance(sim, comm),
        None => 1.0,
    };
    let wall = comm.max_f64(end.wall_s);
    let mut halo_bytes = [sim.fluid.lattice().halo_bytes_per_step() as f64];
    comm.sum_f64(&mut halo_bytes);
    let solver = if sim.grains.is_some() {
        "coupled"
    } else {
        "fluid"
    };
    let mut header = RunHeader::new(
        solver,
        scene.path.clone(),
        scene.scene.title.clone(),
        scene.warnings.clone(),
        comm,
    );
    header.status = end.status;
    header.error = end.error.clone();
    header.restarted_from_step = end.start_step;
    header.steps = steps;
    header.simulated_time_s = scene.units.time_si(steps);
    header.wall_time_s = wall;
    let solver_clock =
        StageClock::with_seconds(&STAGES, &sim.times.seconds).with_waits(&sim.times.waits);
    header.set_traffic(end.traffic, comm);
    header.set_stages(&[&solver_clock, &end.clock], comm);
    let kernel_s = header.stage_seconds[STAGES[stage::COLLIDE_STREAM]];
    header.checkpoints = end.checkpoints.clone();
    header.results = results;
    header.judge(checks, &skipped, end.shortened);
    header.set_memory(st.memory_estimate, comm);
    let summary = Summary {
        run: header,
        scene: scene.scene.clone(),
        precision,
        backend,
        gpu_storage: storage,
        device: sim.fluid.device(),
        partition: (0..comm.size())
            .map(|r| {
                let s = sim.partition.slab(r);
                [s.x_begin, s.x_end]
            })
            .collect(),
        halo_bytes_per_step: halo_bytes[0] as u64,
        units: scene.units,
        cells: [nx, ny],
        fluid_cells: sim.fluid_cells(comm),
        memory_bytes: sim.fluid.lattice().storage_bytes(),
        mlups: updates / wall.max(1e-12) / 1e6,
        kernel_mlups: updates / kernel_s.max(1e-12) / 1e6,
        coupling_pass_seconds,
        coupling_counts,
        rebalances: st.balance.as_ref().map_or(0, |b| b.rebalances),
        load_imbalance,
        snapshot_bytes: st.out.bytes,
        snapshot_write_s: comm.max_f64(st.out.write_s),
        totals_initial: st.totals_initial,
        totals_final,
        probes: last_probe_samples(sim),
    };
    if comm.is_root() {
        for s in &sim.series {
            s.write_csv(out_dir)?;
        }
        let json = crate::summary_units::summary_json(&summary);
        write_atomic(&out_dir.join("summary.json"), &json)?;
    }
    comm.barrier();
    Ok(summary)
}
