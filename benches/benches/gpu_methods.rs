//! The GPU backend per method at 512² and 1024²: every per-frame pass (back faces, front faces,
//! kernel), submitted and waited for. Skips with a notice when no adapter exists.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use refract_core::exit::TirPolicy;
use refract_core::{Camera, CameraDesc, Method};
use refract_cpu::MethodParams;
use refract_geometry::{Mesh, MeshBvh, builtin, normal_distances};
use refract_gpu::{GpuContext, GpuFrame, GpuRenderer, GpuScene};
use refract_trace::Environment;

fn gpu_methods(c: &mut Criterion) {
    let Ok(context) = GpuContext::new() else {
        eprintln!("skipped: no GPU adapter");
        return;
    };
    let renderer = GpuRenderer::new(&context).expect("pipelines");
    let environment = Environment::Procedural;
    let mut meshes: Vec<(&str, Mesh)> = vec![("sphere", builtin::mesh("sphere").expect("builtin"))];
    if let Some(cow) = refract_benches::load_shared_mesh("cow.obj") {
        meshes.push(("cow", cow));
    }
    for (label, mesh) in &meshes {
        let d_n = normal_distances(mesh, &MeshBvh::build(mesh)).values;
        let scene = GpuScene::new(&context, mesh, &d_n, &environment);
        for res in [512u32, 1024] {
            let camera = Camera::new(CameraDesc {
                width: res,
                height: res,
                ..CameraDesc::default()
            })
            .expect("camera");
            let mut group = c.benchmark_group(format!("gpu/{label}/{res}"));
            group.sample_size(10);
            group.throughput(Throughput::Elements(u64::from(res * res)));
            for method in Method::ALL {
                let params = MethodParams {
                    method,
                    ior: 1.5,
                    tir_policy: TirPolicy::ClampToCritical,
                };
                let frame =
                    GpuFrame::new(&context, &renderer, &scene, &camera, &params).expect("frame");
                // Correctness before timing: the refractor is covered and colours are finite.
                frame
                    .execute(&context, &renderer, &scene, true)
                    .expect("execute");
                let out = frame.read(&context).expect("read");
                assert!(
                    out.aov.iter().any(|a| a.covered) && out.color.iter().all(|c| c.is_finite())
                );
                group.bench_function(method.id(), |b| {
                    b.iter(|| {
                        frame
                            .execute(&context, &renderer, &scene, false)
                            .expect("execute")
                    })
                });
            }
            group.finish();
        }
    }
}

criterion_group!(benches, gpu_methods);
criterion_main!(benches);
