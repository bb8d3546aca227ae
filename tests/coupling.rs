//! LBM–DEM coupling: the three interface schemes against the fluid core's own obstacle
//! drag, the momentum balance of fluid + grains, a settling disk, and bad input.
//! `cargo test --release --test coupling -- --nocapture` prints every figure.
mod common;
use common::*;
use grainflow::run::Status;

/// A body-force channel (periodic in x, walls south and north), 96 × 48 cells, with a disk
/// of radius 6 cells at its centre: either a fixed obstacle with wall `scheme`
/// ("staircase" or "interpolated") or a grain held in place (`grain = true`) with coupling
/// `scheme`, and two point probes: on the disk's upstream surface, and off the
/// cell centres beside it.
fn channel(grain: bool, scheme: &str) -> String {
    let body = if grain {
        format!(
            r#"
[grains]
density_kg_m3 = 2500.0
gravity_m_s2 = [0.0, 0.0]
[grains.contact]
normal_stiffness_n_m2 = 1.0e5
tangential_stiffness_n_m2 = 0.5e5
restitution = 0.5
friction = 0.3
[grains.sample]
kind = "list"
grains = [{{ position_m = [0.048, 0.024], radius_m = 0.006, fixed = true }}]
[coupling]
scheme = "{scheme}"

[[probes]]
kind = "grain"
name = "disk"
id = 0
"#
        )
    } else {
        format!(
            r#"
[[obstacles]]
name = "disk"
shape = "circle"
centre_m = [0.048, 0.024]
radius_m = 0.006
wall = "{scheme}"

[[probes]]
kind = "force"
name = "disk"
obstacle = "disk"
"#
        )
    };
    format!(
        r#"title = "channel with a disk"
[domain]
cells = [96, 48]
spacing_m = 0.001

[fluid]
density_kg_m3 = 1000.0
viscosity_m2_s = 1.0e-4
reference_velocity_m_s = 0.01
reference_length_m = 0.012
relaxation_time = 0.8
body_acceleration_m_s2 = [0.002, 0.0]

[boundaries]
west = {{ kind = "periodic" }}
east = {{ kind = "periodic" }}
south = {{ kind = "wall" }}
north = {{ kind = "wall" }}

[run]
steps = 3000

[output]
probe_every_steps = 3000

[[probes]]
kind = "point"
name = "surface"
position_m = [0.042, 0.024]

[[probes]]
kind = "point"
name = "beside"
position_m = [0.0463, 0.0313]
{body}"#
    )
}

fn last_force(s: &grainflow::run::Summary) -> [f64; 2] {
    let p = &s.probes["disk"];
    [p["fx_n_per_m"], p["fy_n_per_m"]]
}

#[test]
fn held_grain_feels_the_obstacle_drag() {
    let dir = tempfile::tempdir().unwrap();
    let (staircase, _a) = run_text(&channel(false, "staircase"), dir.path(), None);
    let (curved, _c) = run_text(&channel(false, "interpolated"), dir.path(), None);
    for s in [&staircase, &curved] {
        assert_eq!(s.run.status, Status::Ok, "{:?}", s.run.error);
    }
    let cases = [
        ("bounce-back", &staircase, 1e-6),
        ("interpolated", &curved, 1e-9),
        ("psm", &curved, 0.05),
    ];
    for (scheme, obstacle, limit) in cases {
        let fo = last_force(obstacle);
        let (g, _b) = run_text(&channel(true, scheme), dir.path(), None);
        assert_eq!(g.run.status, Status::Ok, "{scheme}: {:?}", g.run.error);
        let fg = last_force(&g);
        let rel = (fg[0] - fo[0]).abs() / fo[0].abs();
        eprintln!(
            "{scheme}: obstacle drag {fo:?}, grain drag {fg:?} N/m, relative difference \
             {rel:.3e} (limit {limit})"
        );
        // Same cells, same links: a bounce-back grain must give the staircased obstacle's
        // momentum exchange to round-off (the issue asks 1 %), an interpolated one the
        // curved obstacle's. Partially saturated cells see the same disk another way; they
        // must stay within 5 %.
        assert!(rel <= limit, "{scheme}: {rel}");
        assert!(fg[1].abs() < 1e-3 * fo[0].abs(), "{scheme}: lift {}", fg[1]);
        // The same flow, so the probes next to the disk read the same fluid: the cells
        // beside a grain are read from their own values, not through the rest fill under
        // the grain (they lag the obstacle's by the step the pull looks ahead). The
        // surface probe of a curved obstacle reads the wall's extrapolated value instead.
        let probes: &[&str] = match scheme {
            "bounce-back" => &["surface", "beside"],
            "interpolated" => &["beside"],
            _ => &[],
        };
        for &probe in probes {
            let (a, b) = (&obstacle.probes[probe], &g.probes[probe]);
            eprintln!("{probe}: obstacle {a:?}, grain {b:?}");
            let u = a["ux_m_s"].abs();
            assert!((a["ux_m_s"] - b["ux_m_s"]).abs() < 1e-3 * u, "{probe}");
            let p = a["pressure_pa"].abs();
            assert!(
                (a["pressure_pa"] - b["pressure_pa"]).abs() < 1e-3 * p,
                "{probe}"
            );
        }
    }
}

