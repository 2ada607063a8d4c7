//! The GPU passes of Wyman 2005a §4 on wgpu: back faces and front faces rasterised into float
//! targets, then the per-pixel kernel as a compute pass, then readback into the same
//! [`MethodFrame`] the CPU backend returns.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use refract_core::gpu::{
    ENVIRONMENT_CONSTANT, ENVIRONMENT_LATLONG, ENVIRONMENT_PROCEDURAL, FrameUniforms,
    METHOD_SINGLE, METHOD_TWO_INTERFACE, distance_mode_code, tir_policy_code,
};
use refract_core::kernel::ImageSpaceParams;
use refract_core::{BackSurface, Camera, DistanceMode, ExitNormalSource, Method};
use refract_cpu::{FrameOutputs, MethodAov, MethodFrame, MethodParams};
use refract_geometry::Mesh;
use refract_trace::Environment;
use wgpu::util::DeviceExt;

use crate::context::{GpuContext, GpuError};
use crate::shaders::module_source;

const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Vertex {
    p_ws: [f32; 3],
    n_ws: [f32; 3],
    d_n: f32,
}

/// A refractor and its environment uploaded to the GPU.
pub struct GpuScene {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    environment_texels: wgpu::Buffer,
    environment: (u32, u32, u32, f32, [f32; 4]),
}

impl GpuScene {
    /// Uploads the mesh with its per-vertex `d_N`, and the environment.
    pub fn new(context: &GpuContext, mesh: &Mesh, d_n: &[f32], environment: &Environment) -> Self {
        let vertices: Vec<Vertex> = (0..mesh.positions.len())
            .map(|i| Vertex {
                p_ws: mesh.positions[i].to_array(),
                n_ws: mesh.normals[i].to_array(),
                d_n: d_n.get(i).copied().unwrap_or(0.0),
            })
            .collect();
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let device = &context.device;
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("refractor vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let index_count = indices.len() as u32;
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("refractor indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let (kind, width, height, intensity, constant, texels) = match environment {
            Environment::Procedural => (
                ENVIRONMENT_PROCEDURAL,
                0,
                0,
                1.0,
                [0.0; 4],
                vec![[0.0f32; 4]],
            ),
            Environment::Constant(c) => (
                ENVIRONMENT_CONSTANT,
                0,
                0,
                1.0,
                c.extend(0.0).to_array(),
                vec![[0.0; 4]],
            ),
            Environment::LatLong { map, intensity } => (
                ENVIRONMENT_LATLONG,
                map.width,
                map.height,
                *intensity,
                [0.0; 4],
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
            vertices,
            indices,
            index_count,
            environment_texels,
            environment: (kind, width, height, intensity, constant),
        }
    }
}

/// The compiled pipelines (create once per context).
pub struct GpuRenderer {
    raster_layout: wgpu::BindGroupLayout,
    back_furthest: wgpu::RenderPipeline,
    back_second: wgpu::RenderPipeline,
    front: wgpu::RenderPipeline,
    shade_layout: wgpu::BindGroupLayout,
    shade: wgpu::ComputePipeline,
    /// The kernel without AOV stores (`WRITE_AOVS = false`).
    shade_color_only: wgpu::ComputePipeline,
}

fn texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// A compute-stage storage buffer binding.
pub(crate) fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl GpuRenderer {
    /// Compiles the raster and shading modules and builds the pipelines.
    pub fn new(context: &GpuContext) -> Result<Self, GpuError> {
        context.checked(|| Self::build(&context.device))
    }

    fn build(device: &wgpu::Device) -> Self {
        let raster_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("raster.wgsl"),
            source: wgpu::ShaderSource::Wgsl(module_source("raster").into()),
        });
        let shade_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shade.wgsl"),
            source: wgpu::ShaderSource::Wgsl(module_source("shade").into()),
        });
        let raster_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raster"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let raster_pipeline_layout =
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("raster"),
                bind_group_layouts: &[Some(&raster_layout)],
                immediate_size: 0,
            });
        let vertex_attributes =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32];
        let vertex_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<Vertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &vertex_attributes,
        };
        let target = Some(wgpu::ColorTargetState {
            format: TARGET_FORMAT,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        });
        let raster = |label: &str,
                      cull: wgpu::Face,
                      compare: wgpu::CompareFunction,
                      fragment: &str,
                      targets: &[Option<wgpu::ColorTargetState>]| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&raster_pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &raster_module,
                    entry_point: Some("vs_mesh"),
                    compilation_options: Default::default(),
                    buffers: &[Some(vertex_layout.clone())],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode: Some(cull),
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(compare),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &raster_module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        // Wyman 2005a §3.2: the furthest surface (cull front faces, depth Greater cleared to 0)
        // or the second surface (the nearest back face, Less cleared to 1).
        let back_furthest = raster(
            "back faces (furthest)",
            wgpu::Face::Front,
            wgpu::CompareFunction::Greater,
            "fs_back",
            std::slice::from_ref(&target),
        );
        let back_second = raster(
            "back faces (second)",
            wgpu::Face::Front,
            wgpu::CompareFunction::Less,
            "fs_back",
            std::slice::from_ref(&target),
        );
        let front = raster(
            "front faces",
            wgpu::Face::Back,
            wgpu::CompareFunction::Less,
            "fs_front",
            &[target.clone(), target],
        );

        let shade_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shade"),
            entries: &[
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
        });
        let shade_pipeline_layout =
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("shade"),
                bind_group_layouts: &[Some(&shade_layout)],
                immediate_size: 0,
            });
        let shade_pipeline = |label, constants: &[(&str, f64)]| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&shade_pipeline_layout),
                module: &shade_module,
                entry_point: Some("shade"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    ..Default::default()
                },
                cache: None,
            })
        };
        let shade = shade_pipeline("shade", &[]);
        let shade_color_only = shade_pipeline("shade (colour only)", &[("WRITE_AOVS", 0.0)]);
        Self {
            raster_layout,
            back_furthest,
            back_second,
            front,
            shade_layout,
            shade,
            shade_color_only,
        }
    }
}

