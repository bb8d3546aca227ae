//! Setting the coupled grains up: the checks on the sample, and the DEM walls along the
//! fluid's wall faces.

use dem::{Grains, Wall};
use lbm::lattice::{Face, FaceCondition};

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
