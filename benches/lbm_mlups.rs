//! MLUPS of the fused stream–collide on a 1024 × 1024 periodic box (`GRAINFLOW_BENCH_N`): BGK and MRT (plus TRT),
//! f32 and f64, on 1 and 2 threads, with the two-array kernel and in place (the AA pattern;
//! its push and local steps alternate, so a sample averages both). Criterion times one step;
//! MLUPS = cells / time. Bytes per update: the two-array kernel moves 2 × 9 × sizeof(T) plus,
//! in f32, 9 × sizeof(T) of write-allocate (f64 streams its stores): 144 B (f64), 108 B (f32);
//! in place, 2 × 9 × sizeof(T): 144 B (f64), 72 B (f32).
mod common;
use common::periodic_box;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use grainflow::lbm::{Collision, Real};

/// Box edge: 1024, or `GRAINFLOW_BENCH_N` (e.g. 128 for a box that fits in cache, which
/// shows the compute ceiling).
fn edge() -> usize {
    std::env::var("GRAINFLOW_BENCH_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1024)
}

fn bench_one<T: Real>(c: &mut Criterion, name: &str, collision: Collision) {
    let n = edge();
    let mut group = c.benchmark_group(format!("lbm_{n}x{n}_periodic"));
    group.throughput(Throughput::Elements((n * n) as u64));
    group.sample_size(20);
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        for in_place in [false, true] {
            let kernel = if in_place { "in-place" } else { "two-array" };
            // Built on the first call only, so benchmarks a filter skips allocate nothing.
            let mut lat = None;
            group.bench_function(format!("{name}/{}/{kernel}/{threads}t", T::NAME), |b| {
                let lat = lat.get_or_insert_with(|| {
                    let mut l = periodic_box::<T>(n, n, collision);
                    if in_place {
                        l.make_in_place();
                    }
                    l
                });
                b.iter(|| pool.install(|| lat.step().unwrap()));
            });
        }
    }
    group.finish();
}

fn benches(c: &mut Criterion) {
    let mrt = Collision::Mrt {
        s_e: 1.4,
        s_eps: 1.4,
        s_q: None,
    };
    bench_one::<f64>(c, "bgk", Collision::Bgk);
    bench_one::<f32>(c, "bgk", Collision::Bgk);
    bench_one::<f64>(c, "mrt", mrt);
    bench_one::<f32>(c, "mrt", mrt);
    bench_one::<f64>(c, "trt", Collision::Trt { magic: 3.0 / 16.0 });
    bench_one::<f32>(c, "trt", Collision::Trt { magic: 3.0 / 16.0 });
}

criterion_group!(lbm, benches);
criterion_main!(lbm);
