//! Plane-strain Mohr–Coulomb elastoplasticity for explicit MPM: elastic predictor, a
//! multi-surface return mapping in principal stress space (plane, edge, apex), then a tension
//! cutoff, with optional linear softening of friction and cohesion.
//!
//! Conventions: tension positive, Pa. Stress `[σxx, σyy, σxy, σzz]`; strain increment
//! `[Δεxx, Δεyy, Δεxy]` with Δεxy the tensor shear component, Δεzz = 0. Principal stresses
//! are sorted σ1 ≥ σ2 ≥ σ3. The caller applies the objective (Jaumann) rotation beforehand.
//!
//! Edges are named after the triaxial test the stress resembles (tension positive):
//! * `EdgeCompression`: σ1 = σ2 > σ3 (one major compressive stress: triaxial compression);
//! * `EdgeExtension`: σ1 > σ2 = σ3 (two equal major compressive stresses: triaxial extension).

/// Linear softening of friction and cohesion with equivalent plastic strain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Softening {
    /// Friction angle (deg) reached at `plastic_strain_end` and kept beyond.
    pub residual_friction_deg: f64,
    /// Cohesion (Pa) reached at `plastic_strain_end` and kept beyond.
    pub residual_cohesion_pa: f64,
    /// Equivalent plastic strain (–) up to which the peak strength holds.
    pub plastic_strain_start: f64,
    /// Equivalent plastic strain (–) from which the residual strength holds.
    pub plastic_strain_end: f64,
}

/// Mohr–Coulomb with non-associated flow, tension cutoff and optional softening.
/// Expects E > 0, 0 ≤ ν < 0.5, 0 ≤ φ < 90°, ψ ≥ 0, c ≥ 0 (the scene validator checks).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MohrCoulomb {
    /// Young's modulus E (Pa).
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio ν (–).
    pub poisson_ratio: f64,
    /// Peak friction angle φ (deg).
    pub friction_deg: f64,
    /// Dilation angle ψ (deg) of the plastic potential (ψ = φ: associated). Does not soften.
    pub dilation_deg: f64,
    /// Peak cohesion c (Pa).
    pub cohesion_pa: f64,
    /// Tension cutoff σt (Pa): largest admissible principal stress. Above the MC apex
    /// c·cot φ it never acts.
    pub tension_cutoff_pa: f64,
    /// Optional linear softening of φ and c with equivalent plastic strain.
    pub softening: Option<Softening>,
}

/// Run constants of a [`MohrCoulomb`] material: Lamé parameters (Pa) and the sine and
/// cosine of the peak friction angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prepared {
    /// λ (Pa).
    pub lam: f64,
    /// G (Pa).
    pub g: f64,
    /// sin φ_peak.
    pub sin_phi: f64,
    /// cos φ_peak.
    pub cos_phi: f64,
}

/// What one update did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outcome {
    /// Whether a plastic correction (MC or tension cutoff) was applied.
    pub yielded: bool,
    /// Return-mapping passes: 0 elastic, 1 without softening, at most 50 with it.
    pub iterations: u32,
    /// Where the stress was returned in the final pass.
    pub region: Region,
}

/// Return-mapping region of an update.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Region {
    /// Trial stress admissible; no plastic flow.
    Elastic,
    /// Main plane f(σ1, σ3) = 0 only.
    Plane,
    /// Edge σ1 = σ2 (triaxial compression): planes f(σ1, σ3) and f(σ2, σ3).
    EdgeCompression,
    /// Edge σ2 = σ3 (triaxial extension): planes f(σ1, σ3) and f(σ1, σ2).
    EdgeExtension,
    /// Hydrostatic apex σ1 = σ2 = σ3 = c·cot φ.
    Apex,
    /// The tension cutoff acted (after the MC return, which may also have acted).
    TensionCutoff,
}

/// Most return-mapping passes of the softening iteration.
const MAX_ITER: u32 = 50;

/// Lamé parameters (λ, G) in Pa from Young's modulus (Pa) and Poisson's ratio.
#[inline]
fn lame(e: f64, nu: f64) -> (f64, f64) {
    // λ = Eν/((1+ν)(1−2ν)), G = E/(2(1+ν)) (isotropic linear elasticity).
    (
        e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        e / (2.0 * (1.0 + nu)),
    )
}

#[inline]
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// D·v with the isotropic elastic matrix in principal space (λ+2G diagonal, λ off-diagonal).
#[inline]
fn d_mul(v: [f64; 3], lam: f64, g: f64) -> [f64; 3] {
    // D = λ 1⊗1 + 2G I (isotropic Hooke's law in principal components).
    let t = lam * (v[0] + v[1] + v[2]);
    [t + 2.0 * g * v[0], t + 2.0 * g * v[1], t + 2.0 * g * v[2]]
}