/// Everything one frame of one method needs, allocated once and replayable.
pub struct GpuFrame {
    width: u32,
    height: u32,
    method: Method,
    outputs_kind: FrameOutputs,
    raster_group: wgpu::BindGroup,
    shade_group: wgpu::BindGroup,
    back_view: wgpu::TextureView,
    front_p1_view: wgpu::TextureView,
    front_n1_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    outputs: [wgpu::Buffer; 4],
    readback: [wgpu::Buffer; 4],
    queries: Option<(wgpu::QuerySet, wgpu::Buffer, wgpu::Buffer)>,
}

fn target(
    device: &wgpu::Device,
    label: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
) -> wgpu::TextureView {
    device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        })
        .create_view(&wgpu::TextureViewDescriptor::default())
}

/// GPU time of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuTiming {
    /// Milliseconds between the first and last pass, from timestamp queries when the adapter has
    /// them; otherwise wall-clock around submit + wait.
    pub ms: f64,
    /// Whether `ms` came from timestamp queries.
    pub from_timestamps: bool,
}

impl GpuFrame {
    /// Allocates targets and buffers for `params` at the camera's resolution, checking the
    /// adapter's limits. The frame writes colours and AOVs.
    pub fn new(
        context: &GpuContext,
        renderer: &GpuRenderer,
        scene: &GpuScene,
        camera: &Camera,
        params: &MethodParams,
    ) -> Result<Self, GpuError> {
        Self::with_outputs(
            context,
            renderer,
            scene,
            camera,
            params,
            FrameOutputs::ColorAndAovs,
        )
    }

    /// [`GpuFrame::new`] writing `outputs`: with [`FrameOutputs::Color`] the kernel stores only
    /// the colour (as a real-time renderer would) and [`GpuFrame::read`] returns no AOVs.
    pub fn with_outputs(
        context: &GpuContext,
        renderer: &GpuRenderer,
        scene: &GpuScene,
        camera: &Camera,
        params: &MethodParams,
        outputs: FrameOutputs,
    ) -> Result<Self, GpuError> {
        let distance = params.method.distance_mode();
        ImageSpaceParams::new(params.ior, distance, params.tir_policy)?;
        let (width, height) = (camera.width(), camera.height());
        let limits = context.device.limits();
        let output_bytes = u64::from(width) * u64::from(height) * 16;
        let too_large = |limit: String| GpuError::ResolutionTooLarge {
            width,
            height,
            adapter: context.info.name.clone(),
            limit,
        };
        if width > limits.max_texture_dimension_2d || height > limits.max_texture_dimension_2d {
            return Err(too_large(format!(
                "max 2D texture size {}",
                limits.max_texture_dimension_2d
            )));
        }
        if output_bytes > limits.max_storage_buffer_binding_size
            || output_bytes > limits.max_buffer_size
        {
            return Err(too_large(format!(
                "max storage buffer binding {} bytes",
                limits.max_storage_buffer_binding_size
            )));
        }
        let mut frame = context
            .checked(|| Self::allocate(context, renderer, scene, camera, params, distance))?;
        frame.outputs_kind = outputs;
        Ok(frame)
    }

