//! PNG output of the comparison: tonemapped colour images, false-colour error maps with a
//! colour bar, and TIR masks. Every file is written atomically (refract-scene's one writer).

use std::path::Path;

use glam::Vec3;
use refract_scene::atomic_write::write_png_rgb8;
use refract_scene::tonemap::to_srgb8;

/// Linear radiance, tonemapped to sRGB.
pub fn write_color(path: &Path, width: u32, height: u32, color: &[Vec3]) -> anyhow::Result<()> {
    let pixels: Vec<u8> = color.iter().flat_map(|&c| to_srgb8(c)).collect();
    Ok(write_png_rgb8(path, width, height, &pixels)?)
}

/// The magma colour map at `t ∈ [0, 1]` (from FLIP's own lookup table).
fn magma(lut: &[u8], t: f32) -> [u8; 3] {
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
) -> anyhow::Result<()> {
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
    Ok(write_png_rgb8(path, out_width, height, &pixels)?)
}

/// A mask: magenta where `mask`, the tonemapped image dimmed elsewhere.
pub fn write_mask(
    path: &Path,
    width: u32,
    height: u32,
    mask: &[bool],
    color: &[Vec3],
) -> anyhow::Result<()> {
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
    Ok(write_png_rgb8(path, width, height, &pixels)?)
}