/// D⁻¹·v (compliance) in principal space.
#[inline]
fn d_inv_mul(v: [f64; 3], lam: f64, g: f64) -> [f64; 3] {
    // D⁻¹ = I/(2G) − λ/(2G(3λ+2G)) 1⊗1 (Sherman–Morrison inverse of λ 1⊗1 + 2G I).
    let t = lam / (2.0 * g * (3.0 * lam + 2.0 * g)) * (v[0] + v[1] + v[2]);
    [
        v[0] / (2.0 * g) - t,
        v[1] / (2.0 * g) - t,
        v[2] / (2.0 * g) - t,
    ]
}

/// Principal decomposition of a plane-strain stress: sorted values and the in-plane axes.
#[derive(Debug, Clone, Copy)]
struct Principal {
    /// σ1 ≥ σ2 ≥ σ3 (Pa).
    s: [f64; 3],
    /// Sorted slot of σzz; the other two slots hold the in-plane major, then minor, value.
    zz: usize,
    /// (σxx−σyy)/2, σxy and the Mohr radius R (Pa): fix the in-plane principal axes.
    d: f64,
    sxy: f64,
    r: f64,
}

#[inline]
fn principal(st: &[f64; 4]) -> Principal {
    // Mohr's circle: σa,b = m ± R, m = (σxx+σyy)/2, R = √(((σxx−σyy)/2)² + σxy²).
    let m = 0.5 * (st[0] + st[1]);
    let d = 0.5 * (st[0] - st[1]);
    let r = (d * d + st[2] * st[2]).sqrt();
    let (a, b, z) = (m + r, m - r, st[3]);
    let (s, zz) = if z >= a {
        ([z, a, b], 0)
    } else if z >= b {
        ([a, z, b], 1)
    } else {
        ([a, b, z], 2)
    };
    Principal {
        s,
        zz,
        d,
        sxy: st[2],
        r,
    }
}

/// cos 2θ, sin 2θ of the in-plane major principal axis.
#[inline]
fn axes(p: &Principal) -> (f64, f64) {
    // cos 2θ = (σxx−σyy)/(2R), sin 2θ = σxy/R (Mohr's circle); any axes when R = 0.
    if p.r > 0.0 {
        (p.d / p.r, p.sxy / p.r)
    } else {
        (1.0, 0.0)
    }
}

/// Rebuild `[σxx, σyy, σxy, σzz]` from new sorted values on the principal axes of `p`.
#[inline]
fn rebuild(p: &Principal, s: [f64; 3], st: &mut [f64; 4]) {
    let (a, b) = match p.zz {
        0 => (s[1], s[2]),
        1 => (s[0], s[2]),
        _ => (s[0], s[1]),
    };
    let (c2, s2) = axes(p);
    let (m, r) = (0.5 * (a + b), 0.5 * (a - b));
    // σ = m' + R'(cos 2θ, −cos 2θ, sin 2θ) in (xx, yy, xy) (Mohr's circle, θ unchanged).
    *st = [m + r * c2, m - r * c2, r * s2, s[p.zz]];
}

/// Surfaces at one strength: sin φ, sin ψ, k = 2c cos φ (Pa) and the apex stress (Pa).
#[derive(Debug, Clone, Copy)]
struct Surface {
    sphi: f64,
    spsi: f64,
    k: f64,
    apex: f64,
}

/// MC return of sorted trial principal stresses `t`; `tol` (Pa) is the yield and ordering
/// tolerance. Returns the sorted returned stresses and the region.
fn mc_return(t: [f64; 3], lam: f64, g: f64, sf: &Surface, tol: f64) -> ([f64; 3], Region) {
    let (sp, sg) = (sf.sphi, sf.spsi);
    // f = (σ1−σ3) + (σ1+σ3) sin φ − 2c cos φ = a·σ − k (Mohr–Coulomb, tension positive).
    let a1 = [1.0 + sp, 0.0, -(1.0 - sp)];
    let f1 = dot(a1, t) - sf.k;
    if f1 <= tol {
        return (t, Region::Elastic);
    }
    // ∂g/∂σ of g = (σ1−σ3) + (σ1+σ3) sin ψ (de Souza Neto, Perić & Owen 2008, ch. 8).
    let db1 = d_mul([1.0 + sg, 0.0, -(1.0 - sg)], lam, g);
    // One plane: σ = σtr − Δλ D b, Δλ = f_tr/(a·D b) (de Souza Neto et al. 2008, ch. 8).
    let dl = f1 / dot(a1, db1);
    let s = [t[0] - dl * db1[0], t[1] - dl * db1[1], t[2] - dl * db1[2]];
    if s[0] >= s[1] - tol && s[1] >= s[2] - tol {
        return (s, Region::Plane);
    }
    // Two planes. At most one edge gives a valid return; try first the one whose line the
    // plane return crossed (σ2 > σ1: compression; σ3 > σ2: extension).
    let (ec, ee) = (Region::EdgeCompression, Region::EdgeExtension);
    let order = if s[1] - s[0] >= s[2] - s[1] {
        [ec, ee]
    } else {
        [ee, ec]
    };
    for edge in order {
        let comp = edge == ec;
        // Second plane: f(σ2, σ3) on the compression edge, f(σ1, σ2) on the extension edge.
        let (a2, b2) = if comp {
            ([0.0, 1.0 + sp, -(1.0 - sp)], [0.0, 1.0 + sg, -(1.0 - sg)])
        } else {
            ([1.0 + sp, -(1.0 - sp), 0.0], [1.0 + sg, -(1.0 - sg), 0.0])
        };
        let db2 = d_mul(b2, lam, g);
        let f2 = dot(a2, t) - sf.k;
        // [a_i·D b_j] Δλ_j = f_i,tr, i, j ∈ {1, 2} (Clausen, Damkilde & Andersen 2007, edges).
        let (m11, m12, m21, m22) = (dot(a1, db1), dot(a1, db2), dot(a2, db1), dot(a2, db2));
        let det = m11 * m22 - m12 * m21;
        let l1 = (f1 * m22 - m12 * f2) / det;
        let l2 = (m11 * f2 - m21 * f1) / det;
        let ltol = 1e-10 * (l1.abs() + l2.abs());
        if !(det != 0.0 && l1 >= -ltol && l2 >= -ltol) {
            continue; // also rejects NaN
        }
        // σ = σtr − Δλ1 D b1 − Δλ2 D b2 (same reference); the two equal values made equal.
        let mut s = [0, 1, 2].map(|i| t[i] - l1 * db1[i] - l2 * db2[i]);
        let (i, j) = if comp { (0, 1) } else { (1, 2) };
        let m = 0.5 * (s[i] + s[j]);
        (s[i], s[j]) = (m, m);
        if s[0] >= s[1] - tol && s[1] >= s[2] - tol {
            return (s, edge);
        }
    }
    // Apex: the hydrostatic stress c cot φ, for any ψ (Clausen, Damkilde & Andersen 2007).
    ([sf.apex; 3], Region::Apex)
}

