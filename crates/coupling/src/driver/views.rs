//! The grains in view on this rank: the owned grains and the ghosts from the neighbours,
//! merged by increasing id and converted to lattice units for the coupler.

use super::{LbmDem, Source};
use crate::ghosts::GhostState;
use crate::map::GrainView;
use decomposition::Comm;

impl LbmDem {
    /// Owned grains as their ghosts see them.
    fn owned_states(&self) -> Vec<GhostState> {
        let g = &self.dem.system.grains;
        (0..self.dem.system.owned())
            .map(|i| GhostState {
                id: g.id[i],
                x: [g.x[i], g.y[i]],
                r: g.r[i],
                m: g.m[i],
                v: [g.vx[i], g.vy[i]],
                omega: g.omega[i],
            })
            .collect()
    }

    /// Exchange ghosts with the neighbours and rebuild the views: owned and ghost grains in
    /// increasing id, in lattice units. Collective.
    pub(super) fn refresh_views(&mut self, comm: &dyn Comm) {
        let owned = self.owned_states();
        let ghosts = if self.halo.has_peers() {
            self.halo.exchange_states(comm, &owned)
        } else {
            Vec::new()
        };
        let all: Vec<(GhostState, Source)> = owned
            .into_iter()
            .enumerate()
            .map(|(i, s)| (s, Source::Owned(i as u32)))
            .chain(
                ghosts
                    .into_iter()
                    .map(|(s, side)| (s, Source::Ghost(side as u8))),
            )
            .collect();
        by_id(&all, &mut self.id_order);
        let (dx, dt) = (self.units.dx_m, self.units.dt_s);
        self.views.clear();
        self.ids.clear();
        self.source.clear();
        self.mass.clear();
        self.view_of.clear();
        self.view_of.resize(self.dem.system.owned(), 0);
        for &k in &self.id_order {
            let (s, src) = &all[k as usize];
            // Two ranks across a periodic face: a grain near both faces arrives once per
            // side; the first in storage order is kept.
            if self.ids.last() == Some(&s.id) {
                continue;
            }
            let v = self.views.len();
            self.views.push(GrainView {
                centre: [s.x[0] / dx, s.x[1] / dx],
                radius: s.r / dx * self.hydro_ratio,
                velocity: [s.v[0] * dt / dx, s.v[1] * dt / dx],
                omega: s.omega * dt,
            });
            self.ids.push(s.id);
            self.source.push(*src);
            self.mass.push(s.m);
            if let Source::Owned(i) = src {
                self.view_of[*i as usize] = v as u32;
            }
        }
    }
}

/// Fill `order` with the indices of `all` by increasing id, equal ids in storage order.
/// The last call's order is kept when it still sorts `all`: the grains' storage order changes
/// only when the DEM rebuilds its lists or grains migrate, so most steps check and sort
/// nothing.
fn by_id(all: &[(GhostState, Source)], order: &mut Vec<u32>) {
    let key = |k: u32| (all[k as usize].0.id, k);
    let still = order.len() == all.len() && order.windows(2).all(|w| key(w[0]) < key(w[1]));
    if !still {
        order.clear();
        order.extend(0..all.len() as u32);
        order.sort_unstable_by_key(|&k| key(k));
    }
}
