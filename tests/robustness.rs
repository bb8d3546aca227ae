//! Coupling robustness: refined partially saturated cells stay stable. The full sweep
//! (every scheme × 8–64 cells per diameter × density ratio × Reynolds number) is
//! `jobs/robustness/sweep.py`; its table is in docs/validation.md.
mod common;
use common::*;
use grainflow::run::Status;

/// A disk of 64 cells per diameter settling from rest at Re ≈ 200 (ρ_s/ρ = 1.5, τ = 0.57,
/// TRT) in a channel 4 d wide, as a user refining the lattice would write it.
fn fine_disk(scheme: &str, model: &str) -> String {
    format!(
        r#"title = "settling disk, 64 cells per diameter"
[domain]
cells = [256, 800]
spacing_m = 3.125e-5
[fluid]
density_kg_m3 = 1000.0
viscosity_m2_s = 1.0e-6
reference_velocity_m_s = 0.125
reference_length_m = 0.002
relaxation_time = 0.57
collision = {{ model = "{model}" }}
[boundaries]
west = {{ kind = "wall" }}
east = {{ kind = "wall" }}
south = {{ kind = "wall" }}
north = {{ kind = "wall" }}
[grains]
density_kg_m3 = 1500.0
gravity_m_s2 = [0.0, -9.81]
[grains.contact]
normal_stiffness_n_m2 = 1.0e5
tangential_stiffness_n_m2 = 0.5e5
restitution = 0.5
friction = 0.3
[grains.sample]
kind = "list"
grains = [{{ position_m = [0.004, 0.021875], radius_m = 0.001 }}]
[coupling]
scheme = "{scheme}"
[run]
steps = 7500
[output]
probe_every_steps = 50
every_steps = 7500
pictures = false
[[probes]]
kind = "grain"
name = "disk"
id = 0
"#
    )
}

/// Before fully covered cells took the solid's equilibrium, the reflected
/// non-equilibrium part inside this disk grew until a cell inside it went negative at step
/// ≈ 6200 (`is_full` in `lbm/src/partial.rs`). Now it falls smoothly: the fluid force on
/// it changes sign nowhere in the last third of the run.
#[test]
fn fine_psm_disk_settles_without_blowing_up() {
    for model in ["trt", "bgk"] {
        let (s, out) = run_text(&fine_disk("psm", model), &root(), None);
        assert_eq!(s.run.status, Status::Ok, "{model}: {:?}", s.run.error);
        let rows = std::fs::read_to_string(out.path().join("probe_disk.csv")).unwrap();
        let fy: Vec<f64> = rows
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(8).unwrap().parse().unwrap())
            .collect();
        let last = &fy[fy.len() * 2 / 3..];
        let (lo, hi) = last
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &f| (a.min(f), b.max(f)));
        println!("{model}: vertical fluid force in the last third {lo:.4e} .. {hi:.4e} N/m");
        // Smooth: positive (drag and buoyancy hold the disk up) and within a factor 2.
        assert!(
            lo > 0.0 && hi < 2.0 * lo,
            "{model}: noisy force {lo} .. {hi}"
        );
    }
}

/// A CI-sized subset of the robustness sweep (`jobs/robustness/sweep.py`): every scheme at 8
/// cells per diameter, the lightest and the heaviest grain, Re_t = 100 and 500. Each run
/// finishes, or `check` refuses it as likely unstable; the script exits 1 when a run blows
/// up after `check` passed it.
#[test]
fn sweep_subset_finishes_or_is_refused() {
    let out = tempfile::tempdir().unwrap();
    let o = std::process::Command::new("python3")
        .arg(root().join("jobs/robustness/sweep.py"))
        .args(["--out", out.path().to_str().unwrap()])
        .args(["--bin", env!("CARGO_BIN_EXE_grainflow")])
        .args(["--threads", "1", "--cells", "8", "--ratios", "1.01,8"])
        .args(["--re", "100,500"])
        .output()
        .expect("python3 runs");
    let text = String::from_utf8_lossy(&o.stdout);
    println!("{text}{}", String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "a run blew up after check passed it");
    let rows = std::fs::read_to_string(out.path().join("results.csv")).unwrap();
    let count = |what: &str| rows.lines().filter(|l| l.contains(what)).count();
    assert_eq!(count(",finished,") + count(",refused,"), 12, "{rows}");
    // The measured failures of bounce-back and interpolated bounce-back at this resolution
    // are refused, and PSM runs every case.
    assert!(count(",refused,") >= 3, "{rows}");
    assert!(rows
        .lines()
        .filter(|l| l.starts_with("psm,"))
        .all(|l| l.contains(",finished,")));
}