/// A closed periodic box (no walls, no body force, no gravity) with two grains moving
/// through fluid at rest: fluid + grain momentum must stay constant.
fn momentum_box(scheme: &str) -> String {
    format!(
        r#"title = "momentum balance"
[domain]
cells = [64, 64]
spacing_m = 0.001

[fluid]
density_kg_m3 = 1000.0
viscosity_m2_s = 1.0e-4
reference_velocity_m_s = 0.02
reference_length_m = 0.01
relaxation_time = 0.7

[boundaries]
west = {{ kind = "periodic" }}
east = {{ kind = "periodic" }}
south = {{ kind = "periodic" }}
north = {{ kind = "periodic" }}

[grains]
density_kg_m3 = 3000.0
gravity_m_s2 = [0.0, 0.0]
[grains.contact]
normal_stiffness_n_m2 = 1.0e4
tangential_stiffness_n_m2 = 0.5e4
restitution = 0.8
friction = 0.3
[grains.sample]
kind = "list"
grains = [
  {{ position_m = [0.020, 0.030], radius_m = 0.005, velocity_m_s = [0.01, 0.004], angular_velocity_rad_s = 2.0 }},
  {{ position_m = [0.044, 0.034], radius_m = 0.004, velocity_m_s = [-0.006, -0.002] }},
]
[coupling]
scheme = "{scheme}"

[run]
steps = 10000

[[analyses]]
kind = "momentum-balance"
"#
    )
}

#[test]
fn fluid_and_grain_momentum_is_conserved() {
    let dir = tempfile::tempdir().unwrap();
    for scheme in ["bounce-back", "psm"] {
        let (s, _o) = run_text(&momentum_box(scheme), dir.path(), None);
        assert_eq!(s.run.status, Status::Ok, "{scheme}: {:?}", s.run.error);
        let drift = result(&s, "momentum.relative_drift");
        let (gx, fx) = (
            result(&s, "momentum.grains_x_kg_m_s"),
            result(&s, "momentum.fluid_x_kg_m_s"),
        );
        eprintln!(
            "{scheme}: relative momentum drift over 10⁴ steps {drift:.3e}; grains px {gx:.4e}, fluid px {fx:.4e}"
        );
        // The grains hand a real share of their momentum to the fluid, so the balance is
        // tested, not trivially met.
        assert!(
            fx.abs() > 0.1 * (gx + fx).abs(),
            "{scheme}: the fluid barely moved"
        );
        assert!(drift <= 1e-10, "{scheme}: drift {drift}");
    }
}

/// The settling scene of `jobs/settling/` at 8 cells per diameter (CI speed), each scheme:
/// the scene's checks (terminal velocity and C_D within 5 % of Wu & Shu 2009 at Re = 20).
#[test]
fn settling_disk_reaches_the_reference_terminal_velocity() {
    let mut speeds = Vec::new();
    for scheme in ["bounce-back", "interpolated", "psm"] {
        let text = scene_variant(
            "jobs/settling/disk-8.toml",
            &[("scheme = \"psm\"", &format!("scheme = \"{scheme}\""))],
        );
        let (s, _o) = run_text(&text, &root().join("jobs/settling"), None);
        eprintln!("{scheme}:");
        assert_checks_pass(&s);
        let u = result(&s, "disk.settling_velocity_m_s");
        let cd = result(&s, "disk.drag_coefficient");
        let re = result(&s, "disk.reynolds");
        eprintln!("{scheme}: U = {u:.5e} m/s, Re = {re:.2}, C_D = {cd:.3}");
        speeds.push(u);
    }
    let mean = speeds.iter().sum::<f64>() / 3.0;
    for u in &speeds {
        // The three interfaces resolve the same disk: within 3 % of each other.
        assert!((u - mean).abs() < 0.03 * mean, "{speeds:?}");
    }
}

