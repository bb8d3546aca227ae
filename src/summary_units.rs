//! `summary.json` states the unit of every number in it: keys with a unit suffix (`_s`,
//! `_m_s`, `_bytes`, …) state their own; the others are listed in `quantity_units`, which
//! [`summary_json`] adds: the results' units from their definitions, and the lattice or
//! count units of the solver's own figures.

use analysis::units::{result_unit, suffix_unit};
use serde::Serialize;
use serde_json::{Map, Value};

/// Units of the summary keys without a unit suffix (a dotted path; `*.` before it: any
/// section's key; `.*` after it: any key of that section).
const KEY_UNITS: [(&str, &str); 38] = [
    ("coupling_counts.*", "count"),
    ("coupling_pass_seconds.*", "s"),
    ("ranks", "count"),
    (
        "messages_per_step",
        "point-to-point messages per step, the busiest rank's",
    ),
    (
        "collectives_per_step",
        "collective calls per step, the busiest rank's",
    ),
    ("threads", "count"),
    ("restarted_from_step", "step number"),
    ("steps", "step number"),
    ("snapshots", "count"),
    ("migrated", "count"),
    ("rebalances", "count"),
    (
        "load_imbalance",
        "1 (the busiest rank's own work over the mean, since the last load-balance check)",
    ),
    ("contacts", "count"),
    ("list_rebuilds", "count"),
    ("grains", "count"),
    ("points", "count"),
    ("settle_steps", "count"),
    ("yielding_points", "count"),
    ("fluid_cells", "count"),
    ("cells", "count per axis"),
    ("partition", "cell columns [first, end) per rank"),
    ("slab_columns", "cell columns (rank boundaries)"),
    (
        "mlups",
        "10⁶ cell updates per second, all ranks (the time loop)",
    ),
    (
        "kernel_mlups",
        "10⁶ cell updates per second, all ranks (collide–stream alone)",
    ),
    ("grain_steps_per_s", "grain updates per second, all ranks"),
    (
        "point_steps_per_s",
        "material-point updates per second, all ranks",
    ),
    ("lambda", "1 (time step over the critical time step)"),
    ("momentum", "kg m/s per metre of depth, [x, y]"),
    ("units.nu_lattice", "Δx²/Δt (lattice viscosity)"),
    ("units.u_lattice", "Δx/Δt (lattice velocity)"),
    ("units.tau", "Δt (relaxation time in steps)"),
    ("units.mach", "1"),
    ("units.reynolds", "1"),
    (
        "*.mass",
        "lattice mass: Σ ρ/ρ₀ over the fluid cells (cells)",
    ),
    ("*.momentum_x", "lattice: Σ ρu_x/ρ₀ (cells Δx/Δt)"),
    ("*.momentum_y", "lattice: Σ ρu_y/ρ₀ (cells Δx/Δt)"),
    ("*.kinetic_energy", "lattice: Σ ½ρ|u|²/ρ₀ (cells (Δx/Δt)²)"),
    ("*.max_speed", "Δx/Δt (lattice)"),
];

/// Sections whose numbers are all in one unit or name it themselves.
const SKIPPED: [&str; 3] = ["scene", "stage_seconds", "stages"];

/// The unit of the number at `path` (dotted keys, no indices) whose key does not state it
/// ([`self_described`]), if known.
fn unit_of(path: &str) -> Option<String> {
    if let Some(result) = path.strip_prefix("results.") {
        return result_unit(result).map(str::to_string);
    }
    KEY_UNITS
        .iter()
        .find(|(k, _)| {
            *k == path
                || k.strip_prefix("*.")
                    .is_some_and(|tail| path.ends_with(&format!(".{tail}")))
                || k.strip_suffix(".*").is_some_and(|head| {
                    path.strip_prefix(head)
                        .is_some_and(|rest| rest.starts_with('.') && !rest[1..].contains('.'))
                })
        })
        .map(|(_, u)| u.to_string())
}

/// Whether the key at `path` states its own unit (a suffix, or bytes).
fn self_described(path: &str) -> bool {
    let last = path.rsplit('.').next().unwrap_or(path);
    suffix_unit(last).is_some()
        || last.ends_with("_bytes")
        || last.ends_with("_bytes_per_step")
        || path.starts_with("probes.")
}

/// Every number's path (dotted, arrays as one entry) under `v`.
fn numbers(v: &Value, path: &str, out: &mut Vec<String>) {
    match v {
        Value::Number(_) => out.push(path.to_string()),
        Value::Array(a) if a.iter().any(|x| x.is_number() || x.is_array()) => {
            out.push(path.to_string())
        }
        Value::Object(m) => {
            for (k, x) in m {
                if path.is_empty() && SKIPPED.contains(&k.as_str()) {
                    continue;
                }
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                numbers(x, &p, out);
            }
        }
        _ => {}
    }
}

/// The numbers of a summary whose unit grainflow cannot name (a test keeps this empty).
pub fn unnamed_units(summary: &Value) -> Vec<String> {
    let mut paths = Vec::new();
    numbers(summary, "", &mut paths);
    paths
        .into_iter()
        .filter(|p| !p.starts_with("quantity_units"))
        .filter(|p| !self_described(p) && unit_of(p).is_none())
        .collect()
}

/// `summary` as pretty JSON with `quantity_units`: the unit of every number whose key does
/// not state it.
pub fn summary_json(summary: &impl Serialize) -> Vec<u8> {
    let mut v = serde_json::to_value(summary).expect("a summary serialises");
    let mut paths = Vec::new();
    numbers(&v, "", &mut paths);
    let units: Map<String, Value> = paths
        .iter()
        .filter(|p| !self_described(p))
        .filter_map(|p| unit_of(p).map(|u| (p.clone(), Value::String(u))))
        .collect();
    if let Value::Object(m) = &mut v {
        m.insert("quantity_units".into(), Value::Object(units));
    }
    serde_json::to_vec_pretty(&v).expect("a summary serialises")
}
