//! Pictures a reader can use without the scene file: a panel (a field, grains or material
//! points) above a legend that names the field and its units, shows the colour bar with its
//! limits, the simulated time and a length scale.

use super::colormap;
use super::font;
use super::picture::{write_rgb_png, Scale};
use super::OutputError;
use std::path::Path;

/// An RGB image, rows from the top.
#[derive(Debug, Clone)]
pub struct Image {
    /// Width (pixels).
    pub w: usize,
    /// Height (pixels).
    pub h: usize,
    /// 8-bit RGB, `3 w h` bytes.
    pub rgb: Vec<u8>,
}

/// Black, for walls, outlines and text.
pub const INK: [u8; 3] = [0, 0, 0];

impl Image {
    /// A `w` × `h` image filled with `background`.
    pub fn new(w: usize, h: usize, background: [u8; 3]) -> Self {
        let mut rgb = Vec::with_capacity(3 * w * h);
        for _ in 0..w * h {
            rgb.extend_from_slice(&background);
        }
        Self { w, h, rgb }
    }

    /// Set pixel (`x`, `y`); outside the image, nothing.
    pub fn put(&mut self, x: isize, y: isize, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.w && (y as usize) < self.h {
            let k = (y as usize * self.w + x as usize) * 3;
            self.rgb[k..k + 3].copy_from_slice(&c);
        }
    }

    /// A filled rectangle `[x0, x1) × [y0, y1)`, clipped.
    pub fn fill(&mut self, (x0, y0): (isize, isize), (x1, y1): (isize, isize), c: [u8; 3]) {
        for y in y0.max(0)..y1.min(self.h as isize) {
            for x in x0.max(0)..x1.min(self.w as isize) {
                self.put(x, y, c);
            }
        }
    }

    /// A segment from `a` to `b` (pixels, fractional), `width` pixels wide, kept inside the
    /// image: a wall on the image's edge is drawn along that edge.
    pub fn segment(&mut self, a: [f64; 2], b: [f64; 2], width: usize, c: [u8; 3]) {
        let n = ((b[0] - a[0]).hypot(b[1] - a[1]).ceil() as usize).max(1);
        let (xmax, ymax) = (self.w as f64 - 1.0, self.h as f64 - 1.0);
        let half = width as isize / 2;
        for k in 0..=n {
            let t = k as f64 / n as f64;
            let x = (a[0] + t * (b[0] - a[0])).clamp(0.0, xmax) as isize;
            let y = (a[1] + t * (b[1] - a[1])).clamp(0.0, ymax) as isize;
            let (x0, y0) = (
                (x - half).clamp(0, self.w as isize - width as isize),
                (y - half).clamp(0, self.h as isize - width as isize),
            );
            self.fill((x0, y0), (x0 + width as isize, y0 + width as isize), c);
        }
    }

    /// A disk of radius `r` (pixels) at `centre`, filled with `fill` and outlined in `edge`
    /// when it is at least three pixels across.
    pub fn disk(&mut self, centre: [f64; 2], r: f64, fill: [u8; 3], edge: Option<[u8; 3]>) {
        let r = r.max(0.5);
        let [cx, cy] = centre;
        let inner = (r - 1.0).max(0.0);
        for y in (cy - r).floor() as isize..=(cy + r).ceil() as isize {
            for x in (cx - r).floor() as isize..=(cx + r).ceil() as isize {
                let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
                let d2 = dx * dx + dy * dy;
                if d2 <= r * r {
                    let c = match edge {
                        Some(e) if r >= 1.5 && d2 > inner * inner => e,
                        _ => fill,
                    };
                    self.put(x, y, c);
                }
            }
        }
    }

    /// `text` with its top-left corner at (`x`, `y`).
    pub fn text(&mut self, text: &str, x: usize, y: usize, zoom: usize) {
        let mut set = Vec::new();
        font::draw(text, x, y, zoom, |x, y| set.push((x, y)));
        for (x, y) in set {
            self.put(x as isize, y as isize, INK);
        }
    }
}

