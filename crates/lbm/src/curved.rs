//! Fixed circular obstacles with curved walls: linear interpolated bounce-back (Bouzidi,
//! Firdaouss & Lallemand 2001) at the exact link fraction, executed as a static
//! [`LinkPlan`] of bodies at rest, so every backend and kernel runs it the way it runs
//! grains' links.
//!
//! A circle's cells (those whose centre lies inside, the same rule as
//! [`super::geometry::Shape::rasterise`]) stay plain fluid cells of the lattice: the sweep
//! computes them, nothing reads them, and [`CurvedWalls::interior`] lists them so that fields
//! and probes treat them as solid. The fluid cells next to a circle get their populations
//! from the wall through the plan, and the momentum each link hands to the wall gives the
//! obstacle's force, reduced in global column order ([`CurvedWalls::column_forces`]), so
//! the force has the same bits on any number of ranks.

use super::d2q9::{CX, CY, Q};
use super::geometry::link_fraction;
use super::lattice::Lattice;
use super::moving::{BodyColumns, LinkPlan, MovingCells, MovingLink, RigidMotion};
use super::real::Real;

/// A fixed circle with a curved wall, lattice units (cell (x, y) spans [x, x+1) × [y, y+1)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvedCircle {
    /// Solid id of the obstacle (names it in reports; no cell of the lattice carries it).
    pub solid: u16,
    /// Centre, global lattice coordinates.
    pub centre: [f64; 2],
    /// Radius (cells).
    pub radius: f64,
}

impl CurvedCircle {
    /// Whether the centre of global cell (x, y) lies inside (or on) the circle.
    #[inline]
    pub fn covers(&self, x: i64, y: i64) -> bool {
        let (dx, dy) = (
            x as f64 + 0.5 - self.centre[0],
            y as f64 + 0.5 - self.centre[1],
        );
        dx * dx + dy * dy <= self.radius * self.radius
    }
}

/// The curved walls of one slab: the static link plan of the fluid cells next to them, the
/// momentum each link handed over in the last step, and the cells inside.
#[derive(Debug, Clone, Default)]
pub struct CurvedWalls {
    circles: Vec<CurvedCircle>,
    plan: LinkPlan,
    momentum: Vec<f64>,
    columns: BodyColumns,
    interior: Vec<u32>,
    /// Local slab width and row stride (for the column sums).
    nx: usize,
    stride: usize,
}

impl CurvedWalls {
    /// The plan of `lat`'s slab for `circles` (global lattice coordinates). Links are
    /// interpolated at the exact fraction q where the link meets the circle; below ½ the
    /// fluid neighbour on the far side must be a plain fluid cell outside every circle,
    /// else the link is bounced back half-way (Ladd 1994). Cells of walls, open faces and
    /// halos are never listed; a link to a wall or face cell is left to the lattice.
    pub fn new<T: Real>(lat: &Lattice<T>, circles: &[CurvedCircle]) -> Self {
        let (nx, ny, stride) = (lat.nx(), lat.ny(), lat.stride());
        let x0 = lat.x_offset() as i64;
        let inside = |gx: i64, y: i64| circles.iter().position(|c| c.covers(gx, y));
        let mut plan = LinkPlan {
            x0,
            bodies: circles
                .iter()
                .map(|c| RigidMotion {
                    velocity: [0.0; 2],
                    omega: 0.0,
                    centre: c.centre,
                })
                .collect(),
            ..LinkPlan::default()
        };
        plan.start.push(0);
        let mut interior = Vec::new();
        for y in 0..ny {
            plan.rows.push(plan.cells.len() as u32);
            for x in 0..nx {
                let k = lat.padded_index(x as isize, y as isize);
                let gx = x0 + x as i64;
                if !lat.is_fluid_at(k) {
                    continue;
                }
                if inside(gx, y as i64).is_some() {
                    interior.push(k as u32);
                    continue;
                }
                let centre = [gx as f64 + 0.5, y as f64 + 0.5];
                let mut any = false;
                for i in 1..Q {
                    let (cx, cy) = (CX[i] as i64, CY[i] as i64);
                    let from = lat.padded_index(x as isize - cx as isize, y as isize - cy as isize);
                    if !lat.is_fluid_at(from) {
                        continue;
                    }
                    let Some(b) = inside(gx - cx, y as i64 - cy) else {
                        continue;
                    };
                    let c = &circles[b];
                    let mut q = link_fraction(centre, [-cx as f64, -cy as f64], c.centre, c.radius);
                    if q < 0.5 {
                        // Bouzidi et al. 2001, eq. 5 (q < ½) reads the cell at x + c_i.
                        let far =
                            lat.padded_index(x as isize + cx as isize, y as isize + cy as isize);
                        if !lat.is_fluid_at(far) || inside(gx + cx, y as i64 + cy).is_some() {
                            q = 0.5;
                        }
                    }
                    plan.links.push(MovingLink::new(i, b as u32));
                    plan.fractions.push(q);
                    any = true;
                }
                if any {
                    plan.cells.push(k as u32);
                    plan.start.push(plan.links.len() as u32);
                }
            }
        }
        plan.rows.push(plan.cells.len() as u32);
        Self {
            circles: circles.to_vec(),
            plan,
            momentum: Vec::new(),
            columns: BodyColumns::default(),
            interior,
            nx,
            stride,
        }
    }

