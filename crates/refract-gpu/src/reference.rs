//! The exact reference on the GPU (issue 32): `src/reference.wgsl`, the twin of
//! `refract_trace::Tracer` (both modes: `transmission` and `full`'s Fresnel splitting, any
//! `spp` with the CPU's sample positions) over one BVH of the whole scene ([`crate::bvh`]; each
//! triangle tagged with its mesh). It writes the colour and every AOV layer of the `reference`
//! row (the ground truth of the pixel-centre path), as the CPU reference does;
//! `tests/tests/gpu_reference.rs` holds it to the CPU's.
//!
//! Samples are traced a batch per dispatch ([`GpuReference::set_samples_per_dispatch`]; by
//! default about 2²¹ pixel samples), so that no single dispatch of a converged `full` render
//! runs long enough for a desktop GPU's watchdog; the running sum stays on the GPU between
//! dispatches.
//!
//! Closest hits come from the WGSL traversal of a flattened BVH ([`Traversal::Software`]) or,
//! where the device has wgpu's `EXPERIMENTAL_RAY_QUERY` ([`GpuContext::ray_queries`],
//! `REFRACT_RAY_QUERY`), from the adapter's ray queries over one acceleration structure of the
//! scene ([`Traversal::RayQuery`]); the path code after the hit is the same WGSL.
//!
//! [`crate::GpuRenderer`] renders the `reference` method with it as one of its families
//! (`methods::reference`: the upload in its plan, `GpuReference::encode` and
//! `GpuReference::read` in the shared frame routine), for `render --method reference --backend
//! gpu`, `compare`/`claims --reference-backend gpu` and sweeps; the viewer's split view uses a
//! [`GpuReference`] of its own ([`GpuReference::render`]).

use std::sync::Arc;

use glam::{Vec2, Vec3};
use refract_core::TirPolicy;
use refract_core::microfacet::alpha_from_roughness;
use refract_core::{Camera, gpu::FrameUniforms};
use refract_geometry::{FlatBvh, Mesh};
use refract_scene::spectral::{EmitterSpectrum, SpectralLighting, uplift_tables};
use refract_scene::{
    Aov, Frame, FrameOutputs, InterfaceRule, Layer, RenderError, Scene, TraceMode, TraceSettings,
};
use wgpu::util::DeviceExt;

use crate::bindings::{storage_entry, uniform_entry};
use crate::bvh::{GpuBvh, bvh_layout};
use crate::context::{GpuContext, GpuError};
use crate::frame_uniforms::frame_uniforms;
use crate::scene_buffers::{EnvironmentUniforms, GpuScene};
use crate::shaders::{
    BVH, CORE, ENVIRONMENT, FRAME, MATERIALS, PROCEDURAL_SKY, SPECTRAL, ShaderModule, WgslFile,
};

/// The exact reference's paths (`src/reference.wgsl`).
const REFERENCE: WgslFile = ("reference.wgsl", include_str!("reference.wgsl"));
/// The ray-query module's enable directive (its first file).
const RAY_QUERY_ENABLE: WgslFile = (
    "ray_query_enable.wgsl",
    include_str!("ray_query_enable.wgsl"),
);
/// Closest hits by the adapter's ray queries, `bvh.wgsl`'s interface.
const BVH_RAY_QUERY: WgslFile = ("bvh_ray_query.wgsl", include_str!("bvh_ray_query.wgsl"));

/// The exact reference on the GPU (`refract_gpu::reference`).
pub const REFERENCE_MODULE: ShaderModule = ShaderModule {
    name: "reference",
    files: &[
        CORE,
        PROCEDURAL_SKY,
        SPECTRAL,
        FRAME,
        ENVIRONMENT,
        MATERIALS,
        BVH,
        REFERENCE,
    ],
};

/// The exact reference over the adapter's ray queries (`refract_gpu::reference`, where the
/// adapter has `EXPERIMENTAL_RAY_QUERY`).
pub const REFERENCE_RAY_QUERY_MODULE: ShaderModule = ShaderModule {
    name: "reference-ray-query",
    files: &[
        RAY_QUERY_ENABLE,
        CORE,
        PROCEDURAL_SKY,
        SPECTRAL,
        FRAME,
        ENVIRONMENT,
        MATERIALS,
        BVH_RAY_QUERY,
        REFERENCE,
    ],
};

