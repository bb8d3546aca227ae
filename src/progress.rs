//! Progress reporting: an indicatif bar with step, simulated time, MLUPS and ETA on a
//! terminal; plain periodic log lines otherwise (batch jobs, CI).

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::time::Instant;

/// Progress of a time loop.
pub struct Progress {
    total: u64,
    cells: f64,
    dt: f64,
    bar: Option<ProgressBar>,
    log: bool,
    /// Label of the rate: "MLUPS" (cells = lattice cells) or "M grain-steps/s".
    unit: &'static str,
    start: Instant,
    last_log: Instant,
    /// The step the run started from (a restart's), which the rate and the ETA count from.
    first: u64,
}

impl Progress {
    /// `total` steps over `cells` cells of time step `dt` seconds; `enabled = false` is silent.
    pub fn new(total: u64, cells: f64, dt: f64, enabled: bool) -> Self {
        let tty = std::io::stderr().is_terminal();
        let bar = (enabled && tty).then(|| {
            let b = ProgressBar::new(total);
            b.set_style(
                ProgressStyle::with_template(
                    "{bar:40.cyan/blue} {pos}/{len} steps  {msg}  ETA {eta}",
                )
                .expect("static template")
                .progress_chars("=> "),
            );
            b
        });
        let now = Instant::now();
        Self {
            total,
            cells,
            dt,
            bar,
            log: enabled && !tty,
            unit: "MLUPS",
            start: now,
            last_log: now,
            first: 0,
        }
    }

    /// Label the rate `unit` (e.g. "M grain-steps/s" when `cells` counts grains).
    pub fn with_unit(mut self, unit: &'static str) -> Self {
        self.unit = unit;
        self
    }

    /// The run starts after `step` steps (a restart): the clock and the rate start now.
    pub fn start_at(&mut self, step: u64) {
        self.first = step;
        self.start = Instant::now();
    }

    /// Report that `step` steps are done.
    pub fn update(&mut self, step: u64) {
        let every = (self.total / 10).max(1);
        if let Some(b) = &self.bar {
            if step.is_multiple_of(16) || step == self.total {
                b.set_position(step);
                b.set_message(format!(
                    "t = {:.4e} s  {:.1} {}",
                    step as f64 * self.dt,
                    self.mlups(step),
                    self.unit
                ));
            }
        } else if self.log
            && (step.is_multiple_of(every) || self.last_log.elapsed().as_secs() >= 30)
        {
            self.last_log = Instant::now();
            let el = self.start.elapsed().as_secs_f64();
            let done = step.saturating_sub(self.first).max(1);
            let eta = el / done as f64 * self.total.saturating_sub(step) as f64;
            eprintln!(
                "step {step}/{} ({:.0}%)  t = {:.4e} s  {:.1} {}  elapsed {el:.1} s  ETA {eta:.1} s",
                self.total,
                100.0 * step as f64 / self.total as f64,
                step as f64 * self.dt,
                self.mlups(step),
                self.unit
            );
        }
    }

    fn mlups(&self, step: u64) -> f64 {
        let done = step.saturating_sub(self.first) as f64;
        self.cells * done / self.start.elapsed().as_secs_f64().max(1e-9) / 1e6
    }

    /// Clear the bar.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}
