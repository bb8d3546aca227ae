//! `grainflow check SCENE`: validate a scene of any kind and print what a run of it will use
//! (lattice and units, steps, memory, the stability verdicts), refusing what `run` would
//! refuse for its size.

use anyhow::Result;
use grainflow::run::{step_count, Precision};
use grainflow::scene;
use grainflow::{budget, time_loop};

/// `grainflow check SCENE`: validate any kind of scene and print what a run will use; a
/// run that `run` would refuse for its size (on `ranks` ranks) fails the check.
pub fn check(scene: &std::path::Path, ranks: usize) -> Result<i32> {
    let any = scene::load_any(scene)?;
    let cost = match &any {
        scene::AnyScene::Fluid(s) => {
            if !print_check(s) {
                println!("  refused: the coupled run is likely unstable (see above)");
                return Ok(2);
            }
            let one = s.scene.run.backend == grainflow::scene::Backend::Cpu
                && grainflow::simulation::in_place(s.scene.run.kernel, s.scene.grains.is_some());
            let bytes = match s.scene.run.precision {
                Precision::F32 => 4.0,
                Precision::F64 => 8.0,
            };
            Some(budget::fluid_cost(s, step_count(s, None, None), bytes, one))
        }
        scene::AnyScene::Grains(g) => {
            println!("{}: valid grains scene", g.path.display());
            println!("  title: {}", g.scene.title);
            println!("  walls: {}", g.scene.grains.walls.len());
            println!("  stability: {}", dem_verdict(g.lambda()));
            for w in &g.warnings {
                println!("  warning: {w}");
            }
            g.planned_time_step().map(|dt| {
                let r = &g.scene.run;
                let steps =
                    time_loop::particle_last_step((None, None), (r.steps, r.end_time_s), dt);
                println!("  time step: {dt:.4e} s (the smallest grain's)");
                let grains = g.estimated_grains().unwrap_or(0.0);
                budget::Cost {
                    steps,
                    memory_bytes: grains * budget::GRAIN_BYTES,
                }
            })
        }
        scene::AnyScene::Mpm(m) => {
            print_mpm_check(m);
            let r = &m.scene.run;
            let steps =
                time_loop::particle_last_step((None, None), (r.steps, r.end_time_s), m.setup.dt);
            Some(budget::mpm_cost(m, steps))
        }
    };
    let Some(cost) = cost else {
        println!("  steps: decided by the grains of the sample file");
        return Ok(0);
    };
    println!("  steps: {}", cost.steps);
    println!(
        "  memory: about {:.1} MiB in all, {ranks} rank(s)",
        cost.memory_bytes / 1048576.0
    );
    // Judged as if all the ranks shared this node (a login node, say, cannot know).
    if let Some(why) = budget::objection(cost, ranks, ranks, budget::machine_memory_bytes()) {
        println!("  refused: {why}");
        return Ok(1);
    }
    // The obstacles as `run` draws them (a mask image is read and checked here too).
    if let scene::AnyScene::Fluid(s) = &any {
        grainflow::run::check_quantities(s)?;
        scene::build_lattice(s)?;
    }
    Ok(0)
}

/// What `check` prints about an MPM scene.
fn print_mpm_check(m: &scene::ValidMpmScene) {
    let spec = m.setup.spec;
    println!("{}: valid MPM scene", m.path.display());
    println!("  title: {}", m.scene.title);
    println!(
        "  grid: {} × {} cells of {} m; {:?} shape functions, {:?} update",
        spec.nx, spec.ny, spec.h, m.setup.shape, m.setup.scheme
    );
    println!("  material points: {}", m.points.len());
    println!(
        "  time step: {:.4e} s (CFL limit {:.4e} s)",
        m.setup.dt, m.critical_dt
    );
    let c = m.setup.dt / m.critical_dt;
    let verdict = match grainflow::stability::mpm::courant_limit(grainflow::stability::MPM_CSV) {
        Some(l) if c <= l => format!(
            "Courant number {c:.3}: inside the measured stable range (stable up to {l}, jobs/stability/mpm-courant.csv)"
        ),
        Some(l) => format!(
            "Courant number {c:.3}: likely unstable (measured stable only up to {l}): shorten the time step"
        ),
        None => format!("Courant number {c:.3}: no measured limit"),
    };
    println!("  stability: {verdict}");
    for w in &m.warnings {
        println!("  warning: {w}");
    }
}