/// `struct TraceTriangle` of `src/reference.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct TraceTriangle {
    n0: [f32; 4],
    n1: [f32; 4],
    n2: [f32; 4],
    uv01: [f32; 4],
    uv2: [f32; 4],
}

/// `struct TraceUniforms` of `src/reference.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct TraceUniforms {
    light_direction: [f32; 4],
    light_radiance: [f32; 4],
    light_ambient: [f32; 4],
    ior: f32,
    max_depth: u32,
    interface_rule: u32,
    refractor_count: u32,
    write_records: u32,
    mode: u32,
    spp: u32,
    sample_first: u32,
    sample_end: u32,
    throughput_cutoff: f32,
    rough: u32,
    spectral: u32,
    uplift_res: u32,
    env_spectra: u32,
    _padding: [u32; 2],
    light_ambient_spectrum: [f32; 4],
    light_directional_spectrum: [f32; 4],
}

/// `struct TraceSurface` of `src/reference.wgsl`, one per mesh: a conductor (`eta.w` = 1) or a
/// refractor's media (`absorption.w` = 1 for an absorbing one; `within` [`NO_MEDIUM`] for air).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct TraceSurface {
    eta: [f32; 4],
    k: [f32; 4],
    absorption: [f32; 4],
    ior: f32,
    outside_ior: f32,
    within: u32,
    alpha: f32,
    abbe: f32,
    _padding: [f32; 3],
}

/// `NO_MEDIUM` of `src/reference.wgsl`: air.
const NO_MEDIUM: u32 = u32::MAX;

impl TraceSurface {
    /// A conductor of `roughness` (a diffuse object for `None`).
    fn conductor(conductor: Option<refract_scene::Conductor>, roughness: f32) -> Self {
        let plain = Self {
            abbe: f32::INFINITY,
            ..Self::default()
        };
        conductor.map_or(plain, |c| Self {
            eta: c.eta.extend(1.0).to_array(),
            k: c.k.extend(0.0).to_array(),
            alpha: alpha_from_roughness(roughness),
            ..plain
        })
    }

    /// Refractor `index` of `scene`.
    fn refractor(scene: &Scene, index: usize, refractor: &refract_scene::Refractor) -> Self {
        Self {
            absorption: refractor
                .attenuation()
                .map_or([0.0; 4], |a| a.coefficient().extend(1.0).to_array()),
            ior: refractor.ior(),
            outside_ior: scene.outside_ior(index),
            within: refractor
                .within()
                .and_then(|w| u32::try_from(w).ok())
                .unwrap_or(NO_MEDIUM),
            alpha: alpha_from_roughness(refractor.roughness()),
            abbe: if refractor.is_dispersive() {
                refractor.abbe()
            } else {
                f32::INFINITY
            },
            ..Self::conductor(refractor.conductor(), refractor.roughness())
        }
    }
}

/// What a dispersive scene's spectral render reads (`spectral_data` of `src/reference.wgsl`):
/// the uplift table's brightness axis and coefficients, then the lat-long environment's texel
/// spectra (coefficients and scale) from `env_offset` on; one zero for an RGB scene.
struct SpectralUpload {
    data: Vec<f32>,
    res: u32,
    env_offset: u32,
    ambient: [f32; 4],
    directional: [f32; 4],
    /// Whether the scene is dispersive (rendered spectrally).
    enabled: bool,
}

impl SpectralUpload {
    fn new(scene: &Scene) -> Self {
        if !scene.has_dispersion() {
            return Self {
                data: vec![0.0],
                res: 0,
                env_offset: 0,
                ambient: [0.0; 4],
                directional: [0.0; 4],
                enabled: false,
            };
        }
        let tables = uplift_tables();
        let table = tables.table();
        let lighting = SpectralLighting::new(scene, &table);
        let mut data = Vec::with_capacity(
            tables.scale().len() + tables.data().len() + 4 * lighting.texels.len(),
        );
        data.extend_from_slice(tables.scale());
        data.extend_from_slice(tables.data());
        let env_offset = data.len() as u32;
        for t in &lighting.texels {
            data.extend_from_slice(&t.coefficients);
            data.push(t.scale);
        }
        let packed = |e: &EmitterSpectrum| {
            [
                e.coefficients[0],
                e.coefficients[1],
                e.coefficients[2],
                e.scale,
            ]
        };
        Self {
            res: tables.res() as u32,
            env_offset,
            ambient: packed(&lighting.ambient),
            directional: packed(&lighting.directional),
            data,
            enabled: true,
        }
    }
}

