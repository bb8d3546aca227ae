//! SI ↔ lattice units, derived in this one place.
//!
//! Δx is given; Δt follows from exactly one of: a time step, the lattice velocity of the
//! reference velocity, or the relaxation time. Then ν_lb = ν Δt/Δx², τ = 3ν_lb + ½,
//! u_lb = U Δt/Δx, Ma = u_lb/c_s with c_s = 1/√3, Re = U L/ν (Krüger et al. 2017, ch. 7).

use serde::Serialize;

/// Derived lattice parameters of a scene.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Units {
    /// Δx (m).
    pub dx_m: f64,
    /// Δt (s).
    pub dt_s: f64,
    /// ρ₀ (kg/m³).
    pub density_kg_m3: f64,
    /// Lattice viscosity ν Δt/Δx².
    pub nu_lattice: f64,
    /// Relaxation time τ = 3ν_lb + ½.
    pub tau: f64,
    /// Lattice velocity of the reference velocity.
    pub u_lattice: f64,
    /// Mach number u_lb √3.
    pub mach: f64,
    /// Reynolds number U L / ν.
    pub reynolds: f64,
}

impl Units {
    /// Velocity m/s → lattice.
    pub fn velocity_to_lattice(&self, v: f64) -> f64 {
        v * self.dt_s / self.dx_m
    }
    /// Velocity lattice → m/s.
    pub fn velocity_to_si(&self, v: f64) -> f64 {
        v * self.dx_m / self.dt_s
    }
    /// Length m → lattice cells.
    pub fn length_to_lattice(&self, l: f64) -> f64 {
        l / self.dx_m
    }
    /// Acceleration m/s² → lattice force density (ρ₀ = 1).
    pub fn acceleration_to_lattice(&self, a: f64) -> f64 {
        a * self.dt_s * self.dt_s / self.dx_m
    }
    /// Pressure (Pa, relative) → density deviation, p = c_s² δρ in lattice units.
    pub fn pressure_to_drho(&self, p: f64) -> f64 {
        3.0 * p / (self.density_kg_m3 * (self.dx_m / self.dt_s).powi(2))
    }
    /// Density deviation → pressure (Pa, relative to ρ₀ c_s²).
    pub fn drho_to_pressure(&self, drho: f64) -> f64 {
        drho / 3.0 * self.density_kg_m3 * (self.dx_m / self.dt_s).powi(2)
    }
    /// Lattice force (momentum per step of a 2-D lattice) → N per metre of depth:
    /// mass per depth ρΔx², velocity Δx/Δt, per Δt.
    pub fn force_to_si(&self, f: f64) -> f64 {
        f * self.density_kg_m3 * self.dx_m.powi(3) / self.dt_s.powi(2)
    }
    /// Time step count → seconds.
    pub fn time_si(&self, steps: u64) -> f64 {
        steps as f64 * self.dt_s
    }
}

/// Which input fixes Δt.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeStepChoice {
    /// Δt given.
    TimeStep(f64),
    /// u_lb of the reference velocity given.
    LatticeVelocity(f64),
    /// τ given.
    RelaxationTime(f64),
}

/// The lattice's speed of sound c_s = 1/√3 (lattice units): a fluid cell or a grain at or
/// past it makes a run meaningless.
pub const SOUND_SPEED: f64 = 0.577_350_269_189_625_8;

/// Derive all lattice parameters. Preconditions (checked by validation): positive Δx, ν,
/// ρ₀, U, L, and a positive choice.
pub fn derive(
    dx: f64,
    density: f64,
    nu: f64,
    u_ref: f64,
    l_ref: f64,
    choice: TimeStepChoice,
) -> Units {
    let dt = match choice {
        TimeStepChoice::TimeStep(dt) => dt,
        TimeStepChoice::LatticeVelocity(u) => u * dx / u_ref,
        // τ = 3ν Δt/Δx² + ½  ⇒  Δt = (τ − ½) Δx² / (3ν).
        TimeStepChoice::RelaxationTime(tau) => (tau - 0.5) * dx * dx / (3.0 * nu),
    };
    let nu_lattice = nu * dt / (dx * dx);
    let u_lattice = u_ref * dt / dx;
    Units {
        dx_m: dx,
        dt_s: dt,
        density_kg_m3: density,
        nu_lattice,
        tau: 3.0 * nu_lattice + 0.5,
        u_lattice,
        mach: u_lattice * 3f64.sqrt(),
        reynolds: u_ref * l_ref / nu,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_choices_agree() {
        let a = derive(
            0.01,
            1000.0,
            1e-6,
            0.1,
            1.0,
            TimeStepChoice::TimeStep(0.005),
        );
        let b = derive(
            0.01,
            1000.0,
            1e-6,
            0.1,
            1.0,
            TimeStepChoice::LatticeVelocity(a.u_lattice),
        );
        let c = derive(
            0.01,
            1000.0,
            1e-6,
            0.1,
            1.0,
            TimeStepChoice::RelaxationTime(a.tau),
        );
        for u in [b, c] {
            assert!((u.dt_s - a.dt_s).abs() < 1e-15);
            assert!((u.tau - a.tau).abs() < 1e-12);
        }
        assert!((a.reynolds - 1e5).abs() < 1e-6);
        assert!((a.mach - 0.05 * 3f64.sqrt()).abs() < 1e-12);
        let p = 12.5;
        assert!((a.drho_to_pressure(a.pressure_to_drho(p)) - p).abs() < 1e-12);
    }
}
