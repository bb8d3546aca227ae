//! The optional short-range repulsion between grains and between grains and walls
//! (Glowinski et al. 2001), added to the force held over the DEM sub-steps.

use super::LbmDem;
use crate::map::GrainView;

impl LbmDem {
    /// Glowinski et al. (2001) short-range repulsion between grains closer than `range`
    /// and between grains and walls closer than `range` (walls count as a mirror grain),
    /// added to each owned grain's held force: partners in id order, then walls in order.
    pub(super) fn add_repulsion(&self, range: f64, strength: f64, held: &mut [[f64; 3]]) {
        let (dx, gr) = (self.units.dx_m, self.reduced_gravity);
        let g = &self.dem.system.grains;
        // Candidates on a grid of cells as wide as the largest reach.
        let rmax = self.views.iter().map(|v| v.radius * dx).fold(0.0, f64::max);
        let cell = 2.0 * rmax + range;
        let key = |v: &GrainView| {
            (
                (v.centre[0] * dx / cell).floor() as i64,
                (v.centre[1] * dx / cell).floor() as i64,
            )
        };
        let mut grid: std::collections::BTreeMap<(i64, i64), Vec<u32>> = Default::default();
        for (j, v) in self.views.iter().enumerate() {
            grid.entry(key(v)).or_default().push(j as u32);
        }
        let mut near = Vec::new();
        for (i, h) in held.iter_mut().enumerate() {
            let vi = self.view_of[i] as usize;
            let (cx, cy) = key(&self.views[vi]);
            near.clear();
            for a in -1..=1 {
                for b in -1..=1 {
                    if let Some(list) = grid.get(&(cx + a, cy + b)) {
                        near.extend_from_slice(list);
                    }
                }
            }
            // View indices are in id order.
            near.sort_unstable();
            let wi = self.mass[vi] * gr;
            for &j in &near {
                let j = j as usize;
                if j == vi {
                    continue;
                }
                let (pi, pj) = (&self.views[vi], &self.views[j]);
                let (ddx, ddy) = (
                    (pj.centre[0] - pi.centre[0]) * dx,
                    (pj.centre[1] - pi.centre[1]) * dx,
                );
                let d = ddx.hypot(ddy);
                let gap = d - (pi.radius + pj.radius) * dx;
                if gap < range && d > 0.0 {
                    let w = wi.min(self.mass[j] * gr);
                    let f = strength * w * ((range - gap) / range).powi(2);
                    // Pushes grain i away from grain j.
                    h[0] -= f * ddx / d;
                    h[1] -= f * ddy / d;
                }
            }
            for w in self.dem.system.walls.iter().filter(|w| !w.removed) {
                let c = w.closest_point([g.x[i], g.y[i]]);
                let (ddx, ddy) = (g.x[i] - c[0], g.y[i] - c[1]);
                let d = ddx.hypot(ddy);
                let gap = d - g.r[i];
                if gap < range && d > 0.0 {
                    let f = strength * wi * ((range - gap) / range).powi(2);
                    h[0] += f * ddx / d;
                    h[1] += f * ddy / d;
                }
            }
        }
    }
}
