//! Hostile input: values that once panicked, aborted, hung or were silently accepted now get
//! a clear error that names the key path, from `check` and from `run` alike, before
//! anything large is allocated.

use std::process::Command;

mod common;

/// `grainflow ARGS` on `scene` text written to a temporary folder (with `extra` files):
/// (exit code, stdout + stderr).
fn grainflow(cmd: &str, scene: &str, files: &[(&str, &[u8])], extra: &[&str]) -> (i32, String) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    for (name, bytes) in files {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    let mut args = vec![cmd.to_string(), path.display().to_string()];
    if cmd == "run" {
        let out = dir.path().join("out");
        args.extend(["--out".into(), out.display().to_string(), "--quiet".into()]);
    }
    args.extend(extra.iter().map(|s| s.to_string()));
    let o = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args(&args)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (o.status.code().unwrap_or(-1), text)
}

/// Both `check` and `run` refuse `scene` with exit 1 and a message holding every needle;
/// neither panics.
fn refused(scene: &str, files: &[(&str, &[u8])], needles: &[&str]) {
    for cmd in ["check", "run"] {
        let (code, text) = grainflow(cmd, scene, files, &[]);
        assert_eq!(code, 1, "{cmd}: expected a refusal, got {code}:\n{text}");
        assert!(!text.contains("panicked"), "{cmd} panicked:\n{text}");
        for n in needles {
            assert!(text.contains(n), "{cmd}: message lacks `{n}`:\n{text}");
        }
    }
}

/// `text` with its first line that starts with `prefix` replaced by `line`.
fn replace_line(text: &str, prefix: &str, line: &str) -> String {
    let old = text
        .lines()
        .find(|l| l.starts_with(prefix))
        .unwrap_or_else(|| panic!("no line `{prefix}…` in the scene"));
    text.replacen(old, line, 1)
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(common::root().join(rel)).unwrap()
}

/// `text` with the first `from` replaced by `to` (which must occur).
fn edit(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "`{from}` not in the scene");
    text.replacen(from, to, 1)
}

const FLUID: &str = "tests/scenes/mpi_channel.toml";
const GRAINS: &str = "tests/scenes/grains_collapse.toml";
const MPM: &str = "tests/scenes/mpm_collapse.toml";

#[test]
fn keys_beside_a_tag_that_takes_none_are_errors_with_their_path() {
    let fluid = read(FLUID);
    let bad = replace_line(
        &fluid,
        "south =",
        "south = { kind = \"wall\", velocity_m_s = [0.1, 0.0] }",
    );
    refused(
        &bad,
        &[],
        &[
            "boundaries.south.velocity_m_s",
            "wall",
            "takes no parameter",
        ],
    );
    let bad = edit(
        &fluid,
        "collision = { model = \"mrt\" }",
        "collision = { model = \"bgk\", magic = 0.2 }",
    );
    refused(&bad, &[], &["fluid.collision.magic"]);
    let mpm = read(MPM);
    let bad = replace_line(
        &mpm,
        "east =",
        "east = { kind = \"roller\", friction = 0.5 }",
    );
    refused(&bad, &[], &["boundaries.east.friction"]);
}

#[test]
fn numbers_that_are_not_finite_are_errors_with_their_path() {
    let grains = read(GRAINS);
    refused(
        &edit(
            &grains,
            "friction = 0.4\n",
            "friction = 0.4\nvelocity_m_s = [nan, 0.0]\n",
        ),
        &[],
        &["grains.walls[0].velocity_m_s[0]", "finite"],
    );
    let fluid = read(FLUID);
    refused(
        &format!("{fluid}\n[[checks]]\nquantity = \"run.mass\"\nexpected = 1.0\ntolerance = inf\n"),
        &[],
        &["checks[0].tolerance", "finite"],
    );
    let mpm = read(MPM);
    refused(
        &edit(&mpm, "spacing_m = ", "spacing_m = -inf\n# was "),
        &[],
        &["domain.spacing_m", "finite"],
    );
}

