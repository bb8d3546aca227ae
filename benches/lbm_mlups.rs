//! MLUPS of the fused stream–collide on a 1024 × 1024 periodic box: BGK and MRT (plus TRT),
//! f32 and f64, on 1 and 2 threads. Criterion times one step; MLUPS = cells / time.
//! Bytes per update implied by the two-array kernel: 2 × 9 × sizeof(T) (read + write), plus
//! 9 × sizeof(T) of write-allocate traffic: 216 B (f64) and 108 B (f32).
mod common;
use common::periodic_box;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use grainflow::lbm::{Collision, Real};

const N: usize = 1024;

fn bench_one<T: Real>(c: &mut Criterion, name: &str, collision: Collision) {
    let mut group = c.benchmark_group("lbm_1024x1024_periodic");
    group.throughput(Throughput::Elements((N * N) as u64));
    group.sample_size(20);
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut lat = periodic_box::<T>(N, N, collision);
        group.bench_function(format!("{name}/{}/{threads}t", T::NAME), |b| {
            b.iter(|| pool.install(|| lat.step().unwrap()));
        });
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