/// Maps metres in `region` (lower-left, upper-right corners) to the pixels of a panel whose
/// longer side is `size_px`.
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    lo: [f64; 2],
    hi: [f64; 2],
    /// Pixels per metre.
    pub scale: f64,
}

impl Frame {
    /// The frame of `region` at `size_px` pixels along its longer side.
    pub fn new((lo, hi): ([f64; 2], [f64; 2]), size_px: usize) -> Self {
        let long = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-300);
        Self {
            lo,
            hi,
            scale: size_px as f64 / long,
        }
    }

    /// Panel size (pixels), at least 16 × 16.
    pub fn size(&self) -> (usize, usize) {
        let px = |m: f64| ((m * self.scale).round() as usize).max(16);
        (px(self.hi[0] - self.lo[0]), px(self.hi[1] - self.lo[1]))
    }

    /// The pixel of a point (m), rows from the top.
    pub fn pixel(&self, p: [f64; 2]) -> [f64; 2] {
        [
            (p[0] - self.lo[0]) * self.scale,
            (self.hi[1] - p[1]) * self.scale,
        ]
    }
}

/// What a series of pictures shares: the panel's longer side (pixels) and the top of the
/// colour scale, fixed for the whole run so that frames compare.
#[derive(Debug, Clone, Copy)]
pub struct PictureStyle {
    /// Longer side of the panel (pixels).
    pub size_px: usize,
    /// Top of the colour scale (the field's SI unit).
    pub limit: f64,
}

/// What a picture says about itself.
#[derive(Debug, Clone)]
pub struct Legend {
    /// The field and its units, as printed ("speed (m/s)").
    pub title: String,
    /// The colour scale and its limits (printed at the bar's ends).
    pub scale: Scale,
    /// Simulated time (s).
    pub time_s: f64,
    /// Metres per pixel of the panel, for the length scale.
    pub metres_per_pixel: f64,
}

/// The legend's text size (image pixels per font pixel).
const ZOOM: usize = 2;
/// The colour bar's size (pixels).
const BAR: (usize, usize) = (256, 14);
/// Margin around the legend's rows (pixels).
const PAD: usize = 8;
/// The narrowest picture: room for the colour bar, the length scale and their labels.
const MIN_WIDTH: usize = 640;

/// Write `panel` with `legend` below it as a PNG at `path` (atomically). Both sides of the
/// picture are even, as video encoders need.
pub fn write_figure(path: &Path, panel: &Image, legend: &Legend) -> Result<(), OutputError> {
    let fig = compose(panel, legend);
    write_rgb_png(path, fig.w, fig.h, &fig.rgb)
}

