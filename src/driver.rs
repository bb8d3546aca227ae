//! What every solver's time loop shares: named stage timers, the signals agreed by all
//! ranks at the same cadence, and the header every `summary.json` starts with (the same
//! keys for fluid, coupled, grain and MPM runs).

use analysis::checks::{any_failed, mark_skipped, CheckOutcome};
use analysis::Results;
use decomposition::Comm;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::Instant;

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
    /// Stopped by SIGTERM after writing a checkpoint.
    Interrupted,
}

/// Seconds of one stage over the ranks.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct StageStats {
    /// Sum over ranks.
    pub sum_s: f64,
    /// Slowest rank.
    pub max_s: f64,
    /// Fastest rank.
    pub min_s: f64,
    /// Mean over ranks.
    pub mean_s: f64,
    /// Of the stage's seconds, those a rank spent in communication (collectives and
    /// waiting for messages: blocked on the other ranks, or moving data), the least and the
    /// most over the ranks; absent for a stage its solver times without them. A stage whose
    /// rank's own work is small against the others' shows up here.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wait_s: Option<[f64; 2]>,
}

/// The keys every `summary.json` starts with, whatever the solver (flattened into each
/// solver's summary, which adds its own figures after them).
#[derive(Debug, Clone, Serialize)]
pub struct RunHeader {
    /// grainflow version.
    pub version: &'static str,
    /// What ran: "fluid", "coupled" (fluid with grains), "grains" or "mpm".
    pub solver: &'static str,
    /// Scene file.
    pub scene_path: PathBuf,
    /// Scene title.
    pub title: String,
    /// Outcome.
    pub status: Status,
    /// What went wrong (an instability, with step and place), if anything.
    pub error: Option<String>,
    /// Warnings from validation.
    pub warnings: Vec<String>,
    /// MPI ranks.
    pub ranks: usize,
    /// Rayon threads per rank.
    pub threads: usize,
    /// Whether the idle threads looked for work through the time loop (`--wait-policy`).
    pub idle_workers_active: bool,
    /// Step the run started from (0, or the checkpoint's step on a restart).
    pub restarted_from_step: u64,
    /// Steps taken (the last step's number).
    pub steps: u64,
    /// Simulated time at the end (s).
    pub simulated_time_s: f64,
    /// When the run stopped before its length because the motion settled (its kinetic
    /// energy below the scene's `[run] stop_below_…` threshold), the simulated time (s);
    /// `null` when it ran its length (or stopped otherwise).
    pub settled_at_s: Option<f64>,
    /// Wall time of the time loop (s).
    pub wall_time_s: f64,
    /// Seconds per stage, the slowest rank's (what bounds the run).
    pub stage_seconds: BTreeMap<&'static str, f64>,
    /// Seconds per stage over ranks: sum, max, min, mean (load imbalance shows as max ≫ min).
    pub stages: BTreeMap<&'static str, StageStats>,
    /// Bytes sent between ranks per step of the loop (halo faces, ghost grains, migrations,
    /// grid strips), all ranks together.
    pub message_bytes_per_step: f64,
    /// Point-to-point messages per step of the loop, the busiest rank's.
    pub messages_per_step: f64,
    /// Collective calls per step of the loop (reductions, gathers, barriers; snapshots'
    /// gathers included), the busiest rank's; 0 on one process.
    pub collectives_per_step: f64,
    /// Seconds each rank spent in communication over the loop's steps (in collectives and
    /// waiting for messages; 0 on one rank): the least and the most over the ranks. The
    /// most minus the least is roughly what load imbalance costs.
    pub communication_wait_s: [f64; 2],
    /// The memory `check` estimates for the run, all ranks together (bytes).
    pub memory_estimate_bytes: f64,
    /// The peak resident memory of each rank's process (its high-water mark at the end of
    /// the run) summed over the ranks (bytes); `null` where the system does not say.
    pub peak_memory_bytes: Option<f64>,
    /// Checkpoints written during the run.
    pub checkpoints: Vec<PathBuf>,
    /// Results of the analyses.
    pub results: Results,
    /// Checks with their outcome.
    pub checks: Vec<CheckOutcome>,
    /// Whether the command line cut the run short of the scene's own length (`--steps`,
    /// `--end-time`): the checks are then reported, not judged.
    pub shortened: bool,
    /// The analyses that could not run, each with why.
    pub analyses_skipped: Vec<SkippedAnalysis>,
}

