//! Scene text, as a user or a script might write it, through everything `grainflow check`
//! does: the parse, the validation of every table, the step count, the memory estimate,
//! the stability verdicts and, when the memory is admitted, the lattice with its obstacles
//! and mask image. Any panic, abort, hang (libFuzzer's `-timeout`) or runaway allocation
//! (`-rss_limit_mb`) is a defect: bad input must end in an error that names its key.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

/// The node memory the assessment admits against (bytes): small, so that a scene the fuzzer
/// grows is refused by the memory estimate rather than built, and runs stay fast. `run`
/// applies the same estimate against the machine's real memory.
const NODE_MEMORY: f64 = 256.0 * 1024.0 * 1024.0;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // Relative file names (a mask, a grain list) resolve in fuzz/files/.
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/files/scene.toml"));
    let Ok(any) = grainflow::scene::parse_any(text, path) else {
        return;
    };
    for ranks in [1, 3] {
        let _ = grainflow::check::assess(&any, ranks, Some(NODE_MEMORY), false);
    }
});
