//! The CPU backend at 1024² per method: buffers and kernel separately and together, on the
//! built-in sphere and the real meshes (Wyman 2005a Table 1 models); and the shared stages
//! alone (scan conversion, the back faces resolved).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use refract_core::BackSurface;
use refract_cpu::{
    BackFaces, CpuRenderer, DepthTest, Faces, FrameBuffers, RasterMesh, SurfaceBuffer,
    rasterize_into, render_buffers_into, shade_into,
};
use refract_geometry::{Mesh, builtin};
use refract_scene::{Aov, Family, Frame, FrameOutputs, MethodId, MethodParams, Renderer};

const RES: u32 = 1024;

fn cpu_methods(c: &mut Criterion) {
    let camera = refract_benches::bench_camera(RES);
    let mut meshes: Vec<(&str, Mesh)> = vec![("sphere", builtin::mesh("sphere").expect("builtin"))];
    for (label, file) in [("cow", "cow.obj"), ("teapot", "teapot.obj")]
        .into_iter()
        .chain(refract_benches::BENCH_MESHES.into_iter().skip(1))
    {
        if let Some(mesh) = refract_benches::load_shared_mesh(file) {
            meshes.push((label, mesh));
        }
    }
    for (label, mesh) in meshes {
        let scene = refract_benches::bench_scene(label, mesh, 1.5);
        let mut group = c.benchmark_group(format!("cpu/{label}"));
        group.sample_size(10);
        group.throughput(Throughput::Elements(u64::from(RES * RES)));
        let mut renderer = CpuRenderer::new();
        renderer.prepare(&scene).expect("prepare");
        let mut frame = Frame::default();
        // The image-space family (nearby geometry: benches/nearby_geometry.rs).
        for id in MethodId::approximations().filter(|id| id.info().family == Family::ImageSpace) {
            let params = MethodParams::defaults(id);
            // Correctness before timing: the refractor covers pixels and colours are finite.
            renderer
                .render(&camera, &params, FrameOutputs::ColorAndAovs, &mut frame)
                .expect("frame");
            let covered = frame.flag(Aov::Covered).expect("covered");
            assert!(covered.iter().any(|c| *c) && frame.color.iter().all(|c| c.is_finite()));
            for (name, outputs) in [
                ("frame", FrameOutputs::ColorAndAovs),
                ("frame-colour-only", FrameOutputs::Color),
            ] {
                group.bench_function(format!("{id}/{name}"), |b| {
                    b.iter(|| {
                        renderer
                            .render(&camera, &params, outputs, &mut frame)
                            .expect("frame")
                    })
                });
            }
            // The two-step path, stage by stage (memory reused as in a frame).
            let MethodParams::ImageSpace(method) = params else {
                panic!("{id} is of the image-space family")
            };
            let back = method.back_surface();
            let kernel = method.kernel(scene.refractor.ior()).expect("kernel");
            let mut buffers = FrameBuffers::default();
            group.bench_function(format!("{id}/buffers"), |b| {
                b.iter(|| render_buffers_into(&scene, &camera, back, &mut buffers))
            });
            group.bench_function(format!("{id}/kernel"), |b| {
                b.iter(|| {
                    shade_into(
                        &buffers,
                        &scene.environment,
                        &camera,
                        &kernel,
                        id,
                        FrameOutputs::Color,
                        &mut frame,
                    )
                    .expect("frame")
                })
            });
        }
        // Stages shared by every rasterising method, alone: scan conversion (visibility only)
        // and the back faces rasterised and resolved into normals and distances.
        let raster = RasterMesh::with_scalars(scene.refractor.mesh(), scene.refractor.d_n());
        let mut surface = SurfaceBuffer::new();
        group.bench_function("stage/scan-conversion-front", |b| {
            b.iter(|| {
                rasterize_into(
                    &raster,
                    &camera,
                    Faces::Front,
                    DepthTest::Nearest,
                    &mut surface,
                )
            })
        });
        let mut back = BackFaces::default();
        group.bench_function("stage/back-faces-resolved", |b| {
            b.iter(|| back.render_into(&scene.refractor, &camera, BackSurface::Furthest))
        });
        group.finish();
    }
}

criterion_group!(benches, cpu_methods);
criterion_main!(benches);
