//! CPU/GPU parity of coupled runs (the GPU test binaries share it).

use super::root;
use decomposition::SingleProcess;
use grainflow::lbm::Real;
use grainflow::run::{Backend, GpuStorage, Kernel};
use grainflow::simulation::Simulation;

/// max |a − b| / max |a|.
pub fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
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
pub fn grains<T: Real>(sim: &Simulation<T>) -> Vec<[f64; 7]> {
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

/// Run the coupled scene `text` (its `scheme = "bounce-back"` replaced by `scheme`) for
/// `steps` steps on the CPU and on the GPU, side by side, and check that every grain's
/// position, velocity, spin and hydrodynamic force, and the fluid's velocity and density,
/// agree within `tolerance` (relative to each quantity's largest magnitude).
pub fn compare<T: Real>(text: &str, scheme: &str, steps: usize, tolerance: f64) {
    let text = text.replace(
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
