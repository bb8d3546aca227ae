// D2Q9 lattice Boltzmann on the GPU: the same algorithm as the CPU kernels in src/lbm,
// operation for operation, so both backends agree to round-off.
//
// The host prepends a prelude that defines `real` (f32 or f64), the population bindings
// (split over several buffers when one binding cannot hold the lattice) and the accessors
// `ld` (current buffer), `ldd` / `sto` (destination buffer). Populations are shifted,
// h_i = f_i − w_i, structure-of-arrays: population i of padded cell k is at i·plane + k.
// Overridable constants select the collision at pipeline creation, like the CPU's
// const generics: FAMILY 0 BGK, 1 TRT, 2 MRT; SMAG and FORCED are 0 or 1.

override FAMILY: u32 = 0u;
override SMAG: u32 = 0u;
override FORCED: u32 = 0u;

struct Geo {
    nx: u32,
    ny: u32,
    stride: u32,
    plane: u32,
    // Solids (force slots per special cell).
    ns: u32,
    _pad0: u32,
    // Face kinds, 8 bits each (west, east, south, north): see FACE_*.
    faces: u32,
    // Bit 0: the west halo is exchanged with a peer; bit 1: the east halo.
    peers: u32,
    // Offset of the cell types in `geom` (the plain-cell bit mask comes first).
    types_at: u32,
    // Offsets in `aux`: halo staging, moment output.
    halo_at: u32,
    out_at: u32,
    _pad: u32,
}

const FACE_OTHER: u32 = 0u;
const FACE_PERIODIC: u32 = 1u;
const FACE_FREE_SLIP: u32 = 2u;
const FACE_OUTFLOW: u32 = 3u;
const FACE_VELOCITY: u32 = 4u;
const FACE_PRESSURE: u32 = 5u;

const MAX_SOLID: u32 = 0xFFEFu;
const NONE: u32 = 0xFFFFFFFFu;

// Real parameters (`prm`): collision, force, inlet scale, pressure per face, then solid
// velocities (2 per solid) and Zou–He face velocities (2 per face cell: W, E, S, N).
const P_TAU0: u32 = 0u;
const P_MAGIC: u32 = 1u;
const P_SE: u32 = 2u;
const P_SEPS: u32 = 3u;
const P_SNU: u32 = 4u;
const P_SQ: u32 = 5u;
const P_SQ_MAGIC_WEIGHT: u32 = 6u;
const P_SMAG_K: u32 = 7u;
const P_FX: u32 = 8u;
const P_FY: u32 = 9u;
const P_INLET: u32 = 10u;
const P_PRESSURE: u32 = 11u;
const P_SOLIDS: u32 = 16u;

@group(0) @binding(0) var<uniform> geo: Geo;
@group(0) @binding(1) var<storage, read> prm: array<real>;
// Plain-cell bits (one per padded cell), then one cell type per padded cell.
@group(0) @binding(2) var<storage, read> geom: array<u32>;
// Force slots, halo staging and moment output (offsets in `geo`).
@group(0) @binding(3) var<storage, read_write> aux: array<real>;
// First unstable step, the first bad cell (y·nx + x) in it, and the step counter (steps
// done before the one being computed; advanced on the device so that many steps can be
// queued in one submission).
@group(0) @binding(4) var<storage, read_write> bad: array<atomic<u32>, 4>;
// Cell lists: entry 0 holds the count; then (padded cell, force slot) or (x, y).
@group(1) @binding(0) var<storage, read> list: array<vec2<u32>>;

const CX: array<i32, 9> = array<i32, 9>(0, 1, 0, -1, 0, 1, -1, -1, 1);
const CY: array<i32, 9> = array<i32, 9>(0, 0, 1, 0, -1, 1, 1, -1, -1);
const OPP: array<u32, 9> = array<u32, 9>(0u, 3u, 4u, 1u, 2u, 7u, 8u, 5u, 6u);
const MIRROR_X: array<u32, 9> = array<u32, 9>(0u, 3u, 2u, 1u, 4u, 6u, 5u, 8u, 7u);
const MIRROR_Y: array<u32, 9> = array<u32, 9>(0u, 1u, 4u, 3u, 2u, 8u, 7u, 6u, 5u);
const WT: array<real, 9> = array<real, 9>(
    4.0 / 9.0, 1.0 / 9.0, 1.0 / 9.0, 1.0 / 9.0, 1.0 / 9.0,
    1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0, 1.0 / 36.0);
// Populations leaving through the west face (c_x = −1) and the east face (c_x = +1).
const WESTWARD: array<u32, 3> = array<u32, 3>(3u, 6u, 7u);
const EASTWARD: array<u32, 3> = array<u32, 3>(1u, 5u, 8u);

fn face_kind(face: u32) -> u32 {
    return (geo.faces >> (8u * face)) & 0xFFu;
}

fn is_open(face: u32) -> bool {
    let k = face_kind(face);
    return k == FACE_VELOCITY || k == FACE_PRESSURE;
}

fn cell_type(k: u32) -> u32 {
    return geom[geo.types_at + k];
}

fn is_plain(k: u32) -> bool {
    return ((geom[k >> 5u] >> (k & 31u)) & 1u) == 1u;
}

// Padded index of interior cell (x, y) offset by (dx, dy).
fn idx(x: i32, y: i32) -> u32 {
    return u32(y + 1) * geo.stride + u32(x + 1);
}

// Direction i turned by q quarter turns counter-clockwise (d2q9.rs `rotate`).
fn rot(i: u32, q: u32) -> u32 {
    if i == 0u {
        return 0u;
    }
    if i <= 4u {
        return 1u + (i - 1u + q) % 4u;
    }
    return 5u + (i - 5u + q) % 4u;
}

// Record an unstable cell: only cells of the first unstable step count.
fn flag_bad(x: u32, y: u32) {
    let step = atomicLoad(&bad[2]);
    if atomicLoad(&bad[0]) < step {
        return;
    }
    atomicMin(&bad[0], step);
    atomicMin(&bad[1], y * geo.nx + x);
}

// One thread: the step is done.
@compute @workgroup_size(1)
fn advance_step() {
    atomicAdd(&bad[2], 1u);
}

