//! The background grid: geometry, node fields and the grid boundary conditions.
//!
//! Cells are `h` × `h` squares, `nx` × `ny` of them, with the domain's lower-left corner at
//! the origin. Nodes run from −1 to `nx + 1` (and −1 to `ny + 1`): the outer layer pads the
//! support of GIMP points in the boundary cells and obeys the same boundary condition as
//! the boundary nodes. Node fields are stored column by column (node column `I`, then row).

/// Grid geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridSpec {
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
    /// Cell size (m).
    pub h: f64,
}

impl GridSpec {
    /// Nodes per node column, padding included.
    pub fn rows(&self) -> usize {
        self.ny + 3
    }
    /// Node columns, padding included.
    pub fn cols(&self) -> usize {
        self.nx + 3
    }
    /// Storage index of node (I, J), −1 ≤ I ≤ nx+1, −1 ≤ J ≤ ny+1.
    #[inline(always)]
    pub fn node(&self, i: i64, j: i64) -> usize {
        (i + 1) as usize * self.rows() + (j + 1) as usize
    }
    /// Domain width (m).
    pub fn width(&self) -> f64 {
        self.nx as f64 * self.h
    }
    /// Domain height (m).
    pub fn height(&self) -> f64 {
        self.ny as f64 * self.h
    }
}

/// The condition on one side of the domain, applied to its boundary nodes and padding.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Side {
    /// No condition: material that reaches this side leaves the domain (an error).
    Open,
    /// No-slip: both velocity components are zero.
    Fixed,
    /// Free slip: the normal velocity is zero, the tangential one free.
    Roller,
    /// Coulomb friction: material moving into the side is stopped, and its tangential
    /// velocity is reduced by `friction` times the normal velocity removed; material
    /// moving away separates freely (Bardenhagen et al. 2000 contact, grid form).
    Frictional {
        /// Coulomb friction coefficient μ = tan(wall friction angle).
        friction: f64,
    },
}

/// The four sides of the domain (the scene names them west, east, south, north).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Boundaries {
    /// x = 0.
    pub left: Side,
    /// x = width.
    pub right: Side,
    /// y = 0.
    pub bottom: Side,
    /// y = height.
    pub top: Side,
}

impl Boundaries {
    /// Open on the left, right and top, with `bottom` as the floor: a layer or block on a
    /// base, free everywhere else.
    pub const fn floor(bottom: Side) -> Self {
        Self {
            left: Side::Open,
            right: Side::Open,
            bottom,
            top: Side::Open,
        }
    }
}

/// Apply `side` to a velocity whose wall normal (pointing into the material) is axis
/// `axis` (0 = x, 1 = y) with sign `into` (+1 for the left/bottom side). `v` is the new
/// nodal velocity (m/s).
#[inline(always)]
pub fn apply_side(side: Side, axis: usize, into: f64, v: &mut [f64; 2]) {
    let t = 1 - axis;
    match side {
        Side::Open => {}
        Side::Fixed => *v = [0.0; 2],
        Side::Roller => v[axis] = 0.0,
        Side::Frictional { friction } => {
            let vn = v[axis] * into; // > 0 when moving away from the wall
            if vn < 0.0 {
                v[axis] = 0.0;
                // Coulomb: |Δv_t| ≤ μ |Δv_n| (Bardenhagen et al. 2000, eq. 12).
                let dvt = friction * (-vn);
                let vt = v[t];
                v[t] = if vt.abs() <= dvt {
                    0.0
                } else {
                    vt - dvt * vt.signum()
                };
            }
        }
    }
}

/// The two side walls of a quasi-two-dimensional channel: parallel to the simulated
/// plane, `gap_m` apart. In plane strain they are what holds ε_zz = 0, so each presses on
/// the material with the out-of-plane stress |σ_zz| and resists its in-plane motion with
/// Coulomb friction μ_w |σ_zz| (Janssen 1895; the side-wall term of Jop, Forterre &
/// Pouliquen 2005). Per metre of depth this is a force of up to 2 μ_w |σ_zz| / W per
/// unit area, opposite to the velocity; it never reverses it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SideWalls {
    /// Distance W between the walls (m), > 0.
    pub gap_m: f64,
    /// Coulomb friction coefficient μ_w = tan(wall friction angle), ≥ 0.
    pub friction: f64,
}

impl SideWalls {
    /// The factor 2 μ_w / W (1/m) that turns ∫ |σ_zz| dA into the walls' largest
    /// friction force per metre of depth.
    pub fn coefficient(&self) -> f64 {
        2.0 * self.friction / self.gap_m
    }
}

/// Coulomb friction of the side walls on a node velocity `v` (m/s): its magnitude drops by
/// `dv` = Δt F_w / m (m/s), F_w the node's largest wall force, and stops at zero. The
/// direction is kept.
#[inline(always)]
pub fn apply_side_walls(dv: f64, v: &mut [f64; 2]) {
    let speed = (v[0] * v[0] + v[1] * v[1]).sqrt();
    if speed <= dv {
        *v = [0.0; 2];
    } else if dv > 0.0 {
        let keep = (speed - dv) / speed;
        v[0] *= keep;
        v[1] *= keep;
    }
}

