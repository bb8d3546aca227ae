//! What a run writes: HDF5 snapshots readable with their attributes, an XDMF sidecar that
//! points at them, probe CSVs and a summary.json with derived parameters and checks.
mod common;
use common::*;

#[test]
fn snapshots_probes_and_summary() {
    let text = scene_variant(
        "jobs/obstacle/scene.toml",
        &[
            ("end_time_s = 150.0", "end_time_s = 8.0"),
            ("every_steps = 3000", "every_steps = 400"),
            ("min = 0.04", "min = 0.0"),
        ],
    );
    let (s, d) = run_text(&text, &root().join("jobs/obstacle"), None);
    assert_checks_pass(&s);
    let dir = d.path();
    let f = hdf5::File::open(dir.join("fields.h5")).unwrap();
    let groups = f.member_names().unwrap();
    assert_eq!(
        groups,
        [
            "step_00000000",
            "step_00000400",
            "step_00000800",
            "step_00001000"
        ],
        "{groups:?}"
    );
    let rho = f.dataset("step_00001000/density").unwrap();
    assert_eq!(rho.shape(), [100, 250]);
    let vals: Vec<f64> = rho.read_raw().unwrap();
    // Weakly compressible: the viscous pressure drop (τ = 2, Re = 10) raises the inlet
    // density by about 4 %. The one cell where the uniform inlet meets the no-slip floor is
    // a velocity discontinuity (a true corner singularity) and spikes higher.
    let mut dev: Vec<f64> = vals.iter().map(|v| (v - 1000.0).abs() / 1000.0).collect();
    let corner = dev[0];
    dev.sort_by(f64::total_cmp);
    let (median, p99) = (dev[dev.len() / 2], dev[dev.len() * 99 / 100]);
    assert!(
        median < 0.03 && p99 < 0.06 && corner < 0.2,
        "median {median} p99 {p99} corner {corner}"
    );
    let vel = f.dataset("step_00001000/velocity").unwrap();
    assert_eq!(vel.shape(), [100, 250, 3]);
    let units: hdf5::types::VarLenUnicode = vel.attr("units").unwrap().read_scalar().unwrap();
    assert_eq!(units.as_str(), "m/s");
    let t: f64 = vel.attr("time_s").unwrap().read_scalar().unwrap();
    assert!((t - 8.0).abs() < 1e-9);
    let xdmf = std::fs::read_to_string(dir.join("fields.xdmf")).unwrap();
    assert!(xdmf.contains("fields.h5:/step_00001000/vorticity") && xdmf.contains("2DCoRectMesh"));
    let csv = std::fs::read_to_string(dir.join("probe_gap.csv")).unwrap();
    assert!(csv.starts_with("step,time_s,ux_m_s,uy_m_s,pressure_pa\n"));
    assert_eq!(csv.lines().count(), 1 + 1 + 1000);
    let load = std::fs::read_to_string(dir.join("probe_load.csv")).unwrap();
    assert!(load.starts_with("step,time_s,fx_n_per_m,fy_n_per_m"));
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    for key in [
        "units",
        "mlups",
        "stage_seconds",
        "checks",
        "results",
        "totals_final",
        "scene",
        "probes",
        "stages",
        "ranks",
        "partition",
        "halo_bytes_per_step",
    ] {
        assert!(!j[key].is_null(), "summary.json lacks {key}");
    }
    assert!(j["units"]["tau"].as_f64().unwrap() > 0.5);
    let stages = j["stages"].as_object().unwrap();
    assert_eq!(
        stages.len(),
        grainflow::simulation::STAGES.len() + grainflow::time_loop::LOOP_STAGES.len()
    );
    for (name, st) in stages {
        let (min, mean, max) = (
            st["min_s"].as_f64().unwrap(),
            st["mean_s"].as_f64().unwrap(),
            st["max_s"].as_f64().unwrap(),
        );
        assert!(min <= mean && mean <= max, "{name}: {st}");
    }
    assert_eq!(j["ranks"], 1);
    assert_eq!(j["halo_bytes_per_step"], 0, "one rank exchanges nothing");
}
