//! A rendered frame: radiance and the per-pixel ground truth (AOVs), with multi-channel EXR
//! output and input.

use std::path::Path;

use glam::Vec3;

use crate::error::TraceError;

/// Ground truth of one pixel, from the transmission path through its centre. Quantities that do
/// not exist for a pixel (no refractor there, no exit, no nearby geometry hit) are NaN.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelAov {
    /// First refractor hit `P1`.
    pub p1: Vec3,
    /// Outward shading normal at `P1`.
    pub n1: Vec3,
    /// Direction after the first interface (`T1`).
    pub t1: Vec3,
    /// Exact first exit point `P2`: the first hit from inside (whether it refracts or not).
    pub p2: Vec3,
    /// Outward shading normal at `P2`.
    pub n2: Vec3,
    /// Direction in which the path finally leaves the refractor (the environment lookup
    /// direction; after the second interface for convex objects).
    pub t2: Vec3,
    /// Interfaces crossed by refraction (TIR bounces not counted).
    pub interfaces: u32,
    /// Total internal reflection anywhere on the path.
    pub tir: bool,
    /// Total internal reflection at the first exit `P2`.
    pub tir_first_exit: bool,
    /// Where the escaping ray hit nearby opaque geometry.
    pub p_geom: Vec3,
}

impl PixelAov {
    /// A pixel that does not see the refractor.
    pub const EMPTY: Self = Self {
        p1: Vec3::NAN,
        n1: Vec3::NAN,
        t1: Vec3::NAN,
        p2: Vec3::NAN,
        n2: Vec3::NAN,
        t2: Vec3::NAN,
        interfaces: 0,
        tir: false,
        tir_first_exit: false,
        p_geom: Vec3::NAN,
    };

    /// Whether the pixel's centre ray hits the refractor.
    pub fn covers_refractor(&self) -> bool {
        !self.p1.is_nan()
    }
}

/// A rendered frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB radiance, row-major from the top.
    pub radiance: Vec<Vec3>,
    /// Ground truth per pixel.
    pub aov: Vec<PixelAov>,
    /// Rays traced (closest-hit queries).
    pub rays: u64,
}

const VECTOR_LAYERS: [&str; 7] = ["P1", "N1", "T1", "P2", "N2", "T2", "Pgeom"];

impl Frame {
    /// An empty (black, no refractor) frame.
    pub fn new(width: u32, height: u32) -> Self {
        let n = (width * height) as usize;
        Self {
            width,
            height,
            radiance: vec![Vec3::ZERO; n],
            aov: vec![PixelAov::EMPTY; n],
            rays: 0,
        }
    }

    fn vector(aov: &PixelAov, layer: &str) -> Vec3 {
        match layer {
            "P1" => aov.p1,
            "N1" => aov.n1,
            "T1" => aov.t1,
            "P2" => aov.p2,
            "N2" => aov.n2,
            "T2" => aov.t2,
            _ => aov.p_geom,
        }
    }

