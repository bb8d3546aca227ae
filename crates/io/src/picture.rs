//! PNG pictures of scalar fields (north at the top, solids grey, walls black), scaled to a
//! chosen size; `figure` adds the legend.

use super::atomic::write_atomic;
use super::figure::{Image, INK};
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

/// The faces of a rectangular domain drawn as walls (a black line along the picture's
/// edge): west, east, south, north.
pub type WallFaces = [bool; 4];

/// The field panel of a picture: `values` (row-major from the south row, `nx` × `ny`)
/// coloured by `scale` (values beyond its limits take the end colours), `solid[k]` cells
/// grey, the `walls` faces drawn black, the longer side `size_px` pixels (each pixel takes
/// the cell under its centre).
pub fn field_panel(
    (nx, ny): (usize, usize),
    values: &[f64],
    solid: &[bool],
    scale: Scale,
    walls: WallFaces,
    size_px: usize,
) -> Image {
    let long = nx.max(ny).max(1) as f64;
    let w = ((size_px as f64 * nx as f64 / long).round() as usize).max(1);
    let h = ((size_px as f64 * ny as f64 / long).round() as usize).max(1);
    let mut img = Image::new(w, h, [255, 255, 255]);
    for py in 0..h {
        let y = ny - 1 - ((py as f64 + 0.5) * ny as f64 / h as f64) as usize;
        for px in 0..w {
            let x = ((px as f64 + 0.5) * nx as f64 / w as f64) as usize;
            let k = y * nx + x.min(nx - 1);
            let c = if solid[k] {
                [110, 110, 110]
            } else {
                match scale {
                    Scale::Magnitude(m) => super::colormap::sequential(values[k] / m.max(1e-300)),
                    Scale::Signed(m) => super::colormap::diverging(values[k] / m.max(1e-300)),
                }
            };
            img.rgb[(py * w + px) * 3..][..3].copy_from_slice(&c);
        }
    }
    draw_walls(&mut img, walls);
    img
}

/// Black lines, two pixels wide, along the edges of `img` that are walls.
pub fn draw_walls(img: &mut Image, [west, east, south, north]: WallFaces) {
    let (r, b) = (img.w as f64 - 1.0, img.h as f64 - 1.0);
    for (on, a, e) in [
        (west, [0.0, 0.0], [0.0, b]),
        (east, [r, 0.0], [r, b]),
        (south, [0.0, b], [r, b]),
        (north, [0.0, 0.0], [r, 0.0]),
    ] {
        if on {
            img.segment(a, e, 2, INK);
        }
    }
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
