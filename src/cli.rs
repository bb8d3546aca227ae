//! Command-line interface (clap).

use anyhow::Result;
use clap::{Parser, Subcommand, ValueEnum};
use grainflow::run::{Backend, Kernel, Precision};
use std::path::PathBuf;

/// grainflow: lattice Boltzmann fluid–grain flows for geomechanics.
#[derive(Debug, Parser)]
#[command(name = "grainflow", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Floating-point precision on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum PrecisionArg {
    /// Single precision (half the memory traffic).
    F32,
    /// Double precision.
    F64,
}

/// Device of the fluid solver on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum BackendArg {
    /// rayon threads.
    Cpu,
    /// wgpu compute kernels (Vulkan).
    Gpu,
}

/// GPU population storage on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum GpuStorageArg {
    /// The run's precision.
    Native,
    /// IEEE half storage, f32 arithmetic.
    F16,
}

/// CPU kernel on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum KernelArg {
    /// In place where it measured faster.
    Auto,
    /// Two buffers.
    TwoArray,
    /// One buffer (AA pattern).
    InPlace,
}

/// What idle pool workers do during a time loop, on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum WaitPolicyArg {
    /// `active` where threads × ranks on the node fit its cores, else `passive`.
    Auto,
    /// Keep looking for work (busy cores, short passes start at once).
    Active,
    /// Sleep until woken (rayon's own).
    Passive,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a scene; exits 2 when a check fails, 3 when the run goes unstable, 4 when stopped
    /// by SIGTERM and 64 on a command line that does not parse.
    Run(RunArgs),
    /// Measure the stability limits `check` uses: the fluid's map over τ, lattice Mach
    /// number and operator (a shear layer and a cavity), the DEM's time-step factor λ and the
    /// MPM's Courant number. Writes jobs/stability/*.csv (rebuild to ship them).
    StabilityMap {
        /// Output folder (default: ./stability-map; the shipped maps are jobs/stability).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Validate a scene and print the derived lattice parameters and memory estimate.
    Check {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Ranks the run will use, judged as if they all shared this node (its memory).
        #[arg(long, default_value_t = 1)]
        ranks: usize,
        /// Threads the run will use, for the wall-time estimate (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Judge the run `run --precision` would make.
        #[arg(long, value_enum)]
        precision: Option<PrecisionArg>,
        /// Judge the run `run --backend` would make.
        #[arg(long, value_enum)]
        backend: Option<BackendArg>,
        /// Judge the run `run --kernel` would make.
        #[arg(long, value_enum)]
        kernel: Option<KernelArg>,
        /// Judge a run to this step, as `run --steps` would make it.
        #[arg(long, value_parser = whole_steps, conflicts_with = "end_time")]
        steps: Option<u64>,
        /// Judge a run to this simulated time (s), as `run --end-time` would make it.
        #[arg(long, value_name = "SECONDS", value_parser = positive_seconds)]
        end_time: Option<f64>,
    },
    /// Print version, threads, ranks and the GPU adapters wgpu finds.
    Info {
        /// Worker threads, as `run --threads` would use them (default: all cores, or
        /// RAYON_NUM_THREADS).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Write a complete, commented scene of one kind to start from (stdout, or `--out`).
    Template {
        /// The kind of scene.
        #[arg(value_enum)]
        kind: TemplateKind,
        /// Write it to this file (refused when the file exists).
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

/// The scene templates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TemplateKind {
    /// A fluid: flow past a cylinder in a channel, with probes and the drag analysis.
    Fluid,
    /// Fluid and grains: a disk settling in water.
    Coupled,
    /// Dry grains: a granular column collapse.
    Grains,
    /// A continuum: a Mohr–Coulomb column collapse (MPM).
    Mpm,
}

impl TemplateKind {
    /// The template's text (`templates/*.toml`, compiled in).
    pub fn text(self) -> &'static str {
        match self {
            TemplateKind::Fluid => include_str!("../templates/fluid.toml"),
            TemplateKind::Coupled => include_str!("../templates/coupled.toml"),
            TemplateKind::Grains => include_str!("../templates/grains.toml"),
            TemplateKind::Mpm => include_str!("../templates/mpm.toml"),
        }
    }
}

/// A finite, positive number of seconds (`--end-time`).
fn positive_seconds(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 => Ok(t),
        Ok(t) => Err(format!("{t} is not a positive, finite time in seconds")),
        Err(e) => Err(format!("{text:?} is not a number of seconds: {e}")),
    }
}