/// Tension cutoff σi ≤ σt on sorted principal stresses with associated flow,
/// Δσ = −D Σ_{i∈S} Δλ_i e_i, by an active set S: start with σ1, add σ2, σ3 while they
/// still exceed σt. Returns the stresses and whether the cutoff acted.
fn tension_cutoff(s: [f64; 3], lam: f64, g: f64, st: f64, tol: f64) -> ([f64; 3], bool) {
    if s[0] <= st {
        return (s, false);
    }
    let mut active = [true, false, false];
    let mut out = s;
    for _ in 0..3 {
        let n = active.iter().filter(|&&a| a).count() as f64;
        let r = [0, 1, 2].map(|i| if active[i] { s[i] - st } else { 0.0 });
        // Δλ = D_SS⁻¹ r, D_SS = 2G I + λ 11ᵀ: r/(2G) − λΣr/(2G(2G+nλ)) (Sherman–Morrison).
        let corr = lam * (r[0] + r[1] + r[2]) / (2.0 * g * (2.0 * g + n * lam));
        let mut dl = [0.0; 3];
        for i in (0..3).filter(|&i| active[i]) {
            dl[i] = r[i] / (2.0 * g) - corr;
        }
        let dv = d_mul(dl, lam, g);
        out = [0, 1, 2].map(|i| if active[i] { st } else { s[i] - dv[i] });
        let mut added = false;
        for i in 1..3 {
            if !active[i] && out[i] > st + tol {
                (active[i], added) = (true, true);
            }
        }
        if !added {
            break;
        }
    }
    (out, true)
}

impl MohrCoulomb {
    /// Friction angle (deg) and cohesion (Pa) at equivalent plastic strain `eps_p` (–): peak
    /// values up to `plastic_strain_start`, residual from `plastic_strain_end`, linear in
    /// between; peak values without softening.
    #[inline]
    pub fn strength_at(&self, eps_p: f64) -> (f64, f64) {
        let (phi, c) = (self.friction_deg, self.cohesion_pa);
        let Some(s) = self.softening else {
            return (phi, c);
        };
        let w = if eps_p <= s.plastic_strain_start {
            0.0
        } else if eps_p >= s.plastic_strain_end {
            1.0
        } else {
            (eps_p - s.plastic_strain_start) / (s.plastic_strain_end - s.plastic_strain_start)
        };
        // Linear softening, (1−w)·peak + w·residual (exact at both ends).
        let lerp = |a: f64, b: f64| (1.0 - w) * a + w * b;
        (
            lerp(phi, s.residual_friction_deg),
            lerp(c, s.residual_cohesion_pa),
        )
    }

    /// Yield function value (Pa) of `stress` = [σxx, σyy, σxy, σzz] (Pa, tension positive)
    /// at friction angle `friction_deg` (deg) and cohesion `cohesion_pa` (Pa):
    /// f = (σ1 − σ3) + (σ1 + σ3) sin φ − 2c cos φ; f ≤ 0 is admissible.
    pub fn yield_value(stress: &[f64; 4], friction_deg: f64, cohesion_pa: f64) -> f64 {
        let s = principal(stress).s;
        let (sp, cp) = friction_deg.to_radians().sin_cos();
        // Mohr–Coulomb in principal stresses, tension positive.
        (s[0] - s[2]) + (s[0] + s[2]) * sp - 2.0 * cohesion_pa * cp
    }

