//! A scene uploaded to the GPU once: every mesh as a vertex + index buffer (position, normal,
//! one scalar such as `d_N`, uv and object id per vertex), and the environment.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use refract_core::gpu::{ENVIRONMENT_CONSTANT, ENVIRONMENT_LATLONG, ENVIRONMENT_PROCEDURAL};
use refract_geometry::Mesh;
use refract_scene::{Albedo, Environment, Material, Object, Scene};
use wgpu::util::DeviceExt;

/// One vertex as the raster pass reads it (`shaders/raster.wgsl`, `VertexIn`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct Vertex {
    pub p_ws: [f32; 3],
    pub n_ws: [f32; 3],
    /// `d_N` for the refractor, 0 elsewhere.
    pub scalar: f32,
    /// Texture coordinates (0 for meshes without).
    pub uv: [f32; 2],
    /// Which mesh of the scene: 0 the refractor, `1 + k` opaque object `k`; for the other
    /// refractors ([`GpuScene::other_refractors`]), their index `k ≥ 1` among the refractors.
    pub object: u32,
}

const _: () = assert!(core::mem::size_of::<Vertex>() == 40);

impl Vertex {
    /// The vertex buffer layout of [`Vertex`] (locations 0–4).
    pub(crate) const ATTRIBUTES: [wgpu::VertexAttribute; 5] = wgpu::vertex_attr_array![
        0 => Float32x3, 1 => Float32x3, 2 => Float32, 3 => Float32x2, 4 => Uint32
    ];
}

/// One mesh on the GPU.
pub(crate) struct GpuMesh {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub index_count: u32,
}

impl GpuMesh {
    /// Uploads `mesh` with one scalar per vertex (`scalars` empty: 0) and its object id.
    pub(crate) fn new(
        device: &wgpu::Device,
        label: &str,
        mesh: &Mesh,
        scalars: &[f32],
        object: u32,
    ) -> Self {
        let vertices: Vec<Vertex> = (0..mesh.positions.len())
            .map(|i| Vertex {
                p_ws: mesh.positions[i].to_array(),
                n_ws: mesh.normals[i].to_array(),
                scalar: scalars.get(i).copied().unwrap_or(0.0),
                uv: mesh.uvs.get(i).map_or([0.0; 2], |uv| uv.to_array()),
                object,
            })
            .collect();
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        Self {
            vertices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(&format!("{label} vertices")),
                contents: bytemuck::cast_slice(&vertices),
                usage: wgpu::BufferUsages::VERTEX,
            }),
            index_count: indices.len() as u32,
            indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(&format!("{label} indices")),
                contents: bytemuck::cast_slice(&indices),
                usage: wgpu::BufferUsages::INDEX,
            }),
        }
    }

    /// Draws the whole mesh in `pass` (pipeline and bind groups set by the caller).
    pub(crate) fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }
}

/// How the shading pass looks the environment up (the uniforms' environment fields).
#[derive(Clone, Copy, Debug)]
pub(crate) struct EnvironmentUniforms {
    pub kind: u32,
    pub width: u32,
    pub height: u32,
    pub intensity: f32,
    pub constant: [f32; 4],
}

/// An opaque object's material as `shaders/object_texture.wgsl` reads it (`struct Material`):
/// the twin of [`refract_scene::Albedo`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(crate) struct GpuMaterial {
    pub a: [f32; 4],
    pub b: [f32; 4],
    /// 0 constant, 1 checker, 2 colour chart, 3 wood, 4 conductor (`a` = `F_p` per channel).
    pub kind: u32,
    /// 1: the mesh has no uvs, world `(x, z)` stand in.
    pub world_uv: u32,
    /// Checker squares per unit, or wood rings.
    pub squares: f32,
    pub _padding: u32,
}

const _: () = assert!(core::mem::size_of::<GpuMaterial>() == 48);

