//! Test scaffolding shared by the coupling's map tests: a small deterministic generator
//! and the slabs the tests move grains over.

use super::map::SlabFrame;

/// A small deterministic generator in [0, 1) (no test-only crate needed).
pub fn next(s: &mut u64) -> f64 {
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    (*s >> 11) as f64 / (1u64 << 53) as f64
}

/// Test slab `case`: 70 + case columns starting at global column 23 (case mod 3) of a
/// 160-column lattice, 60 rows, periodic on both axes for even cases; with its solid
/// cells (every 89th padded cell).
pub fn slab(case: usize) -> (SlabFrame, Vec<bool>) {
    let periodic = case % 2 == 0;
    let f = SlabFrame {
        nx: 70 + case,
        ny: 60,
        x0: 23 * (case % 3),
        global_nx: 160,
        stride: 70 + case + 2,
        periodic_x: periodic,
        periodic_y: periodic,
    };
    let cells = f.stride * (f.ny + 2);
    let solid = (0..cells).map(|k| k % 89 == 7).collect();
    (f, solid)
}
