//! A [`Frame`] as files: one EXR with the colour and every AOV layer (linear, 32-bit float),
//! or an sRGB PNG of the colour; both written atomically.

use std::path::Path;

use glam::Vec3;
use refract_scene::{Aov, AovKind, Frame, MAX_FRAME_SIZE, SceneError};

use crate::atomic_write::{write_atomically, write_png_rgb8_described};
use crate::environment_files::exr_size;
use crate::images::check_finite;

const AXES: [&str; 3] = ["X", "Y", "Z"];

/// Writing and reading a [`Frame`] as files (an extension trait: the API crate links no file
/// format).
pub trait FrameFiles: Sized {
    /// Writes one EXR with channels `R G B` and every layer present: vectors as `NAME.X`,
    /// `NAME.Y`, `NAME.Z` (e.g. `T2.X`), counts and flags as one channel (`interfaces`, `tir`),
    /// all 32-bit float. Written atomically (no partial file on failure). A frame with a
    /// non-finite colour is an error naming the count and the first pixel (layers may hold NaN:
    /// "no value here").
    fn write_exr(&self, path: &Path) -> Result<(), SceneError> {
        self.write_exr_described(path, &[])
    }
    /// [`FrameFiles::write_exr`] saying what made the frame: `description`'s `(name, text)`
    /// pairs as text attributes of the EXR's header (text an EXR cannot hold, outside
    /// Latin-1, has its characters replaced by `?`).
    fn write_exr_described(
        &self,
        path: &Path,
        description: &[(&str, String)],
    ) -> Result<(), SceneError>;
    /// Writes the colour as an 8-bit sRGB PNG after [`refract_scene::tonemap::to_srgb8`],
    /// atomically.
    fn write_png(&self, path: &Path) -> Result<(), SceneError> {
        self.write_png_described(path, &[])
    }
    /// [`FrameFiles::write_png`] with `description` as text chunks
    /// ([`crate::atomic_write::write_png_rgb8_described`]).
    fn write_png_described(
        &self,
        path: &Path,
        description: &[(&str, String)],
    ) -> Result<(), SceneError>;
    /// Reads a frame written by [`FrameFiles::write_exr`]: the colour and every layer whose
    /// channels are present (the ray count is not stored: 0).
    fn read_exr(path: &Path) -> Result<Self, SceneError>;
}

impl FrameFiles for Frame {
    fn write_exr_described(
        &self,
        path: &Path,
        description: &[(&str, String)],
    ) -> Result<(), SceneError> {
        use exr::prelude::*;
        check_finite(path, self.width, &self.color)?;
        let mut channels = Vec::new();
        for (k, name) in ["R", "G", "B"].iter().enumerate() {
            let samples = self.color.iter().map(|c| c[k]).collect();
            channels.push(AnyChannel::new(*name, FlatSamples::F32(samples)));
        }
        for (aov, layer) in self.layers() {
            match layer {
                refract_scene::Layer::Vec3(values) => {
                    for (k, axis) in AXES.iter().enumerate() {
                        let samples = values.iter().map(|v| v[k]).collect();
                        channels.push(AnyChannel::new(
                            format!("{}.{axis}", aov.name()).as_str(),
                            FlatSamples::F32(samples),
                        ));
                    }
                }
                refract_scene::Layer::Count(values) => channels.push(AnyChannel::new(
                    aov.name(),
                    FlatSamples::F32(values.iter().map(|&v| v as f32).collect()),
                )),
                refract_scene::Layer::Flag(values) => channels.push(AnyChannel::new(
                    aov.name(),
                    FlatSamples::F32(values.iter().map(|&v| f32::from(u8::from(v))).collect()),
                )),
            }
        }
        let size = (self.width as usize, self.height as usize);
        // Chunks in increasing line order, not in the order parallel compression finishes
        // them: the same frame always gives the same bytes.
        let encoding = Encoding {
            line_order: LineOrder::Increasing,
            ..Encoding::default()
        };
        let mut attributes = LayerAttributes::default();
        let latin1 = |text: &str| {
            let kept: String = text
                .chars()
                .map(|c| if u32::from(c) < 256 { c } else { '?' })
                .collect();
            Text::new_or_none(kept.as_str())
        };
        for (name, text) in description {
            if let (Some(name), Some(text)) = (latin1(name), latin1(text)) {
                attributes.other.insert(name, AttributeValue::Text(text));
            }
        }
        let layer = Layer::new(
            size,
            attributes,
            encoding,
            AnyChannels::sort(channels.into()),
        );
        let image = Image::from_layer(layer);
        write_atomically(path, "the EXR", |w| image.write().to_buffered(w))
    }

