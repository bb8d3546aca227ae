//! The one time loop every solver runs: advance a step, then the after-step hooks in a
//! fixed order (signals, the solver's own observations, snapshot, checkpoint, load
//! balance, progress),
//! and at the end the final snapshot and checkpoint. Fluid, coupled, grain and MPM runs
//! differ only in their [`Stepper`].

use crate::driver::{Lap, Signals, StageClock, Status};
use crate::error::RunError;
use crate::progress::Progress;
use decomposition::Comm;
use scene::{Cadence, Output};
use std::path::PathBuf;
use std::time::Instant;

/// What a step or an after-step hook says about the run.
#[derive(Debug, Clone, PartialEq)]
pub enum Flow {
    /// Go on.
    Go,
    /// The motion has died down (a scene's `stop_below_…`): stop as a finished run.
    Settled,
    /// NaN, infinite energy or non-positive density: stop, keep the output, say where.
    Unstable(String),
}

/// Which hooks run after this step.
#[derive(Debug, Clone, Copy)]
pub struct Due {
    /// The step just taken.
    pub step: u64,
    /// It is the run's last step.
    pub last: bool,
    /// A snapshot follows.
    pub snapshot: bool,
    /// A checkpoint follows.
    pub checkpoint: bool,
}

/// A solver as the time loop drives it. Every method is collective: all ranks call it at
/// the same step.
pub trait Stepper {
    /// Steps taken so far: the number of the last step (the checkpoint's on a restart).
    fn steps_done(&self) -> u64;
    /// Simulated time (s).
    fn time_s(&self) -> f64;
    /// Take one step. [`Flow::Unstable`] stops the run.
    fn advance(&mut self, comm: &dyn Comm) -> Flow;
    /// After a step: the solver's own observations (probes, fronts) and its health and
    /// early-stop tests, knowing which hooks follow.
    fn observe(&mut self, comm: &dyn Comm, due: Due) -> Result<Flow, RunError>;
    /// Write a snapshot of the current state.
    fn snapshot(&mut self, comm: &dyn Comm) -> Result<(), RunError>;
    /// Write `path` from which a run restarts at this step; `next_output_s` is the next
    /// snapshot time of a time cadence (what the restart resumes from).
    fn checkpoint(
        &mut self,
        comm: &dyn Comm,
        path: &std::path::Path,
        next_output_s: f64,
    ) -> Result<(), RunError>;
    /// After the output hooks: spread the work over the ranks again if the solver balances
    /// its own load here (a coupled run's slabs follow its grains). Nothing by default.
    fn rebalance(&mut self, _comm: &dyn Comm, _due: Due) -> Result<(), RunError> {
        Ok(())
    }
}

/// How long and with what cadences a run goes.
#[derive(Debug, Clone)]
pub struct LoopPlan {
    /// The step to stop after.
    pub last_step: u64,
    /// Snapshot cadence.
    pub cadence: Cadence,
    /// The next snapshot time of a time cadence (s): the checkpoint's on a restart.
    pub next_output_s: f64,
    /// Checkpoint every this many steps (0: never).
    pub checkpoint_every_steps: u64,
    /// Checkpoint every this many wall-clock minutes (0: never).
    pub checkpoint_every_minutes: f64,
    /// Checkpoint after the last step.
    pub checkpoint_at_end: bool,
    /// Where checkpoints go.
    pub checkpoint_path: PathBuf,
    /// Whether this run starts from a checkpoint (no snapshot at its first step).
    pub restarted: bool,
    /// Whether the command line (`--steps`, `--end-time`) stops the run before the scene's
    /// own length: its checks are then reported, not judged.
    pub shortened: bool,
}

impl LoopPlan {
    /// The plan of a run to `last_step` with the scene's `[output]`, writing checkpoints
    /// into `out_dir`; `resume_next_output_s` is a restart's next snapshot time.
    pub fn new(
        last_step: u64,
        output: &Output,
        out_dir: &std::path::Path,
        resume_next_output_s: Option<f64>,
    ) -> Self {
        let cadence = output.cadence();
        let first = match cadence {
            Cadence::Seconds(t) => t,
            _ => 0.0,
        };
        LoopPlan {
            last_step,
            cadence,
            next_output_s: resume_next_output_s.unwrap_or(first),
            checkpoint_every_steps: output.checkpoint_every_steps(),
            checkpoint_every_minutes: output.checkpoint_every_minutes(),
            checkpoint_at_end: output.checkpoint_at_end(),
            checkpoint_path: out_dir.join("checkpoint.h5"),
            restarted: resume_next_output_s.is_some(),
            shortened: false,
        }
    }

