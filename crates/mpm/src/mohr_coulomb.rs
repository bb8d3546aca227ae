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

use super::inertial::InertialFriction;

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
    /// Optional rate dependence of φ: the μ(I) law, with `friction_deg` as the static
    /// friction (applied by [`crate::Material::update`]; not combined with softening).
    pub inertial_friction: Option<InertialFriction>,
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
    /// sin ψ (the dilation angle does not soften).
    pub sin_psi: f64,
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
    /// A cohesionless, non-dilatant material: Young's modulus `youngs_modulus_pa` (Pa),
    /// Poisson's ratio `poisson_ratio` (–) and friction angle `friction_deg` (deg); ψ = 0,
    /// c = 0, tension cutoff 0, no softening, no μ(I). Override fields with struct update
    /// syntax for anything else.
    pub fn cohesionless(youngs_modulus_pa: f64, poisson_ratio: f64, friction_deg: f64) -> Self {
        MohrCoulomb {
            youngs_modulus_pa,
            poisson_ratio,
            friction_deg,
            dilation_deg: 0.0,
            cohesion_pa: 0.0,
            tension_cutoff_pa: 0.0,
            softening: None,
            inertial_friction: None,
        }
    }

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
            sin_psi: self.dilation_deg.to_radians().sin(),
        }
    }

    /// [`MohrCoulomb::update`] with the constants of [`MohrCoulomb::prepare`] (same result
    /// bits; saves the divisions and the sines of every update without softening). Without
    /// softening the friction is `k`'s sin φ, cos φ alone (`friction_deg` is not read), so a
    /// caller may pass another φ there (μ(I) does).
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

        let spsi = k.sin_psi;
        let eval = |x: f64| -> (f64, [f64; 3], Region) {
            // Without softening the strength is the prepared peak (no sine per return).
            let (sphi, cphi, c) = if self.softening.is_none() {
                (k.sin_phi, k.cos_phi, self.cohesion_pa)
            } else {
                let (phi, c) = self.strength_at(eps_n + x);
                let (sphi, cphi) = phi.to_radians().sin_cos();
                (sphi, cphi, c)
            };
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
#[path = "mohr_coulomb_tests.rs"]
mod tests;