/// The words of a pixel's path record (`RECORD_WORDS`): eight vectors, a mask, the interfaces
/// crossed, the refractors met.
const RECORD_WORDS: usize = 27;

/// Pixel samples traced per dispatch by default: about two million (1024² at two samples, 96²
/// at 227), a few hundred milliseconds of `full` mode on a desktop GPU.
const DEFAULT_PIXEL_SAMPLES_PER_DISPATCH: u64 = 1 << 21;

/// How the reference finds closest hits on a device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Traversal {
    /// The WGSL traversal of a flattened BVH (`shaders/bvh.wgsl`), on every adapter.
    Software,
    /// The adapter's hardware ray queries (`src/bvh_ray_query.wgsl`) over an acceleration
    /// structure of the scene, where the device has them ([`GpuContext::ray_queries`]).
    RayQuery,
}

/// The reference's compute pipeline and layouts, compiled once per device and shared by every
/// scene uploaded on it.
pub struct ReferencePipeline {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    bvh_layout: wgpu::BindGroupLayout,
    traversal: Traversal,
}

impl ReferencePipeline {
    /// Compiles `src/reference.wgsl` on `context`'s device, over its ray queries when the
    /// device has them enabled, else over the WGSL BVH traversal.
    pub fn new(context: &GpuContext) -> Result<Self, GpuError> {
        if let Some(refusal) = &context.ray_query_refusal {
            return Err(GpuError::RayQuery(refusal.clone()));
        }
        let device = &context.device;
        let traversal = if context.ray_queries {
            Traversal::RayQuery
        } else {
            Traversal::Software
        };
        let module_source = match traversal {
            Traversal::Software => REFERENCE_MODULE.source(),
            Traversal::RayQuery => REFERENCE_RAY_QUERY_MODULE.source(),
        };
        context.checked(|| {
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("reference"),
                entries: &[
                    uniform_entry(0, wgpu::ShaderStages::COMPUTE),
                    uniform_entry(1, wgpu::ShaderStages::COMPUTE),
                    storage_entry(2, true),
                    storage_entry(3, true),
                    storage_entry(4, true),
                    storage_entry(5, true),
                    storage_entry(6, false),
                    storage_entry(7, false),
                    storage_entry(8, true),
                ],
            });
            let bvh_layout = match traversal {
                Traversal::Software => bvh_layout(device),
                Traversal::RayQuery => ray_query_layout(device),
            };
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("reference.wgsl"),
                source: wgpu::ShaderSource::Wgsl(module_source.into()),
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("reference"),
                bind_group_layouts: &[Some(&layout), Some(&bvh_layout)],
                immediate_size: 0,
            });
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("trace_reference"),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some("trace_reference"),
                compilation_options: Default::default(),
                cache: None,
            });
            Self {
                pipeline,
                layout,
                bvh_layout,
                traversal,
            }
        })
    }
}

/// Group 1 of `bvh_ray_query.wgsl`: the scene's acceleration structure and its triangles.
fn ray_query_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("reference ray query"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::AccelerationStructure {
                    vertex_return: false,
                },
                count: None,
            },
            storage_entry(1, true),
        ],
    })
}

/// The scene's acceleration structure for ray queries: one BLAS over `mesh` (every triangle
/// opaque, in the mesh's order: a hit's primitive index is the triangle's index), one TLAS
/// instance with the identity transform; with the triangles' corners for `bvh_triangles`.
struct SceneAccelerationStructure {
    tlas: wgpu::Tlas,
    triangles: wgpu::Buffer,
    /// Kept alive while the TLAS refers to it.
    _blas: wgpu::Blas,
}