    /// The plan, stopping before the scene's own last step `scene_last_step` when
    /// `last_step` is smaller.
    pub fn scene_length(mut self, scene_last_step: u64) -> Self {
        self.shortened = self.last_step < scene_last_step;
        self
    }
}

/// How the loop ended.
#[derive(Debug, Clone)]
pub struct LoopEnd {
    /// Ok (ran to the end or settled), unstable or interrupted (checks come later).
    pub status: Status,
    /// What went wrong, with step and place.
    pub error: Option<String>,
    /// The step the loop started from.
    pub start_step: u64,
    /// Simulated time when the motion settled (s), if it did.
    pub settled_s: Option<f64>,
    /// Wall time of the loop (s), without the final snapshot and checkpoint.
    pub wall_s: f64,
    /// Checkpoints written.
    pub checkpoints: Vec<PathBuf>,
    /// This rank's seconds in the loop's own stages, [`LOOP_STAGES`].
    pub clock: StageClock,
    /// The next snapshot time of a time cadence (s), as a checkpoint stores it.
    pub next_output_s: f64,
    /// The plan's [`LoopPlan::shortened`].
    pub shortened: bool,
    /// What this rank sent through the loop's steps, its snapshots, checkpoints and
    /// rebalances left out.
    pub traffic: decomposition::Traffic,
}

/// The stages the loop times itself; each solver times its own.
pub const LOOP_STAGES: [&str; 3] = ["output", "checkpoint", "rebalance"];

/// Run `stepper` to `plan.last_step` (collective). Writes the first snapshot (not on a
/// restart), snapshots at the cadence, checkpoints when due or asked for by a signal, and
/// at the end the final snapshot (also of an unstable or interrupted state, for diagnosis)
/// and the end checkpoint. I/O errors are errors; instabilities end the loop with
/// [`Status::Unstable`] and keep the output.
pub fn drive(
    stepper: &mut dyn Stepper,
    plan: &LoopPlan,
    progress: &mut Progress,
    comm: &dyn Comm,
) -> Result<LoopEnd, RunError> {
    let mut clock = StageClock::new(&LOOP_STAGES);
    let start_step = stepper.steps_done();
    progress.start_at(start_step);
    let mut snapshot_at = None;
    if !plan.restarted {
        let t = Lap::start();
        stepper.snapshot(comm)?;
        snapshot_at = Some(start_step);
        clock.add("output", t);
    }
    let signals = Signals::install();
    let mut end = LoopEnd {
        status: Status::Ok,
        error: None,
        start_step,
        settled_s: None,
        wall_s: 0.0,
        checkpoints: Vec::new(),
        clock: StageClock::new(&LOOP_STAGES),
        next_output_s: plan.next_output_s,
        shortened: plan.shortened,
        traffic: decomposition::Traffic::default(),
    };
    let traffic_at_start = decomposition::Traffic::now();
    // What the snapshots and checkpoints sent, left out of the steps' traffic.
    let mut output_traffic = decomposition::Traffic::default();
    let mut checkpoint_at = None;
    let mut last_checkpoint = Instant::now();
    let started = Instant::now();
    while stepper.steps_done() < plan.last_step {
        if let Flow::Unstable(e) = stepper.advance(comm) {
            end.status = Status::Unstable;
            end.error = Some(e);
            break;
        }
        let step = stepper.steps_done();
        // Signals and the wall-clock cadence are agreed on by all ranks after every step,
        // so that all ranks checkpoint (and stop) at the same step.
        let wall_due = plan.checkpoint_every_minutes > 0.0
            && last_checkpoint.elapsed().as_secs_f64() >= 60.0 * plan.checkpoint_every_minutes;
        let agreed = signals.agree(comm, wall_due);
        let due = due_after(step, stepper, plan, end.next_output_s, agreed.checkpoint);
        match stepper.observe(comm, due)? {
            Flow::Go => {}
            Flow::Settled => {
                end.settled_s = Some(stepper.time_s());
                break;
            }
            Flow::Unstable(e) => {
                end.status = Status::Unstable;
                end.error = Some(e);
                break;
            }
        }
        if due.snapshot {
            let t = Lap::start();
            if let Cadence::Seconds(every) = plan.cadence {
                if stepper.time_s() >= end.next_output_s {
                    end.next_output_s += every;
                }
            }
            let sent = decomposition::Traffic::now();
            stepper.snapshot(comm)?;
            output_traffic = output_traffic.plus(decomposition::Traffic::now().since(sent));
            snapshot_at = Some(step);
            clock.add("output", t);
        }
        if due.checkpoint {
            let t = Lap::start();
            let sent = decomposition::Traffic::now();
            stepper.checkpoint(comm, &plan.checkpoint_path, end.next_output_s)?;
            output_traffic = output_traffic.plus(decomposition::Traffic::now().since(sent));
            end.checkpoints.push(plan.checkpoint_path.clone());
            checkpoint_at = Some(step);
            last_checkpoint = Instant::now();
            clock.add("checkpoint", t);
        }
        // Not on the last step, nor when the run stops here (a signal's grace period is for
        // the final snapshot and checkpoint); the move's traffic is not a step's.
        if !due.last && !agreed.stop {
            let t = Lap::start();
            let sent = decomposition::Traffic::now();
            stepper.rebalance(comm, due)?;
            output_traffic = output_traffic.plus(decomposition::Traffic::now().since(sent));
            clock.add("rebalance", t);
        }
        progress.update(step);
        if agreed.stop {
            end.status = Status::Interrupted;
            break;
        }
    }
    end.wall_s = started.elapsed().as_secs_f64();
    end.traffic = decomposition::Traffic::now()
        .since(traffic_at_start)
        .since(output_traffic);
    progress.finish();
    finish(
        stepper,
        plan,
        &mut end,
        (snapshot_at, checkpoint_at),
        &mut clock,
        comm,
    )?;
    end.clock = clock;
    Ok(end)
}

