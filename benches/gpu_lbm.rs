//! GPU (wgpu) benchmark: the device's measured copy bandwidth, then MLUPS of the LBM on a
//! large periodic box and the fraction of that bandwidth it reaches (72 B per update in
//! f32, 144 B in f64: one read and one write of 9 populations).
//!
//! `cargo bench --bench gpu_lbm` — box of GRAINFLOW_BENCH_N² cells (default 2048²),
//! GRAINFLOW_BENCH_STEPS steps (default 50).
//! `cargo bench --bench gpu_lbm -- seed` — the seed study's speed-up table: 7.2 million
//! nodes (3000 × 2400), 100 iterations, fluid only: 1 CPU thread, all CPU threads, GPU.
mod common;
use common::periodic_box;
use decomposition::SingleProcess;
use grainflow::lbm::gpu::{GpuContext, GpuFluid};
use grainflow::lbm::{Collision, FluidBackend, Real};
use grainflow::scene::GpuStorage;
use std::sync::Arc;
use std::time::Instant;

fn env(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Device-to-device copy bandwidth (read + write bytes per second), best of 5.
fn copy_bandwidth(ctx: &GpuContext) -> f64 {
    let bytes = (256u64 << 20)
        .min(ctx.limits.max_buffer_size / 2)
        .min(ctx.limits.max_storage_buffer_binding_size.max(64 << 20));
    let make = |usage| {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: bytes,
            usage,
            mapped_at_creation: false,
        })
    };
    let a = make(wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST);
    let b = make(wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST);
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t = Instant::now();
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        for _ in 0..4 {
            enc.copy_buffer_to_buffer(&a, 0, &b, 0, bytes);
            enc.copy_buffer_to_buffer(&b, 0, &a, 0, bytes);
        }
        ctx.queue.submit([enc.finish()]);
        ctx.wait();
        best = best.min(t.elapsed().as_secs_f64());
    }
    2.0 * 8.0 * bytes as f64 / best
}

/// Seconds per step of `fluid` over `steps` steps (after 5 warm-up steps), synchronised.
fn time_steps<T: Real>(fluid: &mut dyn FluidBackend<T>, steps: usize) -> f64 {
    let comm = SingleProcess;
    for _ in 0..5 {
        fluid.stream_collide(&comm).unwrap();
        fluid.update_boundaries();
    }
    fluid.check(&comm).unwrap();
    let t = Instant::now();
    for _ in 0..steps {
        fluid.stream_collide(&comm).unwrap();
        fluid.update_boundaries();
    }
    fluid.check(&comm).unwrap();
    t.elapsed().as_secs_f64() / steps as f64
}

fn gpu_mlups<T: Real>(
    ctx: &Arc<GpuContext>,
    n: usize,
    steps: usize,
    c: Collision,
    storage: GpuStorage,
    bw: f64,
) {
    let mut g = match GpuFluid::new(periodic_box::<T>(n, n, c), ctx.clone(), storage) {
        Ok(g) => g,
        Err(e) => {
            println!("  {} {} {storage:?}: skipped ({e})", c.name(), T::NAME);
            return;
        }
    };
    let s = time_steps(&mut g, steps);
    let mlups = (n * n) as f64 / s / 1e6;
    let stored = if storage == GpuStorage::F16 {
        2
    } else {
        T::BYTES
    };
    let bytes = 2.0 * 9.0 * stored as f64;
    let label = if storage == GpuStorage::F16 {
        "+f16 storage"
    } else {
        ""
    };
    println!(
        "  {:3} {}{label}: {:9.1} MLUPS, {:7.1} GB/s at {} B/update = {:5.1} % of copy bandwidth",
        c.name(),
        T::NAME,
        mlups,
        mlups * 1e6 * bytes / 1e9,
        bytes,
        100.0 * mlups * 1e6 * bytes / bw
    );
}

fn seed_table(ctx: &Arc<GpuContext>) {
    let (nx, ny, steps) = (3000, 2400, 100);
    println!(
        "seed study problem: {nx} x {ny} = {:.1} M nodes, {steps} iterations, BGK f32, periodic",
        (nx * ny) as f64 / 1e6
    );
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut rows = Vec::new();
    for t in [1, threads] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap();
        let mut l = periodic_box::<f32>(nx, ny, Collision::Bgk);
        let s = pool.install(|| time_steps(&mut l, steps));
        rows.push((format!("CPU, {t} thread(s) (rayon)"), s * steps as f64));
    }
    let mut g = GpuFluid::new(
        periodic_box::<f32>(nx, ny, Collision::Bgk),
        ctx.clone(),
        GpuStorage::Native,
    )
    .unwrap();
    let s = time_steps(&mut g, steps);
    rows.push((format!("GPU: {}", ctx.adapter.name), s * steps as f64));
    println!("| device | time for {steps} iterations (s) | MLUPS | speed-up vs 1 thread |");
    println!("|---|---|---|---|");
    for (name, t) in &rows {
        println!(
            "| {name} | {t:.2} | {:.1} | {:.1} |",
            (nx * ny * steps) as f64 / t / 1e6,
            rows[0].1 / t
        );
    }
}

fn main() {
    let ctx = match GpuContext::open() {
        Ok(c) => Arc::new(c),
        Err(e) => {
            println!("gpu_lbm: skipped: {e}");
            return;
        }
    };
    println!(
        "adapter: {} ({}, {}), f64: {}",
        ctx.adapter.name, ctx.adapter.backend, ctx.adapter.device_type, ctx.adapter.f64
    );
    if std::env::args().any(|a| a == "seed") {
        seed_table(&ctx);
        return;
    }
    let bw = copy_bandwidth(&ctx);
    println!("device copy bandwidth: {:.1} GB/s (read + write)", bw / 1e9);
    let n = env("GRAINFLOW_BENCH_N", 2048);
    let steps = env("GRAINFLOW_BENCH_STEPS", 50);
    println!("periodic box {n} x {n}, {steps} steps:");
    let native = GpuStorage::Native;
    gpu_mlups::<f32>(&ctx, n, steps, Collision::Bgk, native, bw);
    gpu_mlups::<f32>(
        &ctx,
        n,
        steps,
        Collision::Mrt {
            s_e: 1.1,
            s_eps: 1.1,
            s_q: None,
        },
        native,
        bw,
    );
    if ctx.adapter.f16 {
        gpu_mlups::<f32>(&ctx, n, steps, Collision::Bgk, GpuStorage::F16, bw);
    }
    if ctx.adapter.f64 {
        gpu_mlups::<f64>(&ctx, n, steps, Collision::Bgk, native, bw);
    }
}
