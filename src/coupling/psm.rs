//! The partially saturated method (Noble & Torczynski 1998; seed eqs. 5.53–5.54): every cell a
//! grain overlaps is collided as a blend of the fluid's operator and the solid's, weighted by
//! the exact solid fraction.

use super::exchange::{CellUpdate, Coupler, CouplingError, ShareRun, MAX_PER_CELL};
use super::map::{GrainView, NONE};
use crate::lbm::collision::{equilibrium, Moments};
use crate::lbm::d2q9::{CX, CY, OPP, Q};
use crate::lbm::{Lattice, Real};
use rayon::prelude::*;

impl Coupler {
    pub(super) fn exchange_psm<T: Real>(
        &mut self,
        lat: &mut Lattice<T>,
        grains: &[GrainView],
        ids: &[u64],
    ) -> Result<(), CouplingError> {
        let f = self.frame;
        let tau = lat.tau0();
        let step = lat.steps_done();
        // Group the shares by cell, cells in order of first appearance (fixed).
        self.runs.clear();
        for (n, sh) in self.shares.iter().enumerate() {
            let slot = &mut self.run_of[sh.cell as usize];
            if *slot == NONE {
                *slot = self.runs.len() as u32;
                self.runs.push(ShareRun {
                    cell: sh.cell,
                    shares: [0; MAX_PER_CELL],
                    n: 0,
                });
            }
            let run = &mut self.runs[*slot as usize];
            if (run.n as usize) < MAX_PER_CELL {
                run.shares[run.n as usize] = n as u32;
                run.n += 1;
            }
        }
        for run in &self.runs {
            self.run_of[run.cell as usize] = NONE;
        }
        let mut updates = std::mem::take(&mut self.updates);
        {
            let (lat, shares) = (&*lat, &self.shares);
            self.runs
                .par_iter()
                .with_min_len(64)
                .map(|sr| {
                    let k = sr.cell as usize;
                    let run = sr.shares[..sr.n as usize]
                        .iter()
                        .map(|&n| &shares[n as usize]);
                    let (x, y) = f.local(k);
                    let h = lat.gather_previous(x as usize, y as usize);
                    let mut post = h;
                    let m = lat.collide_one(&mut post);
                    let m64 = Moments {
                        drho: m.drho.to_f64(),
                        rho: m.rho.to_f64(),
                        ux: m.ux.to_f64(),
                        uy: m.uy.to_f64(),
                    };
                    let eq_fluid = equilibrium(&m64);
                    let hf: [f64; Q] = std::array::from_fn(|i| h[i].to_f64());
                    let eps: f64 = run.clone().map(|s| s.fraction).sum();
                    let eps_c = eps.min(1.0);
                    // Noble & Torczynski 1998, eq. 9: B = ε(τ − ½) / ((1 − ε) + (τ − ½)).
                    let b_total = eps_c * (tau - 0.5) / ((1.0 - eps_c) + (tau - 0.5));
                    let mut u = CellUpdate::new(k as u32);
                    u.h = std::array::from_fn(|i| (1.0 - b_total) * post[i].to_f64());
                    let centre = f.centre(k);
                    for s in run {
                        let grain = &grains[s.grain as usize];
                        let bg = b_total * s.fraction / eps;
                        let us = GrainView {
                            centre: s.centre,
                            ..*grain
                        }
                        .surface_velocity(centre);
                        let eq_solid = equilibrium(&Moments {
                            ux: us[0],
                            uy: us[1],
                            ..m64
                        });
                        let mut p = [0.0; 2];
                        for i in 0..Q {
                            let j = OPP[i];
                            // Noble & Torczynski 1998, eq. 8:
                            // Ω^s_i = [f_ī − f^eq_ī(ρ, u)] − [f_i − f^eq_i(ρ, u_s)].
                            let omega_s = (hf[j] - eq_fluid[j]) - (hf[i] - eq_solid[i]);
                            u.h[i] += bg * (hf[i] + omega_s);
                            p[0] += bg * omega_s * CX[i] as f64;
                            p[1] += bg * omega_s * CY[i] as f64;
                        }
                        // The grain receives what the fluid gains, negated (seed eqs. 5.53–5.54).
                        let r = [centre[0] - s.centre[0], centre[1] - s.centre[1]];
                        u.push(s.grain, [-p[0], -p[1], -(r[0] * p[1] - r[1] * p[0])]);
                    }
                    u.rho = 1.0 + u.h.iter().sum::<f64>();
                    u
                })
                .collect_into_vec(&mut updates);
        }
        let bad = self.apply(lat, &updates);
        self.updates = updates;
        if let Some((k, density)) = bad {
            return Err(self.unstable(step, k, density, grains, ids));
        }
        Ok(())
    }
}