#[test]
fn bad_coupled_scenes_name_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.toml");
    let base = momentum_box("psm");
    let cases: Vec<(String, &str)> = vec![
        (
            base.replace("scheme = \"psm\"", "scheme = \"ibm\""),
            "unknown variant `ibm`",
        ),
        (
            base.replace("density_kg_m3 = 3000.0", "density_kg_m3 = 900.0"),
            "must exceed the fluid's",
        ),
        (
            base.replace("radius_m = 0.004", "radius_m = 0.001"),
            "cells across",
        ),
        (
            base.replace("position_m = [0.044, 0.034]", "position_m = [0.070, 0.034]"),
            "not wholly inside the domain",
        ),
        (
            base.replace("[coupling]\nscheme = \"psm\"\n", ""),
            "add a [coupling] table",
        ),
        (
            {
                let i = base.find("[grains]").unwrap();
                let j = base.find("[run]").unwrap();
                let rest = base[j..].replace("[[analyses]]\nkind = \"momentum-balance\"\n", "");
                format!("{}[coupling]\nscheme = \"psm\"\n{rest}", &base[..i])
            },
            "[coupling] needs grains",
        ),
        (
            base.replace("scheme = \"psm\"", "scheme = \"psm\"\nsubsteps = 0"),
            "substeps",
        ),
        (
            base.replace("restitution = 0.8", "restitution = 0.8\nstiffness = 1"),
            "unknown field `stiffness`",
        ),
    ];
    for (text, needle) in cases {
        std::fs::write(&path, &text).unwrap();
        let e = grainflow::scene::load_any(&path).err();
        let msg = e.map(|e| e.to_string()).unwrap_or_default();
        assert!(msg.contains(needle), "expected `{needle}`, got `{msg}`");
        eprintln!("ok: {msg}");
    }
}

/// The draft-kiss-tumble fall window and terminal velocity are checked when the scene loads.
#[test]
fn bad_dkt_fall_windows_name_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.toml");
    let base = std::fs::read_to_string(root().join("jobs/dkt/dkt-tall.toml")).unwrap();
    let window = "fall_window_s = [7.0, 8.0]\n";
    let terminal = "terminal_velocity_m_s = 1.172e-2";
    assert!(base.contains(window) && base.contains(terminal));
    let (w, t) = ("fall_window_s", "terminal_velocity_m_s");
    let cases: Vec<(String, &str, &str)> = vec![
        (
            base.replace(window, "fall_window_s = [8.0, 7.0]\n"),
            w,
            "fall_window_s must be [from, to] with 0 ≤ from < to",
        ),
        (
            base.replace(window, "fall_window_s = [7.0, 20.0]\n"),
            w,
            "after the run (which ends at 16 s)",
        ),
        (
            base.replace("end_time_s = 16.0", "steps = 1000"),
            w,
            "after the run (which ends at 0.2083",
        ),
        (
            base.replace(window, ""),
            t,
            "terminal_velocity_m_s needs fall_window_s",
        ),
        (
            base.replace(terminal, "terminal_velocity_m_s = -1.0"),
            t,
            "the terminal velocity must be a positive number",
        ),
    ];
    for (text, key, needle) in cases {
        std::fs::write(&path, &text).unwrap();
        let msg = grainflow::scene::load_any(&path)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(msg.contains(needle), "expected `{needle}`, got `{msg}`");
        // The error names the key and its line.
        let at = format!("scene.toml:{}: `{key}`", line_of(&text, key));
        assert!(msg.contains(&at), "expected `{at}`, got `{msg}`");
    }
}