/// The picture `write_figure` writes.
pub fn compose(panel: &Image, legend: &Legend) -> Image {
    let line = font::text_height(ZOOM);
    let legend_h = PAD + line + PAD + BAR.1 + PAD / 2 + line + PAD;
    let w = even(panel.w.max(MIN_WIDTH));
    let h = even(panel.h + legend_h);
    let mut fig = Image::new(w, h, [255, 255, 255]);
    for y in 0..panel.h {
        let (src, dst) = (3 * y * panel.w, 3 * y * w);
        fig.rgb[dst..dst + 3 * panel.w].copy_from_slice(&panel.rgb[src..src + 3 * panel.w]);
    }
    // Row 1: the field and its units; the time at the right.
    let y1 = panel.h + PAD;
    fig.text(&legend.title, PAD, y1, ZOOM);
    let time = format!("t = {} s", number(legend.time_s));
    fig.text(&time, w - PAD - font::text_width(&time, ZOOM), y1, ZOOM);
    // Row 2: the colour bar, framed, and the length scale beside it.
    let y2 = y1 + line + PAD;
    for i in 0..BAR.0 {
        let t = (i as f64 + 0.5) / BAR.0 as f64;
        let c = match legend.scale {
            Scale::Magnitude(_) => colormap::sequential(t),
            Scale::Signed(_) => colormap::diverging(2.0 * t - 1.0),
        };
        let x = (PAD + i) as isize;
        fig.fill((x, y2 as isize), (x + 1, (y2 + BAR.1) as isize), c);
    }
    let (bx0, bx1) = (PAD as f64 - 1.0, (PAD + BAR.0) as f64);
    let (by0, by1) = (y2 as f64 - 1.0, (y2 + BAR.1) as f64);
    for (a, b) in [
        ([bx0, by0], [bx1, by0]),
        ([bx0, by1], [bx1, by1]),
        ([bx0, by0], [bx0, by1]),
        ([bx1, by0], [bx1, by1]),
    ] {
        fig.segment(a, b, 1, INK);
    }
    length_scale(&mut fig, legend.metres_per_pixel, PAD + BAR.0 + 4 * PAD, y2);
    // Row 3: the limits under the bar's ends and middle.
    let y3 = y2 + BAR.1 + PAD / 2;
    let (lo, mid, hi) = match legend.scale {
        Scale::Magnitude(m) => (0.0, m / 2.0, m),
        Scale::Signed(m) => (-m, 0.0, m),
    };
    let (lo, mid, hi) = (number(lo), number(mid), number(hi));
    fig.text(&lo, PAD, y3, ZOOM);
    let mid_x = PAD + BAR.0 / 2 - font::text_width(&mid, ZOOM) / 2;
    fig.text(&mid, mid_x, y3, ZOOM);
    fig.text(&hi, PAD + BAR.0 - font::text_width(&hi, ZOOM), y3, ZOOM);
    fig
}

/// A scale bar of a round length (1, 2 or 5 × 10ᵏ m) about 120 pixels long, with its
/// length printed after it, from (`x`, `y`).
fn length_scale(fig: &mut Image, metres_per_pixel: f64, x: usize, y: usize) {
    if !(metres_per_pixel > 0.0 && metres_per_pixel.is_finite()) {
        return;
    }
    let (mantissa, exp) = round_length(120.0 * metres_per_pixel);
    let length = mantissa * 10f64.powi(exp);
    let px = (length / metres_per_pixel).round();
    let mid = (y + BAR.1 / 2) as f64;
    let (x0, x1) = (x as f64, x as f64 + px);
    fig.segment([x0, mid], [x1, mid], 3, INK);
    fig.segment([x0, y as f64], [x0, (y + BAR.1) as f64], 2, INK);
    fig.segment([x1, y as f64], [x1, (y + BAR.1) as f64], 2, INK);
    let label = length_label(mantissa, exp);
    fig.text(&label, (x1 as usize) + 2 * PAD, y, ZOOM);
}

/// The smallest round value (1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6 or 8 × 10ᵏ) not below `v` (> 0):
/// default colour limits, so that the colour bar's labels are round.
pub fn round_up(v: f64) -> f64 {
    if !(v > 0.0 && v.is_finite()) {
        return v;
    }
    let exp = v.log10().floor() as i32;
    let scale = 10f64.powi(exp);
    [1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0]
        .into_iter()
        .map(|m| m * scale)
        .find(|&r| r >= v * (1.0 - 1e-12))
        .unwrap_or(10.0 * scale)
}

/// The largest 1, 2 or 5 × 10ᵏ not above `target` (> 0): (mantissa, k).
pub fn round_length(target: f64) -> (f64, i32) {
    let exp = target.log10().floor() as i32;
    let lead = target / 10f64.powi(exp);
    let mantissa = [5.0, 2.0, 1.0]
        .into_iter()
        .find(|&m| m <= lead * (1.0 + 1e-12))
        .unwrap_or(1.0);
    (mantissa, exp)
}

