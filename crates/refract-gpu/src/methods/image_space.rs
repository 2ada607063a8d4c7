//! Wyman 2005a image-space refraction on the GPU (methods `single`, `wyman`, `wyman-dv`,
//! `wyman-dn`): the back faces and front faces rasterised into float targets, then the kernel as
//! a compute pass (`shaders/image_space.wgsl`), one pipeline per method (`shade_single`, and
//! `shade_two_interface` with `DISTANCE_MODE` fixed per pipeline); in a scene with opaque
//! objects, the objects drawn over the frame where they are the nearest surface
//! ([`super::objects_over_frame`]); readback into a [`refract_scene::Frame`] with the method's
//! AOV layers.

use glam::Vec3;
use refract_core::BackSurface;
use refract_core::gpu::{
    COVERAGE_BACKGROUND, COVERAGE_DEGENERATE, FrameUniforms, distance_mode_code,
    exit_normal_source_code, exit_normal_source_from_code,
};
use refract_scene::{
    Aov, Frame, FrameOutputs, ImageSpaceMethod, LayerValue, MethodId, PixelLayers, RenderError,
};

use crate::bindings::{bind_group, storage_entry, texture_entry, uniform_entry};
use crate::context::{GpuContext, GpuError};
use crate::family::{GpuFamily, GpuFrameCx};
use crate::frame_uniforms::frame_uniforms;
use crate::methods::MethodPipelines;
use crate::methods::objects_over_frame::{ObjectPipelines, ObjectTargets};
use crate::passes::raster::{
    DEPTH_FORMAT, RasterKind, RasterPass, RasterPipelines, TARGET_FORMAT, target,
};
use crate::scene_buffers::GpuScene;
use crate::shaders::{
    CORE, ENVIRONMENT, FRAME, IMAGE_SPACE, PROCEDURAL_SKY, ShaderModule, TWO_INTERFACE,
};

/// The module of the image-space kernels (Wyman 2005a).
pub(crate) const SHADER: ShaderModule = ShaderModule {
    name: "image_space",
    files: &[
        CORE,
        PROCEDURAL_SKY,
        FRAME,
        ENVIRONMENT,
        TWO_INTERFACE,
        IMAGE_SPACE,
    ],
};

impl GpuFamily for ImageSpacePipelines {
    type Params = ImageSpaceMethod;
    type Targets = ImageSpaceTargets;
    const LABEL: &'static str = "image-space frame";

    fn create(device: &wgpu::Device, _raster: &RasterPipelines) -> Self {
        Self::new(device)
    }

    fn fits(&self, targets: &ImageSpaceTargets, cx: &GpuFrameCx<'_>, _: &ImageSpaceMethod) -> bool {
        let (width, height) = cx.size();
        targets.fits(width, height)
    }

    fn allocate(
        &self,
        cx: &GpuFrameCx<'_>,
        _: &ImageSpaceMethod,
    ) -> Result<ImageSpaceTargets, GpuError> {
        let (width, height) = cx.size();
        let mut targets =
            ImageSpaceTargets::new(cx.context, cx.raster, self, cx.gpu_scene, width, height)?;
        if !cx.scene.objects.is_empty() {
            let objects = cx.context.checked(|| {
                ObjectTargets::allocate(cx, &self.objects, &targets.refractor, &targets.outputs)
            })?;
            targets.objects = Some(objects);
        }
        Ok(targets)
    }

    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        kernel: &ImageSpaceMethod,
        targets: &mut ImageSpaceTargets,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), RenderError> {
        let params = kernel.kernel(cx.scene.refractor.ior())?;
        let uniforms = frame_uniforms(
            cx.camera,
            &cx.gpu_scene.environment,
            params.ior(),
            params.tir_policy,
        );
        targets.encode(cx, self, &uniforms, kernel, encoder);
        Ok(())
    }

    fn color<'t>(&self, targets: &'t Self::Targets) -> &'t wgpu::Buffer {
        &targets.outputs.outputs[0]
    }

    fn read(
        &self,
        cx: &GpuFrameCx<'_>,
        targets: &ImageSpaceTargets,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        targets.read(cx.context, cx.method, cx.outputs, frame)
    }
}

/// The kernel pipelines: `shade_single` and `shade_two_interface` (`DISTANCE_MODE` fixed per
/// method); the objects' pass.
pub(crate) struct ImageSpacePipelines {
    kernels: MethodPipelines,
    objects: ObjectPipelines,
}