/// The DEM time-step factor λ against the measured limit (jobs/stability/dem-lambda.csv).
fn dem_verdict(lambda: f64) -> String {
    match grainflow::stability::dem::lambda_limit(grainflow::stability::DEM_CSV) {
        Some(l) if lambda <= l => format!(
            "time-step factor λ = {lambda:.3}: inside the measured stable range (energy does not grow up to λ = {l}, jobs/stability/dem-lambda.csv)"
        ),
        Some(l) => format!(
            "time-step factor λ = {lambda:.3}: likely unstable (energy measured not to grow only up to λ = {l}): lower lambda"
        ),
        None => format!("time-step factor λ = {lambda:.3}: no measured limit"),
    }
}

/// What `check` prints about a fluid (or coupled) scene; false when the coupled stability
/// map says the run is likely unstable.
fn print_check(s: &scene::ValidScene) -> bool {
    let u = &s.units;
    let [nx, ny] = s.scene.domain.cells;
    println!(
        "scene {} is valid{}",
        s.path.display(),
        if s.scene.title.is_empty() {
            String::new()
        } else {
            format!(": {}", s.scene.title)
        }
    );
    println!(
        "  lattice          {nx} × {ny} cells, Δx = {:.6e} m",
        u.dx_m
    );
    println!("  time step        Δt = {:.6e} s", u.dt_s);
    println!("  relaxation time  τ = {:.6}", u.tau);
    println!("  lattice ν        {:.6e}", u.nu_lattice);
    println!("  lattice velocity {:.6} (Mach {:.4})", u.u_lattice, u.mach);
    let family = match s.scene.fluid.collision {
        scene::CollisionModel::Bgk => "bgk",
        scene::CollisionModel::Trt { .. } => "trt",
        scene::CollisionModel::Mrt { .. } => "mrt",
    };
    let op = grainflow::stability::lbm::Operator::ALL
        .into_iter()
        .find(|o| {
            o.family == family && o.smagorinsky == s.scene.fluid.smagorinsky_constant.is_some()
        })
        .expect("every operator is in the map");
    let verdict = grainflow::stability::StabilityMap::builtin().verdict(&op, u.tau, u.mach);
    println!(
        "  stability        {}",
        verdict.describe(&op, u.tau, u.mach)
    );
    println!("  Reynolds number  {:.4}", u.reynolds);
    // The in-place kernel (the CPU default) holds one distribution buffer.
    let one = s.scene.run.backend == grainflow::scene::Backend::Cpu
        && grainflow::simulation::in_place(s.scene.run.kernel, s.scene.grains.is_some());
    let buffers = if one { 1.0 } else { 2.0 };
    let coupled = s.scene.grains.is_some();
    let bytes = |b: f64| budget::fluid_bytes([nx, ny], buffers, b, coupled);
    println!(
        "  memory estimate  {:.1} MiB in f64, {:.1} MiB in f32 ({} distribution buffer{}, cell types, snapshot fields)",
        bytes(8.0) / 1048576.0,
        bytes(4.0) / 1048576.0,
        buffers,
        if one { ", in place" } else { "s" }
    );
    let mut stable = true;
    match grainflow::coupled::plan(s) {
        Ok(Some(p)) => {
            println!(
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
            println!(
                "  grains           {}; {a:.1}–{b:.1} cells per diameter",
                p.grains
                    .map(|n| n.to_string())
                    .unwrap_or_else(|| "packed at run time".into())
            );
            println!("  DEM stability    {}", dem_verdict(p.dem_lambda));
            if let Some(g) = &s.scene.grains {
                use grainflow::stability::coupled;
                let case = coupled::CoupledCase {
                    scheme: p.scheme.name().to_string(),
                    cells_per_diameter: a,
                    density_ratio: g.density_kg_m3 / s.scene.fluid.density_kg_m3,
                    tau: u.tau,
                    lattice_velocity: u.u_lattice,
                };
                let map = coupled::parse(coupled::COUPLED_CSV);
                let v = coupled::verdict(&map, &case);
                println!("  coupled stability {}", v.describe(&case));
                stable = !matches!(v, coupled::CoupledVerdict::Unstable(_));
            }
        }
        Ok(None) => {}
        Err(e) => println!("  coupling: {e}"),
    }
    for w in &s.warnings {
        println!("  warning: {w}");
    }
    stable
}
