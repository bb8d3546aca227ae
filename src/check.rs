//! `grainflow check SCENE`: what a run of a validated scene of any kind will use (lattice
//! and units, steps, memory, the stability verdicts), refusing what `run` would refuse for
//! its size. The binary prints the report; the scene fuzzer runs the same assessment.

use crate::error::RunError;
use crate::run::{step_count, Precision};
use crate::{budget, time_loop};

/// A line of the report.
macro_rules! say {
    ($out:expr, $($t:tt)*) => { $out.push(format!($($t)*)) };
}

/// What `check` reports: the lines to print and the exit status (0 the scene may run, 1
/// `run` would refuse it for its size, 2 the coupled run is likely unstable).
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// The lines to print, in order.
    pub lines: Vec<String>,
    /// The exit status.
    pub code: i32,
}

/// What `run` would refuse besides (a check that names no result, an unreadable mask), with
/// the report's lines before it.
#[derive(Debug)]
pub struct Refused {
    /// The lines assessed before the refusal.
    pub lines: Vec<String>,
    /// Why.
    pub error: RunError,
}

/// Assess a validated scene for a run on `ranks` ranks sharing a node of `memory` bytes
/// (`None`: unknown). Builds the lattice (obstacles, mask images) only when the run's memory
/// is admitted, so no more than `run` would allocate is allocated. With `timed`, the fluid
/// kernel is measured on this machine (about 0.3 s) for the wall-time estimate, and an
/// operator whose rates the stability map did not measure is run on the spot.
pub fn assess(
    any: &scene::AnyScene,
    ranks: usize,
    memory: Option<f64>,
    timed: bool,
) -> Result<Report, Refused> {
    let mut lines = Vec::new();
    match assess_into(any, (ranks, memory, timed), &mut lines) {
        Ok(code) => Ok(Report { lines, code }),
        Err(error) => Err(Refused { lines, error }),
    }
}

fn assess_into(
    any: &scene::AnyScene,
    (ranks, memory, timed): (usize, Option<f64>, bool),
    out: &mut Vec<String>,
) -> Result<i32, RunError> {
    // A coupled scene's grains and DEM sub-steps per fluid step, from the coupling plan
    // `print_check` reads (for the wall-time estimate).
    let mut dem_load = None;
    let cost = match any {
        scene::AnyScene::Fluid(s) => {
            let (stable, load) = print_check(s, timed, out);
            dem_load = load;
            if !stable {
                say!(
                    out,
                    "  refused: the coupled run is likely unstable (see above)"
                );
                return Ok(2);
            }
            let one = s.scene.run.backend == scene::Backend::Cpu
                && crate::simulation::in_place(s.scene.run.kernel, s.scene.grains.is_some());
            let bytes = match s.scene.run.precision {
                Precision::F32 => 4.0,
                Precision::F64 => 8.0,
            };
            Some(budget::fluid_cost(s, step_count(s), bytes, one, ranks))
        }
        scene::AnyScene::Grains(g) => {
            say!(out, "{}: valid grains scene", g.path.display());
            say!(out, "  title: {}", g.scene.title);
            say!(out, "  walls: {}", g.scene.grains.walls.len());
            say!(out, "  stability: {}", dem_verdict(g.lambda()));
            for w in &g.warnings {
                say!(out, "  warning: {w}");
            }
            g.planned_time_step().map(|dt| {
                let r = &g.scene.run;
                let steps = time_loop::particle_last_step(length_of(r.steps, r.end_time_s), dt);
                say!(out, "  time step: {dt:.4e} s (the smallest grain's)");
                let grains = g.estimated_grains().unwrap_or(0.0);
                budget::grain_cost(grains, steps, ranks)
            })
        }
        scene::AnyScene::Mpm(m) => {
            print_mpm_check(m, out);
            let r = &m.scene.run;
            let steps = time_loop::particle_last_step(length_of(r.steps, r.end_time_s), m.setup.dt);
            Some(budget::mpm_cost(m, steps, ranks))
        }
    };
    let Some(cost) = cost else {
        say!(out, "  steps: decided by the grains of the sample file");
        return Ok(0);
    };
    say!(out, "  steps: {}", cost.steps);
    if timed {
        say!(
            out,
            "  wall time: {}",
            wall_time(any, dem_load, cost.steps, ranks)
        );
    }
    say!(
        out,
        "  memory: about {:.1} MiB in all, {ranks} rank(s)",
        cost.memory_bytes / 1048576.0
    );
    // Judged as if all the ranks shared this node (a login node, say, cannot know).
    if let Some(why) = budget::objection(cost, ranks, ranks, memory) {
        say!(out, "  refused: {why}");
        return Ok(1);
    }
    // The obstacles as `run` draws them (a mask image is read and checked here too).
    if let scene::AnyScene::Fluid(s) = any {
        crate::run::check_quantities(s)?;
        let built = scene::build_lattice(s)?;
        let grains = s.scene.grains.is_some();
        for (o, cells) in s.scene.obstacles.iter().zip(&built.obstacle_cells) {
            let wall = match o.circle_wall(grains) {
                Some(scene::CircleWall::Interpolated) => "curved wall (interpolated bounce-back)",
                _ => "staircase (half-way bounce-back on the cells inside)",
            };
            say!(
                out,
                "  obstacle `{}`: {wall}, {cells} cells inside",
                o.name()
            );
        }
    }
    Ok(0)
}

