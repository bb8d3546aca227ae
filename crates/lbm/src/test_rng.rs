//! A small deterministic generator for the unit tests (no test-only crate needed).

/// The next value in [0, 1) of the xorshift64 sequence held in `s` (Marsaglia 2003).
pub fn next(s: &mut u64) -> f64 {
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    (*s >> 11) as f64 / (1u64 << 53) as f64
}
