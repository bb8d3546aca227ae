//! The coupled step on the wgpu backend against the CPU backend where grains cross periodic
//! faces (Mesa lavapipe in CI; skipped, and passing, when no adapter exists): a box periodic
//! on both axes, one grain crossing the x seam, one the y seam and one the corner, carried
//! across by the flow. The
//! device sums each grain's images across the y seam into the same column sums, and those
//! across the x seam into the grain's other columns, as the host's collect does. After 300
//! steps every grain's state and hydrodynamic force, and the fluid, agree within 1e-10 in
//! f64, for each scheme. (In f32 the forces here differ by about 1.5e-5 of the largest,
//! with the device's sums and with the host's alike: with no gravity the net forces are
//! small against the link momenta they sum, so f32's rounding of the fluid shows; the
//! settling tank of `gpu_coupled.rs` checks f32 within 1e-5.) (A binary of its own: some drivers run out of
//! device contexts in one process, see README.)
mod common;
use common::gpu_parity::compare;

/// 64 × 64 cells, periodic on both axes, driven by a body force; the grains start inside
/// (scenes must) and cross the seams within the first 200 steps.
const SCENE: &str = r#"title = "grains across both periodic seams"
[domain]
cells = [64, 64]
spacing_m = 0.001

[fluid]
density_kg_m3 = 1000.0
viscosity_m2_s = 1.0e-4
reference_velocity_m_s = 0.02
reference_length_m = 0.01
relaxation_time = 0.7
body_acceleration_m_s2 = [0.1, 0.1]

[boundaries]
west = { kind = "periodic" }
east = { kind = "periodic" }
south = { kind = "periodic" }
north = { kind = "periodic" }

[grains]
density_kg_m3 = 3000.0
gravity_m_s2 = [0.0, 0.0]
[grains.contact]
normal_stiffness_n_m2 = 1.0e4
tangential_stiffness_n_m2 = 0.5e4
restitution = 0.8
friction = 0.3
[grains.sample]
kind = "list"
grains = [
  { position_m = [0.0587, 0.032], radius_m = 0.005, velocity_m_s = [0.01, 0.002], angular_velocity_rad_s = 2.0 },
  { position_m = [0.032, 0.0587], radius_m = 0.005, velocity_m_s = [0.002, 0.01] },
  { position_m = [0.0587, 0.0587], radius_m = 0.0045, velocity_m_s = [0.01, 0.01], angular_velocity_rad_s = -3.0 },
]
[coupling]
scheme = "bounce-back"

[run]
steps = 300
"#;

#[test]
fn coupled_gpu_step_matches_the_cpu_across_periodic_seams() {
    let adapters = grainflow::lbm::gpu::list_adapters();
    if !adapters.iter().any(|a| a.f64) {
        eprintln!("SKIPPED: no GPU adapter with f64 (scripts/setup.sh installs Mesa lavapipe)");
        return;
    }
    for scheme in ["bounce-back", "interpolated", "psm"] {
        compare::<f64>(SCENE, scheme, 300, 1e-10);
    }
}