/// An analysis that could not run, and why (for example an averaging window longer than
/// a shortened run).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SkippedAnalysis {
    /// The analysis (its `kind`).
    pub analysis: String,
    /// Why it could not run.
    pub reason: String,
}

impl RunHeader {
    /// The header of a run of `solver` on `comm`: its scene, the machine, and nothing run
    /// yet (status ok, no steps, no results); the time loop fills in the rest.
    pub fn new(
        solver: &'static str,
        scene_path: PathBuf,
        title: String,
        warnings: Vec<String>,
        comm: &dyn Comm,
    ) -> Self {
        RunHeader {
            version: env!("CARGO_PKG_VERSION"),
            solver,
            scene_path,
            title,
            status: Status::Ok,
            error: None,
            warnings,
            ranks: comm.size(),
            threads: rayon::current_num_threads(),
            idle_workers_active: crate::pool::idle_workers_active(),
            restarted_from_step: 0,
            steps: 0,
            simulated_time_s: 0.0,
            settled_at_s: None,
            wall_time_s: 0.0,
            stage_seconds: BTreeMap::new(),
            stages: BTreeMap::new(),
            message_bytes_per_step: 0.0,
            messages_per_step: 0.0,
            collectives_per_step: 0.0,
            communication_wait_s: [0.0; 2],
            memory_estimate_bytes: f64::NAN,
            peak_memory_bytes: None,
            checkpoints: Vec::new(),
            results: Results::new(),
            checks: Vec::new(),
            shortened: false,
            analyses_skipped: Vec::new(),
        }
    }

    /// Record the checks and the skipped analyses, and fail a run that otherwise ended
    /// well when a judged check failed or, at the scene's full length, an analysis could
    /// not run. On a `shortened` run every check is reported but not judged (the scene's
    /// checks state what its full length achieves); elsewhere a check whose quantity a
    /// skipped analysis would have measured is marked with that reason.
    pub fn judge(
        &mut self,
        mut checks: Vec<CheckOutcome>,
        skipped: &[analysis::AnalysisError],
        shortened: bool,
    ) {
        if shortened {
            mark_skipped(
                &mut checks,
                "not judged: --steps or --end-time cut the run short of the scene's length",
                true,
            );
        } else if !skipped.is_empty() {
            let names: Vec<&str> = skipped.iter().map(|e| e.analysis.as_str()).collect();
            let why = format!("not measured: analysis {} could not run", names.join(", "));
            mark_skipped(&mut checks, &why, false);
        }
        let failed = any_failed(&checks) || (!shortened && !skipped.is_empty());
        if self.status == Status::Ok && failed {
            self.status = Status::ChecksFailed;
        }
        self.checks = checks;
        self.shortened = shortened;
        self.analyses_skipped = skipped
            .iter()
            .map(|e| SkippedAnalysis {
                analysis: e.analysis.clone(),
                reason: e.message.clone(),
            })
            .collect();
    }

    /// Record `check`'s memory estimate for the run and the ranks' summed peak resident
    /// memory (collective; call it last, after the output is written).
    pub fn set_memory(&mut self, estimate_bytes: f64, comm: &dyn Comm) {
        self.memory_estimate_bytes = estimate_bytes;
        let mut peak = [crate::budget::peak_resident_bytes().unwrap_or(f64::NAN)];
        comm.sum_f64(&mut peak);
        self.peak_memory_bytes = peak[0].is_finite().then_some(peak[0]);
    }

