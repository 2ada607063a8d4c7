//! Wyman 2005b on the CPU backend at 1024²: every nearby-geometry method on the built-in
//! `chart` scene (a glass sphere before two textured planes), whole colour-only frames, and the
//! NG pass (the opaque objects into the NG texture) alone.

use std::sync::Arc;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use refract_cpu::CpuRenderer;
use refract_cpu::object_surfaces::{NearbyMeshes, NearbyTexture};
use refract_eval::load_scene;
use refract_scene::{Aov, Family, Frame, FrameOutputs, MethodParams, REGISTRY, Renderer};

const RES: u32 = 1024;

fn nearby_geometry(c: &mut Criterion) {
    let scene = Arc::new(load_scene("chart").expect("chart").scene);
    let camera = scene.camera(RES, RES).expect("camera");
    let mut group = c.benchmark_group("cpu/chart");
    group.sample_size(10);
    group.throughput(Throughput::Elements(u64::from(RES * RES)));
    let (mut texture, meshes) = (NearbyTexture::default(), NearbyMeshes::objects(&scene));
    group.bench_function("ng-pass", |b| {
        b.iter(|| texture.render_into(&scene, &meshes, &camera))
    });
    let mut renderer = CpuRenderer::new();
    renderer.prepare(&scene).expect("prepare");
    let mut frame = Frame::default();
    for row in REGISTRY
        .iter()
        .filter(|m| m.family == Family::NearbyGeometry)
    {
        let params = MethodParams::defaults(row.id);
        // Correctness before timing: lookups find the planes and colours are finite.
        renderer
            .render(&camera, &params, FrameOutputs::ColorAndAovs, &mut frame)
            .expect("frame");
        let hits = frame.vec3(Aov::PGeom).expect("P_geom");
        assert!(hits.iter().any(|p| !p.is_nan()) && frame.color.iter().all(|c| c.is_finite()));
        group.bench_function(format!("{}/frame-colour-only", row.name), |b| {
            b.iter(|| {
                renderer
                    .render(&camera, &params, FrameOutputs::Color, &mut frame)
                    .expect("frame")
            })
        });
    }
    group.finish();
}

criterion_group!(benches, nearby_geometry);
criterion_main!(benches);
