//! Wyman 2005a image-space refraction on the GPU (methods `single`, `wyman`, `wyman-dv`,
//! `wyman-dn`): the back faces and front faces rasterised into float targets, then the kernel as
//! a compute pass (`shaders/image_space.wgsl`), one pipeline per method (`shade_single`, and
//! `shade_two_interface` with `DISTANCE_MODE` fixed per pipeline); in a scene with opaque
//! objects, the objects drawn over the frame where they are the nearest surface
//! ([`super::objects_over_frame`]); readback into a [`refract_scene::Frame`] with the method's
//! AOV layers.

use glam::Vec3;
use refract_core::gpu::{FrameUniforms, distance_mode_code};
use refract_scene::{Frame, FrameOutputs, ImageSpaceMethod, MethodId, RenderError};

use crate::bindings::{bind_group, storage_entry, texture_entry, uniform_entry};
use crate::context::{GpuContext, GpuError};
use crate::family::{GpuFamily, GpuFrameCx};
use crate::frame_uniforms::frame_uniforms;
use crate::passes::objects_over_frame::{ObjectPipelines, ObjectTargets};
use crate::passes::outputs::{DecodedPixel, OutputBuffers, check_limits};
use crate::passes::pipelines::MethodPipelines;
use crate::passes::raster::RasterPipelines;
use crate::passes::refractor::RefractorTargets;
use crate::scene_buffers::GpuScene;
use crate::shaders::{
    CORE, ENVIRONMENT, FRAME, IMAGE_SPACE, PROCEDURAL_SKY, ShaderModule, TWO_INTERFACE,
};

/// The family's modules (its conformance is in the shared harness).
pub(crate) const SHADERS: &[ShaderModule] = &[SHADER];

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
        let params = kernel.kernel(cx.ior(&cx.scene.refractor))?;
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
                ImageSpaceMethod::Single(_) => ("shade_single", Vec::new()),
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
            ImageSpaceMethod::Single(_) => None,
        };
        self.refractor.encode(cx, uniforms, back, false, encoder);
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