    /// Record the loop's communication per step from each rank's `traffic` over the steps
    /// it ran (collective; after `steps` and `restarted_from_step` are set).
    pub fn set_traffic(&mut self, traffic: decomposition::Traffic, comm: &dyn Comm) {
        let steps = self.steps.saturating_sub(self.restarted_from_step).max(1) as f64;
        let mut bytes = [traffic.sent_bytes as f64];
        comm.sum_f64(&mut bytes);
        self.message_bytes_per_step = bytes[0] / steps;
        self.messages_per_step = comm.max_f64(traffic.messages as f64) / steps;
        self.collectives_per_step = comm.max_f64(traffic.collectives as f64) / steps;
        let wait = traffic.wait_seconds();
        self.communication_wait_s = [-comm.max_f64(-wait), comm.max_f64(wait)];
    }

    /// Fill in the stage timings from each rank's `clocks` (the solver's and the time
    /// loop's; collective).
    pub fn set_stages(&mut self, clocks: &[&StageClock], comm: &dyn Comm) {
        let names: Vec<&'static str> = clocks
            .iter()
            .flat_map(|c| c.names.iter().copied())
            .collect();
        let seconds: Vec<f64> = clocks
            .iter()
            .flat_map(|c| c.seconds.iter().copied())
            .collect();
        // NaN marks a stage timed without its waits (the same on every rank).
        let waits: Vec<f64> = clocks
            .iter()
            .flat_map(|c| match &c.waits {
                Some(w) => w.clone(),
                None => vec![f64::NAN; c.names.len()],
            })
            .collect();
        let (stages, slowest) = stage_stats(&names, &seconds, &waits, comm);
        self.stages = stages;
        self.stage_seconds = slowest;
    }
}

/// The seconds spent in each named stage of a step on this rank, and of them those spent
/// in communication where the clock was given them.
#[derive(Debug, Clone)]
pub struct StageClock {
    names: &'static [&'static str],
    seconds: Vec<f64>,
    waits: Option<Vec<f64>>,
}

/// When a stage started: the wall clock and this rank's communication wait so far.
#[derive(Debug, Clone, Copy)]
pub struct Lap {
    at: Instant,
    wait_ns: u64,
}

impl Lap {
    /// Start timing now.
    pub fn start() -> Self {
        Lap {
            at: Instant::now(),
            wait_ns: decomposition::Traffic::now().wait_ns,
        }
    }

    /// Seconds since the start, and of them those spent in communication.
    pub fn elapsed(&self) -> (f64, f64) {
        let waited = decomposition::Traffic::now()
            .wait_ns
            .saturating_sub(self.wait_ns);
        (self.at.elapsed().as_secs_f64(), waited as f64 * 1e-9)
    }
}

impl StageClock {
    /// A clock for the stages `names`, in the order a step runs them.
    pub fn new(names: &'static [&'static str]) -> Self {
        StageClock {
            names,
            seconds: vec![0.0; names.len()],
            waits: Some(vec![0.0; names.len()]),
        }
    }

    /// Add the time since `since` to `stage`, and its communication to the stage's wait.
    /// Panics on a name the clock was not made with (a programming error, caught by every
    /// run).
    pub fn add(&mut self, stage: &str, since: Lap) {
        let k = self
            .names
            .iter()
            .position(|n| *n == stage)
            .unwrap_or_else(|| panic!("no stage {stage:?} among {:?}", self.names));
        let (seconds, waited) = since.elapsed();
        self.seconds[k] += seconds;
        if let Some(w) = &mut self.waits {
            w[k] += waited;
        }
    }

    /// Seconds per stage, in the order of the names.
    pub fn seconds(&self) -> &[f64] {
        &self.seconds
    }

    /// A clock for the stages `names` that has run `seconds` (in their order) already:
    /// the stage times a solver keeps itself.
    pub fn with_seconds(names: &'static [&'static str], seconds: &[f64]) -> Self {
        assert_eq!(names.len(), seconds.len(), "one time per stage");
        StageClock {
            names,
            seconds: seconds.to_vec(),
            waits: None,
        }
    }

    /// The same clock, with the seconds of each stage spent in communication.
    pub fn with_waits(mut self, waits: &[f64]) -> Self {
        assert_eq!(self.names.len(), waits.len(), "one wait per stage");
        self.waits = Some(waits.to_vec());
        self
    }
}

