//! The `grainflow` binary: parse the CLI, load the scene, run it. The only place that uses anyhow.

mod cli;
mod malloc;
mod report;

use anyhow::{Context, Result};
use clap::Parser;
use cli::{
    backend_of, kernel_of, precision_of, Cli, Command, GpuStorageArg, RunArgs, WaitPolicyArg,
};
use decomposition::{launched_by_mpi, Comm, MpiComm, SingleProcess};
use grainflow::driver::RunHeader;
use grainflow::pool::{in_pool, WaitPolicy};
use grainflow::run::{run_on, step_count, GpuStorage, Overrides, RunError, RunOptions, Status};
use grainflow::scene;
use report::{exit_code, report};

fn main() {
    report::STARTED.get_or_init(std::time::SystemTime::now);
    // Writing to a closed pipe (`grainflow check … | head`) ends the process quietly, as
    // for other command-line tools, instead of panicking in println!.
    #[cfg(unix)]
    // SAFETY: restoring a signal's default disposition at start-up, before any thread.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    malloc::fix_mmap_threshold();
    match real_main() {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            // One write of the whole line: under mpirun, ranks that fail together then never
            // interleave inside each other's message (a write under 4 KiB to a pipe is atomic).
            use std::io::Write;
            let line = format!("error: {}\n", describe(&e));
            let _ = std::io::stderr().write_all(line.as_bytes());
            std::process::exit(1);
        }
    }
}

/// An error with its causes, each cause once: the libraries' messages often quote their
/// cause already ("cannot read scene file …: No such file or directory"), and the chain
/// would repeat it.
fn describe(e: &anyhow::Error) -> String {
    let mut out = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !out.contains(&c) {
            out.push_str(": ");
            out.push_str(&c);
        }
    }
    out
}

/// The communicator of this process: MPI when started by a launcher (mpirun, srun),
/// otherwise a single process that never initialises MPI.
fn communicator() -> Result<Box<dyn Comm>> {
    if launched_by_mpi() {
        let c = MpiComm::init().context("initialising MPI")?;
        Ok(Box::new(c))
    } else {
        Ok(Box::new(SingleProcess))
    }
}

/// Exit status of a command line that could not be parsed (BSD's EX_USAGE), distinct from
/// 2 (a check failed).
const EXIT_USAGE: i32 = 64;

fn real_main() -> Result<i32> {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // --help and --version print to stdout and succeed; anything else is a usage error.
            let code = if e.use_stderr() { EXIT_USAGE } else { 0 };
            let _ = e.print();
            return Ok(code);
        }
    };
    match cli.command {
        Command::Info { threads } => info(threads),
        Command::Template { kind, out } => template(kind, out),
        Command::Check {
            scene,
            ranks,
            threads,
            precision,
            backend,
            kernel,
            steps,
            end_time,
        } => {
            let overrides = Overrides {
                precision: precision.map(precision_of),
                backend: backend.map(backend_of),
                kernel: kernel.map(kernel_of),
                steps,
                end_time_s: end_time,
                gpu_storage: None,
            };
            check(&scene, ranks, threads, &overrides)
        }
        Command::StabilityMap { out, threads } => stability_map(out, threads),
        Command::Run(args) => run(args),
    }
}

/// `grainflow check SCENE`: validate any kind of scene and print what a run will use (with
/// `overrides`, the run those options of `run` make); a run that `run` would refuse for its
/// size (on `ranks` ranks) fails the check.
fn check(
    scene: &std::path::Path,
    ranks: usize,
    threads: Option<usize>,
    overrides: &Overrides,
) -> Result<i32> {
    if let Some(t) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .context("setting up the thread pool")?;
    }
    let mut any = grainflow::scene::load_any(scene)?;
    overrides.apply(&mut any)?;
    let memory = grainflow::budget::machine_memory_bytes();
    let report = grainflow::check::assess(&any, ranks, memory, true);
    // What was assessed before a refusal is printed first, as it always was.
    let (lines, outcome) = match report {
        Ok(r) => (r.lines, Ok(r.code)),
        Err(grainflow::check::Refused { lines, error }) => (lines, Err(error)),
    };
    for l in lines {
        println!("{l}");
    }
    Ok(outcome?)
}

