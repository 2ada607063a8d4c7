//! Runs one entry point of `shaders/conformance.wgsl` on rows of inputs: the harness that holds
//! the WGSL twin to refract-core.

use glam::Vec4;
use wgpu::util::DeviceExt;

use crate::bindings::storage_entry;
use crate::context::{GpuContext, GpuError};
use crate::shaders::CONFORMANCE_MODULE;

/// The entry points of the conformance module.
pub const ENTRY_POINTS: [&str; 16] = [
    "test_refract",
    "test_reflect",
    "test_face_forward",
    "test_fresnel",
    "test_fresnel_conductor",
    "test_distance",
    "test_exit",
    "test_exit_normal",
    "test_normalize",
    "test_latlong",
    "test_procedural_sky",
    "test_plane",
    "test_seed_fraction",
    "test_dm_texel",
    "test_dm_hit",
    "test_dm_path",
];

/// Evaluates `entry` on `a[i], b[i]` for every row and returns one `Vec4` per row.
pub fn evaluate(
    context: &GpuContext,
    entry: &str,
    a: &[Vec4],
    b: &[Vec4],
) -> Result<Vec<Vec4>, GpuError> {
    assert_eq!(a.len(), b.len(), "one b row per a row");
    let device = &context.device;
    let (pipeline, layout_group) = context.checked(|| {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("conformance.wgsl"),
            source: wgpu::ShaderSource::Wgsl(CONFORMANCE_MODULE.source().into()),
        });
        // An explicit layout: an automatic one would drop the bindings an entry point ignores.
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("conformance"),
            entries: &[
                storage_entry(0, true),
                storage_entry(1, true),
                storage_entry(2, false),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("conformance"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
        (pipeline, layout)
    })?;
    let rows = a.len().max(1);
    let input = |data: &[Vec4], label: &str| {
        let mut bytes: Vec<[f32; 4]> = data.iter().map(|v| v.to_array()).collect();
        bytes.resize(rows, [0.0; 4]);
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(&bytes),
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let (in_a, in_b) = (input(a, "in_a"), input(b, "in_b"));
    let size = (rows * 16) as u64;
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("out"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let read = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("out readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let group = context.checked(|| {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("conformance"),
            layout: &layout_group,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: in_a.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: in_b.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: out.as_entire_binding(),
                },
            ],
        })
    })?;
    let mut encoder =
        device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(entry) });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(entry),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups((rows as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&out, 0, &read, 0, size);
    context.checked(|| context.queue.submit([encoder.finish()]))?;
    let bytes = context.read_buffer(&read)?;
    Ok(bytemuck::cast_slice::<u8, [f32; 4]>(&bytes)
        .iter()
        .take(a.len())
        .map(|v| Vec4::from_array(*v))
        .collect())
}
