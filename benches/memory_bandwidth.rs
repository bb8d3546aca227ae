//! STREAM-style copy and triad on 200 MB of f64, on 1 and 2 threads, counted as STREAM
//! does (no write-allocate), and an in-place update (each value read and written back,
//! x ← 1.0001 x + 1): the in-place LBM kernel's access pattern. Every line it writes was
//! just read, so its 16 bytes per value are the real traffic, with no write-allocate to
//! argue about. It runs over one array and over nine planes at once (as the kernel streams
//! its nine directions, which keeps more misses in flight); the nine-plane figure is the
//! roofline for the in-place kernel's 72 bytes per update in f32 and 144 in f64. The
//! nine-plane update runs twice: on 4 KiB pages (where THP is `madvise` or `never`) and on
//! an array advised onto transparent huge pages, as the lattice's population buffer is
//! (`AlignedBuf`).
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

/// A raw pointer the update's tasks share (each reads and writes its own cells).
struct SharedPtr(*mut f64);
// SAFETY: each task reads and writes only its own range of cells of each plane.
unsafe impl Sync for SharedPtr {}

fn main() {
    let n = 25_000_000; // 200 MB per f64 array
    let a = vec![1.0f64; n];
    let mut b = vec![0.0f64; n];
    let c = vec![2.0f64; n];
    // The same size on huge pages: advised before its first touch, zero-filled by the
    // pool's threads as the lattice's buffer is (`b` is first touched by the parallel
    // passes too).
    let mut h = grainflow::lbm::aligned::AlignedBuf::<f64>::zeros(n);
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
            let update = best_of(5, || {
                b.par_chunks_mut(chunk).for_each(|d| {
                    for v in d.iter_mut() {
                        *v = 1.0001 * *v + 1.0;
                    }
                })
            });
            // The same update over nine planes at once, as the LBM kernel streams its nine
            // directions: each task takes one range of cells of every plane.
            let plane = n / 9;
            let cells = plane / (8 * threads);
            let nine_planes = |array: &mut [f64]| {
                let base = SharedPtr(array.as_mut_ptr());
                (0..plane.div_ceil(cells)).into_par_iter().for_each(|t| {
                    let base = &base;
                    let (lo, hi) = (t * cells, ((t + 1) * cells).min(plane));
                    for k in lo..hi {
                        for i in 0..9 {
                            // SAFETY: tasks take disjoint cell ranges of every plane.
                            unsafe {
                                let v = base.0.add(i * plane + k);
                                *v = 1.0001 * *v + 1.0;
                            }
                        }
                    }
                })
            };
            let update9 = best_of(5, || nine_planes(&mut b));
            let update9_huge = best_of(5, || nine_planes(&mut h));
            println!(
                "memory bandwidth, {threads} thread(s): copy {:.1} GB/s, triad {:.1} GB/s, \
                 update in place {:.1} GB/s (nine planes: {:.1} GB/s; on huge pages: {:.1} GB/s)",
                16.0 * n as f64 / copy / 1e9,
                24.0 * n as f64 / triad / 1e9,
                16.0 * n as f64 / update / 1e9,
                16.0 * (9 * plane) as f64 / update9 / 1e9,
                16.0 * (9 * plane) as f64 / update9_huge / 1e9
            );
        });
    }
    std::hint::black_box((&b, &h));
}
