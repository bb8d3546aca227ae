//! The communicator interface.

/// What the solvers need from a communicator. Kept deliberately small so that a
/// single-process implementation is trivial and an MPI one is a thin wrapper.
///
/// All reductions are *deterministic*: implementations must combine contributions in
/// rank order so that results do not depend on message arrival order.
pub trait Comm: Send + Sync {
    /// This process's rank, `0 <= rank < size`.
    fn rank(&self) -> usize;
    /// Number of ranks.
    fn size(&self) -> usize;
    /// Sum of `values` element-wise over all ranks, combined in rank order; every rank gets
    /// the result in place.
    fn sum_f64(&self, values: &mut [f64]);
    /// Maximum of `value` over all ranks.
    fn max_f64(&self, value: f64) -> f64;
    /// Block until every rank reaches this point.
    fn barrier(&self);
    /// True on the rank that prints logs and writes serial files.
    fn is_root(&self) -> bool {
        self.rank() == 0
    }
}

/// The one-rank communicator: every collective is the identity.
#[derive(Debug, Default, Clone, Copy)]
pub struct SingleProcess;

impl Comm for SingleProcess {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn sum_f64(&self, _values: &mut [f64]) {}
    fn max_f64(&self, value: f64) -> f64 {
        value
    }
    fn barrier(&self) {}
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
    }
}
