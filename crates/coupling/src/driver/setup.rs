//! Setting the coupled grains up: the checks on the sample, the DEM walls along the
//! fluid's wall faces, and the slabs' bounds and reach.

use super::SetupError;
use crate::map::SlabFrame;
use decomposition::{Comm, SlabPartition};
use dem::{DemError, DemSystem, Grains, Wall};
use lbm::lattice::{Face, FaceCondition};
use lbm::{Lattice, Real};

/// Smallest grain diameter, in cells, below which the coupling refuses to run.
pub const MIN_CELLS_PER_DIAMETER: f64 = 3.0;

/// Refuse grains outside the domain or under three cells across: (key, message). Grains
/// the scene places itself may press into a face by 5 % of their radius; grains the DEM
/// placed (`settled`: a sample settled by the run, or a checkpoint's) need only their
/// centre inside, as during a run: a settled grain presses into the wall under it by its
/// contact overlap, which the walls' stiffness and the mass's weight set.
pub fn check_grains(
    g: &Grains,
    domain: [f64; 2],
    dx: f64,
    settled: bool,
) -> Result<(), (&'static str, String)> {
    for i in 0..g.len() {
        let (x, y, r) = (g.x[i], g.y[i], g.r[i]);
        let slack = if settled { r } else { 0.05 * r };
        if x - r < -slack
            || y - r < -slack
            || x + r > domain[0] + slack
            || y + r > domain[1] + slack
        {
            return Err((
                "sample",
                format!(
                    "grain {} at ({x}, {y}) m with radius {r} m is not wholly inside the \
                     fluid domain [0, 0]–{domain:?} m ({}); move it inside",
                    g.id[i],
                    if settled {
                        "its centre is outside"
                    } else {
                        "beyond a contact overlap of 5 % of its radius"
                    }
                ),
            ));
        }
        let cells = 2.0 * r / dx;
        if cells < MIN_CELLS_PER_DIAMETER {
            return Err((
                "sample",
                format!(
                    "grain {} is {cells:.2} cells across; the coupling needs at least \
                     {MIN_CELLS_PER_DIAMETER}: refine the lattice or use larger grains",
                    g.id[i]
                ),
            ));
        }
    }
    Ok(())
}

/// A DEM wall along every wall face (bounce-back, moving or free-slip) of the fluid, so
/// grains cannot leave through them, friction `mu`; except where the scene's own walls
/// `own` already lie along that face (they keep their friction).
pub fn fluid_walls(
    faces: &[FaceCondition; 4],
    domain: [f64; 2],
    mu: f64,
    own: &[Wall],
) -> Vec<Wall> {
    let [lx, ly] = domain;
    let ends = [
        (Face::West, [0.0, 0.0], [0.0, ly]),
        (Face::East, [lx, 0.0], [lx, ly]),
        (Face::South, [0.0, 0.0], [lx, 0.0]),
        (Face::North, [0.0, ly], [lx, ly]),
    ];
    // A wall lies along a face when both its ends are on the face's line.
    let along = |w: &Wall, face: Face| {
        let eps = 1e-9 * lx.max(ly);
        let on = |p: [f64; 2]| match face {
            Face::West => p[0].abs() <= eps,
            Face::East => (p[0] - lx).abs() <= eps,
            Face::South => p[1].abs() <= eps,
            Face::North => (p[1] - ly).abs() <= eps,
        };
        on(w.a) && on(w.b)
    };
    ends.iter()
        .filter(|(f, _, _)| {
            matches!(
                faces[*f as usize],
                FaceCondition::Wall { .. } | FaceCondition::FreeSlip
            ) && !own.iter().any(|w| along(w, *f))
        })
        .map(|&(_, a, b)| Wall::fixed(a, b, mu))
        .collect()
}

/// A DEM error from spreading the grains over the slabs: the rank count is the scene's to
/// change.
pub(super) fn slab_error(e: DemError) -> SetupError {
    match e {
        DemError::Parameter { name: "ranks", .. } => SetupError::Invalid {
            key: "ranks",
            message: format!("{e} (the grains follow the fluid's slabs)"),
        },
        e => SetupError::Dem(e),
    }
}

/// The x-boundaries of the ranks' slabs (m), from the fluid's column partition.
pub(super) fn slab_bounds_m(partition: &SlabPartition, dx_m: f64, comm: &dyn Comm) -> Vec<f64> {
    (0..=comm.size())
        .map(|r| {
            let x = if r < comm.size() {
                partition.slab(r).x_begin
            } else {
                partition.columns()
            };
            x as f64 * dx_m
        })
        .collect()
}

/// How far beyond its slab a rank must see grains (m): a neighbour sees a grain that
/// reaches its cells (two cells beyond the radius, plus the halo column) or that can repel
/// one of its grains (`range`). An error when a slab is narrower than a grain's reach.
pub(super) fn grain_reach(
    rmax: f64,
    range: f64,
    dx_m: f64,
    partition: &SlabPartition,
    comm: &dyn Comm,
) -> Result<f64, SetupError> {
    let margin = (3.0 * dx_m).max(rmax + range + DemSystem::skin_for(rmax) + dx_m);
    let narrowest = (0..comm.size())
        .map(|r| partition.slab(r).width())
        .min()
        .unwrap_or(0) as f64
        * dx_m;
    if comm.size() > 1 && narrowest < 2.0 * rmax + margin {
        return Err(SetupError::Invalid {
            key: "ranks",
            message: format!(
                "a fluid slab is {narrowest} m wide, narrower than a grain's reach \
                 ({:.3e} m): run on fewer ranks",
                2.0 * rmax + margin
            ),
        });
    }
    Ok(margin)
}

/// This rank's slab of the lattice as the coupling sees it.
pub(super) fn slab_frame<T: Real>(lat: &Lattice<T>, faces: &[FaceCondition; 4]) -> SlabFrame {
    SlabFrame {
        nx: lat.nx(),
        ny: lat.ny(),
        x0: lat.x_offset(),
        global_nx: lat.global_nx(),
        stride: lat.stride(),
        periodic_x: faces[Face::West as usize] == FaceCondition::Periodic,
        periodic_y: faces[Face::South as usize] == FaceCondition::Periodic,
    }
}
