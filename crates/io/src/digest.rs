//! Checkpoints that know they are whole: a digest of the file's HDF5 bytes, written into the
//! file's user block (bytes HDF5 leaves to the application) after every rank has written,
//! and verified before a restart reads anything. A flipped bit or a torn write anywhere in
//! the data is refused with a clear message instead of restarting from garbage.

use super::OutputError;
use decomposition::Comm;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::Path;

/// Bytes reserved at the start of every checkpoint for the digest (HDF5's user block: a
/// power of two ≥ 512).
pub const USER_BLOCK: u64 = 512;

/// What the user block starts with.
const MAGIC: &[u8] = b"grainflow checkpoint digest v1 ";

/// A 64-bit digest of `bytes` read as little-endian words (the tail zero-padded), seeded
/// with its length: every word passes an invertible mix, so a change in any one word always
/// changes the digest. Not cryptographic: it guards against corruption, not forgery.
fn digest_stream(mut read: impl Read) -> std::io::Result<(u64, u64)> {
    const K: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut h: u64 = 0x243f_6a88_85a3_08d3;
    let mut len = 0u64;
    let mut buf = vec![0u8; 1 << 22];
    loop {
        let mut filled = 0;
        while filled < buf.len() {
            let n = read.read(&mut buf[filled..])?;
            if n == 0 {
                break;
            }
            filled += n;
        }
        let words = filled.div_ceil(8);
        buf[filled..words * 8].fill(0);
        for w in buf[..words * 8].chunks_exact(8) {
            let w = u64::from_le_bytes(w.try_into().expect("8 bytes"));
            h = (h ^ w).wrapping_mul(K);
            h ^= h >> 29;
        }
        len += filled as u64;
        if filled < buf.len() {
            break;
        }
    }
    h = (h ^ len).wrapping_mul(K);
    Ok((h ^ (h >> 32), len))
}

/// The digest and length of `path`'s bytes after the user block.
fn digest_of(path: &Path) -> std::io::Result<(u64, u64)> {
    let mut f = std::fs::File::open(path)?;
    f.seek(SeekFrom::Start(USER_BLOCK))?;
    digest_stream(std::io::BufReader::new(f))
}

/// The user block's text for a digest.
fn stamp(digest: u64, len: u64) -> Vec<u8> {
    let mut s = MAGIC.to_vec();
    s.extend(format!("{digest:016x} {len}\n").as_bytes());
    s
}

/// Write the digest of `path` (a closed HDF5 file with a [`USER_BLOCK`]) into its user
/// block. One process.
pub fn seal(path: &Path) -> std::io::Result<()> {
    let (digest, len) = digest_of(path)?;
    let mut f = std::fs::OpenOptions::new().write(true).open(path)?;
    f.write_all(&stamp(digest, len))?;
    Ok(())
}

/// Why `path` is not whole, if it is not: a missing digest, another length (truncated or
/// grown), or another digest (bytes changed). One process.
pub fn fault(path: &Path) -> Option<String> {
    let mut head = vec![0u8; USER_BLOCK as usize];
    let read = std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut head));
    if read.is_err() {
        return Some("shorter than its own header: truncated".into());
    }
    let Some(rest) = head.strip_prefix(MAGIC) else {
        return Some(
            "it carries no digest (written by a grainflow before checkpoints were sealed, or \
             its first bytes are damaged)"
                .into(),
        );
    };
    let line = String::from_utf8_lossy(rest);
    let mut words = line.split_whitespace();
    let want = words.next().and_then(|w| u64::from_str_radix(w, 16).ok());
    let want_len = words.next().and_then(|w| w.parse::<u64>().ok());
    let (Some(want), Some(want_len)) = (want, want_len) else {
        return Some("its digest is unreadable (the header is damaged)".into());
    };
    match digest_of(path) {
        Err(e) => Some(format!("cannot be read: {e}")),
        Ok((_, len)) if len != want_len => Some(format!(
            "it holds {len} bytes of data where it was written with {want_len}: truncated or \
             damaged"
        )),
        Ok((got, _)) if got != want => Some(
            "its contents changed after it was written (the digest does not match): the file \
             is damaged"
                .into(),
        ),
        Ok(_) => None,
    }
}

/// [`fault`] judged on rank 0 and shared with every rank (collective): an error naming the
/// fault and the way out, or nothing.
pub fn verify(path: &Path, comm: &dyn Comm) -> Result<(), OutputError> {
    let local = if comm.is_root() { fault(path) } else { None };
    let message = local.unwrap_or_default();
    let all = comm.all_gather_bytes(format!("{message}\0").as_bytes());
    let found = all
        .split(|&b| b == 0)
        .map(|m| String::from_utf8_lossy(m).into_owned())
        .find(|m| !m.is_empty());
    match found {
        None => Ok(()),
        Some(why) => Err(OutputError::Checkpoint {
            path: path.to_owned(),
            message: format!(
                "{why}; it cannot be restarted from. Restart from an older copy, or run the \
                 scene again"
            ),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_changed_word_changes_the_digest() {
        let data: Vec<u8> = (0..100_000u32).flat_map(|i| i.to_le_bytes()).collect();
        let (d0, n0) = digest_stream(&data[..]).unwrap();
        assert_eq!(n0, data.len() as u64);
        for at in [0, 7, 8, 4095, 99_999, data.len() - 1] {
            let mut bad = data.clone();
            bad[at] ^= 1;
            assert_ne!(digest_stream(&bad[..]).unwrap().0, d0, "flip at {at}");
        }
        // A tail of zeros is not the same data.
        let mut longer = data.clone();
        longer.push(0);
        assert_ne!(digest_stream(&longer[..]).unwrap().0, d0);
    }

    #[test]
    fn a_sealed_file_verifies_and_a_damaged_one_does_not() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.h5");
        let mut bytes = vec![0u8; USER_BLOCK as usize];
        bytes.extend((0..50_000u32).flat_map(|i| (i * 7).to_le_bytes()));
        std::fs::write(&path, &bytes).unwrap();
        assert!(fault(&path).unwrap().contains("no digest"));
        seal(&path).unwrap();
        assert_eq!(fault(&path), None);
        let mut damaged = std::fs::read(&path).unwrap();
        damaged[USER_BLOCK as usize + 1234] ^= 0x10;
        std::fs::write(&path, &damaged).unwrap();
        assert!(fault(&path).unwrap().contains("changed"));
        damaged.truncate(damaged.len() - 100);
        std::fs::write(&path, &damaged).unwrap();
        assert!(fault(&path).unwrap().contains("truncated"));
    }
}
