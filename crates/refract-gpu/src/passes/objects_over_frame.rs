//! The opaque objects over an image-space frame (`single`, `wyman`, `wyman-dv`, `wyman-dn`):
//! the objects' surface pass from the eye (the engine family's screen targets), then
//! `draw_objects` of `objects_over_frame.wgsl` (beside this module) as a compute pass after the kernel, writing each
//! pixel whose nearest surface is an object. Scenes without objects skip both. The twin of the
//! CPU backend's `ShadeContext::object`.

use refract_core::gpu::{FrameUniforms, NearbyUniforms};
use refract_scene::FrameOutputs;

use crate::bindings::{bind_group_at, storage_entry, texture_entry, uniform_entry};
use crate::family::GpuFrameCx;
use crate::passes::object_surfaces::{NearbyFrame, nearby_uniforms};
use crate::passes::outputs::OutputBuffers;
use crate::passes::pipelines::PipelineCompiler;
use crate::passes::raster::SurfaceTargets;
use crate::passes::refractor::RefractorTargets;
use crate::shaders::{
    CORE, ENVIRONMENT, FRAME, IMAGE_SPACE, MATERIALS, OBJECT_SURFACES, OBJECT_TEXTURE,
    PROCEDURAL_SKY, ShaderModule, TWO_INTERFACE,
};

/// The module of `draw_objects`: the image-space shader's front-face readers and outputs, the
/// nearby-geometry shader's surface readers.
pub(crate) const SHADER: ShaderModule = ShaderModule {
    name: "objects",
    files: &[
        CORE,
        PROCEDURAL_SKY,
        FRAME,
        ENVIRONMENT,
        TWO_INTERFACE,
        IMAGE_SPACE,
        MATERIALS,
        OBJECT_SURFACES,
        OBJECT_TEXTURE,
        (
            "objects_over_frame.wgsl",
            include_str!("objects_over_frame.wgsl"),
        ),
    ],
};

/// The bindings `draw_objects` reads and writes (numbered as in the image-space and
/// nearby-geometry shaders it shares).
const BINDINGS: [u32; 12] = [0, 1, 2, 5, 6, 7, 8, 11, 12, 13, 14, 15];

/// The `draw_objects` pipelines, with and without AOV stores.
pub(crate) struct ObjectPipelines {
    layout: wgpu::BindGroupLayout,
    with_aovs: wgpu::ComputePipeline,
    colour_only: wgpu::ComputePipeline,
}

impl ObjectPipelines {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let entries = BINDINGS.map(|b| match b {
            0 | 15 => uniform_entry(b, wgpu::ShaderStages::COMPUTE),
            1 | 2 | 12 | 13 | 14 => texture_entry(b),
            11 => storage_entry(b, true),
            _ => storage_entry(b, false),
        });
        let compiler = PipelineCompiler::new(device, &SHADER, &entries);
        let compile = |outputs| {
            compiler.compile(
                &format!("draw objects ({outputs:?})"),
                "draw_objects",
                outputs,
                &[],
            )
        };
        let (with_aovs, colour_only) = (
            compile(FrameOutputs::ColorAndAovs),
            compile(FrameOutputs::Color),
        );
        Self {
            layout: compiler.layout,
            with_aovs,
            colour_only,
        }
    }
}

/// The objects' targets of one resolution: their surface from the eye, its uniforms, the bind
/// group over the frame's refractor targets and outputs.
pub(crate) struct ObjectTargets {
    surface: SurfaceTargets,
    uniforms: wgpu::Buffer,
    group: wgpu::BindGroup,
}

impl ObjectTargets {
    pub(crate) fn allocate(
        cx: &GpuFrameCx<'_>,
        pipelines: &ObjectPipelines,
        refractor: &RefractorTargets,
        outputs: &OutputBuffers,
    ) -> Self {
        let device = &cx.context.device;
        let (width, height) = cx.size();
        let surface = SurfaceTargets::new(device, cx.raster, "objects", width, height);
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("objects uniforms"),
            size: std::mem::size_of::<NearbyUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let texture = wgpu::BindingResource::TextureView;
        let mut resources = vec![
            (0, refractor.uniforms.as_entire_binding()),
            (1, texture(&refractor.front_p1)),
            (2, texture(&refractor.front_n1)),
        ];
        resources.extend((5..).zip(outputs.outputs.iter().map(|o| o.as_entire_binding())));
        resources.push((11, cx.gpu_scene.materials.as_entire_binding()));
        resources.extend((12..).zip(surface.views.iter().map(texture)));
        resources.push((15, uniforms.as_entire_binding()));
        let group = bind_group_at(device, "objects", &pipelines.layout, &resources);
        Self {
            surface,
            uniforms,
            group,
        }
    }

    /// Encodes the objects' surface pass from the eye (before or after the refractor's passes)
    /// and `draw_objects` over the kernel's outputs; `timestamps` marks the frame's end here.
    pub(crate) fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        pipelines: &ObjectPipelines,
        uniforms: &FrameUniforms,
        encoder: &mut wgpu::CommandEncoder,
    ) {
        let eye = NearbyFrame::eye(cx.camera, cx.scene.light);
        cx.context.queue.write_buffer(
            &self.uniforms,
            0,
            bytemuck::bytes_of(&nearby_uniforms(&eye)),
        );
        let objects: Vec<_> = cx.gpu_scene.objects.iter().collect();
        self.surface.encode(
            &cx.context.queue,
            cx.raster,
            encoder,
            cx.camera,
            uniforms,
            &objects,
            cx.timestamps.and_then(|t| t.render_pass("object surfaces")),
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("draw objects"),
            timestamp_writes: cx.timestamps.and_then(|t| t.compute_pass("objects")),
        });
        pass.set_pipeline(match cx.outputs {
            FrameOutputs::ColorAndAovs => &pipelines.with_aovs,
            FrameOutputs::Color => &pipelines.colour_only,
        });
        pass.set_bind_group(0, &self.group, &[]);
        let (width, height) = cx.size();
        pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
    }
}
