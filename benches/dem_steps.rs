//! DEM throughput: grain-steps and contacts per second on 1 and 2 threads, and the cost per
//! grain-step against N (O(N) check).
//!
//! The packing: polydisperse disks (d = 0.92–1.38 mm, uniform) on a triangular lattice of
//! spacing 1.14 mm, about 2.5–3 contacts per grain, no gravity, walls around — the contact
//! density of a settled packing without the minutes of settling.
//! `cargo bench --bench dem_steps` (GRAINFLOW_BENCH_STEPS, default 200).
use grainflow::dem::sample::Rng;
use grainflow::dem::{closed_box, ContactModel, DemSystem, Grains, Wall};
use std::time::Instant;

fn packing(n_side_x: usize, n_side_y: usize) -> (Grains, Vec<Wall>) {
    let s = 1.14e-3;
    let mut rng = Rng::new(42);
    let mut g = Grains::default();
    for row in 0..n_side_y {
        for col in 0..n_side_x {
            let x = (col as f64 + 0.5 * (row % 2) as f64 + 1.0) * s;
            let y = (row as f64 * 0.866 + 1.0) * s;
            let r = 0.46e-3 + 0.23e-3 * rng.uniform();
            g.push([x, y], r, 2500.0, false);
        }
    }
    let (w, h) = (
        (n_side_x as f64 + 2.0) * s,
        (n_side_y as f64 * 0.866 + 2.0) * s,
    );
    (g, closed_box([0.0, 0.0], [w, h], 0.5))
}

fn run(nx: usize, ny: usize, threads: usize, steps: usize) -> (f64, f64, usize) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let (g, walls) = packing(nx, ny);
        let n = g.len();
        let model = ContactModel {
            kn: 1e5,
            kt: 0.5e5,
            restitution: 0.5,
            friction: 0.5,
            rolling_friction: 0.0,
            tangential_damping: 0.0,
        };
        let dt = 1e-7;
        let mut s = DemSystem::new(g, walls, model, [0.0, 0.0], dt, 0.1, true).unwrap();
        for _ in 0..10 {
            s.step();
        }
        let t = Instant::now();
        for _ in 0..steps {
            s.step();
        }
        let secs = t.elapsed().as_secs_f64();
        // The packing barely moves: contacts per step are those of the last step.
        let contacts = s.contacts() * steps;
        (
            (n * steps) as f64 / secs,
            contacts as f64 / secs,
            contacts / steps,
        )
    })
}

/// Write the 50 000-grain packing and its walls as a LAMMPS data file (atom_style sphere,
/// 2-D), for the side-by-side run of `scripts/dem-vs-lammps`.
fn write_lammps_data(path: &str) {
    use std::fmt::Write;
    let (g, walls) = packing(250, 200);
    let (mut xhi, mut yhi) = (0.0f64, 0.0f64);
    for w in &walls {
        xhi = xhi.max(w.a[0]).max(w.b[0]);
        yhi = yhi.max(w.a[1]).max(w.b[1]);
    }
    let mut s = String::new();
    writeln!(s, "grainflow dem_steps packing: {} disks\n", g.len()).unwrap();
    writeln!(s, "{} atoms\n1 atom types\n", g.len()).unwrap();
    writeln!(
        s,
        "0 {xhi} xlo xhi\n0 {yhi} ylo yhi\n-0.001 0.001 zlo zhi\n"
    )
    .unwrap();
    writeln!(s, "Atoms # sphere\n").unwrap();
    for i in 0..g.len() {
        // id type diameter density x y z; LAMMPS takes 2-D disk density as mass/area.
        writeln!(
            s,
            "{} 1 {:.9e} 2500 {:.9e} {:.9e} 0",
            i + 1,
            2.0 * g.r[i],
            g.x[i],
            g.y[i]
        )
        .unwrap();
    }
    std::fs::write(path, s).unwrap();
    println!(
        "wrote {path}: {} grains, box {xhi:.6} x {yhi:.6} m",
        g.len()
    );
}

fn main() {
    if let Some(path) = std::env::args().skip_while(|a| a != "--lammps-data").nth(1) {
        write_lammps_data(&path);
        return;
    }
    let steps: usize = std::env::var("GRAINFLOW_BENCH_STEPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(200);
    println!("50 000 grains (250 x 200), {steps} steps:");
    for threads in [1, 2] {
        let (gs, cs, c) = run(250, 200, threads, steps);
        println!(
            "  {threads} thread(s): {:.2} M grain-steps/s, {:.2} M contacts/s ({:.2} contacts per grain)",
            gs / 1e6,
            cs / 1e6,
            c as f64 / 50_000.0
        );
    }
    println!("cost per grain-step vs N (1 thread):");
    for (nx, ny) in [(125, 100), (250, 200), (500, 400)] {
        let (gs, _, _) = run(nx, ny, 1, steps / 2);
        println!("  N = {:7}: {:.1} ns", nx * ny, 1e9 / gs);
    }
}
