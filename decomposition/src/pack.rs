//! What travels between ranks (ghosts, migration, checkpoint rows): flat messages of f64
//! words, a fixed number per row, ids and other integers as their exact bit patterns.
//! A structure-of-arrays store implements [`PackRows`]; a plain record implements
//! [`Record`], and a `Vec` of records is then a store.

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
    #[should_panic(expected = "not whole rows")]
    fn a_torn_message_is_refused() {
        let mut got: Vec<Probe> = Vec::new();
        unpack_rows(&mut got, &[1.0, 2.0, 3.0]);
    }
}
