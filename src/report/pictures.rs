//! PNG pictures of shadows, all in one colour convention:
//!
//! * **depth**: grey = 1 − z (near = bright, far = dark) — [`depth_colour`];
//! * **layer count**: viridis over 1..=8 surfaces (dark purple = 1, yellow ≥ 8) — [`layers_colour`];
//! * **shadow**: grey = 1 − shadow (lit = white, fully shadowed = black) — [`shadow_colour`];
//!   eye views shade it: grey = 0.15 + 0.85·(n·l)⁺·(1 − shadow);
//! * **|error|** = |G − PCF|: inferno on a square-root scale (black = 0, purple ≈ 0.04,
//!   orange ≈ 0.5, pale yellow = 1) — [`error_colour`], with a colour bar where there is room,
//!   its ticks labelled with their values;
//! * no surface: dark blue-grey [`BACKGROUND`]; non-finite G: magenta [`INVALID`].
//!
//! Light-view picture of one view ([`view_picture`]): five panels of the shadow-map resolution
//! side by side (no labels), separated by 4-pixel mid-grey gaps: front depth | layer count |
//! PCF shadow of the front-layer fragment | technique shadow | |error|. The front layer is lit
//! by definition; the shadows fall on the layers behind it ([`layer_picture`]) and are seen in
//! the eye view ([`eye_picture`]). `render --preview` draws the first two panels
//! ([`preview_picture`]).

use crate::metrics::FrontShadows;
use crate::stack::DepthStack;
use anyhow::{bail, Context, Result};
use std::path::Path;

/// Colour of texels without a surface.
pub const BACKGROUND: [u8; 3] = [28, 36, 52];
/// Colour of non-finite technique outputs.
pub const INVALID: [u8; 3] = [255, 0, 255];
/// Colour of the gaps between panels.
pub const GAP: [u8; 3] = [128, 128, 128];
/// Gap width in pixels.
pub const GAP_PX: usize = 4;
/// Number of panels.
pub const PANELS: usize = 5;

/// An 8-bit RGB image.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Pixels per row.
    pub width: usize,
    /// Rows of pixels.
    pub height: usize,
    /// Row-major RGB bytes, 3 per pixel.
    pub data: Vec<u8>,
}

impl RgbImage {
    /// A `width` × `height` image filled with `fill`.
    pub fn new(width: usize, height: usize, fill: [u8; 3]) -> RgbImage {
        RgbImage {
            width,
            height,
            data: fill.repeat(width * height),
        }
    }
    /// The colour at (x, y).
    pub fn get(&self, x: usize, y: usize) -> [u8; 3] {
        let i = 3 * (y * self.width + x);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }
    /// Sets the colour at (x, y).
    pub fn set(&mut self, x: usize, y: usize, c: [u8; 3]) {
        let i = 3 * (y * self.width + x);
        self.data[i..i + 3].copy_from_slice(&c);
    }
}

const INFERNO: [[u8; 3]; 11] = [
    [0x00, 0x00, 0x04],
    [0x16, 0x0b, 0x39],
    [0x42, 0x0a, 0x68],
    [0x6a, 0x17, 0x6e],
    [0x93, 0x26, 0x67],
    [0xbc, 0x37, 0x54],
    [0xdd, 0x51, 0x3a],
    [0xf3, 0x78, 0x19],
    [0xfc, 0xa5, 0x0a],
    [0xf6, 0xd7, 0x46],
    [0xfc, 0xff, 0xa4],
];

const VIRIDIS: [[u8; 3]; 11] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x24, 0x75],
    [0x41, 0x44, 0x87],
    [0x35, 0x5f, 0x8d],
    [0x2a, 0x78, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x22, 0xa8, 0x84],
    [0x44, 0xbf, 0x70],
    [0x7a, 0xd1, 0x51],
    [0xbd, 0xdf, 0x26],
    [0xfd, 0xe7, 0x25],
];

fn lut(table: &[[u8; 3]; 11], t: f64) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * 10.0;
    let i = (s.floor() as usize).min(9);
    let f = s - i as f64;
    let mut c = [0u8; 3];
    for k in 0..3 {
        let a = table[i][k] as f64;
        let b = table[i + 1][k] as f64;
        c[k] = (a + (b - a) * f).round() as u8;
    }
    c
}

