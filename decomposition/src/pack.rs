//! What travels between ranks. Two forms, one module:
//! - **Rows** (ghost grains, migrating grains and material points, checkpoint rows): flat
//!   messages of f64 words, a fixed number per row, ids and other integers as their exact
//!   bit patterns. A structure-of-arrays store implements [`PackRows`]; a plain record
//!   implements [`Record`], and a `Vec` of records is then a store.
//! - **Faces** (the lattice's halo columns, every step): values in the precision they are
//!   stored in ([`Word`]: f32 or f64), packed straight into a halo's byte buffer with
//!   [`pack_words`] and read back with [`unpack_words`], so an f32 lattice sends 4 bytes a
//!   value, not 8.

/// A store whose rows travel between ranks as [`PackRows::WORDS`] f64 words each.
pub trait PackRows {
    /// Words per row.
    const WORDS: usize;
    /// Append row `i` to `out` as exactly [`PackRows::WORDS`] words.
    fn pack_row(&self, i: usize, out: &mut Vec<f64>);
    /// Append a row from exactly [`PackRows::WORDS`] words written by
    /// [`PackRows::pack_row`].
    fn push_row(&mut self, words: &[f64]);
}

/// A plain record that travels as [`Record::WORDS`] f64 words.
pub trait Record: Sized {
    /// Words per record.
    const WORDS: usize;
    /// Append the record to `out` as exactly [`Record::WORDS`] words.
    fn pack(&self, out: &mut Vec<f64>);
    /// The record from exactly [`Record::WORDS`] words written by [`Record::pack`].
    fn unpack(words: &[f64]) -> Self;
}

impl<R: Record> PackRows for Vec<R> {
    const WORDS: usize = R::WORDS;
    fn pack_row(&self, i: usize, out: &mut Vec<f64>) {
        self[i].pack(out);
    }
    fn push_row(&mut self, words: &[f64]) {
        self.push(R::unpack(words));
    }
}

/// A value that travels as its little-endian bytes: f32 or f64.
pub trait Word: Copy {
    /// Bytes per value.
    const BYTES: usize;
    /// Write the little-endian bytes of `self` into `out[..BYTES]`.
    fn put_le(self, out: &mut [u8]);
    /// Read a value from the little-endian bytes `b[..BYTES]`.
    fn get_le(b: &[u8]) -> Self;
}

macro_rules! impl_word {
    ($t:ty) => {
        impl Word for $t {
            const BYTES: usize = std::mem::size_of::<$t>();
            #[inline(always)]
            fn put_le(self, out: &mut [u8]) {
                out[..Self::BYTES].copy_from_slice(&self.to_le_bytes());
            }
            #[inline(always)]
            fn get_le(b: &[u8]) -> Self {
                <$t>::from_le_bytes(b[..Self::BYTES].try_into().expect("BYTES long"))
            }
        }
    };
}
impl_word!(f32);
impl_word!(f64);

/// Write `values` one after another into `out` as little-endian words; returns how many.
/// Panics when `out` is too short (a buffer sized for another face: a programming error).
#[inline]
pub fn pack_words<W: Word>(out: &mut [u8], values: impl IntoIterator<Item = W>) -> usize {
    let mut n = 0;
    for v in values {
        v.put_le(&mut out[n * W::BYTES..]);
        n += 1;
    }
    n
}

/// The words of `data`, in order (as [`pack_words`] wrote them).
#[inline]
pub fn unpack_words<'a, W: Word + 'a>(data: &'a [u8]) -> impl Iterator<Item = W> + 'a {
    data.chunks_exact(W::BYTES).map(W::get_le)
}

/// The rows `rows` of `store` as one message.
pub fn pack_rows<S: PackRows>(store: &S, rows: impl IntoIterator<Item = usize>) -> Vec<f64> {
    let mut out = Vec::new();
    for i in rows {
        store.pack_row(i, &mut out);
    }
    out
}

/// Append every row of `message` to `store`; returns how many. Panics when the message is
/// not whole rows (a sender and receiver that disagree on the layout: a programming error).
pub fn unpack_rows<S: PackRows>(store: &mut S, message: &[f64]) -> usize {
    assert_eq!(
        message.len() % S::WORDS,
        0,
        "a message of {} words is not whole rows of {}",
        message.len(),
        S::WORDS
    );
    for words in message.chunks_exact(S::WORDS) {
        store.push_row(words);
    }
    message.len() / S::WORDS
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Clone, PartialEq)]
    struct Probe {
        id: u64,
        x: f64,
    }

    impl Record for Probe {
        const WORDS: usize = 2;
        fn pack(&self, out: &mut Vec<f64>) {
            out.extend_from_slice(&[f64::from_bits(self.id), self.x]);
        }
        fn unpack(w: &[f64]) -> Self {
            Probe {
                id: w[0].to_bits(),
                x: w[1],
            }
        }
    }

    #[test]
    fn records_round_trip_with_exact_ids() {
        let sent = vec![
            Probe {
                id: u64::MAX,
                x: -0.0,
            },
            Probe { id: 7, x: 1e300 },
            Probe {
                id: 1 << 63,
                x: f64::MIN_POSITIVE,
            },
        ];
        let msg = pack_rows(&sent, [2, 0]);
        assert_eq!(msg.len(), 4);
        let mut got: Vec<Probe> = Vec::new();
        assert_eq!(unpack_rows(&mut got, &msg), 2);
        assert_eq!(got, vec![sent[2].clone(), sent[0].clone()]);
        assert_eq!(got[1].x.to_bits(), (-0.0f64).to_bits());
    }

    #[test]
    fn words_round_trip_in_their_own_precision() {
        let mut buf = vec![0u8; 3 * 4];
        assert_eq!(pack_words(&mut buf, [1.5f32, -0.0, f32::MAX]), 3);
        let back: Vec<f32> = unpack_words(&buf).collect();
        assert_eq!(back, vec![1.5, -0.0, f32::MAX]);
        assert_eq!(back[1].to_bits(), (-0.0f32).to_bits());
        let mut wide = vec![0u8; 16];
        pack_words(&mut wide, [1e300f64, f64::MIN_POSITIVE]);
        let back: Vec<f64> = unpack_words(&wide).collect();
        assert_eq!(back, vec![1e300, f64::MIN_POSITIVE]);
    }

    #[test]
    #[should_panic(expected = "not whole rows")]
    fn a_torn_message_is_refused() {
        let mut got: Vec<Probe> = Vec::new();
        unpack_rows(&mut got, &[1.0, 2.0, 3.0]);
    }
}
