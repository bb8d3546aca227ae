//! What this process has sent to other ranks: point-to-point bytes (halo faces, ghost
//! grains, migrations, grid strips) and collective calls. Counted by [`crate::MpiComm`]
//! (a single process sends nothing), read by the time loop so that a run can report its
//! communication per step for a scaling model.

use std::sync::atomic::{AtomicU64, Ordering};

static SENT_BYTES: AtomicU64 = AtomicU64::new(0);
static MESSAGES: AtomicU64 = AtomicU64::new(0);
static COLLECTIVES: AtomicU64 = AtomicU64::new(0);
static WAIT_NS: AtomicU64 = AtomicU64::new(0);

/// Counts of this process's communication since it started.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Traffic {
    /// Bytes sent to other ranks in point-to-point messages.
    pub sent_bytes: u64,
    /// Point-to-point messages sent to other ranks.
    pub messages: u64,
    /// Collective calls (all-gathers, gathers, reductions, barriers) this rank joined.
    pub collectives: u64,
    /// Nanoseconds this rank spent inside collectives and waiting for messages (blocked on
    /// the others, or moving data): its time not spent on its own work.
    pub wait_ns: u64,
}

impl Traffic {
    /// The counts now.
    pub fn now() -> Self {
        Traffic {
            sent_bytes: SENT_BYTES.load(Ordering::Relaxed),
            messages: MESSAGES.load(Ordering::Relaxed),
            collectives: COLLECTIVES.load(Ordering::Relaxed),
            wait_ns: WAIT_NS.load(Ordering::Relaxed),
        }
    }

    /// Seconds spent in communication ([`Traffic::wait_ns`]).
    pub fn wait_seconds(&self) -> f64 {
        self.wait_ns as f64 * 1e-9
    }

    /// Both counts added.
    pub fn plus(self, other: Traffic) -> Traffic {
        Traffic {
            sent_bytes: self.sent_bytes + other.sent_bytes,
            messages: self.messages + other.messages,
            collectives: self.collectives + other.collectives,
            wait_ns: self.wait_ns + other.wait_ns,
        }
    }

    /// What was sent between `earlier` and `self`.
    pub fn since(self, earlier: Traffic) -> Traffic {
        Traffic {
            sent_bytes: self.sent_bytes.saturating_sub(earlier.sent_bytes),
            messages: self.messages.saturating_sub(earlier.messages),
            collectives: self.collectives.saturating_sub(earlier.collectives),
            wait_ns: self.wait_ns.saturating_sub(earlier.wait_ns),
        }
    }
}

pub(crate) fn count_sent(messages: usize, bytes: usize) {
    MESSAGES.fetch_add(messages as u64, Ordering::Relaxed);
    SENT_BYTES.fetch_add(bytes as u64, Ordering::Relaxed);
}

pub(crate) fn count_collective(calls: u64) {
    COLLECTIVES.fetch_add(calls, Ordering::Relaxed);
}

pub(crate) fn count_wait(seconds: f64) {
    WAIT_NS.fetch_add((seconds * 1e9) as u64, Ordering::Relaxed);
}