/// `grainflow info`: version, threads, ranks and the GPU adapters.
fn info(threads: Option<usize>) -> Result<i32> {
    if let Some(t) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .context("setting up the thread pool")?;
    }
    println!("grainflow {}", env!("CARGO_PKG_VERSION"));
    println!(
        "threads: {} (rayon; set --threads or RAYON_NUM_THREADS)",
        rayon::current_num_threads()
    );
    println!("precisions: f32, f64 (CPU kernel, structure-of-arrays, fused pull stream-collide)");
    let comm = communicator()?;
    println!(
        "ranks: {} (MPI slab decomposition along x; start with mpirun -np N)",
        comm.size()
    );
    let adapters = grainflow::lbm::gpu::list_adapters();
    if adapters.is_empty() {
        println!("GPU adapters: none found (install a Vulkan driver; `--backend gpu` needs one)");
    } else {
        println!("GPU adapters (wgpu; `--backend gpu` picks the first discrete GPU, or GRAINFLOW_GPU_ADAPTER=i):");
    }
    for (i, a) in adapters.iter().enumerate() {
        println!(
            "  [{i}] {} — {}, {}, driver {}; f64: {}, f16: {}; largest storage binding {} MiB, buffer {} MiB, {} storage buffers per stage",
            a.name,
            a.backend,
            a.device_type,
            a.driver.trim(),
            if a.f64 { "yes" } else { "no (f32 only)" },
            if a.f16 { "yes" } else { "no" },
            a.max_storage_binding >> 20,
            a.max_buffer >> 20,
            a.max_storage_buffers
        );
    }
    Ok(0)
}

/// `grainflow template KIND`: a complete, commented scene to start from, on stdout or into
/// a new file.
fn template(kind: cli::TemplateKind, out: Option<std::path::PathBuf>) -> Result<i32> {
    let text = kind.text();
    match out {
        None => print!("{text}"),
        Some(path) => {
            let mut file = std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
                .with_context(|| {
                    format!("creating {} (an existing file is kept)", path.display())
                })?;
            use std::io::Write;
            file.write_all(text.as_bytes())
                .with_context(|| format!("writing {}", path.display()))?;
            eprintln!(
                "wrote {}; check it with `grainflow check {0}`, run it with `grainflow run {0}`",
                path.display()
            );
        }
    }
    Ok(0)
}

/// `grainflow stability-map`: measure the stability limits and write the maps.
fn stability_map(out: Option<std::path::PathBuf>, threads: Option<usize>) -> Result<i32> {
    if let Some(t) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .context("setting up the thread pool")?;
    }
    // Into a folder of the user's, never the shipped maps unless asked (--out jobs/stability).
    let dir = out.unwrap_or_else(|| std::path::PathBuf::from("stability-map"));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    // The MPM map's scene is built in, so the command runs from any folder.
    const MPM_SCENE: &str = include_str!("../tests/scenes/mpm_collapse.toml");
    let mpm_path = std::path::Path::new("tests/scenes/mpm_collapse.toml");
    let mpm = match scene::parse_any(MPM_SCENE, mpm_path)? {
        scene::AnyScene::Mpm(m) => m,
        _ => anyhow::bail!("tests/scenes/mpm_collapse.toml is not an MPM scene"),
    };
    println!("{}", stability_map_estimate());
    let t = std::time::Instant::now();
    let summary = grainflow::stability::write_maps(&dir, &mpm)
        .with_context(|| format!("writing the maps into {}", dir.display()))?;
    print!("{summary}");
    println!(
        "wrote {}/lbm-map.csv, dem-lambda.csv, mpm-courant.csv in {:.0} s",
        dir.display(),
        t.elapsed().as_secs_f64()
    );
    Ok(0)
}

/// What the stability maps will cost on this machine: the fluid map's cell updates at the
/// measured single-thread speed of its 64² boxes (an upper bound: unstable runs stop early),
/// spread over the pool's threads.
fn stability_map_estimate() -> String {
    use grainflow::budget::walltime::{human, measure_fluid};
    use grainflow::stability as st;
    let runs =
        st::lbm::Flow::ALL.len() * st::lbm::Operator::ALL.len() * st::TAUS.len() * st::MACHS.len();
    let cells = runs as f64 * (st::LBM_SIZE * st::LBM_SIZE * st::LBM_STEPS) as f64;
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map(|p| {
            p.install(|| {
                measure_fluid::<f64>(grainflow::lbm::Collision::Bgk, false, st::LBM_SIZE, 0.2)
            })
        })
        .unwrap_or(f64::NAN);
    let threads = rayon::current_num_threads();
    format!(
        "stability maps: {runs} fluid runs of {0}² cells × {1} steps (at most about {2} on {threads} thread(s) at the measured {3:.0} MLUPS per thread), then {4} DEM and {5} MPM runs",
        st::LBM_SIZE,
        st::LBM_STEPS,
        human(cells / (one * threads as f64)),
        one / 1e6,
        st::LAMBDAS.len(),
        st::COURANTS.len()
    )
}

