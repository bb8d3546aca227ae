//! Outputs a reader can open without the scene file: every XDMF sidecar (fluid, grains, MPM)
//! points at HDF5 datasets that exist with the declared shape and a component count that
//! matches the attribute type ParaView reads (Scalar 1, Vector 3, Tensor 9); the snapshot
//! attributes have one type in every file; pictures carry a legend; a run that reuses a
//! folder leaves no stale picture; the end-of-run listing names every file written.

mod common;
use common::*;
use std::path::Path;

/// Every `<DataItem … Format="HDF">file:/path</DataItem>` of `xdmf` with its Dimensions
/// and the AttributeType of the attribute it belongs to ("Geometry" for geometry).
fn hdf_items(xdmf: &str) -> Vec<(String, Vec<usize>, String)> {
    let mut items = Vec::new();
    let mut kind = String::from("Geometry");
    for line in xdmf.lines() {
        if let Some(at) = line.find("AttributeType=\"") {
            let rest = &line[at + 15..];
            kind = rest[..rest.find('"').unwrap()].to_string();
        }
        if line.contains("<Geometry") {
            kind = "Geometry".into();
        }
        if !line.contains("Format=\"HDF\"") {
            continue;
        }
        let dims_at = line.find("Dimensions=\"").unwrap() + 12;
        let dims: Vec<usize> = line[dims_at..dims_at + line[dims_at..].find('"').unwrap()]
            .split_whitespace()
            .map(|d| d.parse().unwrap())
            .collect();
        let open = line.find('>').unwrap() + 1;
        let close = line.rfind("</DataItem>").unwrap();
        items.push((line[open..close].to_string(), dims, kind.clone()));
    }
    items
}

/// Every HDF item of `dir/name` resolves to a dataset of its declared shape whose last
/// dimension fits its attribute type; returns how many were checked.
fn assert_xdmf_resolves(dir: &Path, name: &str) -> usize {
    let xdmf = std::fs::read_to_string(dir.join(name)).unwrap();
    assert!(xdmf.starts_with("<?xml") && xdmf.trim_end().ends_with("</Xdmf>"));
    let items = hdf_items(&xdmf);
    assert!(!items.is_empty(), "{name}: no HDF data items");
    for (target, dims, kind) in &items {
        let (file, path) = target.split_once(":/").unwrap();
        let f = hdf5::File::open(dir.join(file)).unwrap();
        let ds = f
            .dataset(path)
            .unwrap_or_else(|e| panic!("{name}: {target}: {e}"));
        let shape = ds.shape();
        let flat = |s: &[usize]| s.iter().product::<usize>();
        assert_eq!(
            flat(&shape),
            flat(dims),
            "{name}: {target} {shape:?} vs {dims:?}"
        );
        let comps = match kind.as_str() {
            "Vector" => Some(3),
            "Tensor" => Some(9),
            "Scalar" => None,
            "Geometry" => Some(3),
            other => panic!("{name}: {target}: attribute type {other}"),
        };
        if let Some(c) = comps {
            assert_eq!(dims.last(), Some(&c), "{name}: {target} is a {kind}");
        }
    }
    items.len()
}

/// The `step` attribute of every snapshot group of `file` is an unsigned integer and
/// `time_s` a float.
fn assert_attribute_types(file: &Path) {
    let f = hdf5::File::open(file).unwrap();
    for g in f.member_names().unwrap() {
        let grp = f.group(&g).unwrap();
        let step = grp.attr("step").unwrap();
        assert_eq!(
            step.dtype().unwrap().to_descriptor().unwrap(),
            hdf5::types::TypeDescriptor::Unsigned(hdf5::types::IntSize::U8),
            "{}: {g}/step",
            file.display()
        );
        let _: u64 = step.read_scalar().unwrap();
        let _: f64 = grp.attr("time_s").unwrap().read_scalar().unwrap();
    }
}

/// Every number in `dir/summary.json` has a unit: its key's suffix or `quantity_units`.
fn assert_units_named(dir: &Path) {
    let s = summary(dir);
    let unnamed = grainflow::summary_units::unnamed_units(&s);
    assert!(
        unnamed.is_empty(),
        "{}: numbers without a unit: {unnamed:?}",
        dir.display()
    );
    assert!(s["quantity_units"].is_object());
    // Counts are integers.
    for key in ["steps", "ranks", "threads", "snapshots"] {
        if !s[key].is_null() {
            assert!(s[key].is_u64(), "{key} = {}", s[key]);
        }
    }
}

/// Width and height of a PNG.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    let d = png::Decoder::new(std::io::Cursor::new(bytes));
    let r = d.read_info().unwrap();
    let i = r.info();
    (i.width, i.height)
}

/// The PNGs in `dir/pictures`, sorted.
fn pictures(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir.join("pictures"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".png"))
        .collect();
    v.sort();
    v
}

