//! The opaque objects' surfaces seen from a camera: the nearby-geometry (NG) texture of Wyman
//! 2005b §5 from the NG camera, and the same pass from the eye (the engines' screen texture,
//! the objects drawn over an image-space frame). Its uniform block, the bindings of the
//! kernels that read it, and its WGSL readers (`shaders/object_surfaces.wgsl`).

use glam::UVec2;
use refract_core::Camera;
use refract_core::gpu::{NearbyUniforms, seed_spacing_code};
use refract_core::nearby_geometry::{MAX_PLANES, NearbyLookup, Plane, SeedSpacing};
use refract_scene::DirectionalLight;

use crate::bindings::{storage_entry, texture_entry, uniform_entry};
use crate::passes::outputs::OutputBuffers;
use crate::passes::raster::SurfaceTargets;
use crate::passes::refractor::RefractorTargets;
use crate::scene_buffers::GpuScene;

/// What [`nearby_layout`] binds: the refractor's targets, the environment, six outputs, the
/// materials, the NG (or screen) targets and their uniforms.
pub(crate) fn nearby_resources<'a>(
    refractor: &'a RefractorTargets,
    scene: &'a GpuScene,
    outputs: &'a OutputBuffers,
    ng: &'a SurfaceTargets,
    nearby_uniforms: &'a wgpu::Buffer,
) -> Vec<wgpu::BindingResource<'a>> {
    let mut resources = vec![
        refractor.uniforms.as_entire_binding(),
        wgpu::BindingResource::TextureView(&refractor.front_p1),
        wgpu::BindingResource::TextureView(&refractor.front_n1),
        wgpu::BindingResource::TextureView(&refractor.back),
        scene.environment_texels.as_entire_binding(),
    ];
    resources.extend(outputs.outputs.iter().map(|o| o.as_entire_binding()));
    resources.push(scene.materials.as_entire_binding());
    resources.extend(ng.views.iter().map(wgpu::BindingResource::TextureView));
    resources.push(nearby_uniforms.as_entire_binding());
    resources
}

/// The bindings of `shade_nearby` (and of the engine family's `shade_engine`, which adds its own).
pub(crate) fn nearby_layout() -> Vec<wgpu::BindGroupLayoutEntry> {
    vec![
        uniform_entry(0, wgpu::ShaderStages::COMPUTE),
        texture_entry(1),
        texture_entry(2),
        texture_entry(3),
        storage_entry(4, true),
        storage_entry(5, false),
        storage_entry(6, false),
        storage_entry(7, false),
        storage_entry(8, false),
        storage_entry(9, false),
        storage_entry(10, false),
        storage_entry(11, true),
        texture_entry(12),
        texture_entry(13),
        texture_entry(14),
        uniform_entry(15, wgpu::ShaderStages::COMPUTE),
    ]
}

/// What one frame of a nearby-geometry method needs besides the refractor's camera.
pub(crate) struct NearbyFrame<'a> {
    /// The NG camera (the eye's, widened by the guard band).
    pub ng_camera: &'a Camera,
    /// Guard band in texels.
    pub pad: UVec2,
    /// The planes of the ray-plane and iterative lookups.
    pub planes: &'a [Plane],
    /// The lookup.
    pub lookup: NearbyLookup,
    /// The scene's light.
    pub light: DirectionalLight,
}

impl<'a> NearbyFrame<'a> {
    /// The objects seen from the eye itself, pixel for pixel (no guard band, no lookup): the
    /// engine family's screen texture and the objects the image-space family draws.
    pub(crate) fn eye(camera: &'a Camera, light: DirectionalLight) -> Self {
        Self {
            ng_camera: camera,
            pad: UVec2::ZERO,
            planes: &[],
            lookup: NearbyLookup::KayGreenberg,
            light,
        }
    }
}

/// The uniform block of the lookup.
pub(crate) fn nearby_uniforms(nearby: &NearbyFrame<'_>) -> NearbyUniforms {
    let camera = nearby.ng_camera;
    let mut planes = [[0.0; 4]; MAX_PLANES];
    for (slot, plane) in planes.iter_mut().zip(nearby.planes) {
        *slot = plane.normal.extend(plane.offset).to_array();
    }
    let (iterations, seeds, spacing) = match nearby.lookup {
        NearbyLookup::KayGreenberg | NearbyLookup::RayPlane => (0, 1, SeedSpacing::Screen),
        NearbyLookup::Iterative { iterations } => (iterations, 1, SeedSpacing::Screen),
        NearbyLookup::Seeded {
            iterations,
            seeds,
            spacing,
        } => (iterations, seeds, spacing),
    };
    let light = nearby.light;
    NearbyUniforms {
        world_to_clip: camera.world_to_clip().to_cols_array_2d(),
        eye: camera.eye().extend(1.0).to_array(),
        look_dir: camera.look_dir().extend(0.0).to_array(),
        light_direction: light.direction.extend(0.0).to_array(),
        light_radiance: light.radiance.extend(0.0).to_array(),
        light_ambient: light.ambient.extend(0.0).to_array(),
        planes,
        width: camera.width(),
        height: camera.height(),
        pad_x: nearby.pad.x,
        pad_y: nearby.pad.y,
        plane_count: nearby.planes.len().min(MAX_PLANES) as u32,
        iterations,
        seeds,
        spacing: seed_spacing_code(spacing),
    }
}
