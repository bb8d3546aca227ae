//! The unit of every result an analysis reports, for `summary.json`'s `quantity_units`:
//! from the name's unit suffix (`_m_s`, `_pa`, …) or, for the names without one, from the
//! definition of the quantity.

/// Unit suffixes of quantity names and what they stand for, longest first.
const SUFFIXES: [(&str, &str); 14] = [
    ("_kg_m_s", "kg m/s per metre of depth"),
    ("_n_per_m", "N per metre of depth"),
    ("_kg_m3", "kg/m³"),
    ("_rad_s", "rad/s"),
    ("_m2_s", "m²/s"),
    ("_m_s2", "m/s²"),
    ("_kg_m", "kg per metre of depth"),
    ("_j_m", "J per metre of depth"),
    ("_1_s", "1/s"),
    ("_m_s", "m/s"),
    ("_m2", "m²"),
    ("_pa", "Pa"),
    ("_m", "m"),
    ("_s", "s"),
];

/// The unit a quantity name's suffix states (`front_m` → m), if it has one.
pub fn suffix_unit(name: &str) -> Option<&'static str> {
    SUFFIXES
        .iter()
        .find(|(s, _)| name.ends_with(s))
        .map(|(_, u)| *u)
}

/// Words of dimensionless quantities (errors, ratios, coefficients, numbers).
const DIMENSIONLESS: [&str; 14] = [
    "error",
    "deviation",
    "ratio",
    "drift",
    "coefficient",
    "amplitude",
    "strouhal",
    "reynolds",
    "fraction",
    "runout",
    "drag_factor",
    "oscillation",
    "coefficient_min",
    "coefficient_max",
];

/// The unit of result `name` (`prefix.quantity`), `None` when grainflow does not know it
/// (a test keeps every result it produces known).
pub fn result_unit(name: &str) -> Option<&'static str> {
    let q = name.rsplit_once('.').map_or(name, |(_, q)| q);
    let explicit = match (name, q) {
        ("run.mass", _) => Some("lattice mass: Σ ρ/ρ₀ over the fluid cells (cells)"),
        ("run.mass_drift_per_1e4_steps", _) => {
            Some("1 (relative change of run.mass per 10⁴ steps)")
        }
        (_, "stop_time" | "front_t95" | "front_t10") => {
            Some("√(H_i/g), the column's free-fall time")
        }
        (_, "kiss_time" | "tumble_time" | "separation_time" | "second_kiss_time") => {
            Some("√(D/g), D the grain diameter")
        }
        (_, "min_gap") => Some("D, the grain diameter"),
        (_, "final_height") => Some("L_i, the column's initial length"),
        (_, "draft" | "tumbled" | "separated") => Some("1 (0 or 1)"),
        ("coupling.grains", _) => Some("count"),
        ("coupling.substeps", _) => Some("count"),
        _ => None,
    };
    explicit.or_else(|| suffix_unit(q)).or_else(|| {
        DIMENSIONLESS
            .iter()
            .any(|w| q.contains(w))
            .then_some("1 (dimensionless)")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suffixes_and_names_give_units() {
        assert_eq!(
            result_unit("drag.drag_coefficient"),
            Some("1 (dimensionless)")
        );
        assert_eq!(result_unit("disk.settling_velocity_m_s"), Some("m/s"));
        assert_eq!(result_unit("p.pressure_difference_pa"), Some("Pa"));
        assert_eq!(result_unit("collapse.front_m"), Some("m"));
        assert_eq!(result_unit("permeability.permeability_m2"), Some("m²"));
        assert_eq!(
            result_unit("momentum.fluid_x_kg_m_s"),
            Some("kg m/s per metre of depth")
        );
        assert!(result_unit("collapse.stop_time").unwrap().contains("H_i"));
        assert_eq!(result_unit("mystery.value"), None);
    }
}