    fn write_png_described(
        &self,
        path: &Path,
        description: &[(&str, String)],
    ) -> Result<(), SceneError> {
        check_finite(path, self.width, &self.color)?;
        let pixels: Vec<u8> = self
            .color
            .iter()
            .flat_map(|&c| refract_scene::tonemap::to_srgb8(c))
            .collect();
        write_png_rgb8_described(path, self.width, self.height, &pixels, description)
    }

    fn read_exr(path: &Path) -> Result<Frame, SceneError> {
        use exr::prelude::*;
        let format = |message: String| SceneError::Format {
            path: path.to_owned(),
            message,
        };
        let read_error = |err: exr::error::Error| match err {
            // A missing or unreadable file is an OS error (with its kind), not a format error.
            exr::error::Error::Io(source) => SceneError::Io {
                path: path.to_owned(),
                action: "cannot read the frame file",
                source,
            },
            err => format(format!("not a readable OpenEXR file: {err}")),
        };
        // The header first: a file that declares more pixels than any frame has is refused
        // before its pixels are allocated (issue 54: a 1 KB file declaring 100000² aborted).
        let (w, h) = exr_size(path, read_error)?;
        if w > MAX_FRAME_SIZE || h > MAX_FRAME_SIZE {
            return Err(format(format!(
                "the file declares {w}x{h} pixels; expected a refract frame of at most {MAX_FRAME_SIZE} a side"
            )));
        }
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_file(path)
            .map_err(read_error)?;
        let layer = image.layer_data;
        let (width, height) = (layer.size.width() as u32, layer.size.height() as u32);
        let channel = |name: &str| -> Option<Vec<f32>> {
            layer
                .channel_data
                .list
                .iter()
                .find(|c| c.name.to_string() == name)
                .map(|c| c.sample_data.values_as_f32().collect())
        };
        let mut frame = Self::new(width, height);
        for (k, name) in ["R", "G", "B"].iter().enumerate() {
            let values = channel(name).ok_or_else(|| {
                format(format!(
                    "missing channel `{name}`; expected a refract frame file"
                ))
            })?;
            for (pixel, v) in frame.color.iter_mut().zip(values) {
                pixel[k] = v;
            }
        }
        for aov in Aov::ALL {
            match aov.kind() {
                AovKind::Vec3 => {
                    let axes: Option<Vec<Vec<f32>>> = AXES
                        .iter()
                        .map(|axis| channel(&format!("{}.{axis}", aov.name())))
                        .collect();
                    let Some(axes) = axes else { continue };
                    for (i, v) in frame.vec3_mut(aov).iter_mut().enumerate() {
                        *v = Vec3::new(axes[0][i], axes[1][i], axes[2][i]);
                    }
                }
                AovKind::Count => {
                    let Some(values) = channel(aov.name()) else {
                        continue;
                    };
                    for (c, v) in frame.count_mut(aov).iter_mut().zip(values) {
                        *c = v as u32;
                    }
                }
                AovKind::Flag => {
                    let Some(values) = channel(aov.name()) else {
                        continue;
                    };
                    for (f, v) in frame.flag_mut(aov).iter_mut().zip(values) {
                        *f = v > 0.5;
                    }
                }
            }
        }
        Ok(frame)
    }
}

#[cfg(test)]
mod tests {

