//! The CPU backend at 1024² per method: buffers and kernel separately and together, on the
//! built-in sphere and the real meshes (Wyman 2005a Table 1 models).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use refract_core::exit::TirPolicy;
use refract_core::{Camera, CameraDesc, Method};
use refract_cpu::{
    CpuRenderer, FrameBuffers, FrameOutputs, MethodFrame, MethodParams, PreparedRefractor,
    render_buffers_into, render_method, shade_into,
};
use refract_geometry::{Mesh, MeshBvh, builtin, normal_distances};
use refract_trace::Environment;

const RES: u32 = 1024;

fn cpu_methods(c: &mut Criterion) {
    let camera = Camera::new(CameraDesc {
        width: RES,
        height: RES,
        ..CameraDesc::default()
    })
    .expect("camera");
    let environment = Environment::Procedural;
    let mut meshes: Vec<(&str, Mesh)> = vec![("sphere", builtin::mesh("sphere").expect("builtin"))];
    for (label, file) in [("cow", "cow.obj"), ("teapot", "teapot.obj")]
        .into_iter()
        .chain(refract_benches::BENCH_MESHES.into_iter().skip(1))
    {
        if let Some(mesh) = refract_benches::load_shared_mesh(file) {
            meshes.push((label, mesh));
        }
    }
    for (label, mesh) in &meshes {
        let d_n = normal_distances(mesh, &MeshBvh::build(mesh)).values;
        let refractor = PreparedRefractor { mesh, d_n: &d_n };
        let mut group = c.benchmark_group(format!("cpu/{label}"));
        group.sample_size(10);
        group.throughput(Throughput::Elements(u64::from(RES * RES)));
        for method in Method::ALL {
            let params = MethodParams {
                method,
                ior: 1.5,
                tir_policy: TirPolicy::ClampToCritical,
            };
            // Correctness before timing: the refractor covers pixels and colours are finite.
            let frame = render_method(&refractor, &environment, &camera, &params).expect("frame");
            assert!(
                frame.aov.iter().any(|a| a.covered) && frame.color.iter().all(|c| c.is_finite())
            );
            let mut renderer = CpuRenderer::default();
            group.bench_function(format!("{method}/frame"), |b| {
                b.iter(|| {
                    renderer
                        .render(&refractor, &environment, &camera, &params)
                        .expect("frame");
                })
            });
            let mut colour_only = CpuRenderer::new(FrameOutputs::Color);
            group.bench_function(format!("{method}/frame-colour-only"), |b| {
                b.iter(|| {
                    colour_only
                        .render(&refractor, &environment, &camera, &params)
                        .expect("frame");
                })
            });
            // The two-step path, stage by stage (memory reused as in a frame).
            let mut buffers = FrameBuffers::default();
            group.bench_function(format!("{method}/buffers"), |b| {
                b.iter(|| {
                    render_buffers_into(&refractor, &camera, method, &mut buffers).expect("buffers")
                })
            });
            let mut frame = MethodFrame::default();
            group.bench_function(format!("{method}/kernel"), |b| {
                b.iter(|| {
                    shade_into(&buffers, &environment, &camera, &params, &mut frame).expect("shade")
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, cpu_methods);
criterion_main!(benches);