/// What a coupled scene's grains cost a step, as `check` estimates it.
#[derive(Debug, Clone, Copy)]
struct CoupledLoad {
    /// Grains (a packed sample's estimate before any trim).
    grains: f64,
    /// DEM sub-steps per fluid step.
    substeps: u32,
}

/// The coupling's cost per grain and step, in updates of the measured fluid kernel: the
/// coupling passes and what a grain's partially saturated or link cells add to the sweep.
/// Measured on 2 cores, each run less its plain fluid sweep and its DEM stage: 1620 in the
/// medium submarine landslide (dense, 10 994 grains of 4.6 cells across, 2 threads,
/// flowing to its end; 1590 before its packing was numbered in space), 1830 in the large one (208 778 grains, 2 ranks, at rest; measured
/// before partially saturated chunks with contacts were blended in lanes, which cut the
/// medium one's from 3100) and about 1600 in the seed's Table 5.3 case (2500 disks); the
/// estimate takes 1700, within 10 % of each.
const COUPLING_CELLS_PER_GRAIN: f64 = 1700.0;

/// The estimated wall time of a run of `steps` steps, on this machine and on `ranks` ranks
/// of its size, with what it counts; `dem_load` is a coupled scene's grains.
fn wall_time(
    any: &scene::AnyScene,
    dem_load: Option<CoupledLoad>,
    steps: u64,
    ranks: usize,
) -> String {
    use budget::walltime::{human, measure_fluid, Rates};
    let threads = rayon::current_num_threads();
    let (work_s, basis) = match any {
        scene::AnyScene::Fluid(s) => {
            let collision = scene::lattice_collision(&s.scene.fluid.collision);
            let one = crate::simulation::in_place(s.scene.run.kernel, s.scene.grains.is_some());
            let [nx, ny] = s.scene.domain.cells;
            // A 512² box, larger than the caches as production lattices are; small lattices
            // run slower per cell than it (their per-step costs weigh more) and are
            // underestimated, as docs/scenes.md says.
            let rate = match s.scene.run.precision {
                Precision::F32 => measure_fluid::<f32>(collision, one, 512, 0.3),
                Precision::F64 => measure_fluid::<f64>(collision, one, 512, 0.3),
            };
            let rates = Rates::with_fluid(rate, threads);
            let fluid = (nx * ny) as f64 * steps as f64 / rates.fluid_cells_per_s;
            match dem_load {
                Some(load) => {
                    let grain_steps = load.grains * steps as f64;
                    let dem = grain_steps * load.substeps as f64 / rates.grain_steps_per_s;
                    let coupling = grain_steps * COUPLING_CELLS_PER_GRAIN / rates.fluid_cells_per_s;
                    (
                        fluid + dem + coupling,
                        format!(
                            "the fluid at {:.0} MLUPS measured here, about {:.0} grains with \
                             {} DEM sub-steps, and the coupling at the cost of \
                             {COUPLING_CELLS_PER_GRAIN:.0} fluid cell updates per grain and \
                             step (measured on three coupled cases, within 10 %)",
                            rate / 1e6,
                            load.grains,
                            load.substeps,
                        ),
                    )
                }
                None => (
                    fluid,
                    format!("the fluid kernel measured here at {:.0} MLUPS", rate / 1e6),
                ),
            }
        }
        scene::AnyScene::Grains(g) => {
            let rates = Rates::with_fluid(0.0, threads);
            let grains = g.estimated_grains().unwrap_or(0.0);
            (
                grains * steps as f64 / rates.grain_steps_per_s,
                format!(
                    "about {grains:.0} grains (a packed sample before any trim) at the \
                     benchmarks' {:.1} M grain-steps/s; a settling \
                             phase adds its own steps",
                    rates.grain_steps_per_s / 1e6
                ),
            )
        }
        scene::AnyScene::Mpm(m) => {
            let rates = Rates::with_fluid(0.0, threads);
            let points = m.points.len() as f64;
            (
                points * steps as f64 / rates.point_steps_per_s,
                format!(
                    "{points:.0} points at the benchmarks' {:.1} M point-steps/s",
                    rates.point_steps_per_s / 1e6
                ),
            )
        }
    };
    let about = |s: f64| match human(s) {
        h if h.starts_with("under") => h,
        h => format!("about {h}"),
    };
    let mut line = format!(
        "{} on this machine ({threads} thread(s)): {basis}",
        about(work_s)
    );
    // A fluid or coupled scene's simulated time, for the rate a batch job is planned by.
    let simulated_s = match any {
        scene::AnyScene::Fluid(s) => s.units.dt_s * steps as f64,
        _ => 0.0,
    };
    if ranks > 1 {
        // The measured 2-rank efficiency (README: 87 %) as a guide.
        line.push_str(&format!(
            "; on {ranks} ranks of this size {}",
            about(work_s / (0.85 * ranks as f64))
        ));
    }
    if simulated_s > 0.0 {
        line.push_str(&format!(
            "; {} per simulated second{}",
            human(work_s / simulated_s / (0.85 * ranks as f64).max(1.0)),
            if ranks > 1 {
                format!(" on {ranks} ranks")
            } else {
                String::new()
            }
        ));
    }
    line
}