impl GpuMaterial {
    fn new(object: &Object) -> Self {
        let v = |c: Vec3| c.extend(0.0).to_array();
        let (kind, a, b, squares) = match &object.material {
            Material::Diffuse(Albedo::Constant(c)) => (0, v(*c), [0.0; 4], 0.0),
            Material::Diffuse(Albedo::Checker { a, b, squares }) => (1, v(*a), v(*b), *squares),
            Material::Diffuse(Albedo::ColorChart) => (2, [0.0; 4], [0.0; 4], 0.0),
            Material::Diffuse(Albedo::Wood { light, dark, rings }) => {
                (3, v(*light), v(*dark), *rings)
            }
            Material::Conductor(c) => (4, v(c.f0()), [0.0; 4], 0.0),
        };
        Self {
            a,
            b,
            kind,
            world_uv: u32::from(!object.has_uvs()),
            squares,
            _padding: 0,
        }
    }
}

/// A scene on the GPU: the refractor (with `d_N`), every opaque object, the environment.
pub(crate) struct GpuScene {
    pub refractor: GpuMesh,
    /// Refractors 1.. (with their `d_N`; `object` = their index), drawn by the engine family's
    /// front-face pass beside [`Self::refractor`].
    pub other_refractors: Vec<GpuMesh>,
    pub objects: Vec<GpuMesh>,
    /// One [`GpuMaterial`] per object (one zeroed entry when there is none: bindings cannot be
    /// empty).
    pub materials: wgpu::Buffer,
    pub environment_texels: wgpu::Buffer,
    pub environment: EnvironmentUniforms,
}

impl GpuScene {
    pub(crate) fn new(device: &wgpu::Device, scene: &Scene) -> Self {
        let refractor = &scene.refractor;
        let refractor = GpuMesh::new(device, "refractor", refractor.mesh(), refractor.d_n(), 0);
        let other_refractors = scene
            .other_refractors
            .iter()
            .enumerate()
            .map(|(k, r)| {
                let index = 1 + k as u32;
                GpuMesh::new(
                    device,
                    &format!("refractor {index}"),
                    r.mesh(),
                    r.d_n(),
                    index,
                )
            })
            .collect();
        let objects = scene
            .objects
            .iter()
            .enumerate()
            .map(|(k, o)| GpuMesh::new(device, &format!("object {k}"), o.mesh(), &[], 1 + k as u32))
            .collect();
        let mut materials: Vec<GpuMaterial> = scene.objects.iter().map(GpuMaterial::new).collect();
        if materials.is_empty() {
            materials.push(GpuMaterial::zeroed());
        }
        let materials = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("materials"),
            contents: bytemuck::cast_slice(&materials),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let (environment, texels) = match &scene.environment {
            Environment::Procedural => (
                EnvironmentUniforms {
                    kind: ENVIRONMENT_PROCEDURAL,
                    width: 0,
                    height: 0,
                    intensity: 1.0,
                    constant: [0.0; 4],
                },
                vec![[0.0f32; 4]],
            ),
            Environment::Constant(c) => (
                EnvironmentUniforms {
                    kind: ENVIRONMENT_CONSTANT,
                    width: 0,
                    height: 0,
                    intensity: 1.0,
                    constant: c.extend(0.0).to_array(),
                },
                vec![[0.0; 4]],
            ),
            Environment::LatLong { map, intensity } => (
                EnvironmentUniforms {
                    kind: ENVIRONMENT_LATLONG,
                    width: map.width,
                    height: map.height,
                    intensity: *intensity,
                    constant: [0.0; 4],
                },
                map.texels
                    .iter()
                    .map(|t| t.extend(0.0).to_array())
                    .collect(),
            ),
        };
        let environment_texels = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("environment texels"),
            contents: bytemuck::cast_slice(&texels),
            usage: wgpu::BufferUsages::STORAGE,
        });
        Self {
            refractor,
            other_refractors,
            objects,
            materials,
            environment_texels,
            environment,
        }
    }
}
