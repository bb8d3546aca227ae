//! Turn a validated scene into a lattice setup: rasterise obstacles, number the solids,
//! convert boundary conditions to lattice units.

use super::schema::*;
use super::{SceneError, ValidScene};
use lbm::curved::CurvedCircle;
use lbm::geometry::Shape;
use lbm::lattice::{FaceCondition, LatticeSetup, SolidInfo, MAX_SOLID};
use lbm::Collision;

/// The lattice setup plus what was learned while building it.
#[derive(Debug, Clone)]
pub struct BuiltGeometry {
    /// Ready for [`lbm::Lattice::new`].
    pub setup: LatticeSetup,
    /// Cells taken by each obstacle, in scene order.
    pub obstacle_cells: Vec<usize>,
    /// Circles with curved walls (interpolated bounce-back): their cells stay fluid in
    /// `setup.cells`, and the fluid driver runs their links as a static plan.
    pub curved: Vec<CurvedCircle>,
}

impl BuiltGeometry {
    /// Whether global cell (x, y) is fluid: neither solid in the setup nor inside a
    /// curved circle.
    pub fn is_fluid(&self, x: usize, y: usize) -> bool {
        self.setup.cells[y * self.setup.nx + x] == 0
            && !self.curved.iter().any(|c| c.covers(x as i64, y as i64))
    }
}

/// Solid id of obstacle `name` (walls take the first ids, one per wall face).
pub fn solid_id_of(setup: &LatticeSetup, name: &str) -> Option<u16> {
    setup
        .solids
        .iter()
        .position(|s| s.name == name)
        .map(|i| i as u16 + 1)
}

/// Build the lattice setup of a validated scene.
pub fn build_lattice(v: &ValidScene) -> Result<BuiltGeometry, SceneError> {
    let s = &v.scene;
    let u = &v.units;
    let [nx, ny] = s.domain.cells;
    let invalid = |key: &str, message: String| SceneError::Invalid {
        path: v.path.clone(),
        line: None,
        key: key.into(),
        message,
    };
    let mut solids = Vec::new();
    let b = &s.boundaries;
    let specs = [
        (&b.west, "west", ny),
        (&b.east, "east", ny),
        (&b.south, "south", nx),
        (&b.north, "north", nx),
    ];
    let mut faces: Vec<FaceCondition> = Vec::with_capacity(4);
    for (spec, name, along) in specs {
        let vel = |w: [f64; 2]| [u.velocity_to_lattice(w[0]), u.velocity_to_lattice(w[1])];
        faces.push(match spec {
            BoundarySpec::Periodic => FaceCondition::Periodic,
            BoundarySpec::Wall | BoundarySpec::MovingWall { .. } => {
                let velocity = match spec {
                    BoundarySpec::MovingWall { velocity_m_s } => vel(*velocity_m_s),
                    _ => [0.0, 0.0],
                };
                solids.push(SolidInfo {
                    name: format!("{name}-wall"),
                    velocity,
                });
                FaceCondition::Wall {
                    solid: solids.len() as u16,
                }
            }
            BoundarySpec::FreeSlip => FaceCondition::FreeSlip,
            BoundarySpec::Outflow => FaceCondition::Outflow,
            BoundarySpec::Velocity {
                velocity_m_s,
                profile,
                ..
            } => {
                let peak = vel(*velocity_m_s);
                let values = (0..along)
                    .map(|j| {
                        let sfrac = (j as f64 + 0.5) / along as f64;
                        let scale = match profile {
                            Profile::Uniform => 1.0,
                            Profile::Parabolic => 4.0 * sfrac * (1.0 - sfrac),
                        };
                        [peak[0] * scale, peak[1] * scale]
                    })
                    .collect();
                FaceCondition::Velocity(values)
            }
            BoundarySpec::Pressure { pressure_pa } => {
                FaceCondition::Pressure(u.pressure_to_drho(*pressure_pa))
            }
        });
    }
    let faces: [FaceCondition; 4] = faces.try_into().expect("four faces");
    let mut cells = vec![0u16; nx * ny];
    let mut obstacle_cells = Vec::new();
    let mut curved = Vec::new();
    for o in &s.obstacles {
        let l = |p: [f64; 2]| [u.length_to_lattice(p[0]), u.length_to_lattice(p[1])];
        let shape = match o {
            Obstacle::Rectangle { min_m, max_m, .. } => Shape::Rectangle {
                min: l(*min_m),
                max: l(*max_m),
            },
            Obstacle::Circle {
                centre_m, radius_m, ..
            } => Shape::Circle {
                centre: l(*centre_m),
                radius: u.length_to_lattice(*radius_m),
            },
            Obstacle::Polygon { vertices_m, .. } => {
                Shape::Polygon(vertices_m.iter().map(|p| l(*p)).collect())
            }
            Obstacle::Mask { image, .. } => Shape::Mask(
                load_mask(&v.base_dir.join(image), nx, ny).map_err(|m| invalid("image", m))?,
            ),
        };
        solids.push(SolidInfo {
            name: o.name().to_string(),
            velocity: [0.0, 0.0],
        });
        if solids.len() > MAX_SOLID as usize {
            return Err(invalid(
                "obstacles",
                format!("at most {MAX_SOLID} solids are supported"),
            ));
        }
        let id = solids.len() as u16;
        let taken = match (&shape, o.circle_wall(s.grains.is_some())) {
            (Shape::Circle { centre, radius }, Some(CircleWall::Interpolated)) => {
                let c = CurvedCircle {
                    solid: id,
                    centre: *centre,
                    radius: *radius,
                };
                curved.push(c);
                shape.covered_cells(nx, ny)
            }
            _ => shape.rasterise(&mut cells, nx, ny, id),
        };
        if taken == 0 {
            return Err(invalid(
                "obstacles",
                format!("obstacle `{}` covers no cell centre at spacing {} m; refine spacing_m or enlarge it", o.name(), u.dx_m),
            ));
        }
        obstacle_cells.push(taken);
    }
    let collision = lattice_collision(&s.fluid.collision);
    let g = s.fluid.body_acceleration_m_s2;
    let setup = LatticeSetup {
        nx,
        ny,
        cells,
        faces,
        solids,
        collision,
        tau0: u.tau,
        smagorinsky: s.fluid.smagorinsky_constant,
        force: [
            u.acceleration_to_lattice(g[0]),
            u.acceleration_to_lattice(g[1]),
        ],
    };
    Ok(BuiltGeometry {
        setup,
        obstacle_cells,
        curved,
    })
}

