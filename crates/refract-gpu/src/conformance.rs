//! Runs one entry point of `src/conformance.wgsl` (core leaves and the distance-map search), of
//! `src/conformance_kernels.wgsl` (whole image-space kernels over an analytic back-face buffer)
//! or of a family's own conformance module (its `CONFORMANCE`, beside its module under
//! `src/methods/`: [`evaluate_family`]) on rows of inputs: the harness that holds the WGSL twin
//! to refract-core. A new family brings its conformance module with it and edits nothing here.

use glam::Vec4;
use wgpu::util::DeviceExt;

use refract_core::gpu::distance_mode_code;
use refract_core::{Camera, DistanceMode, TirPolicy};

use crate::bindings::{storage_entry, uniform_entry};
use crate::context::{GpuContext, GpuError};
use crate::frame_uniforms::frame_uniforms;
use crate::scene_buffers::EnvironmentUniforms;
use crate::shaders::{
    CORE, DISTANCE_SEARCH, FRAME, PROCEDURAL_SKY, SPECTRAL, ShaderModule, TWO_INTERFACE, WgslFile,
};

/// The leaves' entry points (`src/conformance.wgsl`).
const CONFORMANCE: WgslFile = ("conformance.wgsl", include_str!("conformance.wgsl"));

/// The whole-kernel entry points (`src/conformance_kernels.wgsl`).
const CONFORMANCE_KERNELS: WgslFile = (
    "conformance_kernels.wgsl",
    include_str!("conformance_kernels.wgsl"),
);

/// The conformance harness (`refract_gpu::conformance`).
pub const CONFORMANCE_MODULE: ShaderModule = ShaderModule {
    name: "conformance",
    files: &[CORE, PROCEDURAL_SKY, SPECTRAL, DISTANCE_SEARCH, CONFORMANCE],
};

/// The module of `src/conformance_kernels.wgsl`.
pub const CONFORMANCE_KERNELS_MODULE: ShaderModule = ShaderModule {
    name: "conformance-kernels",
    files: &[CORE, FRAME, TWO_INTERFACE, CONFORMANCE_KERNELS],
};

/// The entry points of the conformance module.
pub const ENTRY_POINTS: [&str; 22] = [
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
    "test_ggx",
    "test_rough_normal",
    "test_rough_reflected",
    "test_rough_refracted",
    "test_spectral_tables",
    "test_spectral_sample",
];

/// The entry points of the whole-kernel module (`src/conformance_kernels.wgsl`).
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
    run(context, &CONFORMANCE_MODULE, entry, &[], &[], a, b)
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
        &[(0, bytes)],
        &constants,
        a,
        b,
    )
}

/// One evaluation of a family's own conformance module (a family module's `CONFORMANCE`, in
/// [`crate::shader_modules`]): the module and entry point, the frame (its uniforms at binding 0:
/// the camera and the IOR), the family's own uniform blocks at their bindings, and the
/// pipeline's override constants. The rows are bindings 1–3, as in
/// `src/conformance_kernels.wgsl`.
#[derive(Clone, Copy, Debug)]
pub struct FamilyEvaluation<'a> {
    /// The conformance module's name (`engine-conformance`, ...).
    pub module: &'a str,
    /// Its entry point.
    pub entry: &'a str,
    /// The camera of the frame uniforms.
    pub camera: &'a Camera,
    /// The index of refraction of the frame uniforms.
    pub ior: f32,
    /// The family's uniform blocks besides the frame's: `(binding, bytes)`.
    pub uniforms: &'a [(u32, &'a [u8])],
    /// Override constants (`ENGINE_MODEL`, ...).
    pub constants: &'a [(&'a str, f64)],
}

/// The uniform block of the objects' surfaces (binding 15 of the nearby-geometry shaders) for
/// an NG camera with `planes` and `lookup`, as a nearby-geometry frame writes it: for
/// [`FamilyEvaluation::uniforms`].
pub fn nearby_uniforms(
    ng_camera: &Camera,
    planes: &[refract_core::nearby_geometry::Plane],
    lookup: refract_core::nearby_geometry::NearbyLookup,
) -> refract_core::gpu::NearbyUniforms {
    crate::passes::object_surfaces::nearby_uniforms(&crate::passes::object_surfaces::NearbyFrame {
        ng_camera,
        pad: glam::UVec2::ZERO,
        planes,
        lookup,
        light: refract_scene::DirectionalLight::default(),
    })
}

/// Evaluates `evaluation` on `a[i], b[i]` for every row and returns one `Vec4` per row; a
/// module of that name that does not exist is a [`GpuError::Wgpu`] naming it.
pub fn evaluate_family(
    context: &GpuContext,
    evaluation: &FamilyEvaluation<'_>,
    a: &[Vec4],
    b: &[Vec4],
) -> Result<Vec<Vec4>, GpuError> {
    let module = crate::shader_modules()
        .into_iter()
        .find(|m| m.name == evaluation.module)
        .ok_or_else(|| GpuError::Wgpu(format!("no shader module {}", evaluation.module)))?;
    let environment = EnvironmentUniforms {
        kind: 0,
        width: 0,
        height: 0,
        intensity: 0.0,
        constant: [0.0; 4],
    };
    let frame = frame_uniforms(
        evaluation.camera,
        &environment,
        evaluation.ior,
        TirPolicy::default(),
    );
    let mut uniforms = vec![(0, bytemuck::bytes_of(&frame))];
    uniforms.extend_from_slice(evaluation.uniforms);
    run(
        context,
        &module,
        evaluation.entry,
        &uniforms,
        evaluation.constants,
        a,
        b,
    )
}

/// Runs `entry` of `module` over the rows; with `uniforms` (`(binding, bytes)` blocks), the
/// rows are bindings 1–3, else bindings 0–2.
fn run(
    context: &GpuContext,
    module: &ShaderModule,
    entry: &str,
    uniforms: &[(u32, &[u8])],
    constants: &[(&str, f64)],
    a: &[Vec4],
    b: &[Vec4],
) -> Result<Vec<Vec4>, GpuError> {
    assert_eq!(a.len(), b.len(), "one b row per a row");
    let device = &context.device;
    let first = u32::from(!uniforms.is_empty());
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
        for (binding, _) in uniforms {
            entries.push(uniform_entry(*binding, wgpu::ShaderStages::COMPUTE));
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
    let uniform_buffers: Vec<(u32, wgpu::Buffer)> = uniforms
        .iter()
        .map(|(binding, bytes)| {
            let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("conformance uniforms"),
                contents: bytes,
                usage: wgpu::BufferUsages::UNIFORM,
            });
            (*binding, buffer)
        })
        .collect();
    let mut entries: Vec<wgpu::BindGroupEntry<'_>> = [&in_a, &in_b, &out]
        .into_iter()
        .zip(first..)
        .map(|(buffer, binding)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    for (binding, buffer) in &uniform_buffers {
        entries.push(wgpu::BindGroupEntry {
            binding: *binding,
            resource: buffer.as_entire_binding(),
        });
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
