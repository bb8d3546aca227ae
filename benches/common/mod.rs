//! Shared set-up of the LBM benchmarks.
use grainflow::lbm::lattice::{FaceCondition, LatticeSetup};
use grainflow::lbm::{Collision, Lattice, Real};

/// A fully periodic nx × ny box (τ = 0.6) holding a smooth 2-D shear flow (u ≤ 0.05),
/// halos filled, ready to step.
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
