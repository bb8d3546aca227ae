//! Analyses run on rank 0 only (the only rank that holds the whole lattice); every rank then
//! receives rank 0's results, or its error, so that checks, status and exit code agree.

use super::{AnalysisError, Outcome};
use decomposition::Comm;

/// Rank 0's outcome (`Some` there, `None` on the others), on every rank. Collective.
pub fn share_from_root(
    comm: &dyn Comm,
    local: Option<Result<Outcome, AnalysisError>>,
) -> Result<Outcome, AnalysisError> {
    if comm.size() == 1 {
        return local.expect("a single rank is the root");
    }
    let bytes = local.as_ref().map(encode).unwrap_or_default();
    // Only the root contributes, so the gathered bytes are the root's.
    decode(&comm.all_gather_bytes(&bytes))
}

/// Append `s` as its length (u32 LE) and bytes.
fn put_text(out: &mut Vec<u8>, s: &str) {
    out.extend_from_slice(&(s.len() as u32).to_le_bytes());
    out.extend_from_slice(s.as_bytes());
}

/// Byte form: `0`, the result count (u32 LE), (key, value f64 LE bits)*, the skipped count,
/// (analysis, message)*; or `1`, analysis, message. Texts as [`put_text`] writes them.
/// Values travel as bits, NaN included.
fn encode(outcome: &Result<Outcome, AnalysisError>) -> Vec<u8> {
    let mut out = Vec::new();
    match outcome {
        Ok(o) => {
            out.push(0);
            out.extend_from_slice(&(o.results.len() as u32).to_le_bytes());
            for (k, v) in &o.results {
                put_text(&mut out, k);
                out.extend_from_slice(&v.to_bits().to_le_bytes());
            }
            out.extend_from_slice(&(o.skipped.len() as u32).to_le_bytes());
            for e in &o.skipped {
                put_text(&mut out, &e.analysis);
                put_text(&mut out, &e.message);
            }
        }
        Err(e) => {
            out.push(1);
            put_text(&mut out, &e.analysis);
            put_text(&mut out, &e.message);
        }
    }
    out
}

/// Inverse of [`encode`] (whose output it trusts: both ends are this program).
fn decode(bytes: &[u8]) -> Result<Outcome, AnalysisError> {
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let text = |at: usize| {
        let n = word(at) as usize;
        (
            String::from_utf8_lossy(&bytes[at + 4..at + 4 + n]).into_owned(),
            at + 4 + n,
        )
    };
    let error = |at: usize| {
        let (analysis, at) = text(at);
        let (message, at) = text(at);
        (AnalysisError { analysis, message }, at)
    };
    if bytes[0] == 1 {
        return Err(error(1).0);
    }
    let mut o = Outcome::default();
    let mut at = 5;
    for _ in 0..word(1) {
        let (key, next) = text(at);
        let bits = u64::from_le_bytes(bytes[next..next + 8].try_into().expect("8 bytes"));
        o.results.insert(key, f64::from_bits(bits));
        at = next + 8;
    }
    let skipped = word(at);
    at += 4;
    for _ in 0..skipped {
        let (e, next) = error(at);
        o.skipped.push(e);
        at = next;
    }
    Ok(o)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Results;

    #[test]
    fn results_and_errors_survive_the_byte_form() {
        let mut r = Results::new();
        r.insert("dkt.second_kiss_time".into(), f64::NAN);
        r.insert("poiseuille.l2_rel_error".into(), 1.25e-7);
        r.insert("ünïcode.key".into(), -0.0);
        let e = AnalysisError {
            analysis: "ghia".into(),
            message: "needs a moving-wall lid on the north face".into(),
        };
        let sent = Outcome {
            results: r.clone(),
            skipped: vec![e.clone(), e.clone()],
        };
        let back = decode(&encode(&Ok(sent))).unwrap();
        assert_eq!(back.results.len(), 3);
        for (k, v) in &r {
            assert_eq!(back.results[k].to_bits(), v.to_bits(), "{k}");
        }
        assert_eq!(back.skipped.len(), 2);
        assert_eq!(back.skipped[1].message, e.message);
        let empty = decode(&encode(&Ok(Outcome::default()))).unwrap();
        assert!(empty.results.is_empty() && empty.skipped.is_empty());
        let back = decode(&encode(&Err(e.clone()))).unwrap_err();
        assert_eq!((back.analysis, back.message), (e.analysis, e.message));
    }
}