/// `grainflow run`: any kind of scene, on every rank of the launch.
fn run(args: RunArgs) -> Result<i32> {
    let RunArgs {
        scene,
        out,
        precision,
        threads,
        steps,
        end_time,
        quiet,
        restart,
        backend,
        gpu_storage,
        kernel,
        wait_policy,
        force,
    } = args;
    // SIGTERM and SIGUSR1 are caught from here on: during set-up they stop the run at its
    // first step, with a checkpoint of the initial state.
    grainflow::driver::Signals::install();
    let comm = communicator()?;
    let comm = comm.as_ref();
    if let Some(t) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .context("setting up the thread pool")?;
    }
    let spin = match wait_policy {
        WaitPolicyArg::Auto => WaitPolicy::Auto,
        WaitPolicyArg::Active => WaitPolicy::Active,
        WaitPolicyArg::Passive => WaitPolicy::Passive,
    }
    .spins_here(comm);
    let overrides = Overrides {
        precision: precision.map(precision_of),
        backend: backend.map(backend_of),
        gpu_storage: gpu_storage.map(|g| match g {
            GpuStorageArg::Native => GpuStorage::Native,
            GpuStorageArg::F16 => GpuStorage::F16,
        }),
        kernel: kernel.map(kernel_of),
        steps,
        end_time_s: end_time,
    };
    let mut any = scene::load_any(&scene)?;
    let opts = RunOptions {
        out_dir: out.unwrap_or_else(|| default_out(&scene)),
        scene_length: overrides.apply(&mut any)?,
        progress: !quiet,
        restart,
        force,
    };
    match any {
        scene::AnyScene::Fluid(s) => in_pool(comm, spin, || run_fluid_scene(&s, &opts, spin, comm)),
        scene::AnyScene::Grains(g) => in_pool(comm, spin, || run_grain_scene(&g, &opts, comm)),
        scene::AnyScene::Mpm(m) => in_pool(comm, spin, || run_mpm_scene(&m, &opts, comm)),
    }
}

/// Run a fluid (or coupled) scene and report its end.
fn run_fluid_scene(
    s: &scene::ValidScene,
    opts: &RunOptions,
    spin: bool,
    comm: &dyn decomposition::Comm,
) -> Result<i32> {
    if comm.is_root() {
        for w in &s.warnings {
            eprintln!("warning: {w}");
        }
        eprintln!(
            "running {} ({} steps, τ = {:.4}, Ma = {:.3}, Re = {:.4}) on {} rank(s) × {} threads{}",
            s.path.display(),
            step_count(s),
            s.units.tau,
            s.units.mach,
            s.units.reynolds,
            comm.size(),
            rayon::current_num_threads(),
            if spin { " (idle workers active)" } else { "" }
        );
    }
    let summary = match run_on(s, opts, comm) {
        Err(RunError::Interrupted(why)) => {
            let solver = if s.scene.grains.is_some() {
                "coupled"
            } else {
                "fluid"
            };
            let header = RunHeader::new(
                solver,
                s.path.clone(),
                s.scene.title.clone(),
                s.warnings.clone(),
                comm,
            );
            return stopped_before_start(header, why, &opts.out_dir, comm);
        }
        other => other?,
    };
    if !comm.is_root() {
        return Ok(exit_code(summary.run.status));
    }
    println!(
        "{} steps in {:.2} s: {:.1} MLUPS (kernel {:.1})",
        summary.run.steps - summary.run.restarted_from_step,
        summary.run.wall_time_s,
        summary.mlups,
        summary.kernel_mlups
    );
    Ok(report(&summary.run, &opts.out_dir))
}

