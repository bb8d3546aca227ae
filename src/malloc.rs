//! The allocator's set-up for long runs with large, short-lived buffers.

/// Blocks from 4 MiB up come straight from the kernel and go back to it when freed.
///
/// glibc's default threshold rises to the size of each large block freed (up to 32 MiB),
/// so the fields, conversions and coupling tables of a few to a few tens of MB that a run
/// frees and allocates again land in the heap instead, where fragmentation keeps them
/// resident. With the threshold fixed, the medium landslide's peak resident memory is
/// 14 % lower and a 400-step run of it 2–5 % faster (docs/performance.md). A threshold the
/// user set (`MALLOC_MMAP_THRESHOLD_`, or `glibc.malloc.mmap_threshold` in
/// `GLIBC_TUNABLES`) is left alone. Call at start-up, before any other thread exists.
pub fn fix_mmap_threshold() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        let tuned = std::env::var("GLIBC_TUNABLES")
            .is_ok_and(|t| t.contains("glibc.malloc.mmap_threshold"));
        if std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_none() && !tuned {
            // SAFETY: a malloc tuning call at start-up, before any other thread exists.
            unsafe {
                libc::mallopt(libc::M_MMAP_THRESHOLD, 4 << 20);
            }
        }
    }
}
