//! Rasterising any mesh of the scene from any camera on the GPU (the twin of
//! `refract_cpu::surfaces`): the nearest front faces with (P, scalar), (N, 1), (uv, object, 1)
//! in three float targets, read back per pixel.

use glam::{Vec2, Vec3};
use refract_core::Camera;
use refract_core::TirPolicy;
use refract_scene::SurfaceTexel;

use crate::bindings::bind_group;
use crate::context::{GpuContext, GpuError};
use crate::frame_uniforms::frame_uniforms;
use crate::passes::raster::{
    DEPTH_FORMAT, RasterKind, RasterPass, RasterPipelines, TARGET_FORMAT, target,
};
use crate::scene_buffers::{GpuMesh, GpuScene};

/// Texture rows are copied to buffers in multiples of this many bytes.
const ROW_ALIGNMENT: u32 = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;

/// Draws `mesh` seen by `camera` and reads the surface back, row-major from the top.
pub(crate) fn rasterize_surface(
    context: &GpuContext,
    raster: &RasterPipelines,
    scene: &GpuScene,
    mesh: &GpuMesh,
    camera: &Camera,
) -> Result<Vec<Option<SurfaceTexel>>, GpuError> {
    let device = &context.device;
    let (width, height) = (camera.width(), camera.height());
    let limit = device.limits().max_texture_dimension_2d;
    if width > limit || height > limit {
        return Err(GpuError::ResolutionTooLarge {
            width,
            height,
            adapter: context.info.name.clone(),
            limit: format!("max texture dimension {limit}"),
        });
    }
    let uniforms = frame_uniforms(camera, &scene.environment, 1.0, TirPolicy::default());
    let (textures, buffers, bytes_per_row) = context.checked(|| {
        let uniform_buffer = wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("surface uniforms"),
                contents: bytemuck::bytes_of(&uniforms),
                usage: wgpu::BufferUsages::UNIFORM,
            },
        );
        let group = bind_group(
            device,
            "surface",
            &raster.layout,
            &[uniform_buffer.as_entire_binding()],
        );
        let textures = ["P, scalar", "N", "uv, object"]
            .map(|label| target(device, label, width, height, TARGET_FORMAT));
        let views = textures
            .each_ref()
            .map(|t| t.create_view(&wgpu::TextureViewDescriptor::default()));
        let depth = target(device, "surface depth", width, height, DEPTH_FORMAT)
            .create_view(&wgpu::TextureViewDescriptor::default());
        let bytes_per_row = (width * 16).div_ceil(ROW_ALIGNMENT) * ROW_ALIGNMENT;
        let buffers = ["P readback", "N readback", "uv readback"].map(|label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: u64::from(bytes_per_row) * u64::from(height),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("surface"),
        });
        raster.encode(
            &mut encoder,
            &RasterPass {
                kind: RasterKind::Surface,
                camera,
                uniforms: &group,
                peel: None,
                meshes: &[mesh],
                targets: &[&views[0], &views[1], &views[2]],
                depth: &depth,
            },
            None,
        );
        for (texture, buffer) in textures.iter().zip(&buffers) {
            encoder.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(bytes_per_row),
                        rows_per_image: Some(height),
                    },
                },
                wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
            );
        }
        context.queue.submit([encoder.finish()]);
        (textures, buffers, bytes_per_row)
    })?;
    drop(textures);
    let mut planes = Vec::with_capacity(3);
    for buffer in &buffers {
        let bytes = context.read_buffer(buffer)?;
        let texels: Vec<[f32; 4]> = bytes
            .chunks_exact(bytes_per_row as usize)
            .flat_map(|row| {
                bytemuck::cast_slice::<u8, [f32; 4]>(&row[..width as usize * 16]).to_vec()
            })
            .collect();
        planes.push(texels);
    }
    let (p, n, uv) = (&planes[0], &planes[1], &planes[2]);
    Ok((0..(width * height) as usize)
        .map(|i| {
            (n[i][3] >= 0.5).then(|| SurfaceTexel {
                p_ws: Vec3::new(p[i][0], p[i][1], p[i][2]),
                n_ws: Vec3::new(n[i][0], n[i][1], n[i][2]),
                uv: Vec2::new(uv[i][0], uv[i][1]),
                object: uv[i][2].round() as u32,
            })
        })
        .collect())
}
