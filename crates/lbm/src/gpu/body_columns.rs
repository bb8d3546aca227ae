//! The per-body section of a moving step's upload (`shaders/body_columns.wgsl`): where the
//! device sums the momenta of the plan's links or shares per body and column, and the sums
//! read back into the plan's [`BodyColumns`].

use crate::moving::{BodyColumns, RigidMotion};
use crate::Real;

/// Where the per-body sums of a moving step live on the device (see
/// `shaders/body_columns.wgsl`).
pub(crate) struct BodyRun {
    /// Groups of bodies (one thread each).
    pub(crate) groups: usize,
    /// Slots (one per group and column of its boxes).
    pub(crate) slots: usize,
    /// Where the sums start in the real buffer (4 reals per slot).
    pub(crate) out_at: usize,
    /// Reals the kernel writes past the uploaded ones (work and sums).
    pub(crate) scratch: usize,
}

/// Append the per-body section of `shaders/body_columns.wgsl` to a moving kernel's upload
/// (`idx` ends with the plan's per-link or per-share words, `real` with the kernel's data):
/// the groups and boxes from `cols`, the plan's rows (`rows`: ny + 1 values, or empty), and
/// each body's anchor (`bodies`, global lattice coordinates; the slab's column 0 is global
/// column `x0`). `None` when `cols` asks for no sums.
pub(crate) fn append_bodies<T: Real>(
    idx: &mut Vec<u32>,
    real: &mut Vec<T>,
    cols: &BodyColumns,
    rows: &[u32],
    bodies: &[RigidMotion],
    x0: i64,
    ny: usize,
) -> Option<BodyRun> {
    if !cols.wanted() {
        return None;
    }
    assert_eq!(cols.boxes.len(), bodies.len(), "one box per body");
    let (ng, nb, slots) = (cols.groups.len() - 1, bodies.len(), cols.slots());
    // A 1 the compiler cannot see (see `add_compensated`), then the origins.
    real.push(T::from_f64(1.0));
    let origins_at = real.len();
    let work_at = origins_at + 2 * nb;
    let out_at = work_at + 7 * slots;
    idx.extend([ng, nb, ny, origins_at, work_at, out_at].map(|v| v as u32));
    if rows.is_empty() {
        idx.resize(idx.len() + ny + 1, 0);
    } else {
        assert_eq!(rows.len(), ny + 1, "a plan's rows are ny + 1 offsets");
        idx.extend_from_slice(rows);
    }
    for j in 0..ng {
        let [x_lo, width] = cols.columns(j);
        idx.extend_from_slice(&[
            x_lo,
            width,
            cols.first[j],
            cols.groups[j],
            cols.groups[j + 1],
        ]);
    }
    idx.extend_from_slice(&cols.members);
    // Each body's rows and the cell that holds its centre (local column, row), whose
    // centre's arm from the body's centre is made in f64 and is small: a cell's arm is that
    // plus whole cells, the same on any slab, and an f32 run loses nothing to the
    // lattice's size.
    let anchor = |c: f64| c.floor() as i64;
    for (bx, body) in cols.boxes.iter().zip(bodies) {
        let (ax, ay) = (anchor(body.centre[0]) - x0, anchor(body.centre[1]));
        idx.extend_from_slice(&[bx[2], bx[3], ax as i32 as u32, ay as i32 as u32]);
    }
    for body in bodies {
        let c = body.centre;
        real.push(T::from_f64(anchor(c[0]) as f64 + 0.5 - c[0]));
        real.push(T::from_f64(anchor(c[1]) as f64 + 0.5 - c[1]));
    }
    Some(BodyRun {
        groups: ng,
        slots,
        out_at,
        scratch: 11 * slots,
    })
}

/// The sums read back (4 reals per slot: p_x, p_y, torque, count) into `cols`.
pub(crate) fn read_sums<T: Real>(values: &[T], cols: &mut BodyColumns) {
    cols.sums.clear();
    cols.counts.clear();
    for v in values.chunks_exact(4) {
        cols.sums
            .push([v[0].to_f64(), v[1].to_f64(), v[2].to_f64()]);
        cols.counts.push(v[3].to_f64() as u32);
    }
    cols.made = true;
}
