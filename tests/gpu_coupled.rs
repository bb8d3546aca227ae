//! The coupled fluid–grain step on the wgpu backend against the CPU backend (Mesa lavapipe
//! in CI; skipped, and passing, when no adapter exists). The device recomputes the cells at
//! the grains after its sweep and sums their momenta per grain and column; only those sums
//! come back. After 300 steps of ten grains settling, colliding and crossing the tank,
//! every grain's position, velocity, spin and hydrodynamic force, and the fluid's velocity
//! and density, agree within 1e-5 in f32 and 1e-10 in f64, for each scheme.
mod common;
use common::gpu_parity::compare;
use common::root;
use grainflow::run::{Backend, Kernel};

#[test]
fn coupled_gpu_step_matches_the_cpu_for_every_scheme() {
    let adapters = grainflow::lbm::gpu::list_adapters();
    if adapters.is_empty() {
        eprintln!("SKIPPED: no GPU adapter (scripts/setup.sh installs Mesa lavapipe)");
        return;
    }
    let text = std::fs::read_to_string(root().join("tests/scenes/mpi_grains_box.toml")).unwrap();
    for scheme in ["bounce-back", "interpolated", "psm"] {
        compare::<f32>(&text, scheme, 300, 1e-5);
        if adapters.iter().any(|a| a.f64) {
            compare::<f64>(&text, scheme, 300, 1e-10);
        }
    }
}

/// A coupled run that blows up on the device stops as it does on the CPU, naming the same
/// step, cell and grain: the device reports its first bad plan cell with the momenta it
/// reads back (f64, where both backends round alike).
#[test]
fn coupled_gpu_blow_up_names_the_cpus_step_cell_and_grain() {
    let adapters = grainflow::lbm::gpu::list_adapters();
    if !adapters.iter().any(|a| a.f64) {
        eprintln!("SKIPPED: no GPU adapter with f64");
        return;
    }
    use grainflow::run::Precision;
    use grainflow::run::{run, Overrides, RunOptions, Status};
    for scheme in ["bounce-back", "psm"] {
        // The first grain thrown at 1.5 lattice units a step.
        let text = std::fs::read_to_string(root().join("tests/scenes/mpi_grains_box.toml"))
            .unwrap()
            .replace(
                "scheme = \"bounce-back\"",
                &format!("scheme = \"{scheme}\""),
            )
            .replace(
                "radius_m = 0.005, velocity_m_s = [0.04, 0.0] }",
                "radius_m = 0.005, velocity_m_s = [1.5, 0.0] }",
            );
        let path = root().join("tests/scenes/__gpu_blow_up.toml");
        let scene = grainflow::scene::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"));
        let error = |backend| {
            let out = tempfile::tempdir().unwrap();
            let mut scene = scene.clone();
            let overrides = Overrides {
                precision: Some(Precision::F64),
                backend: Some(backend),
                kernel: Some(Kernel::TwoArray),
                ..Default::default()
            };
            let opts = RunOptions {
                out_dir: out.path().to_path_buf(),
                scene_length: overrides.apply_fluid(&mut scene),
                progress: false,
                restart: None,
                force: false,
            };
            let s = run(&scene, &opts).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(s.run.status, Status::Unstable, "{scheme} on {backend:?}");
            s.run.error.unwrap()
        };
        let (cpu, gpu) = (error(Backend::Cpu), error(Backend::Gpu));
        eprintln!("{scheme}\n  cpu: {cpu}\n  gpu: {gpu}");
        // "unstable at step S: cell (X, Y) next to grain G has density …", or (a grain
        // faster than the lattice's sound) "unstable at step S: grain G moves at V cells
        // per step …".
        let head = |e: &str| {
            let e = e.split(" has density").next().unwrap();
            e.split(" cells per step").next().unwrap().to_string()
        };
        assert!(
            cpu.contains("next to grain") || cpu.contains("grain 0 moves at"),
            "{cpu}"
        );
        assert_eq!(head(&cpu), head(&gpu), "{scheme}");
    }
}

/// The small submarine landslide (`jobs/submarine-landslide/sub-small-loose.toml`: 242
/// grains released down a 15° slope, PSM) steps alike on the GPU and the CPU, within the
/// settling box's tolerances, over its first 10 steps. Not longer: the packed mass's
/// contacts amplify rounding differences about tenfold every nine steps at first (f64: 2e-15
/// after 10 steps, 1e-10 after 50, 8e-9 after 200), as any reordering of the sums would, so
/// a longer run agrees in its statistics, not in its bits (run-out 1.060 on lavapipe against
/// 1.011 on the CPU over the whole run).
#[test]
fn the_small_landslide_on_the_gpu_matches_the_cpu() {
    let adapters = grainflow::lbm::gpu::list_adapters();
    if adapters.is_empty() {
        eprintln!("SKIPPED: no GPU adapter (scripts/setup.sh installs Mesa lavapipe)");
        return;
    }
    let text =
        std::fs::read_to_string(root().join("jobs/submarine-landslide/sub-small-loose.toml"))
            .unwrap();
    compare::<f32>(&text, "psm", 10, 1e-5);
    if adapters.iter().any(|a| a.f64) {
        compare::<f64>(&text, "psm", 10, 1e-10);
    }
}
