//! Flows with solid obstacles and open boundaries: lid-driven cavity (Ghia et al. 1982),
//! Schäfer–Turek 2D-1, Kármán vortex street, rectangular obstacle.
mod common;
use common::*;

/// Re = 100: centreline velocities within 0.02 U of Ghia, Ghia & Shin (1982).
#[test]
fn cavity_re100() {
    let (s, _d) = run_scene(&root().join("jobs/cavity/re100.toml"), None);
    assert_checks_pass(&s);
}

/// Re = 1000: within 0.03 U.
#[test]
fn cavity_re1000() {
    let (s, _d) = run_scene(&root().join("jobs/cavity/re1000.toml"), None);
    assert_checks_pass(&s);
}

/// Schäfer & Turek (1996) 2D-1: c_D within 5 % of 5.58 (staircase cylinder, D = 20 cells).
#[test]
fn cylinder_drag() {
    let (s, _d) = run_scene(&root().join("jobs/cylinder/scene.toml"), None);
    assert_checks_pass(&s);
    let cd = result(&s, "drag.drag_coefficient");
    eprintln!(
        "c_D = {cd:.4} ({:+.2} % from 5.58), c_L = {:.5}",
        100.0 * (cd / 5.58 - 1.0),
        result(&s, "drag.lift_coefficient")
    );
}

/// Vortex shedding appears at Re 112 and not at Re 55; Strouhal numbers are reported.
#[test]
fn karman_street_onset() {
    let (s55, _a) = run_scene(&root().join("jobs/karman/re055.toml"), None);
    assert_checks_pass(&s55);
    let (s112, _b) = run_scene(&root().join("jobs/karman/re112.toml"), None);
    assert_checks_pass(&s112);
    let (o55, o112) = (
        result(&s55, "wake.relative_oscillation"),
        result(&s112, "wake.relative_oscillation"),
    );
    assert!(o112 > 10.0 * o55, "shedding contrast {o112} vs {o55}");
    eprintln!(
        "St(Re 112) = {:.4}",
        result(&s112, "wake_pressure.strouhal")
    );
}

/// The seed study's channel with a wall of height H/2 at L/4 runs and accelerates the flow
/// through the gap.
#[test]
fn rectangular_obstacle() {
    let (s, d) = run_scene(&root().join("jobs/obstacle/scene.toml"), None);
    assert_checks_pass(&s);
    assert!(d.path().join("pictures/speed_00018750.png").is_file());
}