/// 1-based line of the first line of `text` that starts with `key`.
fn line_of(text: &str, key: &str) -> usize {
    1 + text
        .lines()
        .position(|l| l.trim_start().starts_with(key))
        .unwrap_or_else(|| panic!("no line starts with {key}"))
}

#[test]
fn coupled_run_that_blows_up_stops_with_the_step() {
    // A grain thrown at Mach ≈ 0.9 in lattice units, with either kind of surface cell.
    for scheme in ["bounce-back", "psm"] {
        let dir = tempfile::tempdir().unwrap();
        let text = momentum_box(scheme)
            .replace("velocity_m_s = [0.01, 0.004]", "velocity_m_s = [1.5, 0.0]")
            .replace("steps = 10000", "steps = 2000");
        let (s, _o) = run_text(&text, dir.path(), None);
        assert_eq!(s.run.status, Status::Unstable, "{scheme}");
        let e = s.run.error.unwrap();
        eprintln!("{scheme}: {e}");
        assert!(e.contains("unstable at step"), "{e}");
        assert!(e.contains("grain 0"), "{e}");
        // The step that went bad, counted from 1 as the fluid's errors count it; its sweep
        // completed, so the run stopped in (and kept, for diagnosis) that step's state.
        assert_eq!(common::unstable_step(&e), s.run.steps, "{scheme}: {e}");
    }
}

/// Draft, kiss and tumble (`jobs/dkt/dkt.toml`, Glowinski et al. 2001's setup, PSM): the
/// scene's checks (draft, kiss, tumble and separation in order, no overlap).
#[test]
fn two_disks_draft_kiss_and_tumble() {
    let (s, _o) = run_scene(&root().join("jobs/dkt/dkt.toml"), None);
    for q in ["kiss_time", "tumble_time", "separation_time", "min_gap"] {
        eprintln!("dkt.{q} = {:.3}", result(&s, &format!("dkt.{q}")));
    }
    assert_checks_pass(&s);
    // The phases come in order.
    let (kiss, tumble) = (result(&s, "dkt.kiss_time"), result(&s, "dkt.tumble_time"));
    assert!(kiss < tumble && tumble <= result(&s, "dkt.separation_time"));
}

/// After the draft, kiss and tumble, the pair in a channel 24 cm tall (`jobs/dkt/dkt-tall.toml`,
/// cut at 8 s for CI): the leading disk falls within 5 % of one disk alone in the channel
/// (`jobs/dkt/single.toml`, run here), averaged over 7–8 s; the trailing one, in the
/// leader's return flow, is slower (measured −8 %; the job's 16 s run shows it drafting into
/// a second kiss).
#[test]
fn after_the_tumble_the_leader_falls_at_the_lone_disk_speed() {
    let dir = root().join("jobs/dkt");
    let (alone, _o) = run_scene(&dir.join("single.toml"), None);
    assert_checks_pass(&alone);
    let ut = result(&alone, "disk.settling_velocity_m_s");
    let text = scene_variant(
        "jobs/dkt/dkt-tall.toml",
        &[
            ("end_time_s = 16.0", "end_time_s = 8.0"),
            (
                "terminal_velocity_m_s = 1.172e-2",
                &format!("terminal_velocity_m_s = {ut:e}"),
            ),
            (
                "[[checks]]\nquantity = \"dkt.second_kiss_time\"\nmin = 0.0\n",
                "",
            ),
        ],
    );
    let (s, _o) = run_text(&text, &dir, None);
    let (lead, trail) = (
        result(&s, "dkt.leader_fall_deviation"),
        result(&s, "dkt.trailer_fall_deviation"),
    );
    eprintln!("alone U_t = {ut:.5e} m/s; leader {lead:+.4}, trailer {trail:+.4}");
    assert_checks_pass(&s);
    assert!(lead.abs() <= 0.05, "leader {lead}");
    assert!(
        trail < lead,
        "the trailer rides in the leader's return flow: {trail} vs {lead}"
    );
    assert!(result(&s, "dkt.second_kiss_time").is_nan());
}