/// What `check` prints about an MPM scene.
fn print_mpm_check(m: &scene::ValidMpmScene, out: &mut Vec<String>) {
    let spec = m.setup.spec;
    say!(out, "{}: valid MPM scene", m.path.display());
    say!(out, "  title: {}", m.scene.title);
    say!(
        out,
        "  grid: {} × {} cells of {} m; {} shape functions, {} update",
        spec.nx,
        spec.ny,
        spec.h,
        format!("{:?}", m.setup.shape).to_lowercase(),
        format!("{:?}", m.setup.scheme).to_lowercase()
    );
    say!(out, "  material points: {}", m.points.len());
    say!(
        out,
        "  time step: {:.4e} s (CFL limit {:.4e} s)",
        m.setup.dt,
        m.critical_dt
    );
    let c = m.setup.dt / m.critical_dt;
    let verdict = match stability::mpm::courant_limit(stability::MPM_CSV) {
        Some(l) if c <= l => format!(
            "Courant number {c:.3}: inside the measured stable range (stable up to {l}, jobs/stability/mpm-courant.csv)"
        ),
        Some(l) => format!(
            "Courant number {c:.3}: likely unstable (measured stable only up to {l}): shorten the time step"
        ),
        None => format!("Courant number {c:.3}: no measured limit"),
    };
    say!(out, "  stability: {verdict}");
    for w in &m.warnings {
        say!(out, "  warning: {w}");
    }
}