impl SceneAccelerationStructure {
    fn build(context: &GpuContext, mesh: &Mesh) -> Result<Self, RenderError> {
        let device = &context.device;
        // An empty scene gets one degenerate triangle, which no ray hits (no empty buffers in
        // WebGPU; Vulkan ignores zero-area triangles).
        let (positions, indices): (Vec<[f32; 3]>, Vec<u32>) = if mesh.triangles.is_empty() {
            (vec![[0.0; 3]; 3], vec![0, 1, 2])
        } else {
            (
                mesh.positions.iter().map(|p| p.to_array()).collect(),
                mesh.triangles.iter().flatten().copied().collect(),
            )
        };
        let corners: Vec<[[f32; 4]; 3]> = indices
            .chunks_exact(3)
            .map(|t| {
                [0, 1, 2].map(|k| {
                    Vec3::from_array(positions[t[k] as usize])
                        .extend(0.0)
                        .to_array()
                })
            })
            .collect();
        let limits = device.limits();
        if corners.len() as u64 > u64::from(limits.max_blas_primitive_count) {
            return Err(RenderError::Parameter(format!(
                "GPU reference: {} triangles exceed {}'s acceleration structures ({} primitives); REFRACT_RAY_QUERY=off traces them with the WGSL traversal",
                corners.len(),
                context.info.name,
                limits.max_blas_primitive_count
            )));
        }
        let size = wgpu::BlasTriangleGeometrySizeDescriptor {
            vertex_format: wgpu::VertexFormat::Float32x3,
            vertex_count: positions.len() as u32,
            index_format: Some(wgpu::IndexFormat::Uint32),
            index_count: Some(indices.len() as u32),
            flags: wgpu::AccelerationStructureGeometryFlags::OPAQUE,
        };
        Ok(context.checked(|| {
            let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("reference blas vertices"),
                contents: bytemuck::cast_slice(&positions),
                usage: wgpu::BufferUsages::BLAS_INPUT,
            });
            let index_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("reference blas indices"),
                contents: bytemuck::cast_slice(&indices),
                usage: wgpu::BufferUsages::BLAS_INPUT,
            });
            let blas = device.create_blas(
                &wgpu::CreateBlasDescriptor {
                    label: Some("reference scene"),
                    flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                    update_mode: wgpu::AccelerationStructureUpdateMode::Build,
                },
                wgpu::BlasGeometrySizeDescriptors::Triangles {
                    descriptors: vec![size.clone()],
                },
            );
            let mut tlas = device.create_tlas(&wgpu::CreateTlasDescriptor {
                label: Some("reference scene"),
                flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                update_mode: wgpu::AccelerationStructureUpdateMode::Build,
                max_instances: 1,
            });
            let identity = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
            if let Some(slot) = tlas.get_mut_single(0) {
                *slot = Some(wgpu::TlasInstance::new(&blas, identity, 0, 0xff));
            }
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("reference acceleration structure"),
            });
            encoder.build_acceleration_structures(
                core::iter::once(&wgpu::BlasBuildEntry {
                    blas: &blas,
                    geometry: wgpu::BlasGeometries::TriangleGeometries(vec![
                        wgpu::BlasTriangleGeometry {
                            size: &size,
                            vertex_buffer: &vertices,
                            first_vertex: 0,
                            vertex_stride: 12,
                            index_buffer: Some(&index_buffer),
                            first_index: Some(0),
                            transform_buffer: None,
                            transform_buffer_offset: None,
                        },
                    ]),
                }),
                core::iter::once(&tlas),
            );
            context.queue.submit([encoder.finish()]);
            Self {
                tlas,
                triangles: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("reference triangles (ray query)"),
                    contents: bytemuck::cast_slice(&corners),
                    usage: wgpu::BufferUsages::STORAGE,
                }),
                _blas: blas,
            }
        })?)
    }

    fn bind_group(&self, device: &wgpu::Device, layout: &wgpu::BindGroupLayout) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("reference ray query"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.tlas.as_binding(),
                },
                entry(1, &self.triangles),
            ],
        })
    }
}

/// A scene uploaded for the GPU reference.
pub struct GpuReference {
    pipeline: Arc<ReferencePipeline>,
    bvh_group: wgpu::BindGroup,
    /// The scene's acceleration structure when the pipeline traverses with ray queries.
    _acceleration: Option<SceneAccelerationStructure>,
    /// The objects' materials (`GpuScene`'s buffer), the environment's texels and uniforms.
    materials: wgpu::Buffer,
    environment_texels: wgpu::Buffer,
    environment: EnvironmentUniforms,
    triangles: wgpu::Buffer,
    /// One [`TraceSurface`] per mesh.
    surfaces: wgpu::Buffer,
    /// [`SpectralUpload::data`].
    spectral: wgpu::Buffer,
    uniforms: TraceUniforms,
    /// Samples per dispatch, `None`: [`DEFAULT_PIXEL_SAMPLES_PER_DISPATCH`] over the pixels.
    samples_per_dispatch: Option<u32>,
    /// The last frame's buffers, reused while the resolution and outputs stay.
    outputs: Option<OutputBuffers>,
}