/// `mantissa` × 10^`exp` metres as a reader writes it: "2 m", "0.05 m", "5 mm", "2e-6 m".
pub fn length_label(mantissa: f64, exp: i32) -> String {
    let m = mantissa as u32;
    match exp {
        e if e >= 0 => format!("{} m", m as u64 * 10u64.pow(e.min(18) as u32)),
        -1 | -2 => format!("{:.*} m", (-exp) as usize, mantissa * 10f64.powi(exp)),
        -3 => format!("{m} mm"),
        -5 | -4 => format!(
            "{:.*} mm",
            (-exp - 3) as usize,
            mantissa * 10f64.powi(exp + 3)
        ),
        _ => format!("{m}e{exp} m"),
    }
}

/// A value with four significant digits, plain between 10⁻³ and 10⁵, else in e-notation.
pub fn number(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if (-3..5).contains(&mag) {
        let decimals = (3 - mag).max(0) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{v:.3e}")
    }
}

fn even(n: usize) -> usize {
    n + n % 2
}

/// The picture series of every solver: file-name prefixes before the step.
pub const SERIES: [&str; 6] = [
    "speed_",
    "vorticity_",
    "pressure_",
    "grains_",
    "grains_step_",
    "mpm_step_",
];

/// Remove the pictures in `dir` of an earlier run, so that a run that reuses a folder leaves
/// no stale picture beside its own: for each series of [`SERIES`], the files
/// `<prefix><step>.png` with `step` after `after` (all when `None`: a fresh run) and the
/// movie `<prefix without its _>.mp4`. A restart passes its checkpoint's step and keeps the
/// pictures up to it. Returns how many were removed.
pub fn remove_stale(dir: &Path, after: Option<u64>) -> std::io::Result<usize> {
    let prefixes = SERIES;
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(0);
    };
    let mut removed = 0;
    for e in entries {
        let e = e?;
        let name = e.file_name().to_string_lossy().into_owned();
        let stale = prefixes.iter().any(|p| {
            if name == format!("{}.mp4", p.trim_end_matches('_')) {
                return true;
            }
            let Some(rest) = name.strip_prefix(p) else {
                return false;
            };
            rest.strip_suffix(".png")
                .and_then(|s| s.parse::<u64>().ok())
                .is_some_and(|step| after.is_none_or(|a| step > a))
        });
        if stale {
            std::fs::remove_file(e.path())?;
            removed += 1;
        }
    }
    Ok(removed)
}