#[test]
fn sizes_beyond_any_machine_are_refused_before_allocating() {
    let fluid = read(FLUID);
    refused(
        &replace_line(&fluid, "cells =", "cells = [9223372036854775807, 40]"),
        &[],
        &["cells", "more than any machine"],
    );
    let grains = read(GRAINS);
    // A radius of 1e-9 m in the packed rectangle: petabytes of grains.
    let tiny = edit(
        &grains,
        "min_radius_m = 0.46e-3, max_radius_m = 0.69e-3",
        "min_radius_m = 1e-9, max_radius_m = 2e-9",
    );
    refused(&tiny, &[], &["sizes", "grains of these radii"]);
    refused(
        &edit(&grains, "max_m = [0.03, 0.03]", "max_m = [1e300, 0.03]"),
        &[],
        &["max_m", "outside the domain"],
    );
    refused(
        &edit(
            &grains,
            "[grains]\n",
            "[grains]\ngravity_m_s2 = [0.0, -1e300]\n",
        ),
        &[],
        &["gravity_m_s2", "out of range"],
    );
    // 20 000² cells of 3 µm with 36 points each: 1.4e10 points.
    let mpm = read(MPM);
    let huge = replace_line(
        &replace_line(&mpm, "cells =", "cells = [20000, 20000]"),
        "spacing_m =",
        "spacing_m = 3e-6",
    );
    let huge = huge.replace("points_per_cell = 2", "points_per_cell = 6");
    refused(&huge, &[], &["points_per_cell", "material points"]);
}

#[test]
fn runs_that_would_never_end_are_refused_with_the_step_count() {
    // A fluid end time of 1e300 s.
    let fluid = read(FLUID);
    refused(
        &replace_line(&fluid, "steps =", "end_time_s = 1e300"),
        &[],
        &["steps", "--force"],
    );
    // A Young's modulus of 1e300 Pa: the CFL step is 1e-150 s.
    let mpm = read(MPM);
    refused(
        &replace_line(&mpm, "youngs_modulus_pa =", "youngs_modulus_pa = 1e300"),
        &[],
        &["steps", "--force"],
    );
    // A DEM time step of 1e-300 s.
    let grains = read(GRAINS);
    let fixed = edit(
        &grains,
        "[grains.contact]",
        "[grains.time_step]\nkind = \"fixed\"\ntime_step_s = 1e-300\n\n[grains.contact]",
    );
    refused(&fixed, &[], &["steps"]);
    // Four billion DEM sub-steps per fluid step.
    let coupled = read("tests/scenes/submerged_small.toml");
    let bad = edit(
        &coupled,
        "[coupling]\n",
        "[coupling]\nsubsteps = 4294967295\n",
    );
    refused(&bad, &[], &["substeps", "sub-steps"]);
}

#[test]
fn nonsense_values_are_refused() {
    let fluid = read(FLUID);
    refused(
        &format!("{fluid}\n[[checks]]\nquantity = \"run.mass\"\nmin = 2.0\nmax = 1.0\n"),
        &[],
        &["min", "no value passes"],
    );
    refused(
        &format!(
            "{fluid}\n[[checks]]\nquantity = \"run.mass\"\nexpected = 1.0\ntolerance = -1.0\n"
        ),
        &[],
        &["tolerance", "≥ 0"],
    );
    // A uniform start at 1000 m/s: about Mach 2000 on this lattice.
    let bad = edit(
        &fluid,
        "[fluid]\n",
        "[fluid]\ninitial = { kind = \"uniform\", velocity_m_s = [1000.0, 0.0] }\n",
    );
    refused(&bad, &[], &["velocity_m_s", "Mach"]);
    let grains = read(GRAINS);
    let settle =
        "settle = { damping_1_s = 30.0, kinetic_energy_per_grain_j_m = 1e-8, max_steps = 100000 }";
    refused(
        &edit(
            &grains,
            settle,
            &settle.replace(" }", ", trim_above_m = -1.0 }"),
        ),
        &[],
        &["trim_above_m", "keeps no grain"],
    );
    // A fixed DEM step above λ Δt_cr: `check` says so, as `run` would.
    let fixed = edit(
        &grains,
        "[grains.contact]",
        "[grains.time_step]\nkind = \"fixed\"\ntime_step_s = 1e-3\n\n[grains.contact]",
    );
    refused(&fixed, &[], &["time_step_s", "exceeds"]);
}