/// A frame's buffers: the uniforms, the colour (the running sum between dispatches) and the
/// path records, each with its readback twin, and the bind group over them.
pub(crate) struct OutputBuffers {
    width: u32,
    height: u32,
    with_records: bool,
    frame: wgpu::Buffer,
    trace: wgpu::Buffer,
    color: (wgpu::Buffer, wgpu::Buffer),
    record: (wgpu::Buffer, wgpu::Buffer),
    group: wgpu::BindGroup,
}

impl OutputBuffers {
    /// Whether these buffers serve a `width × height` frame with `outputs`.
    pub(crate) fn fits(&self, width: u32, height: u32, outputs: FrameOutputs) -> bool {
        let with_records = outputs == FrameOutputs::ColorAndAovs;
        (self.width, self.height, self.with_records) == (width, height, with_records)
    }
}

impl GpuReference {
    /// Compiles the pipeline and uploads `scene`: one BVH over the refractor and every object,
    /// the triangles' normals, texture coordinates and meshes, the objects' materials and
    /// conductors, the environment. [`crate::GpuRenderer`] compiles the pipeline once and
    /// reuses its own upload of the materials and the environment.
    pub fn new(context: &GpuContext, scene: &Scene) -> Result<Self, RenderError> {
        Self::with_pipeline(context, Arc::new(ReferencePipeline::new(context)?), scene)
    }

    /// Uploads `scene` for a pipeline compiled before (on `context`'s device), so that a new
    /// scene (another IOR, say) does not compile the shader again.
    pub fn with_pipeline(
        context: &GpuContext,
        pipeline: Arc<ReferencePipeline>,
        scene: &Scene,
    ) -> Result<Self, RenderError> {
        let uploaded = context.checked(|| GpuScene::new(&context.device, scene))?;
        Self::upload(context, pipeline, scene, &uploaded)
    }