/// Per-stage statistics over the ranks from each rank's `local` seconds (in the order of
/// `names`) and of them those spent in communication (`waits`, NaN where not timed: the
/// same stages on every rank), and the slowest rank's seconds per stage. Collective.
pub fn stage_stats(
    names: &[&'static str],
    local: &[f64],
    waits: &[f64],
    comm: &dyn Comm,
) -> (
    BTreeMap<&'static str, StageStats>,
    BTreeMap<&'static str, f64>,
) {
    let all = comm.all_gather_f64(&[local, waits].concat());
    let (ranks, n) = (comm.size(), names.len());
    let mut stages = BTreeMap::new();
    let mut slowest = BTreeMap::new();
    for (k, name) in names.iter().enumerate() {
        let v: Vec<f64> = (0..ranks).map(|r| all[r * 2 * n + k]).collect();
        let w: Vec<f64> = (0..ranks).map(|r| all[r * 2 * n + n + k]).collect();
        let sum: f64 = v.iter().sum();
        let max = v.iter().cloned().fold(0.0, f64::max);
        let min = v.iter().cloned().fold(f64::INFINITY, f64::min);
        let wait_s = w.iter().all(|x| x.is_finite()).then(|| {
            [
                w.iter().cloned().fold(f64::INFINITY, f64::min),
                w.iter().cloned().fold(0.0, f64::max),
            ]
        });
        stages.insert(
            *name,
            StageStats {
                sum_s: sum,
                max_s: max,
                min_s: min,
                mean_s: sum / ranks as f64,
                wait_s,
            },
        );
        slowest.insert(*name, max);
    }
    (stages, slowest)
}

/// SIGTERM (stop) and SIGUSR1 (checkpoint and go on) flags, registered once per process.
fn signal_flags() -> &'static [Arc<AtomicBool>; 2] {
    static FLAGS: OnceLock<[Arc<AtomicBool>; 2]> = OnceLock::new();
    FLAGS.get_or_init(|| {
        let flags = [
            Arc::new(AtomicBool::new(false)),
            Arc::new(AtomicBool::new(false)),
        ];
        // Registration fails only for forbidden signals; these two are allowed.
        let _ = signal_hook::flag::register(signal_hook::consts::SIGTERM, flags[0].clone());
        let _ = signal_hook::flag::register(signal_hook::consts::SIGUSR1, flags[1].clone());
        flags
    })
}

/// What the ranks agreed on after a step (see [`Signals::agree`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Agreed {
    /// SIGTERM reached a rank: write a checkpoint and stop.
    pub stop: bool,
    /// SIGUSR1 reached a rank, or a wall-clock checkpoint is due on one: write a
    /// checkpoint and go on.
    pub checkpoint: bool,
}

/// SIGTERM and SIGUSR1, as every time loop sees them: agreed by all ranks after every
/// step, so that all ranks checkpoint and stop at the same step.
pub struct Signals {
    flags: &'static [Arc<AtomicBool>; 2],
}

impl Signals {
    /// The process's handlers (installed on the first call).
    pub fn install() -> Self {
        Signals {
            flags: signal_flags(),
        }
    }

    /// Whether any rank received SIGTERM or SIGUSR1 since the last call, or has a
    /// wall-clock checkpoint due (`wall_due`). One reduction over the ranks (none on one
    /// rank). Collective.
    pub fn agree(&self, comm: &dyn Comm, wall_due: bool) -> Agreed {
        let term = self.flags[0].load(Ordering::Relaxed);
        let usr1 = self.flags[1].swap(false, Ordering::Relaxed);
        let local = (term as u8) | (usr1 as u8) << 1 | (wall_due as u8) << 2;
        let agreed = if comm.size() > 1 {
            comm.max_f64(local as f64) as u8
        } else {
            local
        };
        Agreed {
            stop: agreed & 1 != 0,
            checkpoint: agreed != 0,
        }
    }
}