impl ImageSpacePipelines {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let kernels = MethodPipelines::new(
            device,
            &SHADER,
            &[
                uniform_entry(0, wgpu::ShaderStages::COMPUTE),
                texture_entry(1),
                texture_entry(2),
                texture_entry(3),
                storage_entry(4, true),
                storage_entry(5, false),
                storage_entry(6, false),
                storage_entry(7, false),
                storage_entry(8, false),
            ],
            |method: &ImageSpaceMethod| match method {
                ImageSpaceMethod::Single => ("shade_single", Vec::new()),
                ImageSpaceMethod::TwoInterface(p) => (
                    "shade_two_interface",
                    vec![("DISTANCE_MODE", f64::from(distance_mode_code(p.distance)))],
                ),
            },
        );
        Self {
            kernels,
            objects: ObjectPipelines::new(device),
        }
    }
}

/// The refractor's passes of one resolution (Wyman 2005a §4): the frame uniforms, the back-face
/// target, the front-face targets and their depth buffer; shared by the image-space and the
/// nearby-geometry methods.
pub(crate) struct RefractorTargets {
    pub uniforms: wgpu::Buffer,
    raster_group: wgpu::BindGroup,
    pub back: wgpu::TextureView,
    pub front_p1: wgpu::TextureView,
    pub front_n1: wgpu::TextureView,
    depth: wgpu::TextureView,
}

impl RefractorTargets {
    pub(crate) fn allocate(
        device: &wgpu::Device,
        raster: &RasterPipelines,
        width: u32,
        height: u32,
    ) -> Self {
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame uniforms"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let raster_group = bind_group(
            device,
            "raster",
            &raster.layout,
            &[uniforms.as_entire_binding()],
        );
        let view = |label, format| {
            target(device, label, width, height, format)
                .create_view(&wgpu::TextureViewDescriptor::default())
        };
        Self {
            back: view("back faces", TARGET_FORMAT),
            front_p1: view("front P1, d_N", TARGET_FORMAT),
            front_n1: view("front N1", TARGET_FORMAT),
            depth: view("depth", DEPTH_FORMAT),
            uniforms,
            raster_group,
        }
    }

    /// Writes the uniforms and encodes the back faces (when `back` is given) and the front
    /// faces; the first pass writes the frame's start timestamp.
    pub(crate) fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        uniforms: &FrameUniforms,
        back: Option<BackSurface>,
        encoder: &mut wgpu::CommandEncoder,
    ) {
        let GpuFrameCx {
            context,
            raster,
            gpu_scene: scene,
            camera,
            timestamps,
            ..
        } = *cx;
        context
            .queue
            .write_buffer(&self.uniforms, 0, bytemuck::bytes_of(uniforms));
        if let Some(back) = back {
            raster.encode(
                encoder,
                &RasterPass {
                    kind: RasterKind::BackFaces(back),
                    camera,
                    uniforms: &self.raster_group,
                    peel: None,
                    meshes: &[&scene.refractor],
                    targets: &[&self.back],
                    depth: &self.depth,
                },
                timestamps.and_then(|t| t.render_pass("back faces")),
            );
        }
        raster.encode(
            encoder,
            &RasterPass {
                kind: RasterKind::FrontFaces,
                camera,
                uniforms: &self.raster_group,
                peel: None,
                meshes: &[&scene.refractor],
                targets: &[&self.front_p1, &self.front_n1],
                depth: &self.depth,
            },
            timestamps.and_then(|t| t.render_pass("front faces")),
        );
    }
}

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

/// The targets and buffers of image-space frames at one resolution, allocated once and reused
/// for every camera and method at that size.
pub(crate) struct ImageSpaceTargets {
    width: u32,
    height: u32,
    refractor: RefractorTargets,
    shade_group: wgpu::BindGroup,
    /// Colour (w: coverage code), T2 (w: TIR), P~2 (w: exit-normal code), N2 (w: valid).
    outputs: OutputBuffers,
    /// The opaque objects' pass (`None` for a scene without objects).
    objects: Option<ObjectTargets>,
}