    /// Uploads `scene` for `pipeline`, sharing `uploaded`'s materials and environment buffers.
    pub(crate) fn upload(
        context: &GpuContext,
        pipeline: Arc<ReferencePipeline>,
        scene: &Scene,
        uploaded: &GpuScene,
    ) -> Result<Self, RenderError> {
        let (combined, attributes) = combined_mesh(scene);
        context.check_storage::<TraceTriangle>("triangles", attributes.len())?;
        let device = &context.device;
        // The triangles' attributes in the order the traversal reports hits: the BVH's leaf
        // order, or the mesh's own for ray queries.
        let mut acceleration = None;
        let (bvh_group, ordered): (wgpu::BindGroup, Vec<TraceTriangle>) = match pipeline.traversal {
            Traversal::Software => {
                let flat = FlatBvh::build(&combined)
                    .map_err(|err| RenderError::Parameter(format!("GPU reference: {err}")))?;
                let ordered = flat
                    .original
                    .iter()
                    .map(|&i| attributes[i as usize])
                    .collect();
                let bvh = GpuBvh::upload(context, &flat)?;
                (bvh.bind_group(device, &pipeline.bvh_layout), ordered)
            }
            Traversal::RayQuery => {
                let structure = SceneAccelerationStructure::build(context, &combined)?;
                let group =
                    context.checked(|| structure.bind_group(device, &pipeline.bvh_layout))?;
                acceleration = Some(structure);
                (group, attributes)
            }
        };
        let ordered = if ordered.is_empty() {
            vec![TraceTriangle::default()]
        } else {
            ordered
        };
        let surfaces: Vec<TraceSurface> = scene
            .refractors()
            .enumerate()
            .map(|(i, r)| TraceSurface::refractor(scene, i, r))
            .chain(
                scene
                    .objects
                    .iter()
                    .map(|o| TraceSurface::conductor(o.conductor(), o.roughness())),
            )
            .collect();
        let light = &scene.light;
        let spectral = SpectralUpload::new(scene);
        let uniforms = TraceUniforms {
            light_direction: light.direction.extend(0.0).to_array(),
            light_radiance: light.radiance.extend(0.0).to_array(),
            light_ambient: light.ambient.extend(0.0).to_array(),
            ior: scene.refractor.ior(),
            max_depth: 0,
            interface_rule: 0,
            refractor_count: scene.refractor_count() as u32,
            write_records: 0,
            mode: 0,
            spp: 1,
            sample_first: 0,
            sample_end: 1,
            throughput_cutoff: 0.0,
            rough: u32::from(scene.has_roughness()),
            spectral: u32::from(spectral.enabled),
            uplift_res: spectral.res,
            env_spectra: spectral.env_offset,
            _padding: [0; 2],
            light_ambient_spectrum: spectral.ambient,
            light_directional_spectrum: spectral.directional,
        };
        context.check_storage::<f32>("spectral data", spectral.data.len())?;
        Ok(context.checked(|| Self {
            bvh_group,
            _acceleration: acceleration,
            pipeline,
            materials: uploaded.materials.clone(),
            environment_texels: uploaded.environment_texels.clone(),
            environment: uploaded.environment,
            triangles: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("reference triangles"),
                contents: bytemuck::cast_slice(&ordered),
                usage: wgpu::BufferUsages::STORAGE,
            }),
            surfaces: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("reference surfaces"),
                contents: bytemuck::cast_slice(&surfaces),
                usage: wgpu::BufferUsages::STORAGE,
            }),
            spectral: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("reference spectral data"),
                contents: bytemuck::cast_slice(&spectral.data),
                usage: wgpu::BufferUsages::STORAGE,
            }),
            uniforms,
            samples_per_dispatch: None,
            outputs: None,
        })?)
    }

    /// How this reference finds closest hits.
    pub fn traversal(&self) -> Traversal {
        self.pipeline.traversal
    }

    /// Traces at most `samples` samples of every pixel per dispatch (`None`: about 2²¹ pixel
    /// samples a dispatch). The image does not depend on it: the sum is carried between
    /// dispatches in the order the CPU adds the samples.
    pub fn set_samples_per_dispatch(&mut self, samples: Option<u32>) {
        self.samples_per_dispatch = samples.map(|s| s.max(1));
    }

    /// Renders `camera`'s frame with `settings` into `frame`: the colour and every layer of the
    /// `reference` row (`Covered`, `P1` … `PGeom`, `Interfaces`, `RefractorsMet`, `Tir`,
    /// `TirFirstExit`; NaN where
    /// a quantity does not exist, as on the CPU), and `frame.rays`, the closest-hit queries
    /// traced, counted as the CPU tracer counts them.
    pub fn render(
        &mut self,
        context: &GpuContext,
        camera: &Camera,
        settings: &TraceSettings,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let buffers =
            self.take_output_buffers(context, camera.width(), camera.height(), outputs)?;
        let mut encoder = context
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("reference"),
            });
        self.encode(context, camera, settings, &buffers, &mut encoder)?;
        context.checked(|| context.queue.submit([encoder.finish()]))?;
        let read = self.read(context, &buffers, frame);
        self.outputs = Some(buffers);
        read
    }

    /// Encodes the frame's passes into `encoder`: the samples traced a batch per dispatch
    /// ([`Self::set_samples_per_dispatch`]), every batch but the last submitted here (the
    /// running sum stays in `buffers` on the GPU), the last one encoded with the copies to the
    /// readback buffers. The caller submits `encoder` and then reads with [`Self::read`].
    pub(crate) fn encode(
        &self,
        context: &GpuContext,
        camera: &Camera,
        settings: &TraceSettings,
        buffers: &OutputBuffers,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), RenderError> {
        let (width, height) = (camera.width(), camera.height());
        debug_assert_eq!((width, height), (buffers.width, buffers.height));
        let pixels = u64::from(width) * u64::from(height);
        let frame_uniforms: FrameUniforms = frame_uniforms(
            camera,
            &self.environment,
            self.uniforms.ior,
            TirPolicy::default(),
        );
        let spp = settings.spp.max(1);
        let mut trace = TraceUniforms {
            max_depth: settings.max_depth,
            interface_rule: match settings.interface {
                InterfaceRule::ShadingNormal => 0,
                InterfaceRule::GeometricNormal => 1,
            },
            write_records: u32::from(buffers.with_records),
            mode: match settings.mode {
                TraceMode::Transmission => 0,
                TraceMode::Full => 1,
            },
            spp,
            throughput_cutoff: settings.throughput_cutoff,
            ..self.uniforms
        };
        let batch = self.samples_per_dispatch.unwrap_or_else(|| {
            if context.info.device_type == wgpu::DeviceType::Cpu {
                // lavapipe ends every loop of an invocation after 65,535 iterations of all its
                // loops together (gallivm's LP_MAX_TGSI_LOOP_ITERATIONS), silently: the BVH
                // steps of a few hundred rays. One sample a dispatch stays under it.
                return 1;
            }
            (DEFAULT_PIXEL_SAMPLES_PER_DISPATCH / pixels.max(1)).clamp(1, u64::from(spp)) as u32
        });
        let device = &context.device;
        let queue = &context.queue;
        queue.write_buffer(&buffers.frame, 0, bytemuck::bytes_of(&frame_uniforms));
        // The centre path alone when it is the colour (transmission at one sample, nothing rough
        // or dispersive), else the samples in batches.
        let mut first = 0;
        loop {
            trace.sample_first = first;
            trace.sample_end =
                if trace.mode == 0 && spp == 1 && trace.rough == 0 && trace.spectral == 0 {
                    0
                } else {
                    (first + batch).min(spp)
                };
            let last = trace.sample_end == 0 || trace.sample_end == spp;
            // Each batch's uniforms are written before the submission that reads them.
            queue.write_buffer(&buffers.trace, 0, bytemuck::bytes_of(&trace));
            let mut batch_encoder = (!last).then(|| {
                device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("reference batch"),
                })
            });
            let target = batch_encoder.as_mut().unwrap_or(&mut *encoder);
            {
                let mut pass = target.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("trace_reference"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&self.pipeline.pipeline);
                pass.set_bind_group(0, &buffers.group, &[]);
                pass.set_bind_group(1, &self.bvh_group, &[]);
                pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
            }
            match batch_encoder {
                Some(batch_encoder) => {
                    context.checked(|| queue.submit([batch_encoder.finish()]))?;
                    first = trace.sample_end;
                }
                None => {
                    let (color, record) = (&buffers.color, &buffers.record);
                    encoder.copy_buffer_to_buffer(&color.0, 0, &color.1, 0, color.0.size());
                    if buffers.with_records {
                        encoder.copy_buffer_to_buffer(&record.0, 0, &record.1, 0, record.0.size());
                    }
                    return Ok(());
                }
            }
        }
    }

    /// Reads the frame last submitted with `buffers` into `frame` (the colour, the rays and,
    /// with records, the `reference` row's layers).
    pub(crate) fn read(
        &self,
        context: &GpuContext,
        buffers: &OutputBuffers,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let colors = context.read_buffer(&buffers.color.1)?;
        let records = if buffers.with_records {
            context.read_buffer(&buffers.record.1)?
        } else {
            Vec::new()
        };
        write_frame(
            frame,
            buffers.width,
            buffers.height,
            bytemuck::cast_slice(&colors),
            buffers.with_records.then(|| bytemuck::cast_slice(&records)),
        );
        Ok(())
    }

    /// The colour buffer of `buffers`' last frame: one `vec4<f32>` per pixel.
    pub(crate) fn color(buffers: &OutputBuffers) -> &wgpu::Buffer {
        &buffers.color.0
    }

    /// The buffers of a `width × height` frame: the last frame's when it had that size and
    /// outputs (the caller puts them back), else new ones; refused with the adapter's limit
    /// when a binding would exceed it.
    fn take_output_buffers(
        &mut self,
        context: &GpuContext,
        width: u32,
        height: u32,
        outputs: FrameOutputs,
    ) -> Result<OutputBuffers, GpuError> {
        match self.outputs.take() {
            Some(o) if o.fits(width, height, outputs) => Ok(o),
            _ => self.output_buffers(context, width, height, outputs),
        }
    }

    /// New buffers for a `width × height` frame with `outputs`, refused with the adapter's
    /// limit when a binding would exceed it.
    pub(crate) fn output_buffers(
        &self,
        context: &GpuContext,
        width: u32,
        height: u32,
        outputs: FrameOutputs,
    ) -> Result<OutputBuffers, GpuError> {
        let with_records = outputs == FrameOutputs::ColorAndAovs;
        let device = &context.device;
        let pixels = u64::from(width) * u64::from(height);
        let record_bytes = if with_records {
            pixels * 4 * RECORD_WORDS as u64
        } else {
            4
        };
        let limit = device.limits().max_storage_buffer_binding_size;
        if pixels * 16 > limit || record_bytes > limit {
            return Err(GpuError::ResolutionTooLarge {
                width,
                height,
                adapter: context.info.name.clone(),
                limit: format!(
                    "max storage buffer binding size {limit} bytes (16 bytes of colour a pixel, {} of path records with the AOV layers)",
                    4 * RECORD_WORDS
                ),
            });
        }
        let made = context.checked(|| {
            let storage = |label: &str, size: u64| {
                let output = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                let read = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                (output, read)
            };
            let uniform = |label: &str, size: usize| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: size as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            };
            let frame = uniform("reference frame", size_of::<FrameUniforms>());
            let trace = uniform("reference trace", size_of::<TraceUniforms>());
            let color = storage("reference colour", pixels * 16);
            let record = storage("reference records", record_bytes);
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("reference"),
                layout: &self.pipeline.layout,
                entries: &[
                    entry(0, &frame),
                    entry(1, &trace),
                    entry(2, &self.materials),
                    entry(3, &self.surfaces),
                    entry(4, &self.environment_texels),
                    entry(5, &self.triangles),
                    entry(6, &color.0),
                    entry(7, &record.0),
                    entry(8, &self.spectral),
                ],
            });
            OutputBuffers {
                width,
                height,
                with_records,
                frame,
                trace,
                color,
                record,
                group,
            }
        })?;
        Ok(made)
    }
}