/// Encode each picture series `<prefix>*.png` in `dir` as `<prefix>.mp4` with ffmpeg, when
/// ffmpeg is on the PATH and the series has at least two frames; nothing otherwise. Returns
/// the movies written.
pub fn write_movies(dir: &Path, prefixes: &[&str]) -> Vec<std::path::PathBuf> {
    let mut written = Vec::new();
    for p in prefixes {
        let frames = std::fs::read_dir(dir)
            .map(|d| {
                d.filter_map(Result::ok)
                    .filter(|e| {
                        let n = e.file_name().to_string_lossy().into_owned();
                        n.starts_with(p) && n.ends_with(".png")
                    })
                    .count()
            })
            .unwrap_or(0);
        if frames < 2 {
            continue;
        }
        let movie = dir.join(format!("{}.mp4", p.trim_end_matches('_')));
        let tmp = dir.join(format!(".{}.mp4.tmp.mp4", p.trim_end_matches('_')));
        let status = std::process::Command::new("ffmpeg")
            .args(["-y", "-loglevel", "error", "-framerate", "10"])
            .args(["-pattern_type", "glob", "-i"])
            .arg(dir.join(format!("{p}*.png")))
            .args(["-pix_fmt", "yuv420p", "-vcodec", "libx264"])
            .arg(&tmp)
            .stdin(std::process::Stdio::null())
            .status();
        if status.is_ok_and(|s| s.success()) && std::fs::rename(&tmp, &movie).is_ok() {
            written.push(movie);
        } else {
            let _ = std::fs::remove_file(&tmp);
        }
    }
    written
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_keeps_the_aspect_and_puts_north_at_the_top() {
        let f = Frame::new(([0.0, 0.0], [2.0, 1.0]), 800);
        assert_eq!(f.size(), (800, 400));
        assert_eq!(f.pixel([0.0, 1.0]), [0.0, 0.0]);
        assert_eq!(f.pixel([2.0, 0.0]), [800.0, 400.0]);
    }

    #[test]
    fn default_limits_round_up() {
        assert_eq!(round_up(0.8764), 1.0);
        assert_eq!(round_up(1.534), 2.0);
        assert!((round_up(0.13) - 0.15).abs() < 1e-12);
        assert_eq!(round_up(8.333), 10.0);
        assert_eq!(round_up(2.0), 2.0);
    }

    #[test]
    fn round_lengths_and_their_labels() {
        assert_eq!(round_length(0.123), (1.0, -1));
        assert_eq!(round_length(0.3), (2.0, -1));
        assert_eq!(round_length(7.0), (5.0, 0));
        assert_eq!(round_length(0.00049), (2.0, -4));
        assert_eq!(length_label(2.0, 0), "2 m");
        assert_eq!(length_label(5.0, 1), "50 m");
        assert_eq!(length_label(5.0, -2), "0.05 m");
        assert_eq!(length_label(1.0, -1), "0.1 m");
        assert_eq!(length_label(5.0, -3), "5 mm");
        assert_eq!(length_label(2.0, -4), "0.2 mm");
        assert_eq!(length_label(1.0, -7), "1e-7 m");
    }

    #[test]
    fn numbers_keep_four_significant_digits() {
        assert_eq!(number(0.0), "0");
        assert_eq!(number(0.15321), "0.1532");
        assert_eq!(number(-12.5), "-12.5");
        assert_eq!(number(1250.0), "1250");
        assert_eq!(number(2.5e-5), "2.500e-5");
        assert_eq!(number(3.0e7), "3.000e7");
    }

    #[test]
    fn a_figure_has_even_sides_and_room_for_its_legend() {
        let panel = Image::new(101, 51, [10, 20, 30]);
        let legend = Legend {
            title: "speed (m/s)".into(),
            scale: Scale::Magnitude(0.2),
            time_s: 1.25,
            metres_per_pixel: 0.001,
        };
        let fig = compose(&panel, &legend);
        assert!(fig.w >= MIN_WIDTH && fig.w.is_multiple_of(2) && fig.h.is_multiple_of(2));
        assert!(fig.h > panel.h + 2 * font::text_height(ZOOM));
        // The panel is copied unchanged; the legend has ink in it.
        assert_eq!(&fig.rgb[..3], &[10, 20, 30]);
        let legend_rows = &fig.rgb[3 * fig.w * panel.h..];
        assert!(legend_rows.chunks(3).any(|c| c == INK));
    }

    #[test]
    fn stale_pictures_are_removed_and_others_kept() {
        let dir = tempfile::tempdir().unwrap();
        for n in [
            "speed_00000100.png",
            "speed_00000200.png",
            "speed.mp4",
            "notes.txt",
            "speedy_00000300.png",
        ] {
            std::fs::write(dir.path().join(n), b"x").unwrap();
        }
        // A restart from step 100 keeps the pictures up to it.
        let removed = remove_stale(dir.path(), Some(100)).unwrap();
        assert_eq!(removed, 2);
        assert!(dir.path().join("speed_00000100.png").exists());
        assert!(!dir.path().join("speed_00000200.png").exists());
        assert!(!dir.path().join("speed.mp4").exists());
        // A fresh run removes them all.
        let removed = remove_stale(dir.path(), None).unwrap();
        assert_eq!(removed, 1);
        assert!(dir.path().join("notes.txt").exists());
        assert!(dir.path().join("speedy_00000300.png").exists());
    }
}
