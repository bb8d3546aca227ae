//! The wgpu backend against the CPU backend. In CI this runs on Mesa lavapipe (a Vulkan
//! driver on the CPU), so it needs no GPU; without any adapter the tests print that they
//! were skipped and pass.
//!
//! Agreement is measured per field as max |a − b| / max |a| over the lattice (velocity
//! components, density, full populations f = h + w, forces on every solid). After 500
//! steps it must be ≤ 1e-5 in f32 and ≤ 1e-12 in f64.
mod common;
use common::gpu_parity::rel_diff;
use common::{assert_checks_pass, root};
use decomposition::SingleProcess;
use grainflow::lbm::Real;
use grainflow::run::{run, Backend, GpuStorage, Kernel, Overrides, Precision, RunOptions, Status};
use grainflow::simulation::Simulation;
use std::path::Path;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_grainflow");

/// Whether wgpu finds an adapter; prints a skip notice when it does not.
fn have_adapter(test: &str) -> bool {
    let found = !grainflow::lbm::gpu::list_adapters().is_empty();
    if !found {
        eprintln!("SKIPPED {test}: no GPU adapter (scripts/setup.sh installs Mesa lavapipe)");
    }
    found
}

fn compare<T: Real>(scene_path: &str, steps: usize, tolerance: f64) {
    compare_stored::<T>(scene_path, steps, tolerance, GpuStorage::Native);
}

