//! The GPU backend per method at 512² and 1024²: every per-frame pass (back faces, front faces,
//! kernel), submitted and waited for, colour read back. Skips with a notice when no adapter
//! exists.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use refract_geometry::{Mesh, builtin};
use refract_gpu::GpuRenderer;
use refract_scene::{Aov, Frame, FrameOutputs, MethodId, MethodParams, Renderer};

fn gpu_methods(c: &mut Criterion) {
    let Ok(mut renderer) = GpuRenderer::new() else {
        eprintln!("skipped: no GPU adapter");
        return;
    };
    let mut meshes: Vec<(&str, Mesh)> = vec![("sphere", builtin::mesh("sphere").expect("builtin"))];
    if let Some(cow) = refract_benches::load_shared_mesh("cow.obj") {
        meshes.push(("cow", cow));
    }
    let mut frame = Frame::default();
    for (label, mesh) in meshes {
        let scene = refract_benches::bench_scene(label, mesh, 1.5);
        renderer.prepare(&scene).expect("prepare");
        for res in [512u32, 1024] {
            let camera = refract_benches::bench_camera(res);
            let mut group = c.benchmark_group(format!("gpu/{label}/{res}"));
            group.sample_size(10);
            group.throughput(Throughput::Elements(u64::from(res * res)));
            for id in MethodId::approximations() {
                let params = MethodParams::defaults(id);
                // Correctness before timing: the refractor is covered and colours are finite.
                renderer
                    .render(&camera, &params, FrameOutputs::ColorAndAovs, &mut frame)
                    .expect("frame");
                let covered = frame.flag(Aov::Covered).expect("covered");
                assert!(covered.iter().any(|c| *c) && frame.color.iter().all(|c| c.is_finite()));
                group.bench_function(id.name(), |b| {
                    b.iter(|| {
                        renderer
                            .render(&camera, &params, FrameOutputs::Color, &mut frame)
                            .expect("frame")
                    })
                });
            }
            group.finish();
        }
    }
}

criterion_group!(benches, gpu_methods);
criterion_main!(benches);
