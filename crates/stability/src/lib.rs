//! Stability limits measured by sweeps (`grainflow stability-map`), stored in
//! `jobs/stability/`, and the verdicts `grainflow check` gives from them: the fluid's map
//! over relaxation time, lattice Mach number and operator ([`lbm`], [`map`]), the DEM's
//! time-step factor λ ([`dem`]) and the MPM's Courant number ([`mpm`]).

pub mod coupled;
pub mod dem;
pub mod lbm;
pub mod map;
pub mod mpm;

pub use map::{StabilityMap, Verdict};

/// The DEM sweep shipped with grainflow (`lambda,energy_ratio,stable`).
pub const DEM_CSV: &str = include_str!("../../../jobs/stability/dem-lambda.csv");
/// The MPM sweep shipped with grainflow (`courant,max_speed_m_s,stable`).
pub const MPM_CSV: &str = include_str!("../../../jobs/stability/mpm-courant.csv");

use std::path::Path;

/// Relaxation times of the fluid map.
pub const TAUS: [f64; 27] = [
    0.5001, 0.50015, 0.5002, 0.5003, 0.5005, 0.5007, 0.501, 0.5015, 0.502, 0.503, 0.505, 0.507,
    0.51, 0.515, 0.52, 0.525, 0.53, 0.54, 0.55, 0.57, 0.6, 0.65, 0.7, 0.8, 1.0, 1.5, 2.0,
];
/// Lattice Mach numbers of the fluid map.
pub const MACHS: [f64; 16] = [
    0.02, 0.05, 0.075, 0.1, 0.125, 0.15, 0.175, 0.2, 0.225, 0.25, 0.275, 0.3, 0.325, 0.35, 0.375,
    0.4,
];
/// Lattice size and steps of the fluid map's runs.
pub const LBM_SIZE: usize = 64;
/// See [`LBM_SIZE`].
pub const LBM_STEPS: usize = 10_000;
/// Time-step factors of the DEM sweep, and its steps.
pub const LAMBDAS: [f64; 15] = [
    0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.3, 1.5, 2.0,
];
/// See [`LAMBDAS`].
pub const DEM_STEPS: usize = 20_000;
/// Courant numbers of the MPM sweep.
pub const COURANTS: [f64; 10] = [0.1, 0.25, 0.5, 0.75, 0.9, 1.0, 1.1, 1.25, 1.5, 2.0];

/// Run the three sweeps and write `lbm-map.csv`, `dem-lambda.csv` and `mpm-courant.csv` into
/// `dir`; `mpm_scene` is the MPM column the Courant sweep runs. Returns a summary to print.
pub fn write_maps(dir: &Path, mpm_scene: &scene::ValidMpmScene) -> std::io::Result<String> {
    use std::fmt::Write;
    let mut out = String::new();
    let map = StabilityMap {
        samples: lbm::sweep(&TAUS, &MACHS, LBM_SIZE, LBM_STEPS),
    };
    io::atomic::write_atomic(&dir.join("lbm-map.csv"), map.to_csv().as_bytes())
        .map_err(std::io::Error::other)?;
    for op in lbm::Operator::ALL {
        let limits: Vec<String> = MACHS
            .iter()
            .map(|&m| match map.tau_limit(&op, m) {
                Some(t) => format!("Ma {m}: τ ≥ {t}"),
                None => format!("Ma {m}: none"),
            })
            .collect();
        let _ = writeln!(out, "{:9} {}", op.name(), limits.join(", "));
    }
    let pile = dem::settled_pile();
    let mut csv = String::from("lambda,energy_ratio,stable\n");
    for &l in &LAMBDAS {
        let (l, r, ok) = dem::point(&pile, l, DEM_STEPS);
        let _ = writeln!(csv, "{l},{r:.9},{}", ok as u8);
    }
    io::atomic::write_atomic(&dir.join("dem-lambda.csv"), csv.as_bytes())
        .map_err(std::io::Error::other)?;
    let _ = writeln!(out, "DEM: stable up to λ = {:?}", dem::lambda_limit(&csv));
    let mut csv = String::from("courant,max_speed_m_s,stable\n");
    for &c in &COURANTS {
        let (c, v, ok) = mpm::point(mpm_scene, c);
        let _ = writeln!(csv, "{c},{v:.6},{}", ok as u8);
    }
    io::atomic::write_atomic(&dir.join("mpm-courant.csv"), csv.as_bytes())
        .map_err(std::io::Error::other)?;
    let _ = writeln!(
        out,
        "MPM: stable up to Courant {:?}",
        mpm::courant_limit(&csv)
    );
    Ok(out)
}
