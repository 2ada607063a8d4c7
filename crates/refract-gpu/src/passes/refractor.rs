//! The refractor's passes of one resolution (Wyman 2005a §4): its back faces and front faces
//! rasterised into float targets, read by the image-space, nearby-geometry and engine kernels.

use refract_core::BackSurface;
use refract_core::gpu::FrameUniforms;

use crate::bindings::bind_group;
use crate::family::GpuFrameCx;
use crate::passes::raster::{
    DEPTH_FORMAT, RasterKind, RasterPass, RasterPipelines, TARGET_FORMAT, target,
};

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
    /// faces of the first refractor, or of every refractor with `all_refractors` (the nearest
    /// per pixel; `front_n1.w` = 1 + its index); the first pass writes the frame's start
    /// timestamp.
    pub(crate) fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        uniforms: &FrameUniforms,
        back: Option<BackSurface>,
        all_refractors: bool,
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
        let mut meshes = vec![&scene.refractor];
        if all_refractors {
            meshes.extend(&scene.other_refractors);
        }
        raster.encode(
            encoder,
            &RasterPass {
                kind: RasterKind::FrontFaces,
                camera,
                uniforms: &self.raster_group,
                peel: None,
                meshes: &meshes,
                targets: &[&self.front_p1, &self.front_n1],
                depth: &self.depth,
            },
            timestamps.and_then(|t| t.render_pass("front faces")),
        );
    }
}
