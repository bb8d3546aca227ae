//! Boundary conditions that the validation flows do not exercise, checked against exact
//! solutions: free slip, Zou–He corners between two open faces, zero-gradient outflow, and
//! obstacles from a PNG mask.
mod common;
use common::*;
use grainflow::run::Precision;

fn scene(boundaries: &str, extra: &str, initial: &str) -> String {
    format!(
        r#"[domain]
cells = [24, 16]
spacing_m = 0.01
[fluid]
density_kg_m3 = 1.0
viscosity_m2_s = 1.0e-4
reference_velocity_m_s = 0.02
reference_length_m = 0.16
lattice_velocity = 0.05
collision = {{ model = "trt" }}
initial = {initial}
[boundaries]
{boundaries}
[run]
steps = 400
[output]
pictures = false
{extra}"#
    )
}

/// Largest deviation (lattice units) of the final velocity from `u`.
fn max_deviation(text: &str, u: [f64; 2]) -> f64 {
    let dir = tempfile::tempdir().unwrap();
    let (s, out) = run_text(text, dir.path(), Some(Precision::F64));
    assert_eq!(
        s.run.status,
        grainflow::run::Status::Ok,
        "{:?}",
        s.run.error
    );
    let f = hdf5::File::open(out.path().join("fields.h5")).unwrap();
    let v: Vec<f64> = f
        .dataset("step_00000400/velocity")
        .unwrap()
        .read_raw()
        .unwrap();
    // Three components per cell (u_x, u_y, 0).
    v.chunks(3)
        .map(|c| (c[0] - u[0]).abs().max((c[1] - u[1]).abs()).max(c[2].abs()))
        .fold(0.0, f64::max)
}

/// Free-slip walls exert no shear: a uniform stream along them stays uniform to round-off.
#[test]
fn free_slip_keeps_plug_flow() {
    let b = "west = { kind = \"periodic\" }\neast = { kind = \"periodic\" }\nsouth = { kind = \"free-slip\" }\nnorth = { kind = \"free-slip\" }";
    let d = max_deviation(
        &scene(b, "", "{ kind = \"uniform\", velocity_m_s = [0.02, 0.0] }"),
        [0.02, 0.0],
    );
    assert!(d < 1e-12, "deviation {d}");
}

/// Oblique uniform flow in a box with Zou–He velocity on all four faces: every corner is a
/// velocity–velocity corner (Zou & He 1997, sec. 4). The uniform flow is exact.
#[test]
fn zou_he_velocity_faces_and_corners_keep_uniform_flow() {
    let u = [0.012, 0.008];
    let face = format!(
        "{{ kind = \"velocity\", velocity_m_s = [{}, {}] }}",
        u[0], u[1]
    );
    let b = format!("west = {face}\neast = {face}\nsouth = {face}\nnorth = {face}");
    let d = max_deviation(
        &scene(
            &b,
            "",
            &format!(
                "{{ kind = \"uniform\", velocity_m_s = [{}, {}] }}",
                u[0], u[1]
            ),
        ),
        u,
    );
    eprintln!("velocity box: max deviation {d:.2e} m/s");
    assert!(d < 1e-9, "deviation {d}");
}

/// A stream along x: velocity inlet, pressure outlet, and velocity faces carrying the same
/// stream on south and north, so the east corners join a pressure face to velocity faces.
#[test]
fn zou_he_pressure_outlet_and_mixed_corners_keep_uniform_flow() {
    let face = "{ kind = \"velocity\", velocity_m_s = [0.02, 0.0] }";
    let b = format!("west = {face}\neast = {{ kind = \"pressure\", pressure_pa = 0.0 }}\nsouth = {face}\nnorth = {face}");
    let d = max_deviation(
        &scene(&b, "", "{ kind = \"uniform\", velocity_m_s = [0.02, 0.0] }"),
        [0.02, 0.0],
    );
    eprintln!("pressure outlet: max deviation {d:.2e} m/s");
    assert!(d < 1e-9, "deviation {d}");
}

/// Uniform inflow, zero-gradient outflow, free-slip sides: the stream leaves undisturbed.
#[test]
fn outflow_passes_uniform_stream() {
    let b = "west = { kind = \"velocity\", velocity_m_s = [0.02, 0.0] }\neast = { kind = \"outflow\" }\nsouth = { kind = \"free-slip\" }\nnorth = { kind = \"free-slip\" }";
    let d = max_deviation(
        &scene(b, "", "{ kind = \"uniform\", velocity_m_s = [0.02, 0.0] }"),
        [0.02, 0.0],
    );
    assert!(d < 1e-6, "deviation {d}");
}

/// A PNG mask (dark pixels solid, top row north) rasterises cell for cell.
#[test]
fn mask_obstacle_from_png() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (24u32, 16u32);
    // A 4 × 3 dark block whose top-left pixel is at (5, 2) in image coordinates.
    let mut px = vec![255u8; (w * h) as usize];
    for y in 2..5 {
        for x in 5..9 {
            px[(y * w + x) as usize] = 0;
        }
    }
    let mut bytes = Vec::new();
    {
        let mut e = png::Encoder::new(&mut bytes, w, h);
        e.set_color(png::ColorType::Grayscale);
        e.write_header().unwrap().write_image_data(&px).unwrap();
    }
    std::fs::write(dir.path().join("mask.png"), bytes).unwrap();
    let b = "west = { kind = \"periodic\" }\neast = { kind = \"periodic\" }\nsouth = { kind = \"wall\" }\nnorth = { kind = \"wall\" }";
    let text = scene(
        b,
        "[[obstacles]]\nname = \"block\"\nshape = \"mask\"\nimage = \"mask.png\"\n",
        "{ kind = \"rest\" }",
    );
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, &text).unwrap();
    let v = grainflow::scene::load(&path).unwrap();
    let g = grainflow::scene::build_lattice(&v).unwrap();
    assert_eq!(g.obstacle_cells, [12]);
    let id = grainflow::scene::solid_id_of(&g.setup, "block").unwrap();
    // Image row 2 is lattice row 16 − 1 − 2 = 13; rows 11..=13, columns 5..=8.
    for y in 0..16 {
        for x in 0..24 {
            let solid = (11..=13).contains(&y) && (5..=8).contains(&x);
            assert_eq!(g.setup.cells[y * 24 + x] == id, solid, "cell ({x}, {y})");
        }
    }
    // A wrong-size mask is refused with the expected size.
    std::fs::write(
        dir.path().join("mask.png"),
        &std::fs::read(root().join("tests/boundaries.rs")).unwrap()[..10],
    )
    .unwrap();
    let err = grainflow::scene::build_lattice(&grainflow::scene::load(&path).unwrap())
        .unwrap_err()
        .to_string();
    assert!(err.contains("not a readable PNG"), "{err}");
}
