//! PNG output of the comparison: tonemapped colour images, false-colour error maps with a
//! colour bar, and TIR masks. Every file is written atomically ([`crate::atomic_write`]).

use std::path::Path;

use glam::Vec3;
use refract_scene::SceneError;

use crate::atomic_write::write_png_rgb8_described;
use refract_scene::tonemap::to_srgb8;

/// The top of the colour bar of `T2` angle-error maps, degrees.
pub const T2_SCALE_DEG: f32 = 20.0;
/// The top of the colour bar of |P~2 − P2| maps, fraction of the bounding-sphere diameter.
pub const P2_SCALE: f32 = 0.2;

/// Refuses a colour image with a non-finite value (a writer never writes inf or NaN as if it
/// were radiance): the error names the file, the count and the first pixel.
pub fn check_finite(path: &Path, width: u32, color: &[Vec3]) -> Result<(), SceneError> {
    let bad = |c: &&Vec3| !c.is_finite();
    let Some(first) = color.iter().position(|c| bad(&c)) else {
        return Ok(());
    };
    let count = color.iter().filter(bad).count();
    let width = width.max(1) as usize;
    Err(SceneError::Format {
        path: path.to_owned(),
        message: format!(
            "{count} pixels have a non-finite colour (the first at x = {}, y = {}: {}); nothing was written",
            first % width,
            first / width,
            color[first]
        ),
    })
}

/// Linear radiance, tonemapped to sRGB.
pub fn write_color(path: &Path, width: u32, height: u32, color: &[Vec3]) -> Result<(), SceneError> {
    write_color_described(path, width, height, color, &[])
}

/// [`write_color`] with `description` as the PNG's text chunks
/// ([`crate::atomic_write::write_png_rgb8_described`]).
pub fn write_color_described(
    path: &Path,
    width: u32,
    height: u32,
    color: &[Vec3],
    description: &[(&str, String)],
) -> Result<(), SceneError> {
    check_finite(path, width, color)?;
    let pixels: Vec<u8> = color.iter().flat_map(|&c| to_srgb8(c)).collect();
    write_png_rgb8_described(path, width, height, &pixels, description)
}

/// Linear radiance for the report's exposure control, as RGBE (a shared exponent per pixel)
/// in a PNG twice as wide: the left half holds the mantissas `(r, g, b)·256/2^e`, the right
/// half `e + 128` in every channel (an opaque image, so a browser decodes it exactly; 0 is
/// black). The PNG goes into a script, `window.refractHdr["KEY"] = "data:image/png;base64,…"`,
/// because a page opened from `file://` may read the pixels of a data URL but not of a file.
/// Decoding: `c = (m + ½)·2^(e − 136)`.
pub fn write_hdr_script(
    path: &Path,
    key: &str,
    width: u32,
    height: u32,
    color: &[Vec3],
) -> Result<(), SceneError> {
    check_finite(path, width, color)?;
    let w = width as usize;
    let mut pixels = vec![0u8; 2 * w * height as usize * 3];
    for (i, &c) in color.iter().enumerate() {
        let (mantissas, exponent) = rgbe(c);
        let (row, x) = (i / w, i % w);
        let (left, right) = (3 * (row * 2 * w + x), 3 * (row * 2 * w + w + x));
        pixels[left..left + 3].copy_from_slice(&mantissas);
        pixels[right..right + 3].copy_from_slice(&[exponent; 3]);
    }
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        &pixels,
        2 * width,
        height,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| SceneError::Format {
        path: path.to_owned(),
        message: format!("cannot encode the HDR image: {e}"),
    })?;
    let script = format!(
        "(window.refractHdr = window.refractHdr || {{}})[{key:?}] = \"data:image/png;base64,{}\";\n",
        base64::encode(&png)
    );
    crate::atomic_write::write_text_atomically(path, &script)
}

/// RGBE of one linear colour: mantissas `⌊c·256/2^e⌋` and the biased exponent `e + 128`,
/// `2^(e−1) ≤ max(c) < 2^e`; black (and negative, NaN) is all zero. Decoded as
/// `(m + ½)·2^(e − 136)`, within half a mantissa step (`2^(e−9)`).
fn rgbe(c: Vec3) -> ([u8; 3], u8) {
    let c = c
        .to_array()
        .map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 });
    let m = c[0].max(c[1]).max(c[2]);
    if m < 1e-30 {
        return ([0; 3], 0);
    }
    let e = m.log2().floor() as i32 + 1;
    let scale = 256.0 / 2f32.powi(e);
    (
        c.map(|v| (v * scale).min(255.0) as u8),
        (e + 128).clamp(1, 255) as u8,
    )
}

