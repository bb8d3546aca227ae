//! Fast direct-API checks of the lattice (no scene layer): Poiseuille with body force,
//! walls by half-way bounce-back, all three operators.
use grainflow::lbm::lattice::{FaceCondition, LatticeSetup, SolidInfo};
use grainflow::lbm::{Collision, Lattice};

fn poiseuille_error<T: grainflow::lbm::Real>(collision: Collision, tau: f64, ny: usize) -> f64 {
    let nx = 3;
    let g = 1e-6;
    let setup = LatticeSetup {
        nx,
        ny,
        cells: vec![0; nx * ny],
        faces: [
            FaceCondition::Periodic,
            FaceCondition::Periodic,
            FaceCondition::Wall { solid: 1 },
            FaceCondition::Wall { solid: 1 },
        ],
        solids: vec![SolidInfo {
            name: "walls".into(),
            velocity: [0.0, 0.0],
        }],
        collision,
        tau0: tau,
        smagorinsky: None,
        force: [g, 0.0],
    };
    let mut lat = Lattice::<T>::new(setup);
    let nu = (tau - 0.5) / 3.0;
    let steps = (8.0 * (ny * ny) as f64 / nu) as usize;
    for _ in 0..steps {
        lat.step().unwrap();
    }
    let h = ny as f64;
    let mut err: f64 = 0.0;
    let umax = g * h * h / (8.0 * nu);
    for y in 0..ny {
        let yy = y as f64 + 0.5;
        let exact = g / (2.0 * nu) * yy * (h - yy);
        let (_, u) = lat.sample(1, y);
        err = err.max((u[0] - exact).abs() / umax);
    }
    err
}

#[test]
fn poiseuille_exact_at_magic_tau() {
    let tau = 0.5 + 3f64.sqrt() / 4.0;
    let e = poiseuille_error::<f64>(Collision::Bgk, tau, 16);
    assert!(e < 1e-6, "bgk {e}");
    let e = poiseuille_error::<f64>(Collision::Trt { magic: 3.0 / 16.0 }, 0.6, 16);
    assert!(e < 1e-6, "trt {e}");
    let e = poiseuille_error::<f64>(
        Collision::Mrt {
            s_e: 1.2,
            s_eps: 1.2,
            s_q: None,
        },
        0.6,
        16,
    );
    assert!(e < 1e-6, "mrt {e}");
}