    /// Issue 51 #6: a described EXR carries its description as header text attributes and a
    /// described PNG as iTXt chunks, read back by the exr and png crates.
    #[test]
    fn described_files_carry_their_description() {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut frame = Frame::default();
        frame.reset(3, 2);
        let description = [
            ("refract.method", "wyman".to_owned()),
            (
                "refract.device",
                "llvmpipe (LLVM 15, 256 bits) – Vulkan".to_owned(),
            ),
        ];
        let exr_path = dir.path().join("f.exr");
        frame
            .write_exr_described(&exr_path, &description)
            .expect("exr");
        let image = {
            use exr::prelude::ReadChannels as _;
            use exr::prelude::ReadLayers as _;
            exr::prelude::read()
                .no_deep_data()
                .largest_resolution_level()
                .all_channels()
                .first_valid_layer()
                .all_attributes()
                .from_file(&exr_path)
                .expect("read exr")
        };
        let other = &image.layer_data.attributes.other;
        let text = |name: &str| match other.get(&exr::prelude::Text::from(name)) {
            Some(exr::prelude::AttributeValue::Text(t)) => t.to_string(),
            other => panic!("{name}: {other:?}"),
        };
        assert_eq!(text("refract.method"), "wyman");
        // Outside Latin-1 (the en dash) becomes `?`.
        assert_eq!(
            text("refract.device"),
            "llvmpipe (LLVM 15, 256 bits) ? Vulkan"
        );
        let png_path = dir.path().join("f.png");
        frame
            .write_png_described(&png_path, &description)
            .expect("png");
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(&png_path).expect("open"),
        ));
        let reader = decoder.read_info().expect("png info");
        let chunks: Vec<(String, String)> = reader
            .info()
            .utf8_text
            .iter()
            .map(|c| (c.keyword.clone(), c.get_text().expect("utf-8 text")))
            .collect();
        for (keyword, text) in &description {
            assert!(
                chunks.contains(&((*keyword).to_owned(), text.clone())),
                "{chunks:?}"
            );
        }
    }

    use super::*;

    /// Issue 54: an EXR whose header claims 100000² pixels (a file of a few hundred bytes) is
    /// refused with the file's name and the bound, before anything that size is allocated;
    /// it used to abort the process ("memory allocation of 40000000000 bytes failed").
    #[test]
    fn a_header_declaring_a_huge_frame_is_refused_before_allocating() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("huge.exr");
        crate::test_files::write_exr_declaring(&path, 100_000);
        let bytes = std::fs::metadata(&path).expect("size").len();
        assert!(bytes < 2048, "{bytes} bytes");
        let err = Frame::read_exr(&path).expect_err("refused").to_string();
        assert!(
            err.contains("huge.exr") && err.contains("100000x100000") && err.contains("16384"),
            "{err}"
        );
        // A frame within the bound still reads as before.
        let small = dir.path().join("small.exr");
        Frame::new(3, 2).write_exr(&small).expect("write");
        assert_eq!(Frame::read_exr(&small).expect("read").width, 3);
    }

    /// The same frame written twice gives the same bytes (chunks in a fixed order), also when
    /// it has many chunks compressed in parallel.
    #[test]
    fn exr_files_are_byte_identical_between_runs() {
        let mut frame = Frame::new(300, 257);
        for (i, c) in frame.color.iter_mut().enumerate() {
            *c = Vec3::new((i % 7) as f32, (i % 13) as f32 * 0.1, (i as f32).sin());
        }
        frame
            .vec3_mut(Aov::T2)
            .iter_mut()
            .enumerate()
            .for_each(|(i, v)| {
                *v = Vec3::splat((i as f32).cos());
            });
        let dir = tempfile::tempdir().expect("tempdir");
        let bytes: Vec<Vec<u8>> = (0..4)
            .map(|k| {
                let path = dir.path().join(format!("f{k}.exr"));
                frame.write_exr(&path).expect("write");
                std::fs::read(&path).expect("read")
            })
            .collect();
        assert!(bytes.windows(2).all(|w| w[0] == w[1]));
        assert_eq!(
            Frame::read_exr(&dir.path().join("f0.exr"))
                .expect("read")
                .color,
            frame.color
        );
    }

    #[test]
    fn layers_round_trip_through_exr() {
        let mut frame = Frame::new(3, 2);
        frame.color[4] = Vec3::new(0.5, 2.0, 7.0);
        frame.vec3_mut(Aov::T2)[1] = Vec3::new(0.0, 0.6, -0.8);
        frame.flag_mut(Aov::Tir)[5] = true;
        frame.count_mut(Aov::Interfaces)[0] = 2;
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("frame.exr");
        frame.write_exr(&path).expect("write");
        let back = Frame::read_exr(&path).expect("read");
        assert_eq!(back.color, frame.color);
        assert_eq!(
            back.aovs().collect::<Vec<_>>(),
            [Aov::T2, Aov::Interfaces, Aov::Tir]
        );
        assert_eq!(
            back.vec3(Aov::T2).expect("T2")[1],
            Vec3::new(0.0, 0.6, -0.8)
        );
        assert!(back.vec3(Aov::T2).expect("T2")[0].is_nan());
        assert!(back.flag(Aov::Tir).expect("tir")[5]);
        assert_eq!(back.count(Aov::Interfaces).expect("n")[0], 2);
        assert!(back.vec3(Aov::P1).is_none());
    }
}
