//! MLUPS of the fused stream–collide on a 1024 × 1024 periodic box: BGK and MRT (plus TRT),
//! f32 and f64, on 1 and 2 threads. Criterion times one step; MLUPS = cells / time.
//! Bytes per update implied by the two-array kernel: 2 × 9 × sizeof(T) (read + write), plus
//! 9 × sizeof(T) of write-allocate traffic: 216 B (f64) and 108 B (f32).
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use grainflow::lbm::lattice::{FaceCondition, LatticeSetup};
use grainflow::lbm::{Collision, Lattice, Real};

const N: usize = 1024;

fn lattice<T: Real>(collision: Collision) -> Lattice<T> {
    let setup = LatticeSetup {
        nx: N,
        ny: N,
        cells: vec![0; N * N],
        faces: [
            FaceCondition::Periodic,
            FaceCondition::Periodic,
            FaceCondition::Periodic,
            FaceCondition::Periodic,
        ],
        solids: vec![],
        collision,
        tau0: 0.6,
        smagorinsky: None,
        force: [0.0, 0.0],
    };
    let mut l = Lattice::<T>::new(setup);
    for y in 0..N {
        for x in 0..N {
            let (a, b) = (x as f64 / N as f64, y as f64 / N as f64);
            l.set_equilibrium(
                x,
                y,
                1.0,
                [
                    0.05 * (std::f64::consts::TAU * b).sin(),
                    0.05 * (std::f64::consts::TAU * a).sin(),
                ],
            );
        }
    }
    l.update_boundaries();
    l
}

fn bench_one<T: Real>(c: &mut Criterion, name: &str, collision: Collision) {
    let mut group = c.benchmark_group("lbm_1024x1024_periodic");
    group.throughput(Throughput::Elements((N * N) as u64));
    group.sample_size(20);
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut lat = lattice::<T>(collision);
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