/// The GPU run of `scene_path` with populations stored as `storage`, against the CPU.
fn compare_stored<T: Real>(scene_path: &str, steps: usize, tolerance: f64, storage: GpuStorage) {
    let scene = grainflow::scene::load(&root().join(scene_path)).unwrap_or_else(|e| panic!("{e}"));
    let comm = SingleProcess;
    let mut cpu = Simulation::<T>::new(
        &scene,
        &comm,
        Backend::Cpu,
        GpuStorage::Native,
        Kernel::TwoArray,
        None,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut gpu =
        Simulation::<T>::new(&scene, &comm, Backend::Gpu, storage, Kernel::TwoArray, None)
            .unwrap_or_else(|e| panic!("{e}"));
    for _ in 0..steps {
        cpu.step(&comm).expect("CPU run stays stable");
        gpu.step(&comm).expect("GPU run stays stable");
    }
    gpu.check(&comm).expect("GPU run stays stable");
    assert_eq!(gpu.fluid.lattice().steps_done(), steps as u64);
    let (a, b) = (cpu.fields(&comm), gpu.fields(&comm));
    // Velocity as a vector field: max |Δu| over max |u| (a component that is zero up to
    // round-off, like u_y in a channel, would make a per-component ratio meaningless).
    let speed: Vec<f64> = a.ux.iter().zip(&a.uy).map(|(x, y)| x.hypot(*y)).collect();
    let dspeed: Vec<f64> = (0..a.ux.len())
        .map(|k| (a.ux[k] - b.ux[k]).hypot(a.uy[k] - b.uy[k]))
        .collect();
    let vmax = speed.iter().fold(0.0f64, |m, v| m.max(*v));
    let dmax = dspeed.iter().fold(0.0f64, |m, v| m.max(*v));
    let mut report = vec![
        ("velocity", if vmax > 0.0 { dmax / vmax } else { dmax }),
        ("density", rel_diff(&a.rho, &b.rho)),
    ];
    let full = |h: Vec<T>, ny: usize, nx: usize| -> Vec<f64> {
        let w = grainflow::lbm::d2q9::W;
        h.iter()
            .enumerate()
            .map(|(k, v)| v.to_f64() + w[k / (ny * nx)])
            .collect()
    };
    let (nx, ny) = (a.nx, a.ny);
    report.push((
        "populations",
        rel_diff(
            &full(cpu.fluid.export_interior(), ny, nx),
            &full(gpu.fluid.export_interior(), ny, nx),
        ),
    ));
    let (fa, fb) = (cpu.fluid.forces(&comm), gpu.fluid.forces(&comm));
    for (s, (x, y)) in fa.iter().zip(&fb).enumerate() {
        report.push((
            if s == 0 {
                "force solid 1"
            } else {
                "force other solid"
            },
            rel_diff(&[x[0], x[1]], &[y[0], y[1]]),
        ));
    }
    for (name, d) in &report {
        eprintln!(
            "{scene_path} {} after {steps} steps: {name} differs by {d:.2e} (≤ {tolerance:.0e})",
            T::NAME
        );
    }
    for (name, d) in report {
        assert!(
            d <= tolerance,
            "{scene_path} {}: {name} differs by {d:.3e} > {tolerance:.0e}",
            T::NAME
        );
    }
}

fn both_precisions(scene: &str) {
    if !have_adapter(scene) {
        return;
    }
    compare::<f32>(scene, 500, 1e-5);
    let f64_ok = grainflow::lbm::gpu::list_adapters().iter().any(|a| a.f64);
    if f64_ok {
        compare::<f64>(scene, 500, 1e-12);
    } else {
        eprintln!("SKIPPED f64 part of {scene}: the adapter has no SHADER_F64");
    }
}

#[test]
fn poiseuille_agrees_with_cpu() {
    both_precisions("jobs/poiseuille/scene.toml");
}

#[test]
fn ghia_cavity_agrees_with_cpu() {
    both_precisions("jobs/cavity/re100.toml");
}

#[test]
fn schafer_turek_cylinder_agrees_with_cpu() {
    both_precisions("jobs/cylinder/scene.toml");
}

/// MRT + Smagorinsky, a ramped parabolic Zou–He inlet, a pressure outlet with open
/// corners, a moving lid and a cylinder (forces).
#[test]
fn mrt_smagorinsky_channel_agrees_with_cpu() {
    both_precisions("tests/scenes/mpi_channel.toml");
}

/// Periodic seam with obstacles, body force (Guo) and a free-slip floor.
#[test]
fn periodic_forced_free_slip_agrees_with_cpu() {
    both_precisions("tests/scenes/mpi_periodic.toml");
}

/// Velocity face, pressure face and zero-gradient outflow.
#[test]
fn open_faces_and_outflow_agree_with_cpu() {
    both_precisions("tests/scenes/mpi_faces.toml");
}

fn run_on(path: &Path, backend: Backend, precision: Precision) -> grainflow::run::Summary {
    let scene = grainflow::scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    let out = tempfile::tempdir().unwrap();
    let mut scene = scene;
    let overrides = Overrides {
        precision: Some(precision),
        backend: Some(backend),
        ..Default::default()
    };
    let opts = RunOptions {
        out_dir: out.path().to_path_buf(),
        scene_length: overrides.apply_fluid(&mut scene),
        progress: false,
        restart: None,
        force: false,
    };
    run(&scene, &opts).unwrap_or_else(|e| panic!("{e}"))
}

/// The whole Poiseuille validation (to steady state) passes its checks on the GPU, with
/// the same results as the CPU. (Cavity and cylinder to steady state take minutes on
/// lavapipe: `jobs/gpu/validate.sh` runs them.)
#[test]
fn poiseuille_validation_passes_on_the_gpu() {
    if !have_adapter("poiseuille validation") {
        return;
    }
    let path = root().join("jobs/poiseuille/scene.toml");
    let gpu = run_on(&path, Backend::Gpu, Precision::F64);
    assert_checks_pass(&gpu);
    assert!(gpu.device.starts_with("gpu"), "{}", gpu.device);
    let cpu = run_on(&path, Backend::Cpu, Precision::F64);
    for (k, v) in &cpu.run.results {
        let g = gpu.run.results[k];
        // Error metrics are themselves small differences: compare on the scale of 1.
        assert!(
            (g - v).abs() <= 1e-12 * v.abs().max(1.0),
            "{k}: cpu {v} gpu {g}"
        );
    }
}

/// A blow-up is reported with the same step and cell as on the CPU, although the device
/// is only checked every few steps.
#[test]
fn instability_reports_the_same_step_and_cell_as_the_cpu() {
    if !have_adapter("instability") {
        return;
    }
    let text = r#"
title = "blow-up"
[domain]
cells = [16, 8]
spacing_m = 0.01
[fluid]
density_kg_m3 = 1000.0
viscosity_m2_s = 1.0e-7
reference_velocity_m_s = 0.1
reference_length_m = 0.16
lattice_velocity = 0.5
allow_high_mach = true
collision = { model = "bgk" }
[boundaries]
west = { kind = "wall" }
east = { kind = "wall" }
south = { kind = "wall" }
north = { kind = "moving-wall", velocity_m_s = [0.1, 0.0] }
[run]
steps = 5000
"#;
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("blow.toml");
    std::fs::write(&path, text).unwrap();
    let cpu = run_on(&path, Backend::Cpu, Precision::F64);
    let gpu = run_on(&path, Backend::Gpu, Precision::F64);
    assert_eq!(cpu.run.status, Status::Unstable);
    assert_eq!(gpu.run.status, Status::Unstable);
    let (ce, ge) = (cpu.run.error.unwrap(), gpu.run.error.unwrap());
    eprintln!("cpu: {ce}\ngpu: {ge}");
    // "unstable at step S: cell (X, Y) …": the same step and cell.
    let head = |e: &str| e.split(" has density").next().unwrap().to_string();
    assert_eq!(head(&ce), head(&ge));
}

fn cli(args: &[&str], env: &[(&str, &str)]) -> std::process::Output {
    let mut c = Command::new(BIN);
    c.args(args).arg("--quiet").current_dir(root());
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("grainflow starts")
}

/// Splitting the populations over 3 or 9 bindings (what large lattices need) gives the
/// same bits as one binding.
#[test]
fn split_population_buffers_give_identical_results() {
    if !have_adapter("split buffers") {
        return;
    }
    let d = tempfile::tempdir().unwrap();
    let mut outputs = Vec::new();
    for parts in ["1", "3", "9"] {
        let out = d.path().join(format!("split{parts}"));
        let o = cli(
            &[
                "run",
                "tests/scenes/mpi_channel.toml",
                "--backend",
                "gpu",
                "--precision",
                "f32",
                "--out",
                out.to_str().unwrap(),
            ],
            &[("GRAINFLOW_GPU_SPLIT", parts)],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let f = hdf5::File::open(out.join("fields.h5")).unwrap();
        let v = f
            .group("step_00000300")
            .unwrap()
            .dataset("velocity")
            .unwrap()
            .read_raw::<f64>()
            .unwrap();
        outputs.push(v);
    }
    assert!(outputs.iter().all(|v| v == &outputs[0]));
}

/// Without a Vulkan driver, `--backend gpu` fails at once and names the fix.
#[test]
fn no_adapter_gives_a_clear_error() {
    let o = cli(
        &[
            "run",
            "jobs/poiseuille/scene.toml",
            "--backend",
            "gpu",
            "--steps",
            "10",
            "--out",
            "/tmp/grainflow-no-adapter",
        ],
        &[
            ("VK_ICD_FILENAMES", "/nonexistent.json"),
            ("VK_DRIVER_FILES", "/nonexistent.json"),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("no GPU adapter found") && err.contains("--backend cpu"),
        "{err}"
    );
}

/// FP16 population storage with f32 arithmetic (Lehmann et al. 2022, "FP16S") on the
/// cavity: halves memory and traffic; after 500 steps the velocity stays within 2e-3 of
/// the CPU's f32 (measured 8.0e-4 on lavapipe; the README has the steady-state figures).
#[test]
fn fp16_storage_tracks_f32_on_the_cavity() {
    if !have_adapter("fp16 storage") {
        return;
    }
    if !grainflow::lbm::gpu::list_adapters().iter().any(|a| a.f16) {
        eprintln!("SKIPPED fp16 storage: the adapter has no SHADER_F16");
        return;
    }
    compare_stored::<f32>("jobs/cavity/re100.toml", 500, 2e-3, GpuStorage::F16);
}

/// FP16 storage is a GPU option on top of f32 arithmetic; anything else is refused by name.
#[test]
fn fp16_storage_without_gpu_f32_is_refused() {
    let scene = grainflow::scene::load(&root().join("jobs/poiseuille/scene.toml")).unwrap();
    let out = tempfile::tempdir().unwrap();
    for (backend, precision) in [
        (Backend::Cpu, Precision::F32),
        (Backend::Gpu, Precision::F64),
    ] {
        let mut scene = scene.clone();
        let overrides = Overrides {
            precision: Some(precision),
            backend: Some(backend),
            gpu_storage: Some(GpuStorage::F16),
            steps: Some(1),
            ..Default::default()
        };
        let opts = RunOptions {
            out_dir: out.path().to_path_buf(),
            scene_length: overrides.apply_fluid(&mut scene),
            progress: false,
            restart: None,
            force: false,
        };
        let e = match run(&scene, &opts) {
            Ok(_) => panic!("FP16 storage on {backend:?} {precision:?} was accepted"),
            Err(e) => e.to_string(),
        };
        assert!(
            e.contains("gpu_storage") && e.contains("--backend gpu --precision f32"),
            "{e}"
        );
    }
}
