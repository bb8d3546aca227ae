//! An estimated wall time for `check`: the fluid kernel's speed measured on this machine
//! (a short run of the scene's operator, precision and kernel on a periodic box), and the
//! grain and material-point rates measured by the benchmarks (docs/performance.md), scaled
//! by the thread count.

use lbm::lattice::{FaceCondition, LatticeSetup};
use lbm::{Collision, Lattice, Real};
use std::time::Instant;

/// Update rates of this machine's threads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rates {
    /// Fluid cell updates per second (all threads), with the scene's operator and precision.
    pub fluid_cells_per_s: f64,
    /// Grain updates per second (all threads), contacts included.
    pub grain_steps_per_s: f64,
    /// Material-point updates per second (all threads).
    pub point_steps_per_s: f64,
}

/// Grain updates per second of one thread, 50 000 settled disks (the `dem_settled`
/// benchmark on the 2-core reference machines: 8.4–9.1 M).
const GRAIN_STEPS_PER_THREAD: f64 = 8.5e6;
/// Material-point updates per second of one thread (the `mpm_points` benchmark, GIMP, USF,
/// Mohr–Coulomb: 3.9 M).
const POINT_STEPS_PER_THREAD: f64 = 3.9e6;
/// Efficiency of each added thread for grains and points (2 threads gave 1.6× and 1.86×).
const THREAD_EFFICIENCY: f64 = 0.75;

impl Rates {
    /// Rates on `threads` threads, with a measured fluid rate.
    pub fn with_fluid(fluid_cells_per_s: f64, threads: usize) -> Self {
        let t = 1.0 + THREAD_EFFICIENCY * (threads.max(1) as f64 - 1.0);
        Self {
            fluid_cells_per_s,
            grain_steps_per_s: GRAIN_STEPS_PER_THREAD * t,
            point_steps_per_s: POINT_STEPS_PER_THREAD * t,
        }
    }
}

/// Measure the fluid kernel on this machine's current thread pool: `collision` in `T` on a
/// periodic `n` × `n` box (512: larger than the caches, as a real lattice is), in place or
/// with two arrays, stepped for at least `seconds`. Cell updates per second.
pub fn measure_fluid<T: Real>(collision: Collision, in_place: bool, n: usize, seconds: f64) -> f64 {
    let mut lat = periodic_box::<T>(n, n, collision);
    if in_place {
        lat.make_in_place();
    }
    // One step to warm the caches and the pool, then whole pairs (in place alternates two
    // kinds of step).
    let _ = lat.step();
    let t = Instant::now();
    let mut steps = 0u64;
    while steps < 4 || t.elapsed().as_secs_f64() < seconds {
        for _ in 0..2 {
            if lat.step().is_err() {
                break;
            }
        }
        steps += 2;
    }
    (n * n) as f64 * steps as f64 / t.elapsed().as_secs_f64().max(1e-9)
}

/// A fully periodic `nx` × `ny` box (τ = 0.6) holding a smooth 2-D shear flow (u ≤ 0.05),
/// halos filled, ready to step: the lattice the speed measurements (here and in
/// `benches/`) run.
pub fn periodic_box<T: Real>(nx: usize, ny: usize, collision: Collision) -> Lattice<T> {
    let setup = LatticeSetup {
        nx,
        ny,
        cells: vec![0; nx * ny],
        faces: [
            FaceCondition::Periodic,
            FaceCondition::Periodic,
            FaceCondition::Periodic,
            FaceCondition::Periodic,
        ],
        solids: vec![],
        collision,
        tau0: 0.6,
        smagorinsky: None,
        force: [0.0, 0.0],
    };
    let mut l = Lattice::<T>::new(setup);
    for y in 0..ny {
        for x in 0..nx {
            let (a, b) = (x as f64 / nx as f64, y as f64 / ny as f64);
            let u = [
                0.05 * (std::f64::consts::TAU * b).sin(),
                0.05 * (std::f64::consts::TAU * a).sin(),
            ];
            l.set_equilibrium(x, y, 1.0, u);
        }
    }
    l.update_boundaries();
    l
}

/// A wall time (s) as a reader wants it: "40 s", "12 min", "3.5 h", "2.1 days".
pub fn human(seconds: f64) -> String {
    if !seconds.is_finite() {
        return "unknown".into();
    }
    match seconds {
        s if s < 1.0 => "under 1 s".into(),
        s if s < 10.0 => format!("{s:.1} s"),
        s if s < 90.0 => format!("{s:.0} s"),
        s if s < 5400.0 => format!("{:.0} min", s / 60.0),
        s if s < 172_800.0 => format!("{:.1} h", s / 3600.0),
        s => format!("{:.1} days", s / 86400.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_read_naturally() {
        assert_eq!(human(40.0), "40 s");
        assert_eq!(human(0.3), "under 1 s");
        assert_eq!(human(2.25), "2.2 s");
        assert_eq!(human(720.0), "12 min");
        assert_eq!(human(3.5 * 3600.0), "3.5 h");
        assert_eq!(human(3.0 * 86400.0), "3.0 days");
    }

    #[test]
    fn the_fluid_kernel_is_measured() {
        let r = measure_fluid::<f32>(Collision::Bgk, true, 64, 0.01);
        assert!(r.is_finite() && r > 1e5, "{r} cell updates/s");
    }
}
