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
        };
        let dt = 1e-7;
        let mut s = DemSystem::new(g, walls, model, [0.0, 0.0], dt, 0.1, true).unwrap();
        for _ in 0..10 {
            s.step();
        }
        let t = Instant::now();
        let mut contacts = 0;
        for _ in 0..steps {
            s.step();
            contacts += s.contacts();
        }
        let secs = t.elapsed().as_secs_f64();
        (
            (n * steps) as f64 / secs,
            contacts as f64 / secs,
            contacts / steps,
        )
    })
}

fn main() {
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