/// The DEM time-step factor λ against the measured limit (jobs/stability/dem-lambda.csv).
fn dem_verdict(lambda: f64) -> String {
    match stability::dem::lambda_limit(stability::DEM_CSV) {
        Some(l) if lambda <= l => format!(
            "time-step factor λ = {lambda:.3}: inside the measured stable range (energy does not grow up to λ = {l}, jobs/stability/dem-lambda.csv)"
        ),
        Some(l) => format!(
            "time-step factor λ = {lambda:.3}: likely unstable (energy measured not to grow only up to λ = {l}): lower lambda"
        ),
        None => format!("time-step factor λ = {lambda:.3}: no measured limit"),
    }
}

/// What `check` prints about a fluid (or coupled) scene: false when the coupled stability
/// map says the run is likely unstable, and a coupled scene's (grains, DEM sub-steps per
/// fluid step).
fn print_check(
    s: &scene::ValidScene,
    measure: bool,
    out: &mut Vec<String>,
) -> (bool, Option<CoupledLoad>) {
    let u = &s.units;
    let [nx, ny] = s.scene.domain.cells;
    say!(
        out,
        "scene {} is valid{}",
        s.path.display(),
        if s.scene.title.is_empty() {
            String::new()
        } else {
            format!(": {}", s.scene.title)
        }
    );
    say!(
        out,
        "  lattice          {nx} × {ny} cells, Δx = {:.6e} m",
        u.dx_m
    );
    say!(out, "  time step        Δt = {:.6e} s", u.dt_s);
    say!(out, "  relaxation time  τ = {:.6}", u.tau);
    say!(out, "  lattice ν        {:.6e}", u.nu_lattice);
    say!(
        out,
        "  lattice velocity {:.6} (Mach {:.4})",
        u.u_lattice,
        u.mach
    );
    say!(out, "  stability        {}", fluid_verdict(s, measure));
    say!(out, "  Reynolds number  {:.4}", u.reynolds);
    // The in-place kernel (the CPU default) holds one distribution buffer.
    let one = s.scene.run.backend == scene::Backend::Cpu
        && crate::simulation::in_place(s.scene.run.kernel, s.scene.grains.is_some());
    let buffers = if one { 1.0 } else { 2.0 };
    let snapshot = |b: f64| budget::snapshot_bytes_per_cell(&s.scene.output, 1, b);
    let bytes = |b: f64| budget::fluid_bytes([nx, ny], buffers, b, snapshot(b));
    say!(
        out,
        "  memory estimate  {:.1} MiB in f64, {:.1} MiB in f32 ({} distribution buffer{}, cell types{})",
        bytes(8.0) / 1048576.0,
        bytes(4.0) / 1048576.0,
        buffers,
        if one { ", in place" } else { "s" },
        match (
            budget::snapshot_bytes_per_cell(&s.scene.output, 1, 0.0) > 0.0,
            snapshot(4.0) > 0.0
        ) {
            (true, _) => ", snapshot fields",
            (false, true) => ", checkpoint copy",
            _ => "",
        }
    );
    let mut stable = true;
    let mut load = None;
    match crate::coupled::plan(s) {
        Ok(Some(p)) => {
            let grains = p.grains.map(|n| n as f64).or_else(|| {
                let spec = s.scene.grains.as_ref()?;
                scene::estimated_grains(&spec.sample)
            });
            load = Some(CoupledLoad {
                grains: grains.unwrap_or(0.0),
                substeps: p.substeps,
            });
            say!(
                out,
                "  coupling         {} with {} DEM sub-steps per fluid step (Δt_D = {:.4e} s){}",
                p.scheme.name(),
                p.substeps,
                p.dem_time_step_s,
                if p.force_averaging {
                    ", force averaged over two steps"
                } else {
                    ""
                }
            );
            let (a, b) = p.cells_per_diameter;
            say!(
                out,
                "  grains           {}; {a:.1}–{b:.1} cells per diameter",
                p.grains
                    .map(|n| n.to_string())
                    .unwrap_or_else(|| "packed at run time".into())
            );
            say!(out, "  DEM stability    {}", dem_verdict(p.dem_lambda));
            if let Some(g) = &s.scene.grains {
                use stability::coupled;
                let case = coupled::CoupledCase {
                    scheme: p.scheme.name().to_string(),
                    cells_per_diameter: a,
                    density_ratio: g.density_kg_m3 / s.scene.fluid.density_kg_m3,
                    tau: u.tau,
                    lattice_velocity: u.u_lattice,
                };
                let map = coupled::parse(coupled::COUPLED_CSV);
                let v = coupled::verdict(&map, &case);
                say!(out, "  coupled stability {}", v.describe(&case));
                stable = !matches!(
                    v,
                    coupled::CoupledVerdict::Unstable(_)
                        | coupled::CoupledVerdict::BelowStableTau(_)
                );
            }
        }
        Ok(None) => {}
        Err(e) => say!(out, "  coupling: {e}"),
    }
    for w in &s.warnings {
        say!(out, "  warning: {w}");
    }
    (stable, load)
}

