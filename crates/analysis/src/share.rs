//! Analyses run on rank 0 only (the only rank that holds the whole lattice); every rank then
//! receives rank 0's results, or its error, so that checks, status and exit code agree.

use super::{AnalysisError, Results};
use decomposition::Comm;

/// Rank 0's outcome (`Some` there, `None` on the others), on every rank. Collective.
pub fn share_from_root(
    comm: &dyn Comm,
    local: Option<Result<Results, AnalysisError>>,
) -> Result<Results, AnalysisError> {
    if comm.size() == 1 {
        return local.expect("a single rank is the root");
    }
    let bytes = local.as_ref().map(encode).unwrap_or_default();
    // Only the root contributes, so the gathered bytes are the root's.
    decode(&comm.all_gather_bytes(&bytes))
}

/// Byte form: `0` then (key length u32 LE, key, value f64 LE bits)*, or `1` then (analysis
/// length u32 LE, analysis, message). Values travel as bits, NaN included.
fn encode(outcome: &Result<Results, AnalysisError>) -> Vec<u8> {
    let mut out = Vec::new();
    let text = |out: &mut Vec<u8>, s: &str| {
        out.extend_from_slice(&(s.len() as u32).to_le_bytes());
        out.extend_from_slice(s.as_bytes());
    };
    match outcome {
        Ok(r) => {
            out.push(0);
            for (k, v) in r {
                text(&mut out, k);
                out.extend_from_slice(&v.to_bits().to_le_bytes());
            }
        }
        Err(e) => {
            out.push(1);
            text(&mut out, &e.analysis);
            out.extend_from_slice(e.message.as_bytes());
        }
    }
    out
}

/// Inverse of [`encode`] (whose output it trusts: both ends are this program).
fn decode(bytes: &[u8]) -> Result<Results, AnalysisError> {
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let text = |at: usize| {
        let n = word(at) as usize;
        (
            String::from_utf8_lossy(&bytes[at + 4..at + 4 + n]).into_owned(),
            at + 4 + n,
        )
    };
    if bytes[0] == 1 {
        let (analysis, at) = text(1);
        let message = String::from_utf8_lossy(&bytes[at..]).into_owned();
        return Err(AnalysisError { analysis, message });
    }
    let mut r = Results::new();
    let mut at = 1;
    while at < bytes.len() {
        let (key, next) = text(at);
        let bits = u64::from_le_bytes(bytes[next..next + 8].try_into().expect("8 bytes"));
        r.insert(key, f64::from_bits(bits));
        at = next + 8;
    }
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_and_errors_survive_the_byte_form() {
        let mut r = Results::new();
        r.insert("dkt.second_kiss_time".into(), f64::NAN);
        r.insert("poiseuille.l2_rel_error".into(), 1.25e-7);
        r.insert("ünïcode.key".into(), -0.0);
        let back = decode(&encode(&Ok(r.clone()))).unwrap();
        assert_eq!(back.len(), 3);
        for (k, v) in &r {
            assert_eq!(back[k].to_bits(), v.to_bits(), "{k}");
        }
        assert!(decode(&encode(&Ok(Results::new()))).unwrap().is_empty());
        let e = AnalysisError {
            analysis: "ghia".into(),
            message: "needs a moving-wall lid on the north face".into(),
        };
        let back = decode(&encode(&Err(e.clone()))).unwrap_err();
        assert_eq!((back.analysis, back.message), (e.analysis, e.message));
    }
}
