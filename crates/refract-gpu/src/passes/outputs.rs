//! What a kernel writes and how it is read back: storage buffers of 16 bytes a pixel with
//! their readback twins, the adapter's limits for them, and the decoding of the image-space
//! outputs shared by the families built on them.

use glam::Vec3;
use refract_core::gpu::{
    COVERAGE_BACKGROUND, COVERAGE_DEGENERATE, exit_normal_source_code, exit_normal_source_from_code,
};
use refract_scene::{Aov, LayerValue, PixelLayers};

use crate::context::{GpuContext, GpuError};

/// Storage buffers the kernel writes (16 bytes a pixel each) and their readback twins.
pub(crate) struct OutputBuffers {
    pub outputs: Vec<wgpu::Buffer>,
    readback: Vec<wgpu::Buffer>,
}

impl OutputBuffers {
    pub(crate) fn new(device: &wgpu::Device, labels: &[&str], pixels: u64) -> Self {
        let buffer = |label: &str, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: pixels * 16,
                usage,
                mapped_at_creation: false,
            })
        };
        Self {
            outputs: labels
                .iter()
                .map(|l| {
                    buffer(
                        l,
                        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                    )
                })
                .collect(),
            readback: labels
                .iter()
                .map(|l| {
                    buffer(
                        &format!("{l} readback"),
                        wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    )
                })
                .collect(),
        }
    }

    /// Copies the first `count` outputs to their readback buffers.
    pub(crate) fn copy(&self, encoder: &mut wgpu::CommandEncoder, count: usize) {
        for (output, readback) in self.outputs.iter().zip(&self.readback).take(count) {
            encoder.copy_buffer_to_buffer(output, 0, readback, 0, output.size());
        }
    }

    /// Output `i` of the last submitted frame.
    pub(crate) fn read(&self, context: &GpuContext, i: usize) -> Result<Vec<[f32; 4]>, GpuError> {
        Ok(bytemuck::cast_slice::<u8, [f32; 4]>(&context.read_buffer(&self.readback[i])?).to_vec())
    }
}

/// Checks that `width × height` targets and 16-byte-per-pixel storage buffers fit the adapter.
pub(crate) fn check_limits(context: &GpuContext, width: u32, height: u32) -> Result<(), GpuError> {
    let limits = context.device.limits();
    let too_large = |limit: String| GpuError::ResolutionTooLarge {
        width,
        height,
        adapter: context.info.name.clone(),
        limit,
    };
    if width > limits.max_texture_dimension_2d || height > limits.max_texture_dimension_2d {
        return Err(too_large(format!(
            "max texture dimension {}",
            limits.max_texture_dimension_2d
        )));
    }
    let bytes = u64::from(width) * u64::from(height) * 16;
    if bytes > limits.max_storage_buffer_binding_size || bytes > limits.max_buffer_size {
        return Err(too_large(format!(
            "max storage buffer binding {} bytes",
            limits.max_storage_buffer_binding_size
        )));
    }
    Ok(())
}

/// One pixel of the kernel's outputs, decoded with the shared codes
/// (`refract_core::gpu::COVERAGE_*`, [`exit_normal_source_from_code`]) into what the CPU
/// backend writes: NaN vectors where there is no path (background and degenerate pixels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DecodedPixel {
    pub covered: bool,
    pub t2: Vec3,
    pub p2: Vec3,
    pub n2: Vec3,
    pub n2_source: Option<refract_core::ExitNormalSource>,
    pub tir: bool,
}

impl PixelLayers for DecodedPixel {
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        Some(match aov {
            Aov::Covered => LayerValue::Flag(self.covered),
            Aov::Tir => LayerValue::Flag(self.tir),
            Aov::T2 => LayerValue::Vec3(self.t2),
            Aov::P2 => LayerValue::Vec3(self.p2),
            Aov::N2 => LayerValue::Vec3(self.n2),
            Aov::ExitNormalSource => {
                LayerValue::Count(self.n2_source.map_or(0, exit_normal_source_code))
            }
            _ => return None,
        })
    }
}

impl DecodedPixel {
    /// `color.w`: coverage code; `t2.w`: TIR; `p2.w`: exit-normal code; `n2.w`: N2 valid.
    pub(crate) fn new(color: [f32; 4], t2: [f32; 4], p2: [f32; 4], n2: [f32; 4]) -> Self {
        let code = color[3].round() as u32;
        let path = !matches!(code, COVERAGE_BACKGROUND | COVERAGE_DEGENERATE);
        let xyz = |v: [f32; 4], valid: bool| {
            if valid {
                Vec3::new(v[0], v[1], v[2])
            } else {
                Vec3::NAN
            }
        };
        let n2_source = exit_normal_source_from_code(p2[3].round() as u32).filter(|_| path);
        Self {
            covered: code != COVERAGE_BACKGROUND,
            t2: xyz(t2, path),
            p2: xyz(p2, n2_source.is_some()),
            n2: xyz(n2, path && n2[3] > 0.5),
            n2_source,
            tir: path && t2[3] > 0.5,
        }
    }
}

#[cfg(test)]
mod tests {
    use refract_core::ExitNormalSource;
    use refract_core::gpu::COVERAGE_PATH;

    use super::*;

    /// A degenerate pixel (the shader writes `COVERAGE_DEGENERATE` and zero vectors) reads back
    /// as the CPU backend writes it: covered, NaN vectors, no exit normal, no TIR. Before the
    /// shared codes the GPU's zero T2 came back as a direction.
    #[test]
    fn degenerate_pixels_decode_like_the_cpu_backend() {
        let zero = [0.0; 4];
        let degenerate = DecodedPixel::new(
            [0.0, 0.0, 0.0, COVERAGE_DEGENERATE as f32],
            zero,
            zero,
            zero,
        );
        assert!(degenerate.covered && !degenerate.tir && degenerate.n2_source.is_none());
        assert!(degenerate.t2.is_nan() && degenerate.p2.is_nan() && degenerate.n2.is_nan());
        let background = DecodedPixel::new(zero, zero, zero, zero);
        assert!(!background.covered && background.t2.is_nan());
        let source = exit_normal_source_code(ExitNormalSource::SilhouetteFallback) as f32;
        let path = DecodedPixel::new(
            [0.5, 0.5, 0.5, COVERAGE_PATH as f32],
            [0.0, 0.0, -1.0, 1.0],
            [0.1, 0.2, 0.3, source],
            [0.0, 1.0, 0.0, 1.0],
        );
        assert!(path.covered && path.tir);
        assert_eq!(path.n2_source, Some(ExitNormalSource::SilhouetteFallback));
        assert_eq!(
            (path.t2, path.p2, path.n2),
            (Vec3::NEG_Z, Vec3::new(0.1, 0.2, 0.3), Vec3::Y)
        );
    }
}
