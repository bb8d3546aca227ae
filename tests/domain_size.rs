//! A fluid domain given by its size (`[domain] size_m`) when `[fluid]` fixes the relaxation
//! time and the lattice velocity together: the spacing follows from Δx = ν u_lb / (U ν_lb),
//! the cells from the size; τ is kept exact, and every inconsistent combination is an error
//! that names its key.
use grainflow::scene::{parse, SceneError};
use std::path::Path;

/// A lid-driven cavity: ν = 10⁻⁶ m²/s, U = 0.01 m/s, with `domain` and `time` spliced in.
fn cavity(domain: &str, time: &str) -> String {
    format!(
        r#"title = "cavity by size"
[domain]
{domain}
[fluid]
density_kg_m3 = 1000.0
viscosity_m2_s = 1.0e-6
reference_velocity_m_s = 0.01
reference_length_m = 0.1
{time}
[boundaries]
west = {{ kind = "wall" }}
east = {{ kind = "wall" }}
south = {{ kind = "wall" }}
north = {{ kind = "moving-wall", velocity_m_s = [0.01, 0.0] }}
[run]
steps = 10
"#
    )
}

fn error(text: &str) -> String {
    match parse(text, Path::new("s.toml")) {
        Err(e @ SceneError::Invalid { .. }) => e.to_string(),
        Err(e) => panic!("expected a validation error, got {e}"),
        Ok(_) => panic!("expected an error for\n{text}"),
    }
}

#[test]
fn tau_and_lattice_velocity_fix_the_spacing() {
    let both = "relaxation_time = 0.53\nlattice_velocity = 0.05";
    let s = parse(&cavity("size_m = [0.1, 0.1]", both), Path::new("s.toml")).unwrap();
    // ν_lb = 0.01, Δx = 1e-6 · 0.05 / (0.01 · 0.01) = 5e-4 m: 200 cells.
    assert_eq!(s.scene.domain.cells, [200, 200]);
    assert!((s.scene.domain.spacing_m - 5e-4).abs() < 1e-15);
    assert!((s.units.tau - 0.53).abs() < 1e-12, "τ {}", s.units.tau);
    assert!((s.units.u_lattice - 0.05).abs() < 1e-12);
    assert!((s.units.dt_s - 2.5e-3).abs() < 1e-15, "Δt {}", s.units.dt_s);
    // The same units as the scene written with the cells and τ.
    let by_cells = parse(
        &cavity(
            "cells = [200, 200]\nspacing_m = 0.0005",
            "relaxation_time = 0.53",
        ),
        Path::new("s.toml"),
    )
    .unwrap();
    assert_eq!(s.units.tau.to_bits(), by_cells.units.tau.to_bits());
    assert_eq!(s.units.dt_s.to_bits(), by_cells.units.dt_s.to_bits());
    // A width that is not a whole number of cells: τ kept, u_lb moves, and the warnings say so.
    let s = parse(
        &cavity("size_m = [0.1003, 0.05]", both),
        Path::new("s.toml"),
    )
    .unwrap();
    assert_eq!(s.scene.domain.cells, [201, 100]);
    assert!((s.units.tau - 0.53).abs() < 1e-12);
    assert!((s.units.u_lattice - 0.05 * 0.1003 / 201.0 / 5e-4).abs() < 1e-12);
    let w = s.warnings.join("\n");
    assert!(w.contains("201 × 100 cells"), "{w}");
    assert!(w.contains("lattice_velocity is 0.049"), "{w}");
    assert!(w.contains("the height is 100 cells"), "{w}");
}

#[test]
fn inconsistent_domains_name_their_key() {
    let both = "relaxation_time = 0.53\nlattice_velocity = 0.05";
    for (domain, time, needles) in [
        // τ and u_lb with cells and spacing: over-determined.
        (
            "cells = [64, 64]\nspacing_m = 0.001",
            both,
            &["found 2", "size_m"][..],
        ),
        // size_m with only one of them.
        (
            "size_m = [0.1, 0.1]",
            "relaxation_time = 0.53",
            &["`size_m`", "relaxation_time and lattice_velocity"],
        ),
        // size_m beside cells.
        (
            "size_m = [0.1, 0.1]\ncells = [64, 64]",
            both,
            &["`size_m`", "not both"],
        ),
        // Neither.
        ("", both, &["`domain`", "size_m"]),
        // A size that holds less than two cells.
        (
            "size_m = [0.0005, 0.1]",
            both,
            &["`size_m`", "at least 2 × 2"],
        ),
        // Or more than any machine.
        (
            "size_m = [1.0e6, 1.0e6]",
            both,
            &["`size_m`", "more than any machine"],
        ),
        ("size_m = [-0.1, 0.1]", both, &["`size_m`", "positive"]),
    ] {
        let e = error(&cavity(domain, time));
        for n in needles {
            assert!(e.contains(n), "expected `{n}` in: {e}");
        }
    }
}
