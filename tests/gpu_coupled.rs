//! The coupled fluid–grain step on the wgpu backend against the CPU backend (Mesa lavapipe
//! in CI; skipped, and passing, when no adapter exists). The device recomputes the cells at
//! the grains after its sweep and returns one momentum per link or solid share; the host
//! sums them per grain. After 300 steps of ten grains settling, colliding and crossing the
//! tank, every grain's position, velocity, spin and hydrodynamic force, and the fluid's
//! velocity and density, agree within 1e-5 in f32 and 1e-10 in f64, for each scheme.
mod common;
use common::root;
use decomposition::SingleProcess;
use grainflow::lbm::Real;
use grainflow::run::{Backend, GpuStorage, Kernel};
use grainflow::simulation::Simulation;

/// max |a − b| / max |a|.
fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    if scale == 0.0 {
        diff
    } else {
        diff / scale
    }
}

/// Each grain's (x, y, vx, vy, ω, hydrodynamic fx, fy), sorted by id.
fn grains<T: Real>(sim: &Simulation<T>) -> Vec<[f64; 7]> {
    let c = sim.grains.as_ref().expect("coupled");
    let g = &c.system().grains;
    let mut rows: Vec<(u64, [f64; 7])> = (0..c.system().owned())
        .map(|i| {
            let f = c.hydrodynamic(i);
            (
                g.id[i],
                [g.x[i], g.y[i], g.vx[i], g.vy[i], g.omega[i], f[0], f[1]],
            )
        })
        .collect();
    rows.sort_by_key(|r| r.0);
    rows.into_iter().map(|r| r.1).collect()
}

fn compare<T: Real>(scheme: &str, steps: usize, tolerance: f64) {
    let text = std::fs::read_to_string(root().join("tests/scenes/mpi_grains_box.toml"))
        .unwrap()
        .replace(
            "scheme = \"bounce-back\"",
            &format!("scheme = \"{scheme}\""),
        );
    let path = root().join("tests/scenes/__gpu_coupled.toml");
    let scene = grainflow::scene::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"));
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
    let mut gpu = Simulation::<T>::new(
        &scene,
        &comm,
        Backend::Gpu,
        GpuStorage::Native,
        Kernel::TwoArray,
        None,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    for _ in 0..steps {
        cpu.step(&comm).expect("CPU run stays stable");
        gpu.step(&comm).expect("GPU run stays stable");
    }
    gpu.check(&comm).expect("GPU run stays stable");
    let (ga, gb) = (grains(&cpu), grains(&gpu));
    let column = |rows: &[[f64; 7]], k: usize| -> Vec<f64> { rows.iter().map(|r| r[k]).collect() };
    let mut report = Vec::new();
    for (name, k) in [
        ("grain x", 0),
        ("grain y", 1),
        ("grain vx", 2),
        ("grain vy", 3),
        ("grain spin", 4),
        ("hydrodynamic fx", 5),
        ("hydrodynamic fy", 6),
    ] {
        report.push((name, rel_diff(&column(&ga, k), &column(&gb, k))));
    }
    let (a, b) = (cpu.fields(&comm), gpu.fields(&comm));
    let speed: Vec<f64> = a.ux.iter().zip(&a.uy).map(|(x, y)| x.hypot(*y)).collect();
    let vmax = speed.iter().fold(0.0f64, |m, v| m.max(*v));
    let dmax = (0..a.ux.len())
        .map(|k| (a.ux[k] - b.ux[k]).hypot(a.uy[k] - b.uy[k]))
        .fold(0.0f64, f64::max);
    report.push(("fluid velocity", dmax / vmax));
    report.push(("fluid density", rel_diff(&a.rho, &b.rho)));
    for (name, d) in &report {
        eprintln!(
            "{scheme} {} after {steps} steps: {name} differs by {d:.2e} (≤ {tolerance:.0e})",
            T::NAME
        );
    }
    for (name, d) in report {
        assert!(
            d <= tolerance,
            "{scheme} {}: {name} differs by {d:.3e}",
            T::NAME
        );
    }
}

#[test]
fn coupled_gpu_step_matches_the_cpu_for_every_scheme() {
    let adapters = grainflow::gpu::list_adapters();
    if adapters.is_empty() {
        eprintln!("SKIPPED: no GPU adapter (scripts/setup.sh installs Mesa lavapipe)");
        return;
    }
    for scheme in ["bounce-back", "interpolated", "psm"] {
        compare::<f32>(scheme, 300, 1e-5);
        if adapters.iter().any(|a| a.f64) {
            compare::<f64>(scheme, 300, 1e-10);
        }
    }
}

/// A coupled run that blows up on the device stops as it does on the CPU, naming the same
/// step, cell and grain: the device reports its first bad plan cell with the momenta it
/// reads back (f64, where both backends round alike).
#[test]
fn coupled_gpu_blow_up_names_the_cpus_step_cell_and_grain() {
    let adapters = grainflow::gpu::list_adapters();
    if !adapters.iter().any(|a| a.f64) {
        eprintln!("SKIPPED: no GPU adapter with f64");
        return;
    }
    use grainflow::run::Precision;
    use grainflow::run::{run, RunOptions, Status};
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
            let opts = RunOptions {
                out_dir: out.path().to_path_buf(),
                precision: Some(Precision::F64),
                steps: None,
                progress: false,
                restart: None,
                backend: Some(backend),
                gpu_storage: None,
                kernel: Some(Kernel::TwoArray),
            };
            let s = run(&scene, &opts).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(s.status, Status::Unstable, "{scheme} on {backend:?}");
            s.error.unwrap()
        };
        let (cpu, gpu) = (error(Backend::Cpu), error(Backend::Gpu));
        eprintln!("{scheme}\n  cpu: {cpu}\n  gpu: {gpu}");
        // "unstable at step S: cell (X, Y) next to grain G has density …".
        let head = |e: &str| e.split(" has density").next().unwrap().to_string();
        assert!(cpu.contains("next to grain"), "{cpu}");
        assert_eq!(head(&cpu), head(&gpu), "{scheme}");
    }
}