    /// Apply `d_eps` = [Δεxx, Δεyy, Δεxy] (–, tensor shear) to `stress` = [σxx, σyy, σxy, σzz]
    /// (Pa, tension positive): plane-strain elastic predictor, MC return in principal space
    /// (plane → edge → apex), then the tension cutoff applied SEQUENTIALLY after the MC return
    /// (it only lowers f, so the result stays MC-admissible). Principal axes are kept.
    ///
    /// `eps_p` (–) gains Δε_p = √(2/3 Σ_i (Δε^p_i)²) over the principal plastic strain
    /// increments Δε^p = D⁻¹(σ_trial − σ) (= Σ_j Δλ_j ∂g_j/∂σ on planes and edges), MC and
    /// cutoff flow together. With softening the strength is taken at ε_p,n + Δε_p (implicit),
    /// solved by secant/bisection to |G(Δε_p) − Δε_p| ≤ 1e-12 + 1e-10 Δε_p in at most 50
    /// passes; `eps_p` grows by exactly the Δε_p of the final strength, so the result is
    /// admissible at `strength_at(*eps_p)` (f ≈ 0 there when it yielded in shear).
    pub fn update(&self, stress: &mut [f64; 4], d_eps: [f64; 3], eps_p: &mut f64) -> Outcome {
        self.update_prepared(&self.prepare(), stress, d_eps, eps_p)
    }

    /// The constants [`MohrCoulomb::update_prepared`] needs, computed once per run.
    pub fn prepare(&self) -> Prepared {
        let (lam, g) = lame(self.youngs_modulus_pa, self.poisson_ratio);
        let (sin_phi, cos_phi) = self.friction_deg.to_radians().sin_cos();
        Prepared {
            lam,
            g,
            sin_phi,
            cos_phi,
        }
    }

