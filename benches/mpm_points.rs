//! MPM throughput in particle-steps per second, with the split over the stages.
//!
//! The problem of the CB-Geo bar: a granular column collapse of aspect ratio 2
//! with 2 × 2 points per 1 cm cell (180 000 points: 150 × 300 cells), Mohr–Coulomb
//! (φ = 30°, E = 1 MPa, separation at 1.15 V₀ as in the scenes), USF, GIMP and linear shape
//! functions, on 1 and 2 threads; then
//! 10⁶ points (500 × 500 cells) on 1 and 2 threads. The column collapses during the timed
//! steps, so the points move, re-sort and yield as in a production run.
//! Last, the cost of the APIC transfer against FLIP, and of side walls (a quasi-2-D
//! channel), on the CB-Geo problem.
//! `cargo bench --bench mpm_points` (GRAINFLOW_BENCH_STEPS, default 300; GRAINFLOW_BENCH_ONLY
//! = `cbgeo`, `million`, `apic` or `walls` for one part).
use decomposition::SingleProcess;
use grainflow::mpm::mohr_coulomb::MohrCoulomb;
use grainflow::mpm::*;
use std::time::Instant;

const FLIP: VelocityUpdate = VelocityUpdate::Flip { pic: 0.0 };

fn column(
    cells_x: usize,
    cells_y: usize,
    shape: ShapeKind,
    scheme: Scheme,
    update: VelocityUpdate,
) -> MpmSystem {
    let h = 0.01;
    let spec = GridSpec {
        nx: cells_x * 4,
        ny: cells_y + 8,
        h,
    };
    // Separation as in the collapse scenes: without it, linear pure-FLIP points stretched
    // along the floor break the CFL limit after about 300 steps.
    let mat = Material {
        density: 1800.0,
        separation_volume_ratio: 1.15,
        model: Model::MohrCoulomb(MohrCoulomb::cohesionless(1.0e6, 0.3, 30.0)),
    };
    let boundaries = Boundaries {
        left: Side::Roller,
        right: Side::Roller,
        bottom: Side::Frictional { friction: 0.46 },
        top: Side::Open,
    };
    let setup = MpmSetup {
        scheme,
        velocity_update: update,
        ..MpmSetup::plain(spec, shape, boundaries, [0.0, -9.81], mat)
    };
    let mut pts = Points::default();
    let (w, ht) = (cells_x as f64 * h, cells_y as f64 * h);
    let mut id = 0;
    fill(
        &mut pts,
        &Shape::Rectangle {
            min: [0.0, 0.0],
            max: [w, ht],
        },
        &spec,
        2,
        1800.0,
        0,
        &mut id,
    );
    for i in 0..pts.len() {
        let syy = -1800.0 * 9.81 * (ht - pts.pos[i][1]);
        pts.stress[i] = [0.5 * syy, syy, 0.0, 0.5 * syy];
    }
    MpmSystem::new(setup, pts, &SingleProcess).unwrap()
}

fn run(
    cx: usize,
    cy: usize,
    kind: (ShapeKind, Scheme),
    update: VelocityUpdate,
    threads: usize,
    steps: usize,
) {
    run_with(cx, cy, kind, update, None, threads, steps);
}

fn run_with(
    cx: usize,
    cy: usize,
    (shape, scheme): (ShapeKind, Scheme),
    update: VelocityUpdate,
    walls: Option<SideWalls>,
    threads: usize,
    steps: usize,
) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut s = column(cx, cy, shape, scheme, update);
        s.setup.side_walls = walls;
        let n = s.points.len();
        for _ in 0..20 {
            s.step(&SingleProcess).unwrap();
        }
        s.seconds = [0.0; 6];
        let t = Instant::now();
        for _ in 0..steps {
            s.step(&SingleProcess).unwrap();
        }
        let secs = t.elapsed().as_secs_f64();
        let split: Vec<String> = MPM_STAGES
            .iter()
            .zip(s.seconds)
            .map(|(k, v)| format!("{k} {:.0} %", 100.0 * v / secs))
            .collect();
        println!(
            "{n:>8} points {shape:?} {scheme:?} {update:?}{} {threads} thread(s): {:.3e} particle-steps/s ({:.0} ns per point-step); {}; yielded {}",
            if walls.is_some() { ", side walls" } else { "" },
            (n * steps) as f64 / secs,
            secs / (n * steps) as f64 * 1e9 * threads as f64,
            split.join(", "),
            s.yielded
        );
    });
}

fn main() {
    let steps: usize = std::env::var("GRAINFLOW_BENCH_STEPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(300);
    let only = std::env::var("GRAINFLOW_BENCH_ONLY").unwrap_or_default();
    if only.is_empty() || only == "cbgeo" {
        println!("CB-Geo problem: a = 2 column, 150 × 300 cells of 1 cm, 2 × 2 points per cell (bar: 3.1e5 / 4.8e5 GIMP, 4.9e5 linear on 1 thread)");
        for shape in [ShapeKind::Gimp, ShapeKind::Linear] {
            for threads in [1, 2] {
                run(150, 300, (shape, Scheme::Usf), FLIP, threads, steps);
            }
        }
        for scheme in [Scheme::Usl, Scheme::Musl] {
            run(150, 300, (ShapeKind::Gimp, scheme), FLIP, 1, steps);
        }
    }
    if only.is_empty() || only == "million" {
        println!("10⁶ points: 500 × 500 cells of 1 cm, 2 × 2 points per cell, GIMP, USF");
        for threads in [1, 2] {
            run(
                500,
                500,
                (ShapeKind::Gimp, Scheme::Usf),
                FLIP,
                threads,
                steps / 3,
            );
        }
    }
    if only.is_empty() || only == "apic" {
        println!("APIC against FLIP: the CB-Geo problem, GIMP, USF");
        for threads in [1, 2] {
            for update in [FLIP, VelocityUpdate::Apic] {
                run(
                    150,
                    300,
                    (ShapeKind::Gimp, Scheme::Usf),
                    update,
                    threads,
                    steps,
                );
            }
        }
    }
    if only.is_empty() || only == "walls" {
        println!("Side walls (10 cm apart, μ_w = 0.46) against none: the CB-Geo problem, GIMP, USF, FLIP");
        let walls = SideWalls {
            gap_m: 0.1,
            friction: 0.46,
        };
        for threads in [1, 2] {
            for w in [None, Some(walls)] {
                run_with(
                    150,
                    300,
                    (ShapeKind::Gimp, Scheme::Usf),
                    FLIP,
                    w,
                    threads,
                    steps,
                );
            }
        }
    }
}