/// What a grain or MPM run's first log line adds when its idle workers look for work (it
/// prints from inside [`in_pool`]).
fn active_note() -> &'static str {
    if grainflow::pool::idle_workers_active() {
        " (idle workers active)"
    } else {
        ""
    }
}

/// The default output folder of a scene: `runs/<stem>` (`runs/<folder>` for `scene.toml`).
fn default_out(scene: &std::path::Path) -> std::path::PathBuf {
    let stem = scene
        .file_stem()
        .and_then(|x| x.to_str())
        .unwrap_or("scene");
    let parent = scene
        .parent()
        .and_then(|p| p.file_name())
        .and_then(|x| x.to_str())
        .unwrap_or("");
    let name = if stem == "scene" && !parent.is_empty() {
        parent
    } else {
        stem
    };
    std::path::PathBuf::from("runs").join(name)
}

/// Run a grains scene and report like a fluid run.
fn run_grain_scene(
    g: &scene::ValidGrainScene,
    opts: &RunOptions,
    comm: &dyn decomposition::Comm,
) -> Result<i32> {
    for w in &g.warnings {
        if comm.is_root() {
            eprintln!("warning: {w}");
        }
    }
    if comm.is_root() {
        eprintln!(
            "running grains scene {} on {} rank(s) × {} threads{}",
            g.path.display(),
            comm.size(),
            rayon::current_num_threads(),
            active_note()
        );
    }
    let summary = match grainflow::run_grains::run_grains(g, opts, comm) {
        Err(RunError::Interrupted(why)) => {
            let header = RunHeader::new(
                "grains",
                g.path.clone(),
                g.scene.title.clone(),
                g.warnings.clone(),
                comm,
            );
            return stopped_before_start(header, why, &opts.out_dir, comm);
        }
        other => other?,
    };
    if !comm.is_root() {
        return Ok(exit_code(summary.run.status));
    }
    // What the run found (grains that left the domain), after the scene's own warnings.
    for w in summary.run.warnings.iter().skip(g.warnings.len()) {
        eprintln!("warning: {w}");
    }
    println!(
        "{} grains, {} steps (Δt = {:.3e} s, settling {} steps) in {:.2} s: {:.2} M grain-steps/s, {} migrated",
        summary.grains,
        summary.run.steps - summary.run.restarted_from_step,
        summary.time_step_s,
        summary.settle_steps,
        summary.run.wall_time_s,
        summary.grain_steps_per_s / 1e6,
        summary.migrated
    );
    Ok(report(&summary.run, &opts.out_dir))
}

/// A run stopped by SIGTERM before its first step: a `summary.json` that says so (rank 0)
/// and exit status 4.
fn stopped_before_start(
    mut header: RunHeader,
    why: String,
    out: &std::path::Path,
    comm: &dyn decomposition::Comm,
) -> Result<i32> {
    header.status = Status::Interrupted;
    header.error = Some(why.clone());
    if comm.is_root() {
        grainflow::io::atomic::ensure_writable_dir(out)?;
        let json = grainflow::summary_units::summary_json(&header);
        grainflow::io::atomic::write_atomic(&out.join("summary.json"), &json)?;
        eprintln!("error: {why}");
    }
    Ok(exit_code(Status::Interrupted))
}

fn run_mpm_scene(
    m: &scene::ValidMpmScene,
    opts: &RunOptions,
    comm: &dyn decomposition::Comm,
) -> Result<i32> {
    if comm.is_root() {
        for w in &m.warnings {
            eprintln!("warning: {w}");
        }
        eprintln!(
            "running MPM scene {} on {} rank(s) × {} threads{}",
            m.path.display(),
            comm.size(),
            rayon::current_num_threads(),
            active_note()
        );
    }
    let summary = grainflow::run_mpm::run_mpm(m, opts, comm)?;
    if !comm.is_root() {
        return Ok(exit_code(summary.run.status));
    }
    println!(
        "{} material points, {} steps (Δt = {:.3e} s, CFL limit {:.3e} s) in {:.2} s: {:.2} M point-steps/s, {} migrated",
        summary.points,
        summary.run.steps - summary.run.restarted_from_step,
        summary.time_step_s,
        summary.critical_time_step_s,
        summary.run.wall_time_s,
        summary.point_steps_per_s / 1e6,
        summary.migrated
    );
    Ok(report(&summary.run, &opts.out_dir))
}
