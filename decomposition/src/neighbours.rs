//! Exchanges of a slab with its two neighbours (left = side 0, right = side 1): one
//! message per neighbour per round, never one per item.

use crate::{Comm, Incoming, Outgoing};

/// One exchange round with both neighbours: `out[side]` goes to `peers[side]` under tag
/// `tag + side`; `into[side]` is filled from that neighbour (the buffer's length is the
/// expected size). Sides without a neighbour are skipped. Returns the seconds spent
/// waiting.
pub fn swap_neighbours<T: bytemuck::Pod>(
    comm: &dyn Comm,
    peers: [Option<usize>; 2],
    tag: u16,
    out: [&[T]; 2],
    into: [&mut [T]; 2],
) -> f64 {
    let mut sends = Vec::new();
    let mut recvs = Vec::new();
    for (side, inc) in into.into_iter().enumerate() {
        if let Some(p) = peers[side] {
            sends.push(Outgoing {
                peer: p,
                tag: tag + side as u16,
                data: bytemuck::cast_slice(out[side]),
            });
            recvs.push(Incoming {
                peer: p,
                tag: tag + 1 - side as u16,
                data: bytemuck::cast_slice_mut(inc),
            });
        }
    }
    comm.exchange(&sends, &mut recvs, &mut || {})
}

/// Variable-length messages with both neighbours: the lengths first (tags `tags.0`,
/// `tags.0 + 1`), then the payloads (tags `tags.1`, `tags.1 + 1`). Returns what each
/// neighbour sent (empty where there is none) and the seconds spent waiting.
pub fn swap_neighbours_varlen(
    comm: &dyn Comm,
    peers: [Option<usize>; 2],
    tags: (u16, u16),
    msgs: [&[f64]; 2],
) -> ([Vec<f64>; 2], f64) {
    let lens = msgs.map(|m| [m.len() as u64]);
    let mut got_lens = [[0u64], [0u64]];
    let [l0, l1] = &mut got_lens;
    let mut wait = swap_neighbours(comm, peers, tags.0, [&lens[0], &lens[1]], [l0, l1]);
    let mut got = got_lens.map(|[n]| vec![0.0f64; n as usize]);
    let [g0, g1] = &mut got;
    wait += swap_neighbours(comm, peers, tags.1, msgs, [g0, g1]);
    (got, wait)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SingleProcess;

    #[test]
    fn varlen_with_oneself() {
        // A periodic single rank is its own left and right neighbour.
        let (got, _) = swap_neighbours_varlen(
            &SingleProcess,
            [Some(0), Some(0)],
            (10, 20),
            [&[1.0, 2.0], &[3.0]],
        );
        // What went right (side 1) arrives from the left, and vice versa.
        assert_eq!(got, [vec![3.0], vec![1.0, 2.0]]);
    }
}