    /// The circles, in plan-body order.
    pub fn circles(&self) -> &[CurvedCircle] {
        &self.circles
    }

    /// The plan for a step; the sweep writes each link's momentum.
    pub fn moving(&mut self) -> MovingCells<'_> {
        MovingCells::Links(&self.plan, &mut self.momentum, &mut self.columns)
    }

    /// The link plan.
    pub fn plan(&self) -> &LinkPlan {
        &self.plan
    }

    /// Padded indices of the fluid cells next to a curved wall.
    pub fn link_cells(&self) -> &[u32] {
        &self.plan.cells
    }

    /// Global (x, y) of plan cell `n` (a plan index, as a sweep reports a bad cell).
    pub fn cell_of(&self, n: usize) -> (usize, usize) {
        let k = self.plan.cells[n] as usize;
        let x = (k % self.stride - 1) as i64 + self.plan.x0;
        (x as usize, k / self.stride - 1)
    }

    /// Padded indices of the cells inside the circles (solid to fields and probes).
    pub fn interior(&self) -> &[u32] {
        &self.interior
    }

    /// Per circle and local column, the force the fluid exerted on the wall in the last
    /// step, lattice units: −Σ (f*_ī + f_i) c_i over the column's links (seed eq. 5.47),
    /// summed south to north, each cell's links in direction order. Laid out
    /// `[circle][column][fx, fy]`; zero before the first step.
    pub fn column_forces(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.circles.len() * self.nx * 2];
        if self.momentum.len() != self.plan.links.len() {
            return out;
        }
        for (n, &k) in self.plan.cells.iter().enumerate() {
            let x = k as usize % self.stride - 1;
            let range = self.plan.start[n] as usize..self.plan.start[n + 1] as usize;
            for l in range {
                let link = self.plan.links[l];
                let (i, b) = (link.dir(), link.body());
                let m = self.momentum[l];
                let at = 2 * (b * self.nx + x);
                out[at] -= m * CX[i] as f64;
                out[at + 1] -= m * CY[i] as f64;
            }
        }
        out
    }

    /// The total force on each circle from every slab's [`CurvedWalls::column_forces`]
    /// concatenated in rank order (`widths` the slabs' column counts), summed in global
    /// column order: the same bits on any number of ranks.
    pub fn reduce(all: &[f64], widths: &[usize], circles: usize) -> Vec<[f64; 2]> {
        let mut total = vec![[0.0; 2]; circles];
        let mut at = 0;
        let mut per_rank = Vec::with_capacity(widths.len());
        for &w in widths {
            per_rank.push(at);
            at += circles * w * 2;
        }
        for (b, t) in total.iter_mut().enumerate() {
            for (r, &w) in widths.iter().enumerate() {
                let base = per_rank[r] + 2 * b * w;
                for x in 0..w {
                    t[0] += all[base + 2 * x];
                    t[1] += all[base + 2 * x + 1];
                }
            }
        }
        total
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Shape;
    use crate::lattice::{FaceCondition, LatticeSetup, SolidInfo, FLUID};
    use crate::Collision;
    use decomposition::SlabPartition;

    /// A 48 × 40 box with walls, split into `ranks` slabs, and two circles.
    fn slabs(ranks: usize) -> (Vec<Lattice<f64>>, Vec<CurvedCircle>) {
        let (nx, ny) = (48, 40);
        let setup = LatticeSetup {
            nx,
            ny,
            cells: vec![FLUID; nx * ny],
            faces: std::array::from_fn(|_| FaceCondition::Wall { solid: 1 }),
            solids: vec![SolidInfo {
                name: "walls".into(),
                velocity: [0.0; 2],
            }],
            collision: Collision::Bgk,
            tau0: 0.8,
            smagorinsky: None,
            force: [0.0; 2],
        };
        let circles = vec![
            CurvedCircle {
                solid: 2,
                centre: [20.3, 19.7],
                radius: 7.2,
            },
            // Next to the south wall: links from the wall rows are the lattice's.
            CurvedCircle {
                solid: 3,
                centre: [38.0, 3.1],
                radius: 3.0,
            },
        ];
        let p = SlabPartition::uniform(nx, ranks).unwrap();
        let lats = (0..ranks)
            .map(|r| Lattice::<f64>::new_slab(&setup, &p, r))
            .collect();
        (lats, circles)
    }

    /// Every link joins a fluid cell outside both circles to a covered neighbour, with q in
    /// (0, 1] at the circle's surface; q < ½ only where the far neighbour is open fluid;
    /// the plan has every such link exactly once and the interior every covered cell.
    #[test]
    fn links_cut_the_circles_where_they_are() {
        let (lats, circles) = slabs(1);
        let (lat, w) = (&lats[0], CurvedWalls::new(&lats[0], &circles));
        let covered = |x: i64, y: i64| circles.iter().position(|c| c.covers(x, y));
        let inside: usize = circles
            .iter()
            .map(|c| {
                Shape::Circle {
                    centre: c.centre,
                    radius: c.radius,
                }
                .covered_cells(48, 40)
            })
            .sum();
        assert_eq!(w.interior().len(), inside);
        let mut expected = 0;
        for y in 0..40i64 {
            for x in 0..48i64 {
                if covered(x, y).is_none() {
                    expected += (1..Q)
                        .filter(|&i| {
                            let (nx, ny) = (x - CX[i] as i64, y - CY[i] as i64);
                            (0..48).contains(&nx)
                                && (0..40).contains(&ny)
                                && covered(nx, ny).is_some()
                        })
                        .count();
                }
            }
        }
        let p = w.plan();
        assert_eq!(p.links.len(), expected);
        let stride = lat.stride();
        for (n, &k) in p.cells.iter().enumerate() {
            let (x, y) = (
                (k as usize % stride - 1) as i64,
                (k as usize / stride - 1) as i64,
            );
            assert!(covered(x, y).is_none());
            for l in p.start[n] as usize..p.start[n + 1] as usize {
                let (i, b) = (p.links[l].dir(), p.links[l].body());
                let (cx, cy) = (CX[i] as i64, CY[i] as i64);
                assert_eq!(covered(x - cx, y - cy), Some(b));
                let q = p.fractions[l];
                assert!(q > 0.0 && q <= 1.0);
                let c = &circles[b];
                let hit = [
                    x as f64 + 0.5 - q * cx as f64,
                    y as f64 + 0.5 - q * cy as f64,
                ];
                let r = (hit[0] - c.centre[0]).hypot(hit[1] - c.centre[1]);
                if q != 0.5 {
                    assert!((r - c.radius).abs() < 1e-12, "link {l}: q {q} misses");
                }
                if q < 0.5 {
                    let far = (x + cx, y + cy);
                    assert!((0..48).contains(&far.0) && (0..40).contains(&far.1));
                    assert!(covered(far.0, far.1).is_none());
                }
            }
        }
    }

    /// Split over slabs, the plans hold the same links with the same fractions, and a
    /// reduction of per-column forces in rank order adds the columns in the same order.
    #[test]
    fn slabs_plan_the_same_links() {
        let (one, circles) = slabs(1);
        let whole = CurvedWalls::new(&one[0], &circles);
        let (three, _) = slabs(3);
        let mut links = Vec::new();
        for lat in &three {
            let w = CurvedWalls::new(lat, &circles);
            let p = w.plan();
            for n in 0..p.cells.len() {
                let (x, y) = w.cell_of(n);
                for l in p.start[n] as usize..p.start[n + 1] as usize {
                    links.push((y, x, p.links[l], p.fractions[l].to_bits()));
                }
            }
        }
        let mut all = Vec::new();
        let p = whole.plan();
        for n in 0..p.cells.len() {
            let (x, y) = whole.cell_of(n);
            for l in p.start[n] as usize..p.start[n + 1] as usize {
                all.push((y, x, p.links[l], p.fractions[l].to_bits()));
            }
        }
        links.sort_by_key(|a| (a.0, a.1));
        assert_eq!(links, all);
        let cols = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        // One circle, columns of widths 1 and 3: rank 0 then rank 1.
        let t = CurvedWalls::reduce(&cols, &[1, 3], 1);
        assert_eq!(t, vec![[1.0 + 3.0 + 5.0 + 7.0, 2.0 + 4.0 + 6.0 + 8.0]]);
    }
}