/// Node fields of the grid, column-major with padding (see [`GridSpec::node`]). Only the
/// rows in `active[I]` of node column I hold values of the current step.
#[derive(Debug, Clone, Default)]
pub struct NodeFields {
    /// Mass (kg/m).
    pub mass: Vec<f64>,
    /// Momentum (kg/s per metre).
    pub mom: Vec<[f64; 2]>,
    /// Internal plus external force (N/m).
    pub force: Vec<[f64; 2]>,
    /// Largest side-wall friction force, 2 μ_w / W Σ_p S_Ip V_p |σ_zz,p| (N/m); zero
    /// without [`SideWalls`].
    pub wall: Vec<f64>,
    /// Velocity p/m as mapped from the points, before the update and without boundary
    /// conditions (m/s).
    pub v_old: Vec<[f64; 2]>,
    /// Velocity after the update, boundary conditions applied (m/s).
    pub v_new: Vec<[f64; 2]>,
    /// Active node rows of each node column, `[first, end)` as storage offsets within the
    /// column (row J at offset J + 1); empty when no point touches the column.
    pub active: Vec<(u32, u32)>,
}

impl NodeFields {
    /// Zeroed fields for `spec`.
    pub fn new(spec: &GridSpec) -> Self {
        let n = spec.rows() * spec.cols();
        NodeFields {
            mass: vec![0.0; n],
            mom: vec![[0.0; 2]; n],
            force: vec![[0.0; 2]; n],
            wall: vec![0.0; n],
            v_old: vec![[0.0; 2]; n],
            v_new: vec![[0.0; 2]; n],
            active: vec![(0, 0); spec.cols()],
        }
    }

    /// Mass and new velocity of every node, zero where inactive (for output).
    pub fn snapshot(&self, spec: &GridSpec) -> (Vec<f64>, Vec<[f64; 2]>) {
        let rows = spec.rows();
        let mut m = vec![0.0; self.mass.len()];
        let mut v = vec![[0.0; 2]; self.mass.len()];
        for (col, &(a, b)) in self.active.iter().enumerate() {
            for r in a as usize..b as usize {
                let n = col * rows + r;
                m[n] = self.mass[n];
                v[n] = self.v_new[n];
            }
        }
        (m, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frictional_side_stops_and_brakes() {
        let base = Side::Frictional { friction: 0.5 };
        // Moving down at 2 m/s and sideways at 3 m/s: normal removed, tangential −0.5·2.
        let mut v = [3.0, -2.0];
        apply_side(base, 1, 1.0, &mut v);
        assert_eq!(v, [2.0, 0.0]);
        // Slow sideways motion sticks.
        let mut v = [-0.5, -2.0];
        apply_side(base, 1, 1.0, &mut v);
        assert_eq!(v, [0.0, 0.0]);
        // Moving away separates freely.
        let mut v = [3.0, 1.0];
        apply_side(base, 1, 1.0, &mut v);
        assert_eq!(v, [3.0, 1.0]);
        // Right wall (normal −x into the material): moving right is into the wall.
        let mut v = [1.0, 4.0];
        apply_side(Side::Frictional { friction: 1.0 }, 0, -1.0, &mut v);
        assert_eq!(v, [0.0, 3.0]);
        let mut v = [1.0, 4.0];
        apply_side(Side::Roller, 0, -1.0, &mut v);
        assert_eq!(v, [0.0, 4.0]);
    }

    #[test]
    fn side_walls_brake_without_reversing() {
        let walls = SideWalls {
            gap_m: 0.1,
            friction: 0.5,
        };
        assert_eq!(walls.coefficient(), 10.0);
        // |v| = 5 drops by 1 along its own direction.
        let mut v = [3.0, -4.0];
        apply_side_walls(1.0, &mut v);
        assert!((v[0] - 2.4).abs() < 1e-15 && (v[1] + 3.2).abs() < 1e-15);
        // A larger impulse than the momentum stops the node, never reverses it.
        let mut v = [3.0, -4.0];
        apply_side_walls(5.5, &mut v);
        assert_eq!(v, [0.0, 0.0]);
        // No wall force, no change.
        let mut v = [3.0, -4.0];
        apply_side_walls(0.0, &mut v);
        assert_eq!(v, [3.0, -4.0]);
    }

    #[test]
    fn node_indexing_is_column_major_with_padding() {
        let g = GridSpec {
            nx: 4,
            ny: 3,
            h: 0.5,
        };
        assert_eq!(g.node(-1, -1), 0);
        assert_eq!(g.node(-1, 4), 5);
        assert_eq!(g.node(0, -1), 6);
        assert_eq!(g.node(5, 4), g.rows() * g.cols() - 1);
    }
}
