//! A mesh's BVH on the GPU ([`refract_geometry::FlatBvh`] uploaded as two storage buffers) and
//! closest-hit queries against it (`shaders/bvh.wgsl`): the traversal the exact reference will
//! run in WGSL (issue 32), held to the CPU's [`refract_geometry::MeshBvh`] by the conformance
//! test `gpu_bvh_closest_hits_match_the_cpu_bvh`.

use refract_core::Ray;
use refract_geometry::{FlatBvh, FlatNode, FlatTriangle};
use wgpu::util::DeviceExt;

use crate::bindings::storage_entry;
use crate::context::{GpuContext, GpuError};
use crate::shaders::{BVH, ShaderModule, WgslFile};

/// The BVH's batch kernel ([`GpuBvh::closest_hits`]).
const BVH_TRACE: WgslFile = ("bvh_trace.wgsl", include_str!("bvh_trace.wgsl"));

/// Closest-hit queries against a flattened BVH (`refract_gpu::bvh`).
pub const BVH_MODULE: ShaderModule = ShaderModule {
    name: "bvh",
    files: &[BVH, BVH_TRACE],
};

/// A flattened BVH in storage buffers.
pub struct GpuBvh {
    nodes: wgpu::Buffer,
    triangles: wgpu::Buffer,
    /// The mesh's index of each triangle in leaf order.
    original: Vec<u32>,
}

/// One closest hit read back from the GPU.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuHit {
    /// The ray parameter (the rays' directions are unit: the distance).
    pub t: f32,
    /// The mesh's triangle.
    pub triangle: u32,
}

impl GpuBvh {
    /// Uploads `bvh` (an empty BVH gets one placeholder node and triangle: WebGPU has no empty
    /// storage buffers; the shader sees no triangles through `original`'s length).
    pub fn upload(context: &GpuContext, bvh: &FlatBvh) -> Result<Self, GpuError> {
        let device = &context.device;
        let mut nodes = bvh.nodes.clone();
        let mut triangles = bvh.triangles.clone();
        if triangles.is_empty() {
            nodes = vec![FlatNode {
                min: [f32::INFINITY; 3],
                max: [f32::NEG_INFINITY; 3],
                ..FlatNode::default()
            }];
            triangles = vec![FlatTriangle::default()];
        }
        context.check_storage::<FlatNode>("BVH nodes", nodes.len())?;
        context.check_storage::<FlatTriangle>("triangles", triangles.len())?;
        context.checked(|| Self {
            nodes: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("bvh nodes"),
                contents: bytemuck::cast_slice(&nodes),
                usage: wgpu::BufferUsages::STORAGE,
            }),
            triangles: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("bvh triangles"),
                contents: bytemuck::cast_slice(&triangles),
                usage: wgpu::BufferUsages::STORAGE,
            }),
            original: bvh.original.clone(),
        })
    }

    /// The bind group of `bvh.wgsl`'s group 1 ([`bvh_layout`]).
    pub(crate) fn bind_group(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("bvh"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.nodes.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: self.triangles.as_entire_binding(),
                },
            ],
        })
    }

    /// The closest hit of every ray with `t ∈ [t_min, t_max]` (unit directions), traced by
    /// `trace_closest` in `shaders/bvh.wgsl`; `None` for a miss.
    pub fn closest_hits(
        &self,
        context: &GpuContext,
        rays: &[Ray],
        t_min: f32,
        t_max: f32,
    ) -> Result<Vec<Option<GpuHit>>, GpuError> {
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        let device = &context.device;
        let (pipeline, layout) = context.checked(|| {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("bvh.wgsl"),
                source: wgpu::ShaderSource::Wgsl(BVH_MODULE.source().into()),
            });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("bvh rays"),
                entries: &[storage_entry(0, true), storage_entry(1, false)],
            });
            let bvh_layout = bvh_layout(device);
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("bvh"),
                bind_group_layouts: &[Some(&layout), Some(&bvh_layout)],
                immediate_size: 0,
            });
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("trace_closest"),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some("trace_closest"),
                compilation_options: Default::default(),
                cache: None,
            });
            (pipeline, (layout, bvh_layout))
        })?;
        let (layout, bvh_layout) = layout;
        let packed: Vec<[f32; 8]> = rays
            .iter()
            .map(|r| {
                let (o, d) = (r.origin, r.dir);
                [o.x, o.y, o.z, t_min, d.x, d.y, d.z, t_max]
            })
            .collect();
        let size = (rays.len() * 8) as u64;
        let (input, output, read) = context.checked(|| {
            (
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("bvh rays"),
                    contents: bytemuck::cast_slice(&packed),
                    usage: wgpu::BufferUsages::STORAGE,
                }),
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("bvh hits"),
                    size,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("bvh hits readback"),
                    size,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
            )
        })?;
        let group = context.checked(|| {
            let rays = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("bvh rays"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: input.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: output.as_entire_binding(),
                    },
                ],
            });
            (rays, self.bind_group(device, &bvh_layout))
        })?;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("trace_closest"),
        });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("trace_closest"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group.0, &[]);
            pass.set_bind_group(1, &group.1, &[]);
            pass.dispatch_workgroups((rays.len() as u32).div_ceil(64), 1, 1);
        }
        encoder.copy_buffer_to_buffer(&output, 0, &read, 0, size);
        context.checked(|| context.queue.submit([encoder.finish()]))?;
        let bytes = context.read_buffer(&read)?;
        Ok(bytemuck::cast_slice::<u8, [u32; 2]>(&bytes)
            .iter()
            .map(|&[t, triangle]| {
                let t = f32::from_bits(t);
                self.original
                    .get(triangle as usize)
                    .filter(|_| t.is_finite() && t < f32::MAX)
                    .map(|&triangle| GpuHit { t, triangle })
            })
            .collect())
    }
}

/// The layout of `bvh.wgsl`'s group 1: the nodes and the triangles.
pub(crate) fn bvh_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("bvh"),
        entries: &[storage_entry(0, true), storage_entry(1, true)],
    })
}
