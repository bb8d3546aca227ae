//! PNG pictures of scalar fields (north at the top, solids grey, small lattices scaled up).

use super::atomic::write_atomic;
use super::OutputError;
use std::path::Path;

/// Colour scale of a picture.
#[derive(Debug, Clone, Copy)]
pub enum Scale {
    /// Sequential from 0 to the given maximum.
    Magnitude(f64),
    /// Diverging, symmetric about zero with the given limit.
    Signed(f64),
}

/// Render `values` (row-major from the south row, `nx` × `ny`) to a PNG at `path`.
/// `solid[k]` cells are drawn grey.
pub fn write_field_png(
    path: &Path,
    nx: usize,
    ny: usize,
    values: &[f64],
    solid: &[bool],
    scale: Scale,
) -> Result<(), OutputError> {
    let zoom = (512 / nx.max(ny)).clamp(1, 8);
    let (w, h) = (nx * zoom, ny * zoom);
    let mut rgb = vec![0u8; w * h * 3];
    for py in 0..h {
        let y = ny - 1 - py / zoom;
        for px in 0..w {
            let k = y * nx + px / zoom;
            let c = if solid[k] {
                [110, 110, 110]
            } else {
                match scale {
                    Scale::Magnitude(m) => super::colormap::sequential(values[k] / m.max(1e-300)),
                    Scale::Signed(m) => super::colormap::diverging(values[k] / m.max(1e-300)),
                }
            };
            rgb[(py * w + px) * 3..][..3].copy_from_slice(&c);
        }
    }
    write_rgb_png(path, w, h, &rgb)
}

/// Encode `rgb` (8-bit RGB, `w` × `h`, rows from the top) as a PNG written atomically.
pub fn write_rgb_png(path: &Path, w: usize, h: usize, rgb: &[u8]) -> Result<(), OutputError> {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, w as u32, h as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let err = |e: png::EncodingError| OutputError::Png {
            path: path.to_owned(),
            message: e.to_string(),
        };
        let mut wr = enc.write_header().map_err(err)?;
        wr.write_image_data(rgb).map_err(err)?;
    }
    write_atomic(path, &bytes)
}

/// Robust colour limit: the 99th percentile of |v| over fluid cells (so a few extreme cells
/// near sharp corners do not wash the picture out).
pub fn robust_limit(values: &[f64], solid: &[bool]) -> f64 {
    let mut a: Vec<f64> = values
        .iter()
        .zip(solid)
        .filter(|(_, s)| !**s)
        .map(|(v, _)| v.abs())
        .filter(|v| v.is_finite())
        .collect();
    if a.is_empty() {
        return 1.0;
    }
    let k = ((a.len() - 1) as f64 * 0.99) as usize;
    let (_, v, _) = a.select_nth_unstable_by(k, |x, y| x.total_cmp(y));
    *v
}
