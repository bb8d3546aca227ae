//! The halo exchange of one slab: at most two neighbours (left and right along x), one
//! contiguous send and one receive buffer per neighbour, posted non-blocking.
//!
//! The solver packs what crosses each face into [`SlabHalo::send_mut`], calls
//! [`SlabHalo::exchange`] with the work that does not need the halo, and unpacks from
//! [`SlabHalo::recv`]. Buffers are allocated once, at the first exchange of a given size.

use crate::comm::{Comm, Incoming, Outgoing};
use crate::slab::SlabPartition;

/// A side of a slab.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// Towards lower x (the west face of the slab).
    Left = 0,
    /// Towards higher x (the east face of the slab).
    Right = 1,
}

/// Tag of a message travelling towards lower x, and towards higher x.
const TAG_LEFTWARD: u16 = 0;
const TAG_RIGHTWARD: u16 = 1;

/// Neighbours and buffers of one slab's halo exchange.
#[derive(Debug, Clone, Default)]
pub struct SlabHalo {
    peers: [Option<usize>; 2],
    send: [Vec<u8>; 2],
    recv: [Vec<u8>; 2],
    bytes_sent: u64,
}

impl SlabHalo {
    /// The halo of `rank` in `partition`. With `periodic`, the outermost slabs exchange
    /// with each other (a single rank then exchanges with itself).
    pub fn new(partition: &SlabPartition, rank: usize, periodic: bool) -> Self {
        let (l, r) = partition.neighbours(rank, periodic);
        Self {
            peers: [l, r],
            send: Default::default(),
            recv: Default::default(),
            bytes_sent: 0,
        }
    }

    /// The neighbour rank on `side`, if that face is shared with one.
    pub fn peer(&self, side: Side) -> Option<usize> {
        self.peers[side as usize]
    }

    /// Resize the buffers of both sides to `bytes` (allocates only when they grow).
    pub fn set_message_bytes(&mut self, bytes: usize) {
        for b in self.send.iter_mut().chain(self.recv.iter_mut()) {
            b.resize(bytes, 0);
        }
    }

    /// The send buffer towards `side`; pack the face's outgoing data here.
    pub fn send_mut(&mut self, side: Side) -> &mut [u8] {
        &mut self.send[side as usize]
    }

    /// The data received from the neighbour on `side` in the last exchange.
    pub fn recv(&self, side: Side) -> &[u8] {
        &self.recv[side as usize]
    }

    /// Bytes this rank has sent over all exchanges so far.
    pub fn bytes_sent(&self) -> u64 {
        self.bytes_sent
    }

    /// Bytes this rank sends per exchange.
    pub fn bytes_per_exchange(&self) -> u64 {
        self.peers
            .iter()
            .zip(&self.send)
            .filter(|(p, _)| p.is_some())
            .map(|(_, b)| b.len() as u64)
            .sum()
    }

    /// Send both faces, run `overlap` while the messages travel, then wait for both.
    /// Returns the seconds spent waiting after `overlap` (exposed communication).
    pub fn exchange(&mut self, comm: &dyn Comm, overlap: &mut dyn FnMut()) -> f64 {
        let [sl, sr] = &self.send;
        let [rl, rr] = &mut self.recv;
        let mut sends = Vec::with_capacity(2);
        let mut recvs = Vec::with_capacity(2);
        if let Some(p) = self.peers[Side::Left as usize] {
            sends.push(Outgoing {
                peer: p,
                tag: TAG_LEFTWARD,
                data: sl,
            });
            recvs.push(Incoming {
                peer: p,
                tag: TAG_RIGHTWARD,
                data: rl,
            });
        }
        if let Some(p) = self.peers[Side::Right as usize] {
            sends.push(Outgoing {
                peer: p,
                tag: TAG_RIGHTWARD,
                data: sr,
            });
            recvs.push(Incoming {
                peer: p,
                tag: TAG_LEFTWARD,
                data: rr,
            });
        }
        self.bytes_sent += sends.iter().map(|s| s.data.len() as u64).sum::<u64>();
        comm.exchange(&sends, &mut recvs, overlap)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::comm::SingleProcess;

    #[test]
    fn periodic_single_rank_wraps_onto_itself() {
        let p = SlabPartition::uniform(8, 1).unwrap();
        let mut h = SlabHalo::new(&p, 0, true);
        h.set_message_bytes(2);
        h.send_mut(Side::Left).copy_from_slice(&[1, 2]);
        h.send_mut(Side::Right).copy_from_slice(&[3, 4]);
        let waited = h.exchange(&SingleProcess, &mut || {});
        assert!(waited >= 0.0);
        // What leaves through the west face enters through the east face, and vice versa.
        assert_eq!(h.recv(Side::Right), &[1, 2]);
        assert_eq!(h.recv(Side::Left), &[3, 4]);
        assert_eq!(h.bytes_per_exchange(), 4);
    }

    #[test]
    fn closed_single_rank_has_no_peers() {
        let p = SlabPartition::uniform(8, 1).unwrap();
        let mut h = SlabHalo::new(&p, 0, false);
        assert_eq!((h.peer(Side::Left), h.peer(Side::Right)), (None, None));
        h.set_message_bytes(4);
        h.exchange(&SingleProcess, &mut || {});
        assert_eq!(h.bytes_per_exchange(), 0);
    }
}