    fn allocate(
        context: &GpuContext,
        renderer: &GpuRenderer,
        scene: &GpuScene,
        camera: &Camera,
        params: &MethodParams,
        distance: DistanceMode,
    ) -> Self {
        let device = &context.device;
        let (width, height) = (camera.width(), camera.height());
        let (kind, env_w, env_h, intensity, constant) = scene.environment;
        let two_interface = matches!(params.method, Method::TwoInterface { .. });
        let uniforms = FrameUniforms {
            world_to_clip: camera.world_to_clip().to_cols_array_2d(),
            view_to_world: camera.view_to_world().to_cols_array_2d(),
            eye: camera.eye().extend(1.0).to_array(),
            look_dir: camera.look_dir().extend(0.0).to_array(),
            environment_constant: constant,
            width,
            height,
            tan_half_fov_y: (0.5 * camera.desc().fov_y).tan(),
            aspect: width as f32 / height as f32,
            ior: params.ior,
            tir_policy: tir_policy_code(params.tir_policy),
            distance_mode: distance_mode_code(distance),
            method_kind: if two_interface {
                METHOD_TWO_INTERFACE
            } else {
                METHOD_SINGLE
            },
            environment_kind: kind,
            environment_width: env_w,
            environment_height: env_h,
            environment_intensity: intensity,
        };
        let uniform_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("frame uniforms"),
            contents: bytemuck::bytes_of(&uniforms),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let raster_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("raster"),
            layout: &renderer.raster_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform_buffer.as_entire_binding(),
            }],
        });
        // `single` never reads the back faces: a 1×1 target keeps the layout.
        let (back_w, back_h) = if two_interface {
            (width, height)
        } else {
            (1, 1)
        };
        let back_view = target(device, "back faces", back_w, back_h, TARGET_FORMAT);
        let front_p1_view = target(device, "front P1, d_N", width, height, TARGET_FORMAT);
        let front_n1_view = target(device, "front N1", width, height, TARGET_FORMAT);
        let depth_view = target(device, "depth", width, height, DEPTH_FORMAT);
        let size = u64::from(width) * u64::from(height) * 16;
        let outputs = ["colour", "T2", "P2", "N2"].map(|label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        });
        let readback = [
            "colour readback",
            "T2 readback",
            "P2 readback",
            "N2 readback",
        ]
        .map(|label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        let shade_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shade"),
            layout: &renderer.shade_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&front_p1_view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&front_n1_view),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&back_view),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: scene.environment_texels.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: outputs[0].as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: outputs[1].as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 7,
                    resource: outputs[2].as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 8,
                    resource: outputs[3].as_entire_binding(),
                },
            ],
        });
        let queries = context.timestamps.then(|| {
            let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("frame timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            });
            let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let read = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp readback"),
                size: 16,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            (set, resolve, read)
        });
        Self {
            width,
            height,
            method: params.method,
            outputs_kind: FrameOutputs::ColorAndAovs,
            raster_group,
            shade_group,
            back_view,
            front_p1_view,
            front_n1_view,
            depth_view,
            outputs,
            readback,
            queries,
        }
    }

    /// Encodes and runs every per-frame pass (back faces, front faces, kernel) and waits for the
    /// queue. With `copy_out`, also copies the outputs to the readback buffers.
    pub fn execute(
        &self,
        context: &GpuContext,
        renderer: &GpuRenderer,
        scene: &GpuScene,
        copy_out: bool,
    ) -> Result<GpuTiming, GpuError> {
        let start = std::time::Instant::now();
        let mut encoder = context
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        let first_write = |index: u32| {
            self.queries
                .as_ref()
                .map(|(set, _, _)| wgpu::RenderPassTimestampWrites {
                    query_set: set,
                    beginning_of_pass_write_index: Some(index),
                    end_of_pass_write_index: None,
                })
        };
        let depth_attachment = |clear: f32| wgpu::RenderPassDepthStencilAttachment {
            view: &self.depth_view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(clear),
                store: wgpu::StoreOp::Discard,
            }),
            stencil_ops: None,
        };
        fn color(
            view: &wgpu::TextureView,
            clear: wgpu::Color,
        ) -> Option<wgpu::RenderPassColorAttachment<'_>> {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear),
                    store: wgpu::StoreOp::Store,
                },
            })
        }
        let mut first_pass = true;
        if let Method::TwoInterface { back, .. } = self.method {
            let (pipeline, clear_depth) = match back {
                BackSurface::Furthest => (&renderer.back_furthest, 0.0),
                BackSurface::Second => (&renderer.back_second, 1.0),
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("back faces"),
                color_attachments: &[color(
                    &self.back_view,
                    wgpu::Color {
                        r: 0.0,
                        g: 0.0,
                        b: 0.0,
                        a: -1.0,
                    },
                )],
                depth_stencil_attachment: Some(depth_attachment(clear_depth)),
                timestamp_writes: first_write(0),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &self.raster_group, &[]);
            pass.set_vertex_buffer(0, scene.vertices.slice(..));
            pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..scene.index_count, 0, 0..1);
            first_pass = false;
        }
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("front faces"),
                color_attachments: &[
                    color(&self.front_p1_view, wgpu::Color::TRANSPARENT),
                    color(&self.front_n1_view, wgpu::Color::TRANSPARENT),
                ],
                depth_stencil_attachment: Some(depth_attachment(1.0)),
                timestamp_writes: if first_pass { first_write(0) } else { None },
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&renderer.front);
            pass.set_bind_group(0, &self.raster_group, &[]);
            pass.set_vertex_buffer(0, scene.vertices.slice(..));
            pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..scene.index_count, 0, 0..1);
        }
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("kernel"),
                timestamp_writes: self.queries.as_ref().map(|(set, _, _)| {
                    wgpu::ComputePassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: None,
                        end_of_pass_write_index: Some(1),
                    }
                }),
            });
            pass.set_pipeline(match self.outputs_kind {
                FrameOutputs::ColorAndAovs => &renderer.shade,
                FrameOutputs::Color => &renderer.shade_color_only,
            });
            pass.set_bind_group(0, &self.shade_group, &[]);
            pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
        }
        if let Some((set, resolve, read)) = &self.queries {
            encoder.resolve_query_set(set, 0..2, resolve, 0);
            encoder.copy_buffer_to_buffer(resolve, 0, read, 0, 16);
        }
        if copy_out {
            for (output, readback) in self.outputs.iter().zip(&self.readback) {
                encoder.copy_buffer_to_buffer(output, 0, readback, 0, output.size());
            }
        }
        context.checked(|| context.queue.submit([encoder.finish()]))?;
        context.wait()?;
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        match &self.queries {
            Some((_, _, read)) => {
                let bytes = context.read_buffer(read)?;
                let ticks: &[u64] = bytemuck::cast_slice(&bytes);
                let ns = ticks[1].saturating_sub(ticks[0]) as f64
                    * f64::from(context.queue.get_timestamp_period());
                Ok(GpuTiming {
                    ms: ns / 1e6,
                    from_timestamps: true,
                })
            }
            None => Ok(GpuTiming {
                ms: wall_ms,
                from_timestamps: false,
            }),
        }
    }

    /// Reads the outputs of the last [`GpuFrame::execute`] with `copy_out` into a [`MethodFrame`].
    pub fn read(&self, context: &GpuContext) -> Result<MethodFrame, GpuError> {
        let mut data = Vec::with_capacity(4);
        for buffer in &self.readback {
            let bytes = context.read_buffer(buffer)?;
            data.push(bytemuck::cast_slice::<u8, [f32; 4]>(&bytes).to_vec());
        }
        let (color, t2, p2, n2) = (&data[0], &data[1], &data[2], &data[3]);
        let n = (self.width * self.height) as usize;
        let mut frame = MethodFrame {
            width: self.width,
            height: self.height,
            color: Vec::with_capacity(n),
            aov: Vec::with_capacity(n),
        };
        for i in 0..n {
            frame
                .color
                .push(Vec3::new(color[i][0], color[i][1], color[i][2]));
            if self.outputs_kind == FrameOutputs::Color {
                continue;
            }
            if color[i][3] < 0.5 {
                frame.aov.push(MethodAov::BACKGROUND);
                continue;
            }
            let source = match p2[i][3].round() as u32 {
                1 => Some(ExitNormalSource::BackFace),
                2 => Some(ExitNormalSource::SilhouetteFallback),
                _ => None,
            };
            let xyz = |v: [f32; 4]| Vec3::new(v[0], v[1], v[2]);
            frame.aov.push(MethodAov {
                covered: true,
                p2: if source.is_some() {
                    xyz(p2[i])
                } else {
                    Vec3::NAN
                },
                t2: xyz(t2[i]),
                n2: if n2[i][3] > 0.5 {
                    xyz(n2[i])
                } else {
                    Vec3::NAN
                },
                n2_source: source,
                tir: t2[i][3] > 0.5,
            });
        }
        Ok(frame)
    }
}

/// Renders one frame of `params.method` on the GPU and reads it back.
pub fn render_method(
    context: &GpuContext,
    renderer: &GpuRenderer,
    scene: &GpuScene,
    camera: &Camera,
    params: &MethodParams,
) -> Result<(MethodFrame, GpuTiming), GpuError> {
    let frame = GpuFrame::new(context, renderer, scene, camera, params)?;
    let timing = frame.execute(context, renderer, scene, true)?;
    Ok((frame.read(context)?, timing))
}