    /// [`MohrCoulomb::update`] with the constants of [`MohrCoulomb::prepare`] (same result
    /// bits; saves the divisions and the sine of the elastic fast path).
    pub fn update_prepared(
        &self,
        k: &Prepared,
        stress: &mut [f64; 4],
        d_eps: [f64; 3],
        eps_p: &mut f64,
    ) -> Outcome {
        let (lam, g) = (k.lam, k.g);
        let tr = d_eps[0] + d_eps[1];
        // Hooke, plane strain: Δσ = λ tr(Δε) I + 2G Δε, Δεzz = 0.
        stress[0] += lam * tr + 2.0 * g * d_eps[0];
        stress[1] += lam * tr + 2.0 * g * d_eps[1];
        stress[2] += 2.0 * g * d_eps[2];
        stress[3] += lam * tr;

        // Fast path: one square root and one sin_cos show the trial admissible.
        let eps_n = *eps_p;
        let p = principal(stress);
        let t = p.s;
        let peak = self
            .softening
            .is_none_or(|sw| eps_n <= sw.plastic_strain_start);
        let (c, sp, cp) = if peak {
            (self.cohesion_pa, k.sin_phi, k.cos_phi)
        } else {
            let (phi, c) = self.strength_at(eps_n);
            let (sp, cp) = phi.to_radians().sin_cos();
            (c, sp, cp)
        };
        let tol = 1e-12 * (t[0].abs() + t[1].abs() + t[2].abs() + 2.0 * c.abs() * cp);
        // Same Mohr–Coulomb f as `yield_value`.
        let f = (t[0] - t[2]) + (t[0] + t[2]) * sp - 2.0 * c * cp;
        if f <= tol && t[0] <= self.tension_cutoff_pa {
            return Outcome {
                yielded: false,
                iterations: 0,
                region: Region::Elastic,
            };
        }

        let spsi = self.dilation_deg.to_radians().sin();
        let eval = |x: f64| -> (f64, [f64; 3], Region) {
            let (phi, c) = self.strength_at(eps_n + x);
            let (sphi, cphi) = phi.to_radians().sin_cos();
            // Apex c cot φ; with φ = 0 there is none (kept at the trial mean, never reached).
            let apex = if sphi > 1e-12 {
                c * cphi / sphi
            } else {
                (t[0] + t[1] + t[2]) / 3.0
            };
            let sf = Surface {
                sphi,
                spsi,
                k: 2.0 * c * cphi,
                apex,
            };
            let (s, region) = mc_return(t, lam, g, &sf, tol);
            let (s, cut) = tension_cutoff(s, lam, g, self.tension_cutoff_pa, tol);
            let e = d_inv_mul([t[0] - s[0], t[1] - s[1], t[2] - s[2]], lam, g);
            // Δε_p = √(2/3 Σ (Δε^p_i)²) (equivalent plastic strain, as documented above).
            let dep = ((2.0 / 3.0) * dot(e, e)).sqrt();
            (dep, s, if cut { Region::TensionCutoff } else { region })
        };

        let (mut gx, mut s, mut region) = eval(0.0);
        let mut iterations = 1;
        let mut x = gx;
        if matches!(self.softening, Some(sw) if eps_n < sw.plastic_strain_end) {
            // Root of h(x) = G(x) − x, G(x) = Δε_p of a return at strength(ε_p,n + x); h(0) ≥ 0.
            x = 0.0;
            let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
            let (mut x_old, mut h_old) = (f64::NAN, f64::NAN);
            let mut h = gx;
            while iterations < MAX_ITER && h.abs() > 1e-12 + 1e-10 * gx.abs() {
                if h > 0.0 {
                    lo = x;
                } else {
                    hi = x;
                }
                // Secant step kept inside the bracket (else bisection) or, before a bracket
                // exists, ahead of `lo` (else the fixed-point step G(x)).
                let mut xn = if x_old.is_finite() && h != h_old {
                    x - h * (x - x_old) / (h - h_old)
                } else {
                    gx
                };
                if hi.is_finite() {
                    if !(xn > lo && xn < hi) {
                        xn = 0.5 * (lo + hi);
                    }
                } else if !(xn > lo && xn.is_finite()) {
                    xn = gx;
                }
                (x_old, h_old, x) = (x, h, xn);
                (gx, s, region) = eval(x);
                iterations += 1;
                h = gx - x;
            }
        }
        *eps_p = eps_n + x;
        rebuild(&p, s, stress);
        Outcome {
            yielded: region != Region::Elastic,
            iterations,
            region,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use Region::*;

    /// E = 2.5 MPa, ν = 0.25 → λ = G = 1 MPa exactly: D = 1e6 [[3,1,1],[1,3,1],[1,1,3]].
    fn mat(phi: f64, psi: f64, c: f64, st: f64) -> MohrCoulomb {
        MohrCoulomb {
            youngs_modulus_pa: 2.5e6,
            poisson_ratio: 0.25,
            friction_deg: phi,
            dilation_deg: psi,
            cohesion_pa: c,
            tension_cutoff_pa: st,
            softening: None,
        }
    }

    /// c with 2c cos 30° = 10 kPa (c ≈ 5773.5 Pa); the apex c cot 30° is then 10 kPa.
    fn c30() -> f64 {
        5e3 / 30f64.to_radians().cos()
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * a.abs().max(b.abs()).max(1.0)
    }

    /// Update with a zero increment (the given stress is the trial).
    fn ret(m: &MohrCoulomb, trial: [f64; 4], eps_p: f64) -> (Outcome, [f64; 4], f64) {
        let (mut st, mut ep) = (trial, eps_p);
        let o = m.update(&mut st, [0.0; 3], &mut ep);
        (o, st, ep)
    }

    /// Values of `st` on the principal axes of `ax`, in the sorted slots of `ax`.
    fn on_axes(ax: &Principal, st: &[f64; 4]) -> [f64; 3] {
        let (c2, s2) = axes(ax);
        // n·σ·n = m ± ((σxx−σyy)/2 cos 2θ + σxy sin 2θ) on the major/minor in-plane axis.
        let (m, r) = (
            0.5 * (st[0] + st[1]),
            0.5 * (st[0] - st[1]) * c2 + st[2] * s2,
        );
        match ax.zz {
            0 => [st[3], m + r, m - r],
            1 => [m + r, st[3], m - r],
            _ => [m + r, m - r, st[3]],
        }
    }

    #[test]
    fn elastic_increment_is_hooke() {
        // λ = G = 1e6, tr Δε = −1e-5 → λ tr = −10 Pa; Δσxx = −10 + 2e6·1e-5 = 10,
        // Δσyy = −10 − 2e6·2e-5 = −50, Δσxy = 2e6·3e-6 = 6, Δσzz = −10. Far inside the surface.
        let m = mat(30.0, 0.0, 1e6, 1e9);
        let (mut st, mut ep) = ([-1e4, -2e4, 1e3, -1.5e4], 0.25);
        let o = m.update(&mut st, [1e-5, -2e-5, 3e-6], &mut ep);
        assert_eq!((o.yielded, o.iterations, o.region), (false, 0, Elastic));
        let want = [-1e4 + 10.0, -2e4 - 50.0, 1e3 + 6.0, -1.5e4 - 10.0];
        assert!((0..4).all(|i| (st[i] - want[i]).abs() < 1e-9), "{st:?}");
        assert_eq!(ep, 0.25);
    }

    #[test]
    fn plane_return_matches_closed_form() {
        // Trial principal (0, −20e3, −60e3) = (σyy, σzz, σxx); φ = 30°, 2c cos φ = 1e4:
        // f = 60e3 − 30e3 − 1e4 = 20e3, a = (1.5, 0, −0.5).
        // ψ = 30°: b = a, D b = 1e6 (4, 1, 0), a·Db = 6e6, Δλ = 1/300 →
        //   σ = (−40e3/3, −70e3/3, −60e3), Δε_p = Δλ √(2/3 (1.5² + 0.5²)) = √(5/3)/300.
        // ψ = 0: b = (1, 0, −1), D b = 1e6 (2, 0, −2), a·Db = 4e6, Δλ = 5e-3 →
        //   σ = (−10e3, −20e3, −50e3), Δε_p = 5e-3 √(4/3).
        let cases = [
            (
                30.0,
                [-40.0 / 3.0, -70.0 / 3.0, -60.0],
                (5.0f64 / 3.0).sqrt() / 300.0,
            ),
            (0.0, [-10.0, -20.0, -50.0], 5e-3 * (4.0f64 / 3.0).sqrt()),
        ];
        for (psi, want_kpa, dep) in cases {
            let want = want_kpa.map(|v| 1e3 * v);
            let (o, st, ep) = ret(&mat(30.0, psi, c30(), 1e9), [-60e3, 0.0, 0.0, -20e3], 0.0);
            assert_eq!((o.region, o.iterations, o.yielded), (Plane, 1, true));
            let got = [st[1], st[3], st[0]];
            assert!((0..3).all(|i| close(got[i], want[i], 1e-9)), "{got:?}");
            assert!(st[2].abs() < 1e-9 && close(ep, dep, 1e-9), "{ep} vs {dep}");
            assert!(MohrCoulomb::yield_value(&st, 30.0, c30()).abs() < 1e-6 * 6e4);
            // σ_trial − σ is parallel to D ∂g/∂σ: zero cross product.
            let sg = psi.to_radians().sin();
            let b = d_mul([1.0 + sg, 0.0, sg - 1.0], 1e6, 1e6);
            let ds = [-got[0], -20e3 - got[1], -60e3 - got[2]];
            let cr = [
                ds[1] * b[2] - ds[2] * b[1],
                ds[2] * b[0] - ds[0] * b[2],
                ds[0] * b[1] - ds[1] * b[0],
            ];
            assert!(dot(cr, cr).sqrt() <= 1e-9 * (dot(ds, ds) * dot(b, b)).sqrt());
        }
    }

    #[test]
    fn edges_and_apex() {
        // φ = 30°, 2c cos φ = 1e4, apex 1e4 Pa. Hand solutions of [a_i·D b_j] Δλ = f_i:
        // compression, trial (0, −1e3, −60e3), ψ = 30°: A = [[6, 1.5], [1.5, 6]]e6,
        //   f = (20e3, 18.5e3), Δλ = (2.7333e-3, 2.4e-3) → σ1 = σ2 = −40e3/3, σ3 = −60e3;
        //   ψ = 0: A = [[4, 1], [1, 4]]e6, Δλ = (4.1e-3, 3.6e-3) → (−8200, −8200, −44600).
        // extension, trial (0, −59e3, −60e3), ψ = 30°: A = [[6, 5.5], [5.5, 6]]e6,
        //   f = (20e3, 19.5e3), Δλ = (12.75, 7)/5.75 e-3 → σ1 = −316e3/23, σ2 = σ3 = −1408e3/23;
        //   ψ = 0: A = [[4, 3], [3, 4]]e6, Δλ = (21.5, 18)/7 e-3 → (−79e3/7, −377e3/7, −377e3/7).
        // apex: trial (50e3, 49e3, 48e3) fails both edges (σ3 > σ1, resp. σ2 > σ1) → 1e4;
        //   with c = 0 the trial (1e3, 900, 800) goes to 0.
        // Stresses below in kPa.
        let (c, e, x) = (c30(), -377.0 / 7.0, -1408.0 / 23.0);
        let (ec, ee) = (EdgeCompression, EdgeExtension);
        let cases = [
            (
                30.0,
                c,
                [0.0, -1.0, -60.0],
                ec,
                [-40.0 / 3.0, -40.0 / 3.0, -60.0],
            ),
            (0.0, c, [0.0, -1.0, -60.0], ec, [-8.2, -8.2, -44.6]),
            (30.0, c, [0.0, -59.0, -60.0], ee, [-316.0 / 23.0, x, x]),
            (0.0, c, [0.0, -59.0, -60.0], ee, [-79.0 / 7.0, e, e]),
            (30.0, c, [50.0, 49.0, 48.0], Apex, [10.0; 3]),
            (0.0, c, [50.0, 49.0, 48.0], Apex, [10.0; 3]),
            (10.0, c, [50.0, 49.0, 48.0], Apex, [10.0; 3]),
            (30.0, 0.0, [1.0, 0.9, 0.8], Apex, [0.0; 3]),
            (0.0, 0.0, [1.0, 0.9, 0.8], Apex, [0.0; 3]),
        ];
        for (psi, c, t, region, want) in cases {
            let (t, want) = (t.map(|v| 1e3 * v), want.map(|v| 1e3 * v));
            // σxx = σ1, σyy = σ3, σzz = σ2: zz in the middle slot.
            let (o, st, ep) = ret(&mat(30.0, psi, c, 1e9), [t[0], t[2], 0.0, t[1]], 0.0);
            let s = principal(&st).s;
            assert_eq!(o.region, region, "ψ = {psi}, {t:?} → {s:?}");
            assert!(
                (0..3).all(|i| close(s[i], want[i], 1e-9)),
                "{s:?} vs {want:?}"
            );
            assert!(MohrCoulomb::yield_value(&st, 30.0, c) <= 1e-9 * 6e4);
            assert!(s[0] >= s[1] && s[1] >= s[2] && ep > 0.0);
        }
    }

    #[test]
    fn associated_return_is_the_closest_point() {
        // With ψ = φ the return is the projection onto the convex elastic domain in the energy
        // norm ⟨a, b⟩ = a : D⁻¹ : b, so ⟨σ_tr − σ, σ* − σ⟩ ≤ 0 for every admissible σ*; the other
        // results serve as σ*. This checks the whole region logic (plane, both edges, apex).
        let m = mat(35.0, 35.0, 2e4, 1e9);
        let mut seed = 7u64;
        let mut rnd = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let pairs: Vec<_> = (0..300)
            .map(|_| {
                let t = [3e4, 3e4, 0.0, 3e4].map(|v| v + 1e5 * rnd());
                (t, ret(&m, t, 0.0).1)
            })
            .collect();
        let inner = |a: [f64; 4], b: [f64; 4]| {
            dot(d_inv_mul([a[0], a[1], a[3]], 1e6, 1e6), [b[0], b[1], b[3]]) + a[2] * b[2] / 1e6
        };
        for (t, s) in &pairs {
            let r = [0, 1, 2, 3].map(|i| t[i] - s[i]);
            for (_, q) in &pairs {
                let v = inner(r, [0, 1, 2, 3].map(|i| q[i] - s[i]));
                assert!(v <= 1e-9 * 1e-2 * 1e5, "{t:?} → {s:?}: {v}");
            }
        }
    }

    #[test]
    fn rotation_invariance() {
        // The return changes principal values only, so rotating the trial by α and the result
        // back by −α reproduces the unrotated result (to round-off).
        fn rot(s: [f64; 4], a: f64) -> [f64; 4] {
            let (sn, cs) = a.sin_cos();
            let (c2, s2, sc) = (cs * cs, sn * sn, sn * cs);
            [
                c2 * s[0] + s2 * s[1] + 2.0 * sc * s[2],
                s2 * s[0] + c2 * s[1] - 2.0 * sc * s[2],
                sc * (s[1] - s[0]) + (c2 - s2) * s[2],
                s[3],
            ]
        }
        let m = mat(30.0, 5.0, c30(), 5e3);
        for tr in [
            [-60e3, 0.0, 0.0, -20e3],
            [-30e3, -10e3, 25e3, -20e3],
            [-60e3, 0.0, 0.0, -1e3],
            [20e3, -3e3, 4e3, 1e3],
            [50e3, 48e3, 0.0, 49e3],
        ] {
            for a in [0.3, 1.1, -2.0] {
                let ((o0, s0, e0), (o1, s1, e1)) = (ret(&m, tr, 0.0), ret(&m, rot(tr, a), 0.0));
                let back = rot(s1, -a);
                assert!(o0.region == o1.region && close(e0, e1, 1e-9));
                assert!(
                    (0..4).all(|i| (back[i] - s0[i]).abs() < 6e-5),
                    "{back:?} {s0:?}"
                );
            }
        }
    }

    #[test]
    fn tension_cutoff_caps_principal_stresses() {
        // 2c cos 30° = 1e6 (apex 1e6 Pa), σt = 1e4. Uniaxial σxx = 5e4: f = 7.5e4 − 1e6 < 0,
        // only the cutoff acts: Δλ = 4e4/(λ+2G) = 4e4/3e6, σxx = 1e4, σyy = σzz = −λΔλ = −4e4/3.
        let m = mat(30.0, 0.0, 100.0 * c30(), 1e4);
        let (o, st, _) = ret(&m, [5e4, 0.0, 0.0, 0.0], 0.0);
        assert_eq!(o.region, TensionCutoff);
        let want = [1e4, -4e4 / 3.0, 0.0, -4e4 / 3.0];
        assert!((0..4).all(|i| close(st[i], want[i], 1e-12)), "{st:?}");
        // Hydrostatic 5e4 (MC-admissible): all three exceed σt and all come back to σt.
        let (_, st, _) = ret(&m, [5e4, 5e4, 0.0, 5e4], 0.0);
        assert!([0, 1, 3].iter().all(|&i| close(st[i], 1e4, 1e-12)) && st[2] == 0.0);
        // (5e4, 2e4, 0): after the σ1 return σzz = 2e4 − 4e4/3 < σt, so σ1 alone is active.
        let (_, st, _) = ret(&m, [5e4, 0.0, 0.0, 2e4], 0.0);
        assert!(close(st[0], 1e4, 1e-12) && close(st[3], 2e4 - 4e4 / 3.0, 1e-12));
    }

    fn soft_mat() -> MohrCoulomb {
        let mut m = mat(30.0, 0.0, c30(), 1e9);
        m.softening = Some(Softening {
            residual_friction_deg: 20.0,
            residual_cohesion_pa: 0.2 * c30(),
            plastic_strain_start: 0.002,
            plastic_strain_end: 0.01,
        });
        m
    }

    #[test]
    fn softening_interpolates_linearly() {
        // ε_p = 0.004 is a quarter of the way from 0.002 to 0.01: φ = 27.5°, c = 0.8 c0.
        let m = soft_mat();
        assert_eq!(m.strength_at(0.001), (30.0, c30()));
        assert_eq!(m.strength_at(0.02), (20.0, 0.2 * c30()));
        let (phi, c) = m.strength_at(0.004);
        assert!(close(phi, 27.5, 1e-12) && close(c, 0.8 * c30(), 1e-12));
    }

    #[test]
    fn softening_return_is_consistent() {
        // The plane trial of the closed-form test (Δε_p ≈ 5.8e-3 at peak strength), a larger one
        // that passes the end of softening, and an edge trial: the iteration converges, f = 0 at
        // strength_at(ε_p), and ε_p − ε_p,n = √(2/3 |D⁻¹(σ_tr − σ)|²) of the returned stress.
        let m = soft_mat();
        for trial in [
            [-60e3, 0.0, 0.0, -20e3],
            [-200e3, 0.0, 0.0, -50e3],
            [-60e3, -1e3, 0.0, 0.0],
        ] {
            let (o, st, ep) = ret(&m, trial, 0.001);
            assert!(o.yielded && (2..MAX_ITER).contains(&o.iterations), "{o:?}");
            let (phi, c) = m.strength_at(ep);
            assert!(phi < 30.0 && MohrCoulomb::yield_value(&st, phi, c).abs() < 1e-6 * 6e4);
            let (pt, ps) = (principal(&trial).s, principal(&st).s);
            let e = d_inv_mul([0, 1, 2].map(|i| pt[i] - ps[i]), 1e6, 1e6);
            assert!(
                close(ep - 0.001, (2.0 / 3.0 * dot(e, e)).sqrt(), 1e-8),
                "{ep}"
            );
        }
    }

    #[test]
    fn randomized_consistency() {
        // Random materials (φ ≤ 45°, ψ ≤ φ, c ≥ 0, σt below or above the apex, some softening),
        // stresses and increments: every result is finite and admissible (MC and cutoff), ε_p
        // does not decrease, the principal values keep the trial's order on the trial's axes,
        // and every region occurs.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut regions = [0usize; 6];
        for _ in 0..20000 {
            let (phi, c) = (45.0 * rnd(), if rnd() < 0.3 { 0.0 } else { 1e5 * rnd() });
            // σt below the apex c cot φ (acts) or above it (never acts).
            let apex = c / phi.to_radians().tan().max(1e-7);
            let cut = apex * if rnd() < 0.5 { rnd() } else { 2.0 };
            let mut m = mat(phi, phi * rnd(), c, cut);
            (m.youngs_modulus_pa, m.poisson_ratio) = (10f64.powf(6.0 + 3.0 * rnd()), 0.45 * rnd());
            if rnd() < 0.3 {
                m.softening = Some(Softening {
                    residual_friction_deg: phi * rnd(),
                    residual_cohesion_pa: c * rnd(),
                    plastic_strain_start: 0.01 * rnd(),
                    plastic_strain_end: 0.01 + 0.05 * rnd(),
                });
            }
            let s = 10f64.powf(3.0 + 3.0 * rnd());
            let mut st = [0.0; 4].map(|_: f64| s * (2.0 * rnd() - 1.5));
            let de = s / m.youngs_modulus_pa;
            let d = [0.0; 3].map(|_: f64| de * (2.0 * rnd() - 1.0));
            let mut ep = 0.02 * rnd() * rnd().round();
            let ep0 = ep;
            // The trial, for its principal axes and the scale.
            let (lam, g) = lame(m.youngs_modulus_pa, m.poisson_ratio);
            let tr = d[0] + d[1];
            let trial = [
                st[0] + lam * tr + 2.0 * g * d[0],
                st[1] + lam * tr + 2.0 * g * d[1],
                st[2] + 2.0 * g * d[2],
                st[3] + lam * tr,
            ];
            let pt = principal(&trial);
            let scale = pt.s[0].abs() + pt.s[2].abs() + c + 1.0;
            let o = m.update(&mut st, d, &mut ep);
            regions[o.region as usize] += 1;
            let (phi_n, c_n) = m.strength_at(ep);
            assert!(st.iter().all(|v| v.is_finite()), "{m:?} {trial:?} → {st:?}");
            let f = MohrCoulomb::yield_value(&st, phi_n, c_n);
            assert!(f <= 1e-9 * scale, "{m:?} {trial:?}");
            assert!(principal(&st).s[0] <= m.tension_cutoff_pa + 1e-9 * scale);
            assert!(ep >= ep0 && ep.is_finite() && o.iterations <= MAX_ITER);
            let v = on_axes(&pt, &st);
            let tol = 1e-9 * scale;
            assert!(v[0] >= v[1] - tol && v[1] >= v[2] - tol, "{v:?}");
        }
        assert!(regions.iter().all(|&n| n > 0), "{regions:?}");
    }
}
