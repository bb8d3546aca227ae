//! The Open MPI communicator (rsmpi). MPI is called from the main thread only
//! (`MPI_THREAD_FUNNELED`); rayon workers never touch it.

use crate::comm::{Comm, Incoming, Outgoing};
use mpi::collective::{CommunicatorCollectives, Root, SystemOperation};
use mpi::datatype::PartitionMut;
use mpi::point_to_point::{Destination, Source};
use mpi::topology::{Communicator, SimpleCommunicator};
use mpi::traits::AsRaw;
use mpi::Count;
use std::time::Instant;

/// The raw MPI communicator handle (`MPI_Comm`), for parallel HDF5.
pub type RawComm = mpi::ffi::MPI_Comm;

/// Whether this process was started by an MPI launcher (mpirun, srun, …). A plain
/// `grainflow run` is then a one-rank job that never initialises MPI.
pub fn launched_by_mpi() -> bool {
    [
        "OMPI_COMM_WORLD_SIZE",
        "PMI_SIZE",
        "PMIX_RANK",
        "MPI_LOCALNRANKS",
        "SLURM_STEP_NUM_TASKS",
    ]
    .iter()
    .any(|v| std::env::var_os(v).is_some())
}

/// `MPI_COMM_WORLD` of an initialised MPI universe. Dropping it finalises MPI.
pub struct MpiComm {
    world: SimpleCommunicator,
    rank: usize,
    size: usize,
    /// The library granted MPI_THREAD_SERIALIZED or more.
    serialized: bool,
    /// Ranks of `world` on this rank's node (`MPI_Comm_split_type`, shared memory).
    ranks_on_node: usize,
    // Declared last: finalises MPI after `world` is dropped.
    _universe: mpi::environment::Universe,
}

// SAFETY: grainflow calls `Comm` methods from its time loop only, one call at a time: on
// the thread that initialised MPI, or, where the library granted MPI_THREAD_SERIALIZED
// (`any_thread`), on the one pool worker that runs the loop. The handle itself is an
// immutable pointer that Open MPI allows to be shared.
unsafe impl Send for MpiComm {}
unsafe impl Sync for MpiComm {}

impl MpiComm {
    /// Initialise MPI, asking for serialized threading (calls from any one thread at a
    /// time: the time loop runs on a pool worker, see [`Comm::any_thread`]). `None` if MPI
    /// was already initialised.
    pub fn init() -> Option<Self> {
        let (universe, granted) = mpi::initialize_with_threading(mpi::Threading::Serialized)?;
        let world = universe.world();
        let ranks_on_node = world.split_shared(world.rank()).size() as usize;
        Some(Self {
            rank: world.rank() as usize,
            size: world.size() as usize,
            world,
            serialized: granted >= mpi::Threading::Serialized,
            ranks_on_node,
            _universe: universe,
        })
    }

    /// Count `calls` MPI collectives for [`crate::Traffic`] (none on one rank: it talks to
    /// no one).
    fn count_collectives(&self, calls: u64) {
        if self.size > 1 {
            crate::traffic::count_collective(calls);
        }
    }

    fn counts(&self, n: usize) -> (Vec<Count>, Vec<Count>, usize) {
        let mut counts = vec![0 as Count; self.size];
        self.world.all_gather_into(&(n as Count), &mut counts[..]);
        Self::offsets(counts)
    }

    /// Displacements and total of per-rank `counts`.
    fn offsets(counts: Vec<Count>) -> (Vec<Count>, Vec<Count>, usize) {
        let displs: Vec<Count> = counts
            .iter()
            .scan(0, |acc, &c| {
                let d = *acc;
                *acc += c;
                Some(d)
            })
            .collect();
        let total = counts.iter().map(|&c| c as usize).sum();
        (counts, displs, total)
    }
}

