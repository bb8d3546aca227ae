//! The DEM's stability limit, measured: a pile of the column-collapse study's disks, settled,
//! then run without damping at time steps λ Δt_cr. Stable while its total energy does not
//! grow (the contacts dissipate; velocity Verlet adds energy once the step is too long).

use dem::{closed_box, random_sequential_addition, settle, ContactModel, DemSystem};
use dem::{stable_time_step, SizeDistribution};

/// The contact law of the column-collapse study (jobs/column-collapse).
fn model() -> ContactModel {
    ContactModel {
        kn: 1.0e6,
        kt: 0.5e6,
        restitution: 0.75,
        friction: 0.53,
        rolling_friction: 0.3,
        tangential_damping: 0.0,
    }
}

/// A settled pile of about 300 disks (d = 0.92–1.38 mm) in a 24 mm box, at rest.
pub fn settled_pile() -> DemSystem {
    let sizes = SizeDistribution::Uniform {
        min: 0.46e-3,
        max: 0.69e-3,
    };
    let grains =
        random_sequential_addition([0.0, 0.0], [0.024, 0.03], sizes, 2500.0, 0.55, 7, 20_000);
    let model = model();
    let dt = stable_time_step(&grains, &model, 0.1);
    let walls = closed_box([0.0, 0.0], [0.024, 0.04], 0.46);
    let mut sys = DemSystem::new(grains, walls, model, [0.0, -9.81], dt, 0.1, false)
        .expect("the pile's parameters are valid");
    settle(&mut sys, 20.0, 1e-10, 400_000);
    for v in [
        &mut sys.grains.vx,
        &mut sys.grains.vy,
        &mut sys.grains.omega,
    ] {
        v.iter_mut().for_each(|x| *x = 0.0);
    }
    sys
}

/// Run `pile` for `steps` steps of λ Δt_cr; the total energy at the end over that at the
/// start (potential energy measured from the floor, so both are positive).
pub fn energy_ratio(pile: &DemSystem, lambda: f64, steps: usize) -> f64 {
    let mut sys = pile.clone();
    sys.dt = lambda * sys.stable_time_step(1.0);
    let e0 = sys.energy();
    for _ in 0..steps {
        sys.step();
    }
    let e1 = sys.energy();
    if e1.is_finite() {
        e1 / e0
    } else {
        f64::INFINITY
    }
}

/// One λ of the sweep: (λ, energy ratio, stable = the ratio stayed at or below 1 + 1e-3).
pub fn point(pile: &DemSystem, lambda: f64, steps: usize) -> (f64, f64, bool) {
    let r = energy_ratio(pile, lambda, steps);
    (lambda, r, r <= 1.0 + 1e-3)
}

/// The largest measured λ up to which every measured λ was stable, from the CSV rows
/// `lambda,energy_ratio,stable` (None when the first is not).
pub fn lambda_limit(csv: &str) -> Option<f64> {
    let mut rows: Vec<(f64, bool)> = csv
        .lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            Some((f.first()?.parse().ok()?, *f.get(2)? == "1"))
        })
        .collect();
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut limit = None;
    for (l, ok) in rows {
        if !ok {
            break;
        }
        limit = Some(l);
    }
    limit
}
