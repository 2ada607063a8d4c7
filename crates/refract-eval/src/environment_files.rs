//! Lat-long environment maps from files: `.exr` (half or float, RGB or RGBA) and Radiance
//! `.hdr`, sizes checked before any texel is allocated.

use std::path::Path;

use glam::Vec3;
use refract_scene::{EnvironmentReport, LatLongMap, SceneError};

/// Loads a lat-long `.exr` (half or float, RGB or RGBA) or Radiance `.hdr` map. Negative and
/// non-finite values are clamped to 0 and counted in the report.
pub fn load_latlong(path: &Path) -> Result<(LatLongMap, EnvironmentReport), SceneError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    // The declared size is checked before any texel is allocated.
    let declared = match extension.as_deref() {
        Some("exr") => Some(exr_size(path, |err| {
            format_error(path, format!("not a readable OpenEXR file: {err}"))
        })?),
        Some("hdr") => Some(
            image::ImageReader::open(path)
                .and_then(|r| r.with_guessed_format())
                .map_err(|source| SceneError::Io {
                    path: path.to_owned(),
                    action: "cannot read the environment map",
                    source,
                })?
                .into_dimensions()
                .map_err(|err| {
                    format_error(path, format!("not a readable Radiance .hdr file: {err}"))
                })?,
        ),
        _ => None,
    };
    if let Some((w, h)) = declared {
        check_size(path, w, h)?;
    }
    let (width, height, mut rgb) = match extension.as_deref() {
        Some("exr") => read_exr(path)?,
        Some("hdr") => read_hdr(path)?,
        _ => {
            return Err(SceneError::Format {
                path: path.to_owned(),
                message: "unsupported environment map; expected a lat-long .exr or .hdr file"
                    .into(),
            });
        }
    };
    if let Some(v) = rgb
        .iter()
        .find(|v| v.is_finite() && **v > MAX_ENVIRONMENT_RADIANCE)
    {
        return Err(format_error(
            path,
            format!(
                "a texel holds {v:e}; expected radiance from 0 to {MAX_ENVIRONMENT_RADIANCE:e} \
                 (larger values overflow f32 when a renderer sums them)"
            ),
        ));
    }
    let mut report = EnvironmentReport::default();
    for v in &mut rgb {
        if !v.is_finite() {
            *v = 0.0;
            report.non_finite_replaced += 1;
        } else if *v < 0.0 {
            *v = 0.0;
            report.negative_clamped += 1;
        }
    }
    let texels = rgb.chunks_exact(3).map(Vec3::from_slice).collect();
    Ok((
        LatLongMap {
            width,
            height,
            texels,
        },
        report,
    ))
}

/// The largest radiance an environment texel may hold: a renderer sums texels (bilinear taps,
/// samples, Fresnel branches, the scene's `intensity` up to 10⁶), and 10²⁰ leaves those sums
/// 10¹⁸ below `f32::MAX`; a real sky's sun is below 10¹⁰.
pub const MAX_ENVIRONMENT_RADIANCE: f32 = 1e20;

/// The largest width of an environment map (a lat-long map is twice as wide as high).
pub const MAX_ENVIRONMENT_WIDTH: u32 = 16384;
/// The largest height of an environment map.
pub const MAX_ENVIRONMENT_HEIGHT: u32 = 8192;

fn check_size(path: &Path, width: u32, height: u32) -> Result<(), SceneError> {
    if width == 0 || height == 0 {
        return Err(format_error(
            path,
            format!("the map is {width}x{height}; expected at least 1x1 texels"),
        ));
    }
    if width > MAX_ENVIRONMENT_WIDTH || height > MAX_ENVIRONMENT_HEIGHT {
        return Err(format_error(
            path,
            format!(
                "the map declares {width}x{height} texels; expected at most \
                 {MAX_ENVIRONMENT_WIDTH}x{MAX_ENVIRONMENT_HEIGHT} (width x height)"
            ),
        ));
    }
    Ok(())
}

/// The size of the largest layer an EXR header declares, read without its pixels; a read
/// error becomes `on_error`'s [`SceneError`] (the frame loader keeps OS errors as
/// [`SceneError::Io`]).
pub(crate) fn exr_size(
    path: &Path,
    on_error: impl FnOnce(exr::error::Error) -> SceneError,
) -> Result<(u32, u32), SceneError> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(on_error)?;
    let (w, h) = meta
        .headers
        .iter()
        .fold((0usize, 0usize), |(w, h), header| {
            (
                w.max(header.layer_size.width()),
                h.max(header.layer_size.height()),
            )
        });
    let clamp = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
    Ok((clamp(w), clamp(h)))
}

