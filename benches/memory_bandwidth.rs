//! STREAM-style copy and triad on 200 MB of f64 (the roofline for the LBM kernel), on 1 and
//! 2 threads. Bytes are counted as STREAM does (no write-allocate).
use rayon::prelude::*;
use std::time::Instant;

fn best_of<F: FnMut()>(reps: usize, mut f: F) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let n = 25_000_000; // 200 MB per f64 array
    let a = vec![1.0f64; n];
    let mut b = vec![0.0f64; n];
    let c = vec![2.0f64; n];
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let chunk = n / (8 * threads);
            let copy = best_of(5, || {
                b.par_chunks_mut(chunk)
                    .zip(a.par_chunks(chunk))
                    .for_each(|(d, s)| d.copy_from_slice(s))
            });
            let triad = best_of(5, || {
                b.par_chunks_mut(chunk)
                    .zip(a.par_chunks(chunk))
                    .zip(c.par_chunks(chunk))
                    .for_each(|((d, x), y)| {
                        for k in 0..d.len() {
                            d[k] = x[k] + 3.0 * y[k];
                        }
                    })
            });
            println!(
                "memory bandwidth, {threads} thread(s): copy {:.1} GB/s, triad {:.1} GB/s",
                16.0 * n as f64 / copy / 1e9,
                24.0 * n as f64 / triad / 1e9
            );
        });
    }
    std::hint::black_box(&b);
}