/// The inferno colour map (matplotlib, sampled at tenths, linear in between), t ∈ [0,1].
pub fn inferno(t: f64) -> [u8; 3] {
    lut(&INFERNO, t)
}

/// The viridis colour map (matplotlib, sampled at tenths, linear in between), t ∈ [0,1].
pub fn viridis(t: f64) -> [u8; 3] {
    lut(&VIRIDIS, t)
}

fn grey(v: f64) -> [u8; 3] {
    let g = (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    [g, g, g]
}

/// Depth z ∈ [0,1]: grey 1 − z (near = bright); non-finite (no surface) = [`BACKGROUND`].
pub fn depth_colour(z: f64) -> [u8; 3] {
    if z.is_finite() {
        grey(1.0 - z)
    } else {
        BACKGROUND
    }
}

/// Surfaces along a texel's ray: viridis over 1..=8 (0 = [`BACKGROUND`]).
pub fn layers_colour(n: usize) -> [u8; 3] {
    if n == 0 {
        BACKGROUND
    } else {
        viridis((n as f64 - 1.0) / 7.0)
    }
}

/// Shadow intensity s (1 = fully shadowed): grey 1 − s (lit = white).
pub fn shadow_colour(s: f64) -> [u8; 3] {
    grey(1.0 - s)
}

/// |G − PCF| through inferno on a square-root scale.
pub fn error_colour(e: f64) -> [u8; 3] {
    inferno(e.abs().sqrt())
}

/// Width of the colour bar right of a |error| heat map, pixels.
pub const BAR_PX: usize = 16;
/// Values of |G − PCF| marked on the colour bar (white ticks): 0, 0.01, 0.04, 0.25, 1.
pub const BAR_TICKS: [f64; 5] = [0.0, 0.01, 0.04, 0.25, 1.0];

/// Width of the tick labels right of the colour bar, pixels.
pub const BAR_LABEL_PX: usize = 36;
/// The labels of [`BAR_TICKS`].
const BAR_TICK_LABELS: [&str; 5] = ["0", "0.01", "0.04", "0.25", "1"];

/// A 3×5 pixel font for the tick labels: per glyph five rows, bit 2 = left column.
fn glyph(c: char) -> [u8; 5] {
    match c {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 7, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 1, 1, 1],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        '.' => [0, 0, 0, 0, 2],
        _ => [0; 5],
    }
}

/// Draw `text` in black with its top-left corner at (x0, y0), each font pixel a `scale`² block;
/// pixels outside the image are skipped.
fn draw_text(img: &mut RgbImage, x0: usize, y0: usize, text: &str, scale: usize) {
    for (k, c) in text.chars().enumerate() {
        for (row, bits) in glyph(c).iter().enumerate() {
            for col in 0..3 {
                if bits & (4 >> col) == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let (x, y) = (x0 + (4 * k + col) * scale + dx, y0 + row * scale + dy);
                        if x < img.width && y < img.height {
                            img.set(x, y, [0, 0, 0]);
                        }
                    }
                }
            }
        }
    }
}

/// The |error| colour bar in columns x0..x0 + [`BAR_PX`] of `img` (bottom = 0, top = 1, white
/// ticks at [`BAR_TICKS`]), and right of it, on white in the next [`BAR_LABEL_PX`] columns, a
/// black tick and the value of each tick (font pixels doubled from 160 pixels of height).
fn colour_bar(img: &mut RgbImage, x0: usize) {
    let n = img.height;
    for y in 0..n {
        let v = 1.0 - y as f64 / (n.max(2) - 1) as f64;
        for x in 0..BAR_PX {
            img.set(x0 + x, y, error_colour(v));
        }
        for x in BAR_PX..BAR_PX + BAR_LABEL_PX {
            img.set(x0 + x, y, [255, 255, 255]);
        }
    }
    let scale = if n >= 160 { 2 } else { 1 };
    for (t, label) in BAR_TICKS.iter().zip(BAR_TICK_LABELS) {
        let y = (((1.0 - t.sqrt()) * (n.max(2) - 1) as f64).round() as usize).min(n - 1);
        for x in 0..BAR_PX / 2 {
            img.set(x0 + x, y, [255, 255, 255]);
        }
        for x in BAR_PX..BAR_PX + 2 {
            img.set(x0 + x, y, [0, 0, 0]);
        }
        let top = y
            .saturating_sub(5 * scale / 2)
            .min(n.saturating_sub(5 * scale));
        draw_text(img, x0 + BAR_PX + 4, top, label, scale);
    }
}