/// A step count of at least 1 (`--steps`).
fn whole_steps(text: &str) -> Result<u64, String> {
    match text.parse::<u64>() {
        Ok(0) => Err("a run takes at least one step: give --steps 1 or more".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(format!("{text:?} is not a whole number of steps: {e}")),
    }
}

/// The arguments of `grainflow run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Output folder (default: runs/<scene name>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Precision, overriding the scene's.
    #[arg(long, value_enum)]
    pub precision: Option<PrecisionArg>,
    /// Worker threads (default: all cores, or RAYON_NUM_THREADS).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Run to this step (at least 1), overriding the scene's length; any kind of scene.
    #[arg(long, value_parser = whole_steps, conflicts_with = "end_time")]
    pub steps: Option<u64>,
    /// Run to this simulated time (s), overriding the scene's length; any kind of scene.
    #[arg(long, value_name = "SECONDS", value_parser = positive_seconds)]
    pub end_time: Option<f64>,
    /// No progress output.
    #[arg(long)]
    pub quiet: bool,
    /// Continue from a checkpoint (e.g. runs/NAME/checkpoint.h5), on any rank count.
    #[arg(long, value_name = "CHECKPOINT")]
    pub restart: Option<PathBuf>,
    /// Device of the fluid solver, overriding the scene's `[run] backend`.
    #[arg(long, value_enum)]
    pub backend: Option<BackendArg>,
    /// GPU population storage, overriding the scene's `[run] gpu_storage`: `f16` halves
    /// memory and traffic (f32 arithmetic; needs `--backend gpu --precision f32`).
    #[arg(long, value_enum)]
    pub gpu_storage: Option<GpuStorageArg>,
    /// CPU kernel, overriding the scene's `[run] kernel`: `in-place` (the AA pattern)
    /// halves the memory; `auto` takes it where it measured faster.
    #[arg(long, value_enum)]
    pub kernel: Option<KernelArg>,
    /// What idle worker threads do while the time loop runs: `active` keeps them
    /// looking for work (as OMP_WAIT_POLICY=active; the coupled step about 2 % shorter on 2
    /// cores), `passive` lets them sleep; `auto` is active unless the threads of the
    /// ranks on this node outnumber its cores.
    #[arg(long, value_enum, default_value = "auto")]
    pub wait_policy: WaitPolicyArg,
    /// Start even when the run would take more than 10⁹ steps or more memory than this
    /// node has (both are refused otherwise, with the figures).
    #[arg(long)]
    pub force: bool,
}

/// The scene's precision for `--precision`.
pub fn precision_of(p: PrecisionArg) -> Precision {
    match p {
        PrecisionArg::F32 => Precision::F32,
        PrecisionArg::F64 => Precision::F64,
    }
}

/// The scene's backend for `--backend`.
pub fn backend_of(b: BackendArg) -> Backend {
    match b {
        BackendArg::Cpu => Backend::Cpu,
        BackendArg::Gpu => Backend::Gpu,
    }
}

/// The scene's kernel for `--kernel`.
pub fn kernel_of(k: KernelArg) -> Kernel {
    match k {
        KernelArg::Auto => Kernel::Auto,
        KernelArg::TwoArray => Kernel::TwoArray,
        KernelArg::InPlace => Kernel::InPlace,
    }
}
