//! Pictures of grains: disks coloured by speed on white, the walls in black, with a legend
//! (`figure`); and grains drawn over a fluid field in coupled runs.

use super::figure::{write_figure, Frame, Image, Legend, PictureStyle, INK};
use super::picture::Scale;
use super::OutputError;
use decomposition::Comm;
use dem::DemSystem;
use std::path::Path;

/// Every rank's grains as (x, y, r, speed) in m and m/s, on rank 0 (`None` elsewhere).
/// Collective.
pub fn gather_grains(sys: &DemSystem, comm: &dyn Comm) -> Option<Vec<[f64; 4]>> {
    let g = &sys.grains;
    let mut local = Vec::with_capacity(sys.owned() * 4);
    for i in 0..sys.owned() {
        local.extend_from_slice(&[g.x[i], g.y[i], g.r[i], g.vx[i].hypot(g.vy[i])]);
    }
    let all = comm.all_gather_f64(&local);
    comm.is_root().then(|| {
        all.chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()
    })
}

/// Draw `grains` (from [`gather_grains`]) over a fluid field's `panel` framed by `frame`:
/// light grey disks outlined in black, so that the field stays readable between them.
pub fn draw_grains_over(panel: &mut Image, frame: &Frame, grains: &[[f64; 4]]) {
    for g in grains {
        let r = g[2] * frame.scale;
        panel.disk(frame.pixel([g[0], g[1]]), r, [225, 225, 225], Some(INK));
    }
}

/// Draw the grains of every rank into `path` (rank 0 writes; collective): disks on white
/// framing `region` (m), coloured by speed from 0 to `style.limit` (m/s), walls as black
/// segments (walls on the region's edge drawn along the picture's edge), with a legend
/// giving the time `time_s`.
pub fn write_grains_png(
    path: &Path,
    sys: &DemSystem,
    region: ([f64; 2], [f64; 2]),
    style: PictureStyle,
    time_s: f64,
    comm: &dyn Comm,
) -> Result<(), OutputError> {
    let Some(all) = gather_grains(sys, comm) else {
        return Ok(());
    };
    let frame = Frame::new(region, style.size_px);
    let (w, h) = frame.size();
    let mut panel = Image::new(w, h, [255, 255, 255]);
    let vmax = style.limit.max(1e-300);
    for c in &all {
        let colour = super::colormap::sequential(c[3] / vmax);
        panel.disk(frame.pixel([c[0], c[1]]), c[2] * frame.scale, colour, None);
    }
    for w in sys.walls.iter().filter(|w| !w.removed) {
        panel.segment(frame.pixel(w.a), frame.pixel(w.b), 2, INK);
    }
    let legend = Legend {
        title: "grain speed (m/s)".into(),
        scale: Scale::Magnitude(style.limit),
        time_s,
        metres_per_pixel: 1.0 / frame.scale,
    };
    write_figure(path, &panel, &legend)
}