#[test]
fn a_mask_whose_header_claims_a_huge_image_is_refused_before_decoding() {
    // A PNG header that claims 100 000 × 100 000 pixels, 60-odd bytes long.
    let png = huge_png_header(100_000, 100_000);
    let fluid = read(FLUID);
    let scene = format!(
        "{fluid}\n[[obstacles]]\nshape = \"mask\"\nname = \"mask\"\nimage = \"mask.png\"\n"
    );
    refused(
        &scene,
        &[("mask.png", &png)],
        &["100000×100000", "must match the lattice"],
    );
}

/// A PNG signature, an IHDR for a `w` × `h` grey image and a token IDAT and IEND.
fn huge_png_header(w: u32, h: u32) -> Vec<u8> {
    fn crc(bytes: &[u8]) -> u32 {
        let mut c = 0xffff_ffffu32;
        for &b in bytes {
            c ^= b as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xedb8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
        }
        !c
    }
    fn chunk(out: &mut Vec<u8>, kind: &[u8], data: &[u8]) {
        out.extend((data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend(data);
        out.extend(&body);
        out.extend(crc(&body).to_be_bytes());
    }
    let mut out = vec![0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
    let mut ihdr = Vec::new();
    ihdr.extend(w.to_be_bytes());
    ihdr.extend(h.to_be_bytes());
    ihdr.extend([8, 0, 0, 0, 0]);
    chunk(&mut out, b"IHDR", &ihdr);
    chunk(
        &mut out,
        b"IDAT",
        &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
    );
    chunk(&mut out, b"IEND", &[]);
    out
}

#[test]
fn force_starts_a_run_beyond_the_step_limit_and_sigterm_stops_it() {
    let fluid = read(FLUID);
    let long = replace_line(&fluid, "steps =", "steps = 2000000000");
    let (code, text) = grainflow("run", &long, &[], &[]);
    assert_eq!(code, 1, "{text}");
    assert!(text.contains("2000000000 steps"), "{text}");
    // With --force it starts; SIGTERM then stops it with a checkpoint (exit 4).
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("long.toml");
    std::fs::write(&path, &long).unwrap();
    let out = dir.path().join("out");
    let child = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args([
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--quiet", "--threads", "1", "--force"])
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(600));
    let _ = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status();
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(4), "SIGTERM exits with status 4");
    assert!(out.join("checkpoint.h5").is_file());
    assert_eq!(common::summary(&out)["status"], "interrupted");
}

#[test]
fn damaged_grain_and_mpm_checkpoints_are_refused() {
    for scene in [GRAINS, MPM] {
        let dir = tempfile::tempdir().unwrap();
        let text = read(scene).replace("[output]\n", "[output]\ncheckpoint_at_end = true\n");
        let path = dir.path().join("scene.toml");
        std::fs::write(&path, text).unwrap();
        let out = dir.path().join("out");
        let run = |steps: &str, extra: &[&str]| {
            let mut args = vec![
                "run",
                path.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ];
            args.extend_from_slice(&["--quiet", "--steps", steps]);
            args.extend_from_slice(extra);
            Command::new(env!("CARGO_BIN_EXE_grainflow"))
                .args(&args)
                .output()
                .unwrap()
        };
        assert!(run("20", &[]).status.success(), "{scene}");
        let ck = out.join("checkpoint.h5");
        let mut bytes = std::fs::read(&ck).unwrap();
        let at = bytes.len() * 2 / 3;
        bytes[at] ^= 0x01;
        let bad = dir.path().join("bad.h5");
        std::fs::write(&bad, &bytes).unwrap();
        let o = run("30", &["--restart", bad.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{scene}: {err}");
        assert!(err.contains("contents changed"), "{scene}: {err}");
        // The intact checkpoint still restarts.
        let o = run("30", &["--restart", ck.to_str().unwrap()]);
        assert!(
            o.status.success(),
            "{scene}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}