/// Which hooks follow `step`: a snapshot at the cadence or the last step, a checkpoint at
/// its cadence, the last step (with `checkpoint_at_end`) or when the ranks agreed on one.
fn due_after(
    step: u64,
    stepper: &dyn Stepper,
    plan: &LoopPlan,
    next_output_s: f64,
    agreed_checkpoint: bool,
) -> Due {
    let last = step >= plan.last_step;
    let snapshot = last
        || match plan.cadence {
            Cadence::Ends => false,
            Cadence::Steps(n) => step.is_multiple_of(n),
            Cadence::Seconds(_) => stepper.time_s() >= next_output_s,
        };
    let checkpoint = agreed_checkpoint
        || (plan.checkpoint_every_steps > 0 && step.is_multiple_of(plan.checkpoint_every_steps))
        || (last && plan.checkpoint_at_end);
    Due {
        step,
        last,
        snapshot,
        checkpoint,
    }
}

/// After the loop: the final snapshot (also of an unstable or interrupted state, for
/// diagnosis) unless the last step has one, and the end checkpoint of a finished run
/// unless the last step has one. `written` holds the steps of the last snapshot and
/// checkpoint.
fn finish(
    stepper: &mut dyn Stepper,
    plan: &LoopPlan,
    end: &mut LoopEnd,
    written: (Option<u64>, Option<u64>),
    clock: &mut StageClock,
    comm: &dyn Comm,
) -> Result<(), RunError> {
    let step = stepper.steps_done();
    // A restart that takes no step has nothing new to write.
    let moved = step > end.start_step || !plan.restarted;
    if moved && written.0 != Some(step) {
        // A step that fails leaves the step count where it was: its snapshot is then the
        // last good state.
        let t = Lap::start();
        stepper.snapshot(comm)?;
        clock.add("output", t);
    }
    if end.status == Status::Ok && plan.checkpoint_at_end && written.1 != Some(step) {
        let t = Lap::start();
        stepper.checkpoint(comm, &plan.checkpoint_path, end.next_output_s)?;
        end.checkpoints.push(plan.checkpoint_path.clone());
        clock.add("checkpoint", t);
    }
    Ok(())
}

/// The first snapshot time of a time cadence after `t` (s), for a restart whose checkpoint
/// does not store it (the fluid's): the next whole multiple of `every_s`.
pub fn next_output_after(t: f64, output: &Output) -> f64 {
    match output.cadence() {
        Cadence::Seconds(every) => ((t / every).floor() + 1.0) * every,
        _ => 0.0,
    }
}

/// The step a grain or MPM run of `length` stops after: its steps, else its end time
/// rounded up to the step that reaches it (`dt` in s).
pub fn particle_last_step(length: crate::run::Length, dt: f64) -> u64 {
    let reach = |t: f64| (t / dt).ceil() as u64;
    length
        .steps
        .unwrap_or_else(|| reach(length.end_time_s.unwrap_or(0.0)))
}
