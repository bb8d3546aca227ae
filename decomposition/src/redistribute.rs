//! Moving a slab-partitioned field to another partition of the same columns: what a
//! rebalance does with the populations (each rank sends the columns it no longer owns to
//! their new owners, point to point, and keeps the rest in place).

use crate::comm::{Comm, Incoming, Outgoing};
use crate::slab::SlabPartition;

/// Message tags of a move (distinct from the halos', the DEM's, the MPM's and the
/// coupling's); a large move is cut into pieces, each under its own tag.
const TAG_BASE: u16 = 1000;
/// Pieces of one move between two ranks, at most (the tags they use).
const MAX_PIECES: usize = 30_000;
/// Largest piece (bytes), far under MPI's 2³¹ − 1 count limit.
const PIECE_BYTES: usize = 1 << 28;

/// The columns two slabs share, `[begin, end)`, if any.
fn shared(a: crate::Slab, b: crate::Slab) -> Option<(usize, usize)> {
    let (begin, end) = (a.x_begin.max(b.x_begin), a.x_end.min(b.x_end));
    (begin < end).then_some((begin, end))
}

/// A piece of a block to receive: from `peer` under `tag`, rows from `first_row` of the
/// global columns `columns` (`[begin, end)`).
struct Piece<T> {
    peer: usize,
    tag: u16,
    first_row: usize,
    columns: (usize, usize),
    data: Vec<T>,
}

/// Rows per piece for a block `width` columns wide of `T`s.
fn rows_per_piece<T>(rows: usize, width: usize) -> usize {
    let row_bytes = (width * std::mem::size_of::<T>()).max(1);
    (PIECE_BYTES / row_bytes)
        .max(1)
        .max(rows.div_ceil(MAX_PIECES))
}

/// This rank's block of a field on partition `new`, from its block `data` on `old`. A
/// block is `rows` rows of the slab's width (row-major: row `j` of the slab holds
/// `data[j * width..(j + 1) * width]`). Columns this rank owns in both partitions are
/// copied; the others travel point to point, one message (or a few pieces, for a large
/// one) per pair of ranks that share columns. Besides `data` and the result, a rank holds
/// the columns it sends and those it receives while they travel. Collective: every rank calls it with the
/// same partitions (same column count and rank count as `comm`).
pub fn move_columns<T: bytemuck::Pod>(
    comm: &dyn Comm,
    old: &SlabPartition,
    new: &SlabPartition,
    rows: usize,
    data: &[T],
) -> Vec<T> {
    let me = comm.rank();
    let (mine_old, mine_new) = (old.slab(me), new.slab(me));
    assert_eq!(data.len(), rows * mine_old.width(), "block size");
    assert_eq!(old.columns(), new.columns(), "the same columns");
    // What goes: per peer, its columns of this block, piece by piece.
    let mut sends: Vec<(usize, u16, Vec<T>)> = Vec::new();
    for peer in (0..comm.size()).filter(|&r| r != me) {
        let Some((b, e)) = shared(mine_old, new.slab(peer)) else {
            continue;
        };
        let per = rows_per_piece::<T>(rows, e - b);
        for (piece, j0) in (0..rows).step_by(per).enumerate() {
            let mut msg = Vec::with_capacity((e - b) * per);
            for j in j0..(j0 + per).min(rows) {
                let from = j * mine_old.width() + (b - mine_old.x_begin);
                msg.extend_from_slice(&data[from..from + e - b]);
            }
            sends.push((peer, TAG_BASE + piece as u16, msg));
        }
    }
    // What comes: per peer, the columns it held of this rank's new slab.
    let mut recvs: Vec<Piece<T>> = Vec::new();
    for peer in (0..comm.size()).filter(|&r| r != me) {
        let Some((b, e)) = shared(old.slab(peer), mine_new) else {
            continue;
        };
        let per = rows_per_piece::<T>(rows, e - b);
        for (piece, j0) in (0..rows).step_by(per).enumerate() {
            let n = (j0 + per).min(rows) - j0;
            let buf = vec![T::zeroed(); n * (e - b)];
            recvs.push(Piece {
                peer,
                tag: TAG_BASE + piece as u16,
                first_row: j0,
                columns: (b, e),
                data: buf,
            });
        }
    }
    {
        let outgoing: Vec<Outgoing<'_>> = sends
            .iter()
            .map(|(peer, tag, msg)| Outgoing {
                peer: *peer,
                tag: *tag,
                data: bytemuck::cast_slice(msg),
            })
            .collect();
        let mut incoming: Vec<Incoming<'_>> = recvs
            .iter_mut()
            .map(|p| Incoming {
                peer: p.peer,
                tag: p.tag,
                data: bytemuck::cast_slice_mut(&mut p.data),
            })
            .collect();
        comm.exchange(&outgoing, &mut incoming, &mut || {});
    }
    drop(sends);
    // The new block, allocated once the messages are out: what stays, then what came.
    let mut out = vec![T::zeroed(); rows * mine_new.width()];
    if let Some((b, e)) = shared(mine_old, mine_new) {
        for j in 0..rows {
            let from = j * mine_old.width() + (b - mine_old.x_begin);
            let to = j * mine_new.width() + (b - mine_new.x_begin);
            out[to..to + e - b].copy_from_slice(&data[from..from + e - b]);
        }
    }
    for p in &recvs {
        let (b, e) = p.columns;
        for (k, row) in p.data.chunks_exact(e - b).enumerate() {
            let to = (p.first_row + k) * mine_new.width() + (b - mine_new.x_begin);
            out[to..to + e - b].copy_from_slice(row);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SingleProcess;

    #[test]
    fn one_rank_keeps_its_block() {
        let p = SlabPartition::uniform(7, 1).unwrap();
        let data: Vec<f32> = (0..21).map(|v| v as f32).collect();
        assert_eq!(move_columns(&SingleProcess, &p, &p, 3, &data), data);
    }
}