/// `render --preview`: front depth | layer count (panels 1 and 2 of [`view_picture`]).
pub fn preview_picture(stack: &DepthStack) -> RgbImage {
    let (w, h) = (stack.meta.width, stack.meta.height);
    let mut img = RgbImage::new(2 * w + GAP_PX, h, GAP);
    for y in 0..h {
        for x in 0..w {
            let t = y * w + x;
            let z0 = stack.depth.first().map_or(f32::INFINITY, |l| l[t]);
            let layers = stack.depth.iter().filter(|l| l[t].is_finite()).count();
            img.set(x, y, depth_colour(z0 as f64));
            img.set(w + GAP_PX + x, y, layers_colour(layers));
        }
    }
    img
}

/// Where the shadows cast onto layer `layer` fall, in the light view: depth of that layer |
/// PCF shadow | technique shadow | |error| with its colour bar (`shadows` from
/// [`crate::metrics::layer_shadows`]); texels with fewer surfaces are [`BACKGROUND`].
pub fn layer_picture(stack: &DepthStack, layer: usize, shadows: &FrontShadows) -> Result<RgbImage> {
    let (w, h) = (stack.meta.width, stack.meta.height);
    let n = w * h;
    if shadows.pcf.len() != n || shadows.g.len() != n || layer >= stack.depth.len() {
        bail!(
            "pictures: {}/{} layer {layer}: {} / {} shadow values for {} layers, expected {n}",
            stack.meta.scene,
            stack.meta.view,
            shadows.pcf.len(),
            shadows.g.len(),
            stack.depth.len()
        );
    }
    let mut img = RgbImage::new(4 * w + 4 * GAP_PX + BAR_PX + BAR_LABEL_PX, h, GAP);
    for y in 0..h {
        for x in 0..w {
            let t = y * w + x;
            let z = stack.depth[layer][t];
            let cols = if !z.is_finite() {
                [BACKGROUND; 4]
            } else {
                let (pcf, g) = (shadows.pcf[t], shadows.g[t]);
                let (tech, err) = if g.is_finite() {
                    (shadow_colour(g), error_colour(g - pcf))
                } else {
                    (INVALID, INVALID)
                };
                [depth_colour(z as f64), shadow_colour(pcf), tech, err]
            };
            for (p, c) in cols.iter().enumerate() {
                img.set(p * (w + GAP_PX) + x, y, *c);
            }
        }
    }
    colour_bar(&mut img, 4 * (w + GAP_PX));
    Ok(img)
}

/// The five-panel picture of one view (see the module doc for the panel order and colours).
/// `shadows` holds the front-layer PCF and technique values ([`crate::metrics::front_shadows`]).
pub fn view_picture(stack: &DepthStack, shadows: &FrontShadows) -> Result<RgbImage> {
    let (w, h) = (stack.meta.width, stack.meta.height);
    let n = w * h;
    if shadows.pcf.len() != n || shadows.g.len() != n {
        bail!(
            "pictures: {}/{}: shadow maps have {} / {} values, expected {n}",
            stack.meta.scene,
            stack.meta.view,
            shadows.pcf.len(),
            shadows.g.len()
        );
    }
    let mut img = RgbImage::new(PANELS * w + (PANELS - 1) * GAP_PX, h, GAP);
    for y in 0..h {
        for x in 0..w {
            let t = y * w + x;
            let z0 = stack.depth.first().map_or(f32::INFINITY, |l| l[t]);
            let layers = stack.depth.iter().filter(|l| l[t].is_finite()).count();
            let cols: [[u8; 3]; PANELS] = if !z0.is_finite() {
                [BACKGROUND; PANELS]
            } else {
                let pcf = shadows.pcf[t];
                let g = shadows.g[t];
                let (tech, err) = if g.is_finite() {
                    (shadow_colour(g), error_colour(g - pcf))
                } else {
                    (INVALID, INVALID)
                };
                [
                    depth_colour(z0 as f64),
                    layers_colour(layers),
                    shadow_colour(pcf),
                    tech,
                    err,
                ]
            };
            for (p, c) in cols.iter().enumerate() {
                img.set(p * (w + GAP_PX) + x, y, *c);
            }
        }
    }
    Ok(img)
}

