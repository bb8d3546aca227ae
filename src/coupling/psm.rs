//! The partially saturated method (Noble & Torczynski 1998; seed eqs. 5.53–5.54): every cell a
//! grain overlaps is collided as a blend of the fluid's operator and the solid's, weighted by
//! the exact solid fraction.

use super::exchange::{Coupler, Owner, Unstable};
use super::gather::{gather, gather2, group_by_row};
use super::map::{for_shares, GrainView, NONE};
use crate::lbm::moving::SolidShare;
use crate::lbm::{Lattice, Real};

/// Most grains that can share one cell (disks at least three cells across).
pub(super) const MAX_PER_CELL: usize = 8;

impl Coupler {
    /// The solid fraction of every interior fluid cell each grain overlaps, grain by grain
    /// (id order), each image's cells in row order; in parallel over the grains.
    pub(super) fn map_shares<T: Real>(&mut self, lat: &Lattice<T>, views: &[GrainView]) {
        let f = self.frame;
        let fluid = |k: usize| lat.is_fluid_at(k);
        gather(
            views.len(),
            &mut self.offsets,
            &mut self.shares,
            |g| {
                let mut n = 0;
                for_shares(&f, &fluid, views, g, false, |_| n += 1);
                n
            },
            |g, out| {
                let mut at = 0;
                for_shares(&f, &fluid, views, g, true, |s| {
                    out[at] = s;
                    at += 1;
                });
            },
        );
    }

    /// Group the shares by cell (cells in order of first appearance, then grouped by row;
    /// each cell's shares in grain order) and plan the partially saturated collision.
    pub(super) fn plan_psm<T: Real>(&mut self, lat: &Lattice<T>, views: &[GrainView]) {
        let f = self.frame;
        let tau = lat.tau0();
        let mut members = std::mem::take(&mut self.members);
        let mut counts = std::mem::take(&mut self.member_count);
        let mut cells = std::mem::take(&mut self.candidates);
        members.clear();
        counts.clear();
        cells.clear();
        for (n, sh) in self.shares.iter().enumerate() {
            let slot = &mut self.slot[sh.cell as usize];
            if *slot == NONE {
                *slot = cells.len() as u32;
                cells.push(sh.cell);
                members.push([0; MAX_PER_CELL]);
                counts.push(0);
            }
            let c = *slot as usize;
            if (counts[c] as usize) < MAX_PER_CELL {
                members[c][counts[c] as usize] = n as u32;
                counts[c] += 1;
            }
        }
        for &k in &cells {
            self.slot[k as usize] = NONE;
        }
        let plan = &mut self.psm;
        group_by_row(
            cells.len(),
            f.ny,
            |c| f.local(cells[c] as usize).1 as usize,
            &mut plan.rows,
            &mut self.order,
        );
        let (order, shares) = (&self.order, &self.shares);
        let eps_of = |c: usize| -> f64 {
            members[c][..counts[c] as usize]
                .iter()
                .map(|&s| shares[s as usize].fraction)
                .sum()
        };
        plan.cells.clear();
        plan.cells.extend(order.iter().map(|&o| cells[o as usize]));
        plan.total.clear();
        plan.total.extend(order.iter().map(|&o| {
            let e = eps_of(o as usize).min(1.0);
            // Noble & Torczynski 1998, eq. 9: B = ε(τ − ½) / ((1 − ε) + (τ − ½)).
            e * (tau - 0.5) / ((1.0 - e) + (tau - 0.5))
        }));
        let (pcells, totals) = (&plan.cells, &plan.total);
        gather2(
            order.len(),
            &mut plan.start,
            &mut plan.shares,
            &mut self.share_owner,
            |c| counts[order[c] as usize] as usize,
            |c, out, own| {
                let o = order[c] as usize;
                let m = &members[o][..counts[o] as usize];
                let eps = eps_of(o);
                let centre = f.centre(pcells[c] as usize);
                for (j, &s) in m.iter().enumerate() {
                    let sh = &shares[s as usize];
                    let grain = &views[sh.grain as usize];
                    out[j] = SolidShare {
                        // A cell whose overlap rounds to nothing stays plain fluid.
                        b: if eps > 0.0 {
                            totals[c] * sh.fraction / eps
                        } else {
                            0.0
                        },
                        velocity: GrainView {
                            centre: sh.centre,
                            ..*grain
                        }
                        .surface_velocity(centre),
                    };
                    own[j] = Owner {
                        grain: sh.grain,
                        image_x: sh.centre[0],
                        arm: [centre[0] - sh.centre[0], centre[1] - sh.centre[1]],
                    };
                }
            },
        );
        self.members = members;
        self.member_count = counts;
        self.candidates = cells;
    }

    /// Add each share's momentum (as the sweep reported it) to its grain's column sums, in
    /// plan order. Maps the first bad plan cell to (cell, grain, density).
    pub(super) fn collect_psm(
        &mut self,
        views: &[GrainView],
        bad: Option<(usize, f64)>,
    ) -> Option<Unstable> {
        for (c, &k) in self.psm.cells.iter().enumerate() {
            let col = self.column(k as usize);
            for s in self.psm.start[c] as usize..self.psm.start[c + 1] as usize {
                let (o, p) = (&self.share_owner[s], self.share_momentum[s]);
                let g = o.grain as usize;
                // The grain receives what the fluid gains, negated (seed eqs. 5.53–5.54).
                let load = [p[0], p[1], o.arm[0] * p[1] - o.arm[1] * p[0]];
                self.sums.add(g, views[g].centre[0], o.image_x, col, load);
            }
        }
        bad.map(|(c, rho)| {
            let s = self.psm.start[c] as usize;
            (self.psm.cells[c] as usize, self.share_owner[s].grain, rho)
        })
    }
}