/// The magma colour map at `t ∈ [0, 1]` (from FLIP's own lookup table).
pub fn magma(lut: &[u8], t: f32) -> [u8; 3] {
    let k = (t.clamp(0.0, 1.0) * 255.0).round() as usize;
    [lut[3 * k], lut[3 * k + 1], lut[3 * k + 2]]
}

/// Width of the colour bar appended on the right of every error map.
pub const BAR_WIDTH: u32 = 16;

/// A false-colour map of `values` (0 → black, `max` → white-yellow, magma), NaN drawn in dark
/// grey, with a vertical colour bar on the right (bottom 0, top `max`).
pub fn write_error_map(
    path: &Path,
    width: u32,
    height: u32,
    values: &[f32],
    max: f32,
) -> Result<(), SceneError> {
    write_error_map_described(path, width, height, values, max, &[])
}

/// [`write_error_map`] with `description` as the PNG's text chunks.
pub fn write_error_map_described(
    path: &Path,
    width: u32,
    height: u32,
    values: &[f32],
    max: f32,
    description: &[(&str, String)],
) -> Result<(), SceneError> {
    let lut = nv_flip::magma_lut().to_vec();
    let out_width = width + BAR_WIDTH;
    let mut pixels = Vec::with_capacity((out_width * height * 3) as usize);
    for y in 0..height {
        for x in 0..width {
            let v = values[(y * width + x) as usize];
            pixels.extend(if v.is_nan() {
                [40, 40, 40]
            } else {
                magma(&lut, v / max)
            });
        }
        for x in 0..BAR_WIDTH {
            let t = 1.0 - y as f32 / (height - 1).max(1) as f32;
            pixels.extend(if x < 3 {
                [255, 255, 255]
            } else {
                magma(&lut, t)
            });
        }
    }
    write_png_rgb8_described(path, out_width, height, &pixels, description)
}

/// A mask: magenta where `mask`, the tonemapped image dimmed elsewhere.
pub fn write_mask(
    path: &Path,
    width: u32,
    height: u32,
    mask: &[bool],
    color: &[Vec3],
) -> Result<(), SceneError> {
    write_mask_described(path, width, height, mask, color, &[])
}

/// [`write_mask`] with `description` as the PNG's text chunks.
pub fn write_mask_described(
    path: &Path,
    width: u32,
    height: u32,
    mask: &[bool],
    color: &[Vec3],
    description: &[(&str, String)],
) -> Result<(), SceneError> {
    let pixels: Vec<u8> = mask
        .iter()
        .zip(color)
        .flat_map(|(&m, &c)| {
            if m {
                [255, 60, 200]
            } else {
                to_srgb8(c).map(|v| v / 3)
            }
        })
        .collect();
    write_png_rgb8_described(path, width, height, &pixels, description)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RGBE round trips within half a mantissa step of the largest channel.
    #[test]
    fn rgbe_round_trips() {
        let decode = |(m, e): ([u8; 3], u8)| {
            if e == 0 {
                Vec3::ZERO
            } else {
                Vec3::from_array(m.map(|m| (f32::from(m) + 0.5) * 2f32.powi(i32::from(e) - 136)))
            }
        };
        for c in [
            Vec3::new(0.5, 0.25, 0.125),
            Vec3::new(12.0, 0.001, 3.0),
            Vec3::new(1e-4, 2e-4, 3e-4),
            Vec3::splat(1.0),
            Vec3::new(250.0, 0.0, 1.0),
        ] {
            let d = decode(rgbe(c));
            let step = 2f32.powi(c.max_element().log2().floor() as i32 + 1 - 9);
            assert!((d - c).abs().max_element() <= step, "{c} -> {d}");
        }
        assert_eq!(rgbe(Vec3::ZERO), ([0; 3], 0));
        assert_eq!(rgbe(Vec3::new(f32::NAN, -1.0, 0.0)), ([0; 3], 0));
    }
}