impl ImageSpaceTargets {
    /// Allocates the targets for `width × height`, checking the adapter's limits.
    pub(crate) fn new(
        context: &GpuContext,
        raster: &RasterPipelines,
        pipelines: &ImageSpacePipelines,
        scene: &GpuScene,
        width: u32,
        height: u32,
    ) -> Result<Self, GpuError> {
        check_limits(context, width, height)?;
        context.checked(|| Self::allocate(&context.device, raster, pipelines, scene, width, height))
    }

    fn allocate(
        device: &wgpu::Device,
        raster: &RasterPipelines,
        pipelines: &ImageSpacePipelines,
        scene: &GpuScene,
        width: u32,
        height: u32,
    ) -> Self {
        let refractor = RefractorTargets::allocate(device, raster, width, height);
        let outputs = OutputBuffers::new(
            device,
            &["colour", "T2", "P2", "N2"],
            u64::from(width) * u64::from(height),
        );
        let shade_group = bind_group(
            device,
            "image space",
            &pipelines.kernels.layout,
            &[
                refractor.uniforms.as_entire_binding(),
                wgpu::BindingResource::TextureView(&refractor.front_p1),
                wgpu::BindingResource::TextureView(&refractor.front_n1),
                wgpu::BindingResource::TextureView(&refractor.back),
                scene.environment_texels.as_entire_binding(),
                outputs.outputs[0].as_entire_binding(),
                outputs.outputs[1].as_entire_binding(),
                outputs.outputs[2].as_entire_binding(),
                outputs.outputs[3].as_entire_binding(),
            ],
        );
        Self {
            width,
            height,
            refractor,
            shade_group,
            outputs,
            objects: None,
        }
    }

    /// Whether these targets are for `width × height`.
    pub(crate) fn fits(&self, width: u32, height: u32) -> bool {
        (self.width, self.height) == (width, height)
    }

    /// Encodes every per-frame pass (back faces for two interfaces, front faces, the kernel, the
    /// objects where the scene has any) and the copies of the outputs to the readback buffers.
    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        pipelines: &ImageSpacePipelines,
        uniforms: &FrameUniforms,
        kernel: &ImageSpaceMethod,
        encoder: &mut wgpu::CommandEncoder,
    ) {
        let GpuFrameCx {
            method: id,
            outputs,
            timestamps,
            ..
        } = *cx;
        let back = match kernel {
            ImageSpaceMethod::TwoInterface(p) => Some(p.back),
            ImageSpaceMethod::Single => None,
        };
        self.refractor.encode(cx, uniforms, back, encoder);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("image-space kernel"),
                timestamp_writes: timestamps.and_then(|t| t.compute_pass("image-space kernel")),
            });
            pass.set_pipeline(pipelines.kernels.get(id, outputs));
            pass.set_bind_group(0, &self.shade_group, &[]);
            pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
        }
        if let Some(objects) = &self.objects {
            objects.encode(cx, &pipelines.objects, uniforms, encoder);
        }
        if let Some(timestamps) = timestamps {
            timestamps.resolve(encoder);
        }
        let copies = match outputs {
            FrameOutputs::ColorAndAovs => 4,
            FrameOutputs::Color => 1,
        };
        if cx.readback {
            self.outputs.copy(encoder, copies);
        }
    }

    /// Reads the outputs of the last submitted frame into `frame`: the colour and, with
    /// [`FrameOutputs::ColorAndAovs`], the layers of `method`'s registry row. Degenerate pixels
    /// (coverage code [`COVERAGE_DEGENERATE`]) have NaN vectors, as on the CPU.
    pub(crate) fn read(
        &self,
        context: &GpuContext,
        method: MethodId,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let color = self.outputs.read(context, 0)?;
        frame.resize_for_overwrite(self.width, self.height);
        for (out, c) in frame.color.iter_mut().zip(&color) {
            *out = Vec3::new(c[0], c[1], c[2]);
        }
        if outputs == FrameOutputs::Color {
            return Ok(());
        }
        let (t2, p2, n2) = (
            self.outputs.read(context, 1)?,
            self.outputs.read(context, 2)?,
            self.outputs.read(context, 3)?,
        );
        let pixels: Vec<DecodedPixel> = (0..frame.pixel_count())
            .map(|i| DecodedPixel::new(color[i], t2[i], p2[i], n2[i]))
            .collect();
        frame.write_row_layers(method, &pixels)?;
        Ok(())
    }
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