impl Comm for MpiComm {
    fn rank(&self) -> usize {
        self.rank
    }
    fn any_thread(&self) -> bool {
        self.serialized
    }
    fn ranks_on_node(&self) -> usize {
        self.ranks_on_node
    }
    fn size(&self) -> usize {
        self.size
    }
    fn all_gather_f64(&self, local: &[f64]) -> Vec<f64> {
        let t = Instant::now();
        self.count_collectives(2);
        let (counts, displs, total) = self.counts(local.len());
        let mut out = vec![0.0; total];
        let mut part = PartitionMut::new(&mut out[..], &counts[..], &displs[..]);
        self.world.all_gather_varcount_into(local, &mut part);
        crate::traffic::count_wait(t.elapsed().as_secs_f64());
        out
    }
    fn all_gather_bytes(&self, local: &[u8]) -> Vec<u8> {
        let t = Instant::now();
        self.count_collectives(2);
        let (counts, displs, total) = self.counts(local.len());
        let mut out = vec![0u8; total];
        let mut part = PartitionMut::new(&mut out[..], &counts[..], &displs[..]);
        self.world.all_gather_varcount_into(local, &mut part);
        crate::traffic::count_wait(t.elapsed().as_secs_f64());
        out
    }
    /// Two `MPI_Gather`s to rank 0 (the counts, then the values): the other ranks keep
    /// nothing of the result.
    fn gather_f64(&self, local: &[f64]) -> Vec<f64> {
        self.count_collectives(2);
        let root = self.world.process_at_rank(0);
        let n = local.len() as Count;
        if self.rank != 0 {
            root.gather_into(&n);
            root.gather_varcount_into(local);
            return Vec::new();
        }
        let mut counts = vec![0 as Count; self.size];
        root.gather_into_root(&n, &mut counts[..]);
        let (counts, displs, total) = Self::offsets(counts);
        let mut out = vec![0.0; total];
        let mut part = PartitionMut::new(&mut out[..], &counts[..], &displs[..]);
        root.gather_varcount_into_root(local, &mut part);
        out
    }
    fn barrier(&self) {
        let t = Instant::now();
        self.count_collectives(1);
        self.world.barrier();
        crate::traffic::count_wait(t.elapsed().as_secs_f64());
    }
    /// One `MPI_Allreduce(MAX)`: called every step (instability and signal agreement), so
    /// it avoids the two collectives of the gather-based default. Max is order-independent.
    fn max_f64(&self, value: f64) -> f64 {
        self.count_collectives(1);
        // MPI's MAX is undefined for NaN: carry "some rank has NaN" as a second value.
        let send = if value.is_nan() {
            [f64::NEG_INFINITY, 1.0]
        } else {
            [value, 0.0]
        };
        let mut out = [0.0; 2];
        let t = Instant::now();
        self.world
            .all_reduce_into(&send[..], &mut out[..], SystemOperation::max());
        crate::traffic::count_wait(t.elapsed().as_secs_f64());
        if out[1] > 0.0 {
            f64::NAN
        } else {
            out[0]
        }
    }
    fn exchange(
        &self,
        sends: &[Outgoing<'_>],
        recvs: &mut [Incoming<'_>],
        overlap: &mut dyn FnMut(),
    ) -> f64 {
        let away = sends.iter().filter(|s| s.peer != self.rank);
        crate::traffic::count_sent(away.clone().count(), away.map(|s| s.data.len()).sum());
        mpi::request::scope(|scope| {
            // Receives first, so that eager messages land directly in their buffers.
            let rreq: Vec<_> = recvs
                .iter_mut()
                .map(|r| {
                    self.world
                        .process_at_rank(r.peer as i32)
                        .immediate_receive_into_with_tag(scope, &mut *r.data, r.tag as i32)
                })
                .collect();
            let sreq: Vec<_> = sends
                .iter()
                .map(|s| {
                    self.world
                        .process_at_rank(s.peer as i32)
                        .immediate_send_with_tag(scope, s.data, s.tag as i32)
                })
                .collect();
            overlap();
            let t = Instant::now();
            for r in rreq {
                r.wait();
            }
            for s in sreq {
                s.wait();
            }
            let waited = t.elapsed().as_secs_f64();
            crate::traffic::count_wait(waited);
            waited
        })
    }
    fn raw_mpi(&self) -> Option<RawComm> {
        Some(self.world.as_raw())
    }
}