/// Read a PNG mask of exactly nx × ny pixels; dark pixels (luma < 128) are solid. The image's
/// top row is the north edge.
fn load_mask(path: &std::path::Path, nx: usize, ny: usize) -> Result<Vec<bool>, String> {
    let file = std::fs::File::open(path)
        .map_err(|e| format!("cannot open mask {}: {e}", path.display()))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("mask {} is not a readable PNG: {e}", path.display()))?;
    // The size from the header, before a pixel buffer is allocated for it.
    let (width, height) = (reader.info().width, reader.info().height);
    if (width as usize, height as usize) != (nx, ny) {
        return Err(format!(
            "mask {} is {width}×{height} pixels; it must match the lattice, {nx}×{ny}",
            path.display(),
        ));
    }
    let mut data = vec![0; reader.output_buffer_size().ok_or("mask too large")?];
    let info = reader
        .next_frame(&mut data)
        .map_err(|e| format!("mask {}: {e}", path.display()))?;
    let channels = info.color_type.samples();
    let mut mask = vec![false; nx * ny];
    for row in 0..ny {
        for x in 0..nx {
            let px = &data[row * info.line_size + x * channels..];
            let luma = if channels >= 3 {
                (px[0] as u32 * 3 + px[1] as u32 * 6 + px[2] as u32) / 10
            } else {
                px[0] as u32
            };
            mask[(ny - 1 - row) * nx + x] = luma < 128;
        }
    }
    Ok(mask)
}

/// The lattice's collision operator for a scene's `[fluid] collision`.
pub fn lattice_collision(model: &CollisionModel) -> Collision {
    match *model {
        CollisionModel::Bgk => Collision::Bgk,
        CollisionModel::Trt { magic } => Collision::Trt { magic },
        CollisionModel::Mrt { s_e, s_eps, s_q } => Collision::Mrt { s_e, s_eps, s_q },
    }
}