/// The colour and the reference row's layers from the kernel's outputs.
fn write_frame(
    frame: &mut Frame,
    width: u32,
    height: u32,
    colors: &[[f32; 4]],
    records: Option<&[u32]>,
) {
    let n = (width * height) as usize;
    frame.reset(width, height);
    frame.color = colors[..n]
        .iter()
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    // Each pixel's closest-hit queries, counted by the kernel (colour's w).
    frame.rays = colors[..n].iter().map(|c| c[3] as u64).sum();
    let Some(records) = records else {
        return;
    };
    let record = |i: usize| &records[RECORD_WORDS * i..][..RECORD_WORDS];
    let mask = |i: usize| record(i)[24];
    let vector = |k: usize| -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let r = record(i);
                if mask(i) & (1 << k) == 0 {
                    Vec3::NAN
                } else {
                    Vec3::from_array([0, 1, 2].map(|c| f32::from_bits(r[3 * k + c])))
                }
            })
            .collect()
    };
    let vectors = [
        Aov::P1,
        Aov::N1,
        Aov::T1,
        Aov::P2,
        Aov::N2,
        Aov::T2,
        Aov::TOut,
        Aov::PGeom,
    ];
    for (k, aov) in vectors.into_iter().enumerate() {
        frame.insert_layer(aov, Layer::Vec3(vector(k)));
    }
    let flag = |bit: u32| -> Vec<bool> { (0..n).map(|i| mask(i) & (1 << bit) != 0).collect() };
    frame.insert_layer(Aov::Covered, Layer::Flag(flag(8)));
    frame.insert_layer(Aov::Tir, Layer::Flag(flag(9)));
    frame.insert_layer(Aov::TirFirstExit, Layer::Flag(flag(10)));
    frame.insert_layer(
        Aov::Interfaces,
        Layer::Count((0..n).map(|i| record(i)[25]).collect()),
    );
    frame.insert_layer(
        Aov::RefractorsMet,
        Layer::Count((0..n).map(|i| record(i)[26]).collect()),
    );
}