/// The fluid's stability verdict: from the measured map when the scene's operator has the
/// rates the map measured; otherwise, with `measure`, both test flows are run on the spot
/// with the scene's own rates at its τ and Mach (64², 10 000 steps each, about two
/// seconds).
fn fluid_verdict(s: &scene::ValidScene, measure: bool) -> String {
    use stability::lbm::{run_rates, Flow, Operator, Rates};
    let (u, f) = (&s.units, &s.scene.fluid);
    let rates = Rates {
        collision: scene::lattice_collision(&f.collision),
        smagorinsky: f.smagorinsky_constant,
    };
    let op = Operator::of(&rates.collision, f.smagorinsky_constant.is_some());
    let by_map = stability::StabilityMap::builtin().verdict(&op, u.tau, u.mach);
    if op.measured(&rates.collision, rates.smagorinsky) {
        return by_map.describe(&op, u.tau, u.mach);
    }
    if !measure {
        return format!(
            "judged with the map's rates, not this scene's: {}",
            by_map.describe(&op, u.tau, u.mach)
        );
    }
    let (n, steps) = (stability::LBM_SIZE, stability::LBM_STEPS);
    let run = |flow| run_rates(flow, rates, u.tau, u.mach, n, steps);
    let (shear, cavity) = rayon::join(|| run(Flow::ShearLayer), || run(Flow::Cavity));
    let word = |ok: bool| {
        if ok {
            "stable"
        } else {
            "blew up or overshot 1.5 × its driving speed"
        }
    };
    let measured = format!(
        "measured now with this scene's rates ({}) at τ = {:.4}, Ma = {:.3}: shear layer {}, cavity {} ({n}², {steps} steps)",
        rates_text(&rates),
        u.tau,
        u.mach,
        word(shear),
        word(cavity)
    );
    match (shear, cavity) {
        (true, true) => format!("inside the stable region, {measured}"),
        (false, false) => format!(
            "likely unstable, {measured}: raise τ, lower the lattice velocity, or change the rates"
        ),
        _ => format!(
            "stable in one test flow only, {measured}: which one this scene resembles decides"
        ),
    }
}

/// The rates of an operator, for a report.
fn rates_text(r: &stability::lbm::Rates) -> String {
    use lbm::collision::Collision;
    let op = match r.collision {
        Collision::Bgk => "BGK".to_string(),
        Collision::Trt { magic } => format!("TRT Λ = {magic}"),
        Collision::Mrt { s_e, s_eps, s_q } => format!(
            "MRT s_e = {s_e}, s_ε = {s_eps}, s_q = {}",
            s_q.map_or("from Λ = 3/16".to_string(), |q| q.to_string())
        ),
    };
    match r.smagorinsky {
        Some(c) => format!("{op}, Smagorinsky C_s = {c}"),
        None => op,
    }
}

/// A `[run]` section's length.
fn length_of(steps: Option<u64>, end_time_s: Option<f64>) -> crate::run::Length {
    crate::run::Length { steps, end_time_s }
}