    fn vector_mut<'f>(aov: &'f mut PixelAov, layer: &str) -> &'f mut Vec3 {
        match layer {
            "P1" => &mut aov.p1,
            "N1" => &mut aov.n1,
            "T1" => &mut aov.t1,
            "P2" => &mut aov.p2,
            "N2" => &mut aov.n2,
            "T2" => &mut aov.t2,
            _ => &mut aov.p_geom,
        }
    }

    /// Writes one EXR with channels `R G B`, `P1.X P1.Y P1.Z`, `N1.*`, `T1.*`, `P2.*`, `N2.*`,
    /// `T2.*`, `Pgeom.*` (NaN where absent), `interfaces`, `tir`, `tir_first_exit` (0/1), all
    /// 32-bit float. Written to a temporary name and renamed, so no partial file is left.
    pub fn write_exr(&self, path: &Path) -> Result<(), TraceError> {
        use exr::prelude::*;
        let mut channels = Vec::new();
        let rgb = ["R", "G", "B"];
        for (k, name) in rgb.iter().enumerate() {
            let samples = self.radiance.iter().map(|c| c[k]).collect();
            channels.push(AnyChannel::new(*name, FlatSamples::F32(samples)));
        }
        for layer in VECTOR_LAYERS {
            for (k, axis) in ["X", "Y", "Z"].iter().enumerate() {
                let samples = self.aov.iter().map(|a| Self::vector(a, layer)[k]).collect();
                channels.push(AnyChannel::new(
                    format!("{layer}.{axis}").as_str(),
                    FlatSamples::F32(samples),
                ));
            }
        }
        type Scalar = fn(&PixelAov) -> f32;
        let scalars: [(&str, Scalar); 3] = [
            ("interfaces", |a| a.interfaces as f32),
            ("tir", |a| f32::from(u8::from(a.tir))),
            ("tir_first_exit", |a| f32::from(u8::from(a.tir_first_exit))),
        ];
        for (name, value) in scalars {
            channels.push(AnyChannel::new(
                name,
                FlatSamples::F32(self.aov.iter().map(value).collect()),
            ));
        }
        let size = (self.width as usize, self.height as usize);
        let image = Image::from_channels(size, AnyChannels::sort(channels.into()));
        let temporary = path.with_extension("exr.partial");
        image
            .write()
            .to_file(&temporary)
            .map_err(|err| TraceError::Format {
                path: path.to_owned(),
                message: format!("cannot write EXR: {err}"),
            })?;
        std::fs::rename(&temporary, path).map_err(|source| TraceError::Io {
            path: path.to_owned(),
            action: "cannot move the finished EXR into place",
            source,
        })
    }

    /// Writes the radiance as an 8-bit sRGB PNG after [`crate::tonemap::to_srgb8`], through a
    /// temporary name and a rename.
    pub fn write_png(&self, path: &Path) -> Result<(), TraceError> {
        let pixels: Vec<u8> = self
            .radiance
            .iter()
            .flat_map(|&c| crate::tonemap::to_srgb8(c))
            .collect();
        let temporary = path.with_extension("png.partial");
        image::save_buffer_with_format(
            &temporary,
            &pixels,
            self.width,
            self.height,
            image::ExtendedColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(|err| TraceError::Format {
            path: path.to_owned(),
            message: format!("cannot write PNG: {err}"),
        })?;
        std::fs::rename(&temporary, path).map_err(|source| TraceError::Io {
            path: path.to_owned(),
            action: "cannot move the finished PNG into place",
            source,
        })
    }

    /// Reads a frame written by [`Frame::write_exr`] (the ray count is not stored: 0).
    pub fn read_exr(path: &Path) -> Result<Self, TraceError> {
        use exr::prelude::*;
        let format = |message: String| TraceError::Format {
            path: path.to_owned(),
            message,
        };
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_file(path)
            .map_err(|err| format(format!("not a readable OpenEXR file: {err}")))?;
        let layer = image.layer_data;
        let (width, height) = (layer.size.width() as u32, layer.size.height() as u32);
        let channel = |name: &str| -> std::result::Result<Vec<f32>, TraceError> {
            layer
                .channel_data
                .list
                .iter()
                .find(|c| c.name.to_string() == name)
                .map(|c| c.sample_data.values_as_f32().collect())
                .ok_or_else(|| {
                    format(format!(
                        "missing channel `{name}`; expected a refract AOV file"
                    ))
                })
        };
        let mut frame = Self::new(width, height);
        for (k, name) in ["R", "G", "B"].iter().enumerate() {
            for (pixel, v) in frame.radiance.iter_mut().zip(channel(name)?) {
                pixel[k] = v;
            }
        }
        for layer_name in VECTOR_LAYERS {
            for (k, axis) in ["X", "Y", "Z"].iter().enumerate() {
                let values = channel(&format!("{layer_name}.{axis}"))?;
                for (aov, v) in frame.aov.iter_mut().zip(values) {
                    Self::vector_mut(aov, layer_name)[k] = v;
                }
            }
        }
        for (aov, v) in frame.aov.iter_mut().zip(channel("interfaces")?) {
            aov.interfaces = v as u32;
        }
        for (aov, v) in frame.aov.iter_mut().zip(channel("tir")?) {
            aov.tir = v > 0.5;
        }
        for (aov, v) in frame.aov.iter_mut().zip(channel("tir_first_exit")?) {
            aov.tir_first_exit = v > 0.5;
        }
        Ok(frame)
    }
}