/// Every refractor (mesh `i`) and every object (mesh `refractor_count + k`) as one mesh for the
/// BVH, and each triangle's attributes in that order.
fn combined_mesh(scene: &Scene) -> (Mesh, Vec<TraceTriangle>) {
    let mut combined = Mesh {
        name: "scene (refractors and objects)".into(),
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        triangles: Vec::new(),
    };
    let mut attributes = Vec::new();
    let meshes = scene
        .refractors()
        .map(|r| r.mesh())
        .chain(scene.objects.iter().map(|o| o.mesh()));
    for (id, mesh) in meshes.enumerate() {
        let base = combined.positions.len() as u32;
        combined.positions.extend_from_slice(&mesh.positions);
        combined.normals.extend_from_slice(&mesh.normals);
        for t in &mesh.triangles {
            combined.triangles.push(t.map(|v| v + base));
            let n = |k: usize, w: f32| mesh.normals[t[k] as usize].extend(w).to_array();
            let uv = |k: usize| mesh.uvs.get(t[k] as usize).copied().unwrap_or(Vec2::ZERO);
            let (uv0, uv1, uv2) = (uv(0), uv(1), uv(2));
            attributes.push(TraceTriangle {
                n0: n(0, id as f32),
                n1: n(1, 0.0),
                n2: n(2, 0.0),
                uv01: [uv0.x, uv0.y, uv1.x, uv1.y],
                uv2: [uv2.x, uv2.y, 0.0, 0.0],
            });
        }
    }
    (combined, attributes)
}

/// A whole-buffer binding.
fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}