/// `grainflow run` (1 rank) with its stdout.
fn run(scene: &str, out: &Path, extra: &[&str]) -> String {
    let mut args = vec!["run", scene, "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = grainflow(1, &args);
    assert!(o.status.success(), "{scene}: {:?}", o.status);
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn fluid_outputs_open_in_paraview_and_pictures_explain_themselves() {
    let tmp = tempfile::tempdir().unwrap();
    // The rank tests' channel with a cylinder, drawn.
    let text = std::fs::read_to_string(root().join("tests/scenes/mpi_channel.toml"))
        .unwrap()
        .replace("pictures = false\n", "");
    let first = tmp.path().join("channel.toml");
    std::fs::write(&first, &text).unwrap();
    let out = tmp.path().join("out");
    let stdout = run(first.to_str().unwrap(), &out, &[]);
    assert!(assert_xdmf_resolves(&out, "fields.xdmf") >= 4 * 4);
    assert_attribute_types(&out.join("fields.h5"));
    let f = hdf5::File::open(out.join("fields.h5")).unwrap();
    let p = f.dataset("step_00000300/pressure").unwrap();
    let units: hdf5::types::VarLenUnicode = p.attr("units").unwrap().read_scalar().unwrap();
    assert_eq!(units.as_str(), "Pa");
    // The pressure is c_s² (ρ − ρ₀) in Pa: it agrees with the density dataset.
    let (rho, pa): (Vec<f64>, Vec<f64>) = (
        f.dataset("step_00000300/density")
            .unwrap()
            .read_raw()
            .unwrap(),
        p.read_raw().unwrap(),
    );
    let summary = summary(&out);
    let c2 = summary["units"]["dx_m"].as_f64().unwrap().powi(2)
        / summary["units"]["dt_s"].as_f64().unwrap().powi(2)
        / 3.0;
    for (r, p) in rho.iter().zip(&pa) {
        assert!(
            (p - c2 * (r - 1000.0)).abs() <= 1e-9 * c2 * 1000.0,
            "{p} vs ρ {r}"
        );
    }
    // Closed before the run below writes the file again (HDF5 locks open files).
    drop((p, f));
    // Pictures: the panel (1024 pixels along the longer side) above a legend, even sides.
    let pics = pictures(&out);
    assert_eq!(pics.len(), 2 * 4, "{pics:?}");
    let (w, h) = png_size(&out.join("pictures").join(&pics[0]));
    assert_eq!(w, 1024);
    assert!(h > (1024 * 42 / 120) as u32 + 40 && h % 2 == 0, "{w} × {h}");
    // The listing names every file written.
    for name in [
        "summary.json",
        "fields.h5",
        "fields.xdmf",
        "probe_drag.csv",
        "checkpoint.h5",
    ] {
        assert!(stdout.contains(name), "the listing lacks {name}:\n{stdout}");
    }
    assert!(stdout.contains("pictures/ (8 PNG)"), "{stdout}");
    assert_units_named(&out);
    // Run again into the same folder with fewer snapshots: no stale picture stays, and the
    // scene's picture options apply.
    let text = text
        .replace(
            "[output]\n",
            "[output]\npicture_field = \"pressure\"\npicture_size_px = 240\npicture_limits = { pressure_pa = 2.0 }\n",
        )
        .replace("every_steps = 100", "every_steps = 300");
    let again = tmp.path().join("again.toml");
    std::fs::write(&again, text).unwrap();
    run(again.to_str().unwrap(), &out, &[]);
    assert_eq!(
        pictures(&out),
        ["pressure_00000000.png", "pressure_00000300.png"],
        "stale pictures were left"
    );
    let (w, _) = png_size(&out.join("pictures/pressure_00000300.png"));
    assert_eq!(w, 640, "a 240-pixel panel in the narrowest legend");
}

#[test]
fn grain_and_mpm_outputs_open_in_paraview() {
    let tmp = tempfile::tempdir().unwrap();
    let grains = tmp.path().join("grains");
    run(
        root()
            .join("tests/scenes/grains_collapse.toml")
            .to_str()
            .unwrap(),
        &grains,
        &["--end-time", "0.08"],
    );
    assert!(assert_xdmf_resolves(&grains, "grains.xdmf") >= 3);
    assert_attribute_types(&grains.join("grains.h5"));
    assert!(pictures(&grains).len() >= 2);
    assert_units_named(&grains);
    let mpm = tmp.path().join("mpm");
    run(
        root()
            .join("tests/scenes/mpm_collapse.toml")
            .to_str()
            .unwrap(),
        &mpm,
        &["--end-time", "0.08"],
    );
    let n = assert_xdmf_resolves(&mpm, "mpm.xdmf");
    assert!(n >= 3);
    let xdmf = std::fs::read_to_string(mpm.join("mpm.xdmf")).unwrap();
    assert!(xdmf.contains("Name=\"stress\" AttributeType=\"Tensor\""));
    assert_attribute_types(&mpm.join("mpm.h5"));
    assert_units_named(&mpm);
    // A coupled run (the settling disk, a few steps).
    let coupled = tmp.path().join("coupled");
    run(
        root().join("jobs/settling/disk-8.toml").to_str().unwrap(),
        &coupled,
        &["--steps", "20"],
    );
    assert_units_named(&coupled);
    let (w, h) = png_size(&mpm.join("pictures").join(&pictures(&mpm)[0]));
    assert!(w >= 640 && w % 2 == 0 && h % 2 == 0);
    // With ffmpeg on the PATH (scripts/setup.sh installs it), the series becomes a movie.
    let ffmpeg = std::process::Command::new("ffmpeg")
        .arg("-version")
        .output()
        .is_ok_and(|o| o.status.success());
    if ffmpeg {
        let movie = mpm.join("pictures/mpm_step.mp4");
        assert!(
            std::fs::metadata(&movie).is_ok_and(|m| m.len() > 1000),
            "no movie at {}",
            movie.display()
        );
    } else {
        eprintln!("ffmpeg is not on the PATH: the movie is not tested");
    }
}