fn format_error(path: &Path, message: impl Into<String>) -> SceneError {
    SceneError::Format {
        path: path.to_owned(),
        message: message.into(),
    }
}

/// RGB of the first layer that has R, G and B channels (any layer name prefix).
fn read_exr(path: &Path) -> Result<(u32, u32, Vec<f32>), SceneError> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|err| format_error(path, format!("not a readable OpenEXR file: {err}")))?;
    for layer in &image.layer_data {
        let find = |name: &str| {
            layer.channel_data.list.iter().find(|c| {
                let full = c.name.to_string();
                full == name || full.ends_with(&format!(".{name}"))
            })
        };
        let (Some(r), Some(g), Some(b)) = (find("R"), find("G"), find("B")) else {
            continue;
        };
        let size = layer.size;
        let (r, g, b): (Vec<f32>, Vec<f32>, Vec<f32>) = (
            r.sample_data.values_as_f32().collect(),
            g.sample_data.values_as_f32().collect(),
            b.sample_data.values_as_f32().collect(),
        );
        let rgb = (0..r.len()).flat_map(|i| [r[i], g[i], b[i]]).collect();
        return Ok((size.width() as u32, size.height() as u32, rgb));
    }
    Err(format_error(
        path,
        "no layer with R, G and B channels; expected an RGB(A) lat-long map",
    ))
}

fn read_hdr(path: &Path) -> Result<(u32, u32, Vec<f32>), SceneError> {
    let image = image::open(path)
        .map_err(|err| format_error(path, format!("not a readable Radiance .hdr file: {err}")))?;
    let rgb = image.to_rgb32f();
    Ok((rgb.width(), rgb.height(), rgb.into_raw()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame_files::FrameFiles;

    /// An EXR claiming 100000 × 100000 texels is refused before anything is allocated, and a
    /// 0 × 0 map is an error naming the file, not a division by zero later.
    #[test]
    fn oversized_and_empty_maps_are_refused_up_front() {
        let dir = tempfile::tempdir().expect("tempdir");
        let huge = dir.path().join("huge.exr");
        // A real tiny EXR whose declared data window is then patched to 100000 × 100000.
        crate::test_files::write_exr_declaring(&huge, 100_000);
        let err = load_latlong(&huge).expect_err("huge");
        let text = err.to_string();
        assert!(
            text.contains("huge.exr") && text.contains("100000x100000"),
            "{text}"
        );

        // Issue 54 #19: 16384 texels high (docs/scenes.md: 16384 x 8192 is the largest).
        let tall = dir.path().join("tall.hdr");
        std::fs::write(
            &tall,
            b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16384 +X 8192\n",
        )
        .expect("write");
        let err = load_latlong(&tall).expect_err("tall").to_string();
        assert!(
            err.contains("tall.hdr")
                && err.contains("8192x16384 texels; expected at most 16384x8192"),
            "{err}"
        );

        let empty = dir.path().join("empty.hdr");
        std::fs::write(&empty, b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 0 +X 0\n")
            .expect("write");
        let err = load_latlong(&empty).expect_err("empty");
        assert!(err.to_string().contains("empty.hdr"), "{err}");
    }

    /// A map whose texels hold 3e38 (they overflow to inf when a renderer sums them) is an
    /// error naming the file and the range, and a frame with a non-finite colour is never
    /// written (issue 34, item 6).
    #[test]
    fn huge_texels_are_refused_and_non_finite_frames_are_not_written() {
        let dir = tempfile::tempdir().expect("tempdir");
        let map = dir.path().join("bright.exr");
        let mut frame = refract_scene::Frame::new(4, 2);
        frame.color[3] = Vec3::splat(3e38);
        frame.write_exr(&map).expect("a finite frame is written");
        let err = load_latlong(&map).expect_err("3e38").to_string();
        assert!(err.contains("bright.exr") && err.contains("1e20"), "{err}");

        frame.color[5] = Vec3::new(f32::INFINITY, 0.0, 0.0);
        frame.color[6] = Vec3::NAN;
        for name in ["inf.exr", "inf.png"] {
            let path = dir.path().join(name);
            let err = if name.ends_with("exr") {
                frame.write_exr(&path)
            } else {
                frame.write_png(&path)
            }
            .expect_err("non-finite")
            .to_string();
            assert!(
                err.contains(name) && err.contains("2 pixels") && err.contains("x = 1, y = 1"),
                "{err}"
            );
            assert!(!path.exists(), "{name} written");
        }
    }
}