/// A coupled run writes the grains beside the fluid (grains.h5 + grains.xdmf at the same
/// snapshot times) and draws them into the pictures.
#[test]
fn coupled_output_has_fluid_and_grains() {
    let dir = tempfile::tempdir().unwrap();
    let text = momentum_box("psm").replace(
        "steps = 10000\n",
        "steps = 200\n\n[output]\nevery_steps = 100\n",
    );
    let (s, out) = run_text(&text, dir.path(), None);
    assert_eq!(s.run.status, Status::Ok, "{:?}", s.run.error);
    let d = out.path();
    let g = hdf5::File::open(d.join("grains.h5")).unwrap();
    for step in ["step_00000000", "step_00000100", "step_00000200"] {
        let pos = g.dataset(&format!("{step}/position")).unwrap();
        assert_eq!(pos.shape(), vec![2, 3], "{step}");
        assert!(hdf5::File::open(d.join("fields.h5"))
            .unwrap()
            .dataset(&format!("{step}/velocity"))
            .is_ok());
    }
    let xdmf = std::fs::read_to_string(d.join("grains.xdmf")).unwrap();
    assert!(xdmf.contains("grains.h5:/step_00000200/position"));
    // The speed picture draws the grains over the field as light grey disks outlined in
    // black, at 1024 / 64 = 16 pixels per cell.
    let png = std::fs::read(d.join("pictures/speed_00000200.png")).unwrap();
    let decoder = png::Decoder::new(std::io::Cursor::new(png));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.width, 1024, "the panel is 1024 pixels wide");
    let grey = buf[..info.buffer_size()]
        .chunks(3)
        .filter(|p| p == &[225, 225, 225])
        .count();
    // Disks of radius 5 and 4 cells (80 and 64 pixels), filled inside their one-pixel rim.
    let expected = std::f64::consts::PI * (79.0f64.powi(2) + 63.0f64.powi(2));
    assert!(
        (grey as f64 - expected).abs() < 0.05 * expected,
        "{grey} grey pixels, expected about {expected:.0}"
    );
    // The grains' own picture is beside it, and the series carries no stale frames.
    assert!(d.join("pictures/grains_00000200.png").is_file());
}

/// The coupled step gives the same bits on 1 and 2 threads (forces are summed in a fixed
/// order), for every scheme.
#[test]
fn coupled_results_do_not_depend_on_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    for scheme in ["bounce-back", "interpolated", "psm"] {
        let text = momentum_box(scheme)
            .replace("steps = 10000", "steps = 600\n\n[output]\nprobe_every_steps = 50")
            .replace("[[analyses]]\nkind = \"momentum-balance\"\n", "")
            + "\n[[probes]]\nkind = \"grain\"\nname = \"g0\"\nid = 0\n\n[[probes]]\nkind = \"grain\"\nname = \"g1\"\nid = 1\n";
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let (s, _o) = run_text(&text, dir.path(), None);
                assert_eq!(s.run.status, Status::Ok, "{scheme}: {:?}", s.run.error);
                s.probes
            })
        };
        let (a, b) = (run(1), run(2));
        for (name, row) in &a {
            for (col, v) in row {
                assert_eq!(
                    v.to_bits(),
                    b[name][col].to_bits(),
                    "{scheme}: {name}.{col} differs: {v} vs {}",
                    b[name][col]
                );
            }
        }
        eprintln!(
            "{scheme}: 1 and 2 threads agree bit for bit ({:?})",
            a["g0"]
        );
    }
}

/// `check` warns when the grains may outrun the lattice: the settling disk made of glass
/// under full gravity (ρ_s = 2500 kg/m³, g = 9.81 m/s²) falls at about 0.2 m/s, twenty times
/// the scene's reference velocity and past the lattice's speed of sound; the scene as
/// shipped gives no such warning.
#[test]
fn grains_faster_than_the_lattice_allows_are_warned_of() {
    let path = root().join("jobs/settling/disk-16.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let warned = |t: &str| {
        let s = grainflow::scene::parse(t, &path).unwrap_or_else(|e| panic!("{e}"));
        s.warnings.iter().any(|w| w.contains("grains may reach"))
    };
    assert!(!warned(&text));
    let heavy = text
        .replace("density_kg_m3 = 1500.0", "density_kg_m3 = 2500.0")
        .replace(
            "gravity_m_s2 = [0.0, -0.13317]",
            "gravity_m_s2 = [0.0, -9.81]",
        );
    assert!(warned(&heavy));
}
