//! Where a time loop runs in the thread pool, and what the pool's other workers do between
//! its parallel passes.
//!
//! A coupled step runs a dozen and more parallel passes, several of them short (tens of µs),
//! with serial work between them. An idle rayon worker spins briefly and then sleeps; the
//! next pass must wake it (a futex call by the loop's thread) and it joins late (tens of µs
//! on a VM), so a short pass runs mostly on one thread. Under the `active` wait policy the
//! other workers keep looking for work until the loop ends, as OpenMP threads do under
//! `OMP_WAIT_POLICY=active`: they take a pass's work as soon as it exists, and they keep
//! their cores busy while the loop does serial work or waits for MPI. Results do not depend
//! on it (every parallel pass gives the same bits on any schedule).

use decomposition::Comm;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set while a time loop runs with its idle workers looking for work.
static ACTIVE: AtomicBool = AtomicBool::new(false);

/// Whether the idle workers look for work now (inside [`in_pool`] with `spin`): what a
/// run's `summary.json` reports as `idle_workers_active`.
pub fn idle_workers_active() -> bool {
    ACTIVE.load(Ordering::Relaxed)
}

/// What the pool's idle workers do while a time loop runs (`grainflow run --wait-policy`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum WaitPolicy {
    /// `Active` where every thread of every rank on this node has a core of its own
    /// ([`WaitPolicy::spins`]), else `Passive`.
    #[default]
    Auto,
    /// Keep looking for work until the loop ends (cores stay busy).
    Active,
    /// rayon's own: spin briefly, then sleep until new work wakes the worker.
    Passive,
}

impl WaitPolicy {
    /// Whether idle workers look for work through the loop, for `threads` pool threads per
    /// rank, `ranks_on_node` ranks on this node and `cores` hardware threads on it. Never
    /// with one thread (there is no other worker).
    pub fn spins(self, threads: usize, ranks_on_node: usize, cores: usize) -> bool {
        threads > 1
            && match self {
                Self::Active => true,
                Self::Passive => false,
                Self::Auto => threads.saturating_mul(ranks_on_node.max(1)) <= cores,
            }
    }

    /// [`WaitPolicy::spins`] for the global pool, the ranks of `comm` on this node and the
    /// cores the OS gives this process; false where the loop cannot run on a worker
    /// ([`Comm::any_thread`]), which [`in_pool`] needs for spinning.
    pub fn spins_here(self, comm: &dyn Comm) -> bool {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        comm.any_thread() && self.spins(rayon::current_num_threads(), comm.ranks_on_node(), cores)
    }
}

/// Run the time loop `run` on a worker of the global pool where `comm` allows it
/// ([`Comm::any_thread`]), else on this thread; with `spin`, the pool's other workers look
/// for work until `run` returns (or unwinds). On a worker, the loop's own parallel passes
/// start from inside the pool: the calling thread neither sleeps until each ends nor has
/// to be woken after it. `spin` needs the loop on a worker and is ignored otherwise.
pub fn in_pool<R: Send>(comm: &dyn Comm, spin: bool, run: impl FnOnce() -> R + Send) -> R {
    if !comm.any_thread() {
        return run();
    }
    let done = AtomicBool::new(false);
    rayon::scope(|s| {
        if spin {
            ACTIVE.store(true, Ordering::Relaxed);
            let (home, done) = (rayon::current_thread_index(), &done);
            // One job per worker: each but the loop's own looks for work until the end.
            s.spawn_broadcast(move |_, ctx| {
                if Some(ctx.index()) != home {
                    look_for_work(done);
                }
            });
        }
        // Set when `run` returns or unwinds, so that the scope's workers end either way.
        let _end = SetOnDrop(&done);
        run()
    })
}

/// Run the pool's pending work as it appears, until `done`.
fn look_for_work(done: &AtomicBool) {
    while !done.load(Ordering::Acquire) {
        if let Some(rayon::Yield::Idle) = rayon::yield_now() {
            // A short pause between looks, so that the looking does not keep the deques'
            // cache lines away from the worker that pushes to them.
            for _ in 0..32 {
                std::hint::spin_loop();
            }
        }
    }
}

/// Sets its flag when dropped.
struct SetOnDrop<'a>(&'a AtomicBool);

impl Drop for SetOnDrop<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
        ACTIVE.store(false, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use decomposition::SingleProcess;
    use rayon::prelude::*;

    #[test]
    fn auto_spins_only_when_every_thread_has_a_core() {
        let auto = WaitPolicy::Auto;
        assert!(auto.spins(2, 1, 2));
        assert!(auto.spins(4, 4, 16));
        assert!(
            !auto.spins(2, 2, 2),
            "two ranks of two threads on two cores"
        );
        assert!(!auto.spins(1, 1, 8), "one thread has no other worker");
        assert!(WaitPolicy::Active.spins(8, 8, 2));
        assert!(!WaitPolicy::Active.spins(1, 1, 2));
        assert!(!WaitPolicy::Passive.spins(2, 1, 64));
    }

    /// A loop of nested parallel passes ends, on a pool of 3 workers, with the same sums
    /// whether the idle workers spin or not, and ends when it panics too.
    #[test]
    fn a_loop_ends_with_the_same_results_whether_workers_spin() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let comm = SingleProcess;
        let sums = |spin: bool| {
            pool.install(|| {
                in_pool(&comm, spin, || {
                    (0..200u64)
                        .map(|step| {
                            (0..1000u64)
                                .into_par_iter()
                                .map(|i| {
                                    (0..50u64)
                                        .into_par_iter()
                                        .map(|j| i * j + step)
                                        .sum::<u64>()
                                })
                                .sum::<u64>()
                        })
                        .collect::<Vec<_>>()
                })
            })
        };
        assert_eq!(sums(true), sums(false));
        let seen = pool.install(|| in_pool(&comm, true, idle_workers_active));
        assert!(
            seen && !idle_workers_active(),
            "active inside the loop only"
        );
        let unwound = pool.install(|| {
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                in_pool(&comm, true, || -> u64 { panic!("a step failed") })
            }))
        });
        assert!(unwound.is_err(), "the panic reaches the caller");
    }
}
