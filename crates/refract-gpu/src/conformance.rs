//! Runs one entry point of `shaders/conformance.wgsl` (leaves and the distance-map search) or of
//! `shaders/conformance_kernels.wgsl` (whole image-space kernels over an analytic back-face
//! buffer) on rows of inputs: the harness that holds the WGSL twin to refract-core.

use glam::Vec4;
use wgpu::util::DeviceExt;

use refract_core::gpu::distance_mode_code;
use refract_core::{Camera, DistanceMode, TirPolicy};

use crate::bindings::{storage_entry, uniform_entry};
use crate::context::{GpuContext, GpuError};
use crate::frame_uniforms::frame_uniforms;
use crate::scene_buffers::EnvironmentUniforms;
use crate::shaders::{CONFORMANCE_KERNELS_MODULE, CONFORMANCE_MODULE, ShaderModule};

/// The entry points of the conformance module.
pub const ENTRY_POINTS: [&str; 21] = [
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
    "test_proxy_sphere_point",
    "test_proxy_sphere_dir",
    "test_proxy_box",
    "test_volume_exit",
    "test_engine_screen",
];

/// The entry points of the whole-kernel module (`shaders/conformance_kernels.wgsl`).
pub const KERNEL_ENTRY_POINTS: [&str; 4] = [
    "test_one_interface",
    "test_two_interface_t2",
    "test_two_interface_p2",
    "test_two_interface_n2",
];

/// Evaluates `entry` on `a[i], b[i]` for every row and returns one `Vec4` per row.
pub fn evaluate(
    context: &GpuContext,
    entry: &str,
    a: &[Vec4],
    b: &[Vec4],
) -> Result<Vec<Vec4>, GpuError> {
    run(context, &CONFORMANCE_MODULE, entry, None, &[], a, b)
}

/// The frame a whole-kernel evaluation runs in: the camera, and the index of refraction, TIR
/// policy and distance mode of a `wyman`-family frame.
#[derive(Clone, Copy, Debug)]
pub struct KernelFrame<'a> {
    /// The camera (the frame's size, eye, projection).
    pub camera: &'a Camera,
    /// The refractor's index of refraction.
    pub ior: f32,
    /// The TIR policy at the exit.
    pub tir: TirPolicy,
    /// How `d~` is approximated (the pipeline's `DISTANCE_MODE`).
    pub distance_mode: DistanceMode,
}

/// Evaluates `entry` of the whole-kernel module ([`KERNEL_ENTRY_POINTS`]) on `a[i], b[i]`: the
/// image-space kernels of `shaders/two_interface.wgsl` in `frame`, through an analytic
/// back-face buffer (the far side of a unit sphere at the origin).
pub fn evaluate_kernel(
    context: &GpuContext,
    entry: &str,
    frame: &KernelFrame<'_>,
    a: &[Vec4],
    b: &[Vec4],
) -> Result<Vec<Vec4>, GpuError> {
    let environment = EnvironmentUniforms {
        kind: 0,
        width: 0,
        height: 0,
        intensity: 0.0,
        constant: [0.0; 4],
    };
    let uniforms = frame_uniforms(frame.camera, &environment, frame.ior, frame.tir);
    let mode = f64::from(distance_mode_code(frame.distance_mode));
    let constants = [("DISTANCE_MODE", mode)];
    let bytes = bytemuck::bytes_of(&uniforms);
    run(
        context,
        &CONFORMANCE_KERNELS_MODULE,
        entry,
        Some(bytes),
        &constants,
        a,
        b,
    )
}

/// Runs `entry` of `module` over the rows; with `uniforms`, binding 0 is that uniform block and
/// the rows are bindings 1–3, else the rows are bindings 0–2.
fn run(
    context: &GpuContext,
    module: &ShaderModule,
    entry: &str,
    uniforms: Option<&[u8]>,
    constants: &[(&str, f64)],
    a: &[Vec4],
    b: &[Vec4],
) -> Result<Vec<Vec4>, GpuError> {
    assert_eq!(a.len(), b.len(), "one b row per a row");
    let device = &context.device;
    let first = u32::from(uniforms.is_some());
    let (pipeline, layout_group) = context.checked(|| {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(module.name),
            source: wgpu::ShaderSource::Wgsl(module.source().into()),
        });
        // An explicit layout: an automatic one would drop the bindings an entry point ignores.
        let mut entries = vec![
            storage_entry(first, true),
            storage_entry(first + 1, true),
            storage_entry(first + 2, false),
        ];
        if uniforms.is_some() {
            entries.insert(0, uniform_entry(0, wgpu::ShaderStages::COMPUTE));
        }
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("conformance"),
            entries: &entries,
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
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
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
    let uniform_buffer = uniforms.map(|bytes| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("frame uniforms"),
            contents: bytes,
            usage: wgpu::BufferUsages::UNIFORM,
        })
    });
    let mut entries: Vec<wgpu::BindGroupEntry<'_>> = [&in_a, &in_b, &out]
        .into_iter()
        .zip(first..)
        .map(|(buffer, binding)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    if let Some(buffer) = &uniform_buffer {
        entries.insert(
            0,
            wgpu::BindGroupEntry {
                binding: 0,
                resource: buffer.as_entire_binding(),
            },
        );
    }
    let group = context.checked(|| {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("conformance"),
            layout: &layout_group,
            entries: &entries,
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
