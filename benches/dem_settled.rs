//! DEM throughput on a settled packing, the LAMMPS comparison case: 50 000
//! polydisperse disks (d = 0.92–1.38 mm, uniform radii) packed by random addition into a
//! box and settled under gravity, then advanced with gravity on 1 and 2 threads.
//!
//! The settled packing is cached in `target/dem-settled-50k.csv` (settling takes a few
//! minutes once). `cargo bench --bench dem_settled` (GRAINFLOW_BENCH_STEPS, default 400);
//! `-- --lammps-data PATH` writes the same packing for LAMMPS and prints the time step
//! and box (see `scripts/dem-vs-lammps`).
use grainflow::dem::sample::{load_csv, random_sequential_addition, settle};
use grainflow::dem::{
    closed_box, stable_time_step, ContactModel, DemSystem, Grains, SizeDistribution, Wall,
};
use std::fmt::Write;
use std::path::Path;
use std::time::Instant;

const BOX: [f64; 2] = [0.32, 0.36];
const CACHE: &str = "target/dem-settled-50k.csv";

fn model() -> ContactModel {
    ContactModel {
        kn: 1e5,
        kt: 0.5e5,
        restitution: 0.5,
        friction: 0.5,
        rolling_friction: 0.0,
        tangential_damping: 0.0,
    }
}

fn walls() -> Vec<Wall> {
    closed_box([0.0, 0.0], BOX, 0.5)
}

fn dt(g: &Grains) -> f64 {
    stable_time_step(g, &model(), 0.1)
}

/// The settled packing: from the cache, or packed and settled now (and cached).
fn packing() -> Grains {
    if Path::new(CACHE).is_file() {
        return load_csv(Path::new(CACHE), 2500.0).expect("cached packing reads");
    }
    eprintln!("settling 50 000 grains once (cached in {CACHE}) ...");
    let sizes = SizeDistribution::Uniform {
        min: 0.46e-3,
        max: 0.69e-3,
    };
    let mut g = random_sequential_addition([0.0, 0.0], BOX, sizes, 2500.0, 0.55, 7, 20_000);
    g.truncate(50_000);
    let step = dt(&g);
    let mut s = DemSystem::new(g, walls(), model(), [0.0, -9.81], step, 0.1, false).unwrap();
    let steps = settle(&mut s, 20.0, 1e-10, 400_000);
    eprintln!("settled in {steps} steps");
    let mut csv = String::from("x,y,r\n");
    for i in 0..s.grains.len() {
        let _ = writeln!(
            csv,
            "{:e},{:e},{:e}",
            s.grains.x[i], s.grains.y[i], s.grains.r[i]
        );
    }
    std::fs::write(CACHE, csv).expect("cache written");
    load_csv(Path::new(CACHE), 2500.0).unwrap()
}

fn write_lammps_data(path: &str, g: &Grains) {
    let mut s = String::new();
    let _ = writeln!(s, "grainflow dem_settled packing: {} disks\n", g.len());
    let _ = writeln!(s, "{} atoms\n1 atom types\n", g.len());
    let _ = writeln!(
        s,
        "0 {} xlo xhi\n0 {} ylo yhi\n-0.001 0.001 zlo zhi\n",
        BOX[0], BOX[1]
    );
    let _ = writeln!(s, "Atoms # sphere\n");
    for i in 0..g.len() {
        // id type diameter density x y z; LAMMPS takes a 2-D disk's density as mass/area.
        let _ = writeln!(
            s,
            "{} 1 {:.9e} 2500 {:.9e} {:.9e} 0",
            i + 1,
            2.0 * g.r[i],
            g.x[i],
            g.y[i]
        );
    }
    std::fs::write(path, s).unwrap();
    println!(
        "dt {:e} xhi {} yhi {} grains {}",
        dt(g),
        BOX[0],
        BOX[1],
        g.len()
    );
}

fn main() {
    let g = packing();
    if let Some(path) = std::env::args().skip_while(|a| a != "--lammps-data").nth(1) {
        write_lammps_data(&path, &g);
        return;
    }
    let steps: usize = std::env::var("GRAINFLOW_BENCH_STEPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(400);
    let n = g.len();
    println!(
        "settled packing, {n} grains, gravity, dt = {:.3e} s, {steps} steps:",
        dt(&g)
    );
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (rate, per_grain, rebuilds) = pool.install(|| {
            let mut s =
                DemSystem::new(g.clone(), walls(), model(), [0.0, -9.81], dt(&g), 0.1, true)
                    .unwrap();
            for _ in 0..20 {
                s.step();
            }
            let before = s.list_rebuilds();
            let t = Instant::now();
            for _ in 0..steps {
                s.step();
            }
            let secs = t.elapsed().as_secs_f64();
            (
                (n * steps) as f64 / secs,
                s.contacts() as f64 / n as f64,
                s.list_rebuilds() - before,
            )
        });
        println!(
            "  {threads} thread(s): {:.2} M grain-steps/s, {:.2} M contacts/s ({per_grain:.2} contacts per grain, {rebuilds} list rebuilds)",
            rate / 1e6,
            rate * per_grain / 1e6
        );
    }
}