/// Writes an RGB image as an 8-bit PNG.
pub fn write_png(path: &Path, img: &RgbImage) -> Result<()> {
    let (dir, name) = crate::artefact::OutDir::for_file(path, true)?;
    write_png_to(&dir, &name, img)
}

/// Write `img` as the PNG output `name` of `out` (the output writer).
pub fn write_png_to(out: &crate::artefact::OutDir, name: &str, img: &RgbImage) -> Result<()> {
    out.write_with(name, |file| {
        let mut enc = png::Encoder::new(
            std::io::BufWriter::new(file),
            img.width as u32,
            img.height as u32,
        );
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header()?;
        writer.write_image_data(&img.data)?;
        writer.finish()?;
        Ok(())
    })
    .context("cannot write picture")?;
    Ok(())
}

/// The eye-view comparison of one view: PCF-shaded image | technique-shaded image | |G − PCF|
/// heat map (inferno on a square-root scale, as panel 5 of [`view_picture`]) with its colour
/// bar (bottom = 0, top = 1, ticks at [`BAR_TICKS`]). Grey = 0.15 + 0.85·(n·l)⁺·(1 − shadow);
/// pixels without a surface are [`BACKGROUND`], non-finite G is [`INVALID`].
pub fn eye_picture(
    view: &crate::metrics::eye::EyeView,
    light_dir: [f64; 3],
    pcf: &[f64],
    g: &[f64],
) -> Result<RgbImage> {
    let n = view.resolution;
    if pcf.len() != n * n || g.len() != n * n {
        bail!(
            "eye picture: {} / {} shadow values, expected {}",
            pcf.len(),
            g.len(),
            n * n
        );
    }
    let mut img = RgbImage::new(3 * n + 3 * GAP_PX + BAR_PX + BAR_LABEL_PX, n, GAP);
    for y in 0..n {
        for x in 0..n {
            let i = y * n + x;
            let cols = match &view.points[i] {
                None => [BACKGROUND; 3],
                Some(p) => {
                    let a = grey(crate::metrics::eye::shade(p, light_dir, pcf[i]));
                    if g[i].is_finite() {
                        [
                            a,
                            grey(crate::metrics::eye::shade(p, light_dir, g[i])),
                            error_colour(g[i] - pcf[i]),
                        ]
                    } else {
                        [a, INVALID, INVALID]
                    }
                }
            };
            for (k, c) in cols.iter().enumerate() {
                img.set(k * (n + GAP_PX) + x, y, *c);
            }
        }
    }
    colour_bar(&mut img, 3 * (n + GAP_PX));
    Ok(img)
}

/// The eye-view picture of `subject` in `cmp` ([`eye_picture`]; for PCF itself the heat map
/// is 0).
pub fn eye_comparison(
    cmp: &crate::metrics::eye::EyeComparison,
    stack: &DepthStack,
    subject: crate::metrics::Subject,
    bias: &crate::metrics::Bias,
) -> Result<RgbImage> {
    let g = cmp.subject(stack, subject, bias)?;
    eye_picture(&cmp.view, cmp.light_dir, &cmp.pcf, &g)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_maps_hit_their_samples() {
        assert_eq!(inferno(0.0), INFERNO[0]);
        assert_eq!(inferno(1.0), INFERNO[10]);
        assert_eq!(viridis(0.5), VIRIDIS[5]);
        assert_eq!(inferno(f64::NAN), INFERNO[0]);
        // inferno is monotone in luminance-ish (sum of channels) at the samples
        let s: Vec<u32> = (0..=10)
            .map(|i| inferno(i as f64 / 10.0).iter().map(|&c| c as u32).sum())
            .collect();
        assert!(s.windows(2).all(|w| w[0] < w[1]), "{s:?}");
    }
}
