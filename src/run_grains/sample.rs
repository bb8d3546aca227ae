//! The sample of a grains run: packed (random addition, distributed settling, trimming)
//! or loaded, spread over the ranks' slabs; and the collective gathers of its state.

use crate::error::RunError;
use decomposition::PackRows;
use decomposition::{reproducible_sums, Comm};
use dem::parallel::balanced_bounds;
use dem::sample::{load_csv, random_sequential_addition};
use dem::{DemError, DemSystem, Grains, SlabDem};
use scene::{size_distribution, SampleSpec, ValidGrainScene};

/// Every rank's owned grains, gathered on every rank and sorted by id (collective).
pub fn gather_grains(sys: &DemSystem, comm: &dyn Comm) -> Grains {
    let mut local = Vec::with_capacity(sys.owned() * Grains::WORDS);
    for i in 0..sys.owned() {
        sys.grains.pack_row(i, &mut local);
    }
    let all = comm.all_gather_f64(&local);
    let mut rows: Vec<&[f64]> = all.chunks_exact(Grains::WORDS).collect();
    rows.sort_by_key(|p| p[9].to_bits());
    let mut g = Grains::default();
    for p in rows {
        g.push_row(p);
    }
    g
}

/// Global sums of kinetic energy, momentum and grain count, the same bits whatever the
/// grains' storage order (a restart reorders them) and rank count (collective).
pub(super) fn global_state(d: &SlabDem, comm: &dyn Comm) -> (f64, [f64; 2], f64) {
    let g = &d.system.grains;
    let n = d.system.owned();
    let mut columns = [
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    ];
    for i in 0..n {
        let ke = g.kinetic_energy_of_grain(i);
        columns[0].push(ke);
        columns[1].push(g.m[i] * g.vx[i]);
        columns[2].push(g.m[i] * g.vy[i]);
    }
    let refs: Vec<&[f64]> = columns.iter().map(|c| c.as_slice()).collect();
    let s = reproducible_sums(&refs, comm);
    let mut count = [n as f64];
    comm.sum_f64(&mut count);
    (s[0], [s[1], s[2]], count[0])
}

/// Prepare the sample of `scene` (identical on every rank; settling runs distributed).
/// Returns the grains (ids 0..N) and the settling steps.
pub(crate) fn prepare(scene: &ValidGrainScene, comm: &dyn Comm) -> Result<(Grains, u64), RunError> {
    let s = &scene.scene;
    let rho = s.grains.density_kg_m3;
    let (grains, settle) = match &s.grains.sample {
        SampleSpec::Csv { file } => (load_csv(&scene.base_dir.join(file), rho)?, None),
        SampleSpec::List { grains } => {
            let mut g = Grains::default();
            for l in grains {
                let n = g.push(l.position_m, l.radius_m, rho, false);
                g.vx[n] = l.velocity_m_s[0];
                g.vy[n] = l.velocity_m_s[1];
                g.omega[n] = l.angular_velocity_rad_s;
            }
            (g, None)
        }
        SampleSpec::Pack {
            min_m,
            max_m,
            sizes,
            solid_fraction,
            seed,
            settle,
        } => (
            random_sequential_addition(
                *min_m,
                *max_m,
                size_distribution(sizes),
                rho,
                *solid_fraction,
                *seed,
                20_000,
            ),
            settle.clone(),
        ),
    };
    let size = s.domain.size();
    let outside = (0..grains.len()).find(|&i| {
        let (x, y, r) = (grains.x[i], grains.y[i], grains.r[i]);
        !(x - r >= 0.0 && x + r <= size[0] && y - r >= 0.0 && y + r <= size[1])
    });
    if let Some(i) = outside {
        return Err(scene
            .invalid(
                "file",
                format!(
                    "grain {i} of the sample at ({}, {}) m with radius {} m is not wholly \
                     inside the domain [0, 0]–{size:?} m",
                    grains.x[i], grains.y[i], grains.r[i]
                ),
            )
            .into());
    }
    if grains.is_empty() {
        return Err(DemError::Parameter {
            name: "sample",
            value: 0.0,
            why: "the sample holds no grains: enlarge the packing rectangle or check the CSV",
        }
        .into());
    }
    let Some(st) = settle else {
        return Ok((grains, 0));
    };
    let mut d = start(scene, grains, true, comm)?;
    d.system.global_damping = st.damping_1_s;
    if let Some(f) = st.friction {
        d.system.model.friction = f;
        d.system.model.rolling_friction = 0.0;
        for w in &mut d.system.walls {
            w.friction = f;
        }
    }
    let mut steps = 0;
    let n = d.global_count(comm) as f64;
    let signals = crate::driver::Signals::install();
    loop {
        for _ in 0..100 {
            d.step(comm);
        }
        steps += 100;
        // SIGTERM while settling ends the run before its first step: nothing to keep.
        if signals.agree(comm, false).stop {
            return Err(RunError::Interrupted(format!(
                "stopped by SIGTERM while settling the sample (step {steps}), before the run's \
                 first step: nothing was computed and no checkpoint written"
            )));
        }
        let (ke, _, _) = global_state(&d, comm);
        if ke / n < st.kinetic_energy_per_grain_j_m {
            break;
        }
        if steps >= st.max_steps {
            return Err(DemError::Parameter {
                name: "max_steps",
                value: st.max_steps as f64,
                why: "settling did not bring the kinetic energy per grain below \
                      kinetic_energy_per_grain_j_m: raise max_steps or damping_1_s",
            }
            .into());
        }
    }
    let settled = gather_grains(&d.system, comm);
    // Keep the grains below the trim height, at rest, renumbered 0..N.
    let mut g = Grains::default();
    for i in 0..settled.len() {
        if st.trim_above_m.is_some_and(|h| settled.y[i] > h) {
            continue;
        }
        let mut p = Vec::with_capacity(Grains::WORDS);
        settled.pack_row(i, &mut p);
        p[2] = 0.0;
        p[3] = 0.0;
        p[5] = 0.0;
        p[9] = f64::from_bits(g.len() as u64);
        g.push_row(&p);
    }
    if g.is_empty() {
        return Err(DemError::Parameter {
            name: "trim_above_m",
            value: st.trim_above_m.unwrap_or(f64::NAN),
            why: "trimming removed every settled grain: set trim_above_m above the settled \
                  layer's bottom",
        }
        .into());
    }
    Ok((g, steps))
}

/// Slab boundaries for `grains` over the ranks of `comm`, balanced by grain count.
pub(super) fn bounds_for(scene: &ValidGrainScene, grains: &Grains, comm: &dyn Comm) -> Vec<f64> {
    let s = &scene.scene;
    let rmax = grains.r.iter().cloned().fold(0.0, f64::max);
    let cutoff = 2.0 * rmax + DemSystem::skin_for(rmax);
    balanced_bounds(&grains.x, 0.0, s.domain.size()[0], comm.size(), cutoff)
}

/// A distributed system of `grains` with the scene's walls and contacts.
pub(super) fn start(
    scene: &ValidGrainScene,
    grains: Grains,
    allow_overlap: bool,
    comm: &dyn Comm,
) -> Result<SlabDem, RunError> {
    let s = &scene.scene;
    let bounds = bounds_for(scene, &grains, comm);
    let setup = scene.dem_setup(&grains);
    let mut d = SlabDem::new(grains, &bounds, setup, allow_overlap, comm)?;
    d.system.global_damping = s.grains.global_damping_1_s;
    Ok(d)
}
