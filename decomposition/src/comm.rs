//! The communicator interface and its single-process implementation.

use std::time::Instant;

/// A message to send during [`Comm::exchange`]: `data` goes to rank `peer` under `tag`.
#[derive(Debug, Clone, Copy)]
pub struct Outgoing<'a> {
    /// Destination rank.
    pub peer: usize,
    /// Message tag; matched with the [`Incoming`] of the same tag on the peer.
    pub tag: u16,
    /// Payload.
    pub data: &'a [u8],
}

/// A message to receive during [`Comm::exchange`]: exactly `data.len()` bytes from `peer`
/// under `tag`.
#[derive(Debug)]
pub struct Incoming<'a> {
    /// Source rank.
    pub peer: usize,
    /// Message tag.
    pub tag: u16,
    /// Destination of the payload; its length is the expected message size.
    pub data: &'a mut [u8],
}

/// What the solvers need from a communicator. Kept deliberately small so that a
/// single-process implementation is trivial and the MPI one is a thin wrapper.
///
/// All reductions are *deterministic*: contributions are combined in rank order, never in
/// message arrival order, so a result depends only on the values, not on timing.
pub trait Comm: Send + Sync {
    /// This process's rank, `0 <= rank < size`.
    fn rank(&self) -> usize;
    /// Number of ranks.
    fn size(&self) -> usize;
    /// Every rank's `local` slice concatenated in rank order (slices may differ in length).
    fn all_gather_f64(&self, local: &[f64]) -> Vec<f64>;
    /// Every rank's `local` slice of bytes concatenated in rank order.
    fn all_gather_bytes(&self, local: &[u8]) -> Vec<u8>;
    /// Every rank's `local` slice concatenated in rank order on the root (rank 0), an empty
    /// vector on the other ranks: for data only the root uses (the whole lattice for
    /// pictures and end-of-run analyses), which no other rank should have to hold.
    /// Collective.
    fn gather_f64(&self, local: &[f64]) -> Vec<f64> {
        let all = self.all_gather_f64(local);
        if self.is_root() {
            all
        } else {
            Vec::new()
        }
    }
    /// Block until every rank reaches this point.
    fn barrier(&self);
    /// Post every receive and send of one exchange round without blocking, run `overlap`
    /// while the messages travel, then wait for all of them. Returns the seconds spent
    /// waiting after `overlap` finished (the exposed communication time).
    ///
    /// Precondition: every [`Incoming`] is matched by exactly one [`Outgoing`] of the same
    /// tag and size on its peer, and vice versa.
    fn exchange(
        &self,
        sends: &[Outgoing<'_>],
        recvs: &mut [Incoming<'_>],
        overlap: &mut dyn FnMut(),
    ) -> f64;
    /// The raw MPI communicator, for libraries that do their own MPI-IO (parallel HDF5);
    /// `None` for a communicator that is not backed by MPI.
    fn raw_mpi(&self) -> Option<crate::RawComm> {
        None
    }
    /// Element-wise sum of `values` over all ranks, added in rank order; every rank gets
    /// the same bits in place.
    fn sum_f64(&self, values: &mut [f64]) {
        if self.size() == 1 {
            return;
        }
        let all = self.all_gather_f64(values);
        let n = values.len();
        for (i, v) in values.iter_mut().enumerate() {
            *v = (0..self.size()).fold(0.0, |acc, r| acc + all[r * n + i]);
        }
    }
    /// Maximum of `value` over all ranks (NaN wins, so a NaN anywhere is seen everywhere).
    fn max_f64(&self, value: f64) -> f64 {
        if self.size() == 1 {
            return value;
        }
        self.all_gather_f64(&[value])
            .into_iter()
            .fold(f64::NEG_INFINITY, |a, b| {
                if a.is_nan() || b > a || b.is_nan() {
                    b
                } else {
                    a
                }
            })
    }
    /// True on every rank if `flag` is true on any rank.
    fn any(&self, flag: bool) -> bool {
        self.max_f64(flag as u8 as f64) > 0.0
    }
    /// Whether this communicator may be called from a thread other than the one that
    /// created it (one call at a time): then the time loop can run on a worker of the
    /// thread pool. True without MPI; with MPI, where the library granted
    /// `MPI_THREAD_SERIALIZED` or more.
    fn any_thread(&self) -> bool {
        true
    }
    /// How many ranks of this communicator share this rank's node (its memory and cores),
    /// this one included: 1 without MPI.
    fn ranks_on_node(&self) -> usize {
        1
    }
    /// True on the rank that prints logs and writes serial files.
    fn is_root(&self) -> bool {
        self.rank() == 0
    }
}

/// The left fold, in order, of every rank's values concatenated in rank order. This is
/// the partition-independent sum: when each rank holds the per-column partial sums of the
/// columns it owns, the result has the same bits on any number of ranks.
pub fn ordered_sum(comm: &dyn Comm, local: &[f64]) -> f64 {
    comm.all_gather_f64(local).iter().fold(0.0, |a, b| a + b)
}

/// The one-rank communicator: collectives are the identity, and messages to self are
/// delivered by copying (so a periodic halo exchange with oneself works).
#[derive(Debug, Default, Clone, Copy)]
pub struct SingleProcess;

impl Comm for SingleProcess {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn all_gather_f64(&self, local: &[f64]) -> Vec<f64> {
        local.to_vec()
    }
    fn all_gather_bytes(&self, local: &[u8]) -> Vec<u8> {
        local.to_vec()
    }
    fn barrier(&self) {}
    fn exchange(
        &self,
        sends: &[Outgoing<'_>],
        recvs: &mut [Incoming<'_>],
        overlap: &mut dyn FnMut(),
    ) -> f64 {
        overlap();
        let t = Instant::now();
        for r in recvs.iter_mut() {
            assert_eq!(r.peer, 0, "single process: receive from rank {}", r.peer);
            let s = sends
                .iter()
                .find(|s| s.peer == 0 && s.tag == r.tag)
                .unwrap_or_else(|| panic!("single process: no send with tag {}", r.tag));
            r.data.copy_from_slice(s.data);
        }
        t.elapsed().as_secs_f64()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_process_collectives_are_identity() {
        let c = SingleProcess;
        assert_eq!((c.rank(), c.size()), (0, 1));
        assert!(c.is_root());
        let mut v = [1.5, -2.0];
        c.sum_f64(&mut v);
        assert_eq!(v, [1.5, -2.0]);
        assert_eq!(c.max_f64(3.0), 3.0);
        assert!(c.any(true) && !c.any(false));
        assert_eq!(ordered_sum(&c, &[0.1, 0.2, 0.3]), (0.1 + 0.2) + 0.3);
        assert_eq!(c.gather_f64(&[4.0, 5.0]), [4.0, 5.0]);
    }

    #[test]
    fn self_exchange_copies_by_tag() {
        let c = SingleProcess;
        let (a, b) = ([1u8, 2, 3], [9u8, 8]);
        let (mut ra, mut rb) = ([0u8; 3], [0u8; 2]);
        let mut ran = false;
        c.exchange(
            &[
                Outgoing {
                    peer: 0,
                    tag: 7,
                    data: &b,
                },
                Outgoing {
                    peer: 0,
                    tag: 5,
                    data: &a,
                },
            ],
            &mut [
                Incoming {
                    peer: 0,
                    tag: 5,
                    data: &mut ra,
                },
                Incoming {
                    peer: 0,
                    tag: 7,
                    data: &mut rb,
                },
            ],
            &mut || ran = true,
        );
        assert!(ran);
        assert_eq!((ra, rb), (a, b));
    }
}
