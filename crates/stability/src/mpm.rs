//! The MPM's stability limit, measured: a small column collapse (tests/scenes/mpm_collapse.toml,
//! GIMP, Mohr–Coulomb) run for 0.12 s at time steps C · h / c. Stable while every step succeeds
//! and no point moves faster than ten times the free-fall speed over the column height.

use decomposition::SingleProcess;
use mpm::system::MpmSystem;
use scene::ValidMpmScene;

/// One Courant number of the sweep: (C, the largest point speed reached in m/s, stable).
pub fn point(scene: &ValidMpmScene, courant: f64) -> (f64, f64, bool) {
    let mut setup = scene.setup.clone();
    setup.dt = courant * scene.critical_dt;
    let comm = SingleProcess;
    let Ok(mut sys) = MpmSystem::new(setup, scene.points.clone(), &comm) else {
        return (courant, f64::NAN, false);
    };
    let g = scene.scene.mpm.gravity_m_s2[0].hypot(scene.scene.mpm.gravity_m_s2[1]);
    let bound = 10.0 * (2.0 * g * scene.setup.spec.height()).sqrt();
    let steps = (scene.end_time_s() / sys.setup.dt).ceil() as usize;
    let mut fastest = 0.0f64;
    for step in 0..steps {
        if sys.step(&comm).is_err() {
            return (courant, f64::INFINITY, false);
        }
        if step % 50 == 0 || step + 1 == steps {
            let v = sys
                .points
                .vel
                .iter()
                .map(|v| v[0].hypot(v[1]))
                .fold(
                    0.0,
                    |a: f64, b| if b.is_nan() { f64::INFINITY } else { a.max(b) },
                );
            fastest = fastest.max(v);
            if !(fastest <= bound) {
                return (courant, fastest, false);
            }
        }
    }
    (courant, fastest, true)
}

/// The largest measured Courant number up to which every measured one was stable, from the
/// CSV rows `courant,max_speed_m_s,stable` (None when the first is not).
pub fn courant_limit(csv: &str) -> Option<f64> {
    super::dem::lambda_limit(csv)
}
