//! Kakimoto et al. 2007 on the CPU backend at 1024²: the per-frame plan alone (per-vertex rays
//! by BVH, virtual viewpoints, view volumes, texture coordinates) and whole colour-only frames
//! (every view rasterised, the pixels that are shown or read shaded eight at a time), on the
//! reflection, multiple-reflection and lens scenes of the paper's §5, with maps sized from the
//! footprint and fixed at 1024 texels.

use std::sync::Arc;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use refract_cpu::CpuRenderer;
use refract_eval::load_scene;
use refract_scene::pvrr::PvrrPlanner;
use refract_scene::{Frame, FrameOutputs, MethodId, MethodParams, Renderer};

const RES: u32 = 1024;

fn pvrr(c: &mut Criterion) {
    let mut group = c.benchmark_group("cpu/pvrr");
    group.sample_size(10);
    group.throughput(Throughput::Elements(u64::from(RES * RES)));
    for (name, dispersion, sizing) in [
        ("convex-mirror", "0", "footprint"),
        ("convex-mirror", "0", "fixed"),
        ("mirror-stack", "0", "footprint"),
        ("mirror-stack", "0", "fixed"),
        ("spectacles", "0", "footprint"),
        ("spectacles", "10", "footprint"),
    ] {
        let scene = Arc::new(load_scene(name).expect("built-in").scene);
        let camera = scene.camera(RES, RES).expect("camera");
        let mut params = MethodParams::defaults(MethodId::Pvrr);
        params
            .set("dispersion", dispersion, "bench")
            .expect("dispersion");
        params.set("sizing", sizing, "bench").expect("sizing");
        let MethodParams::Pvrr(p) = params else {
            unreachable!("pvrr parameters")
        };
        let mut planner = PvrrPlanner::default();
        planner.prepare(&scene);
        // Correctness before timing: the plan maps the reflector seen from the eye.
        let plan = planner.plan(&scene, &camera, &p).expect("plan");
        assert!(plan.views.len() >= 2 && plan.rays() > 0, "{name}");
        let label = format!("{name}/dispersion={dispersion}/sizing={sizing}");
        group.bench_function(format!("{label}/plan"), |b| {
            b.iter(|| planner.plan(&scene, &camera, &p).expect("plan").rays())
        });
        let mut renderer = CpuRenderer::new();
        renderer.prepare(&scene).expect("prepare");
        let mut frame = Frame::default();
        renderer
            .render(&camera, &params, FrameOutputs::Color, &mut frame)
            .expect("frame");
        assert!(frame.color.iter().all(|c| c.is_finite()), "{name}");
        group.bench_function(format!("{label}/frame-colour-only"), |b| {
            b.iter(|| {
                renderer
                    .render(&camera, &params, FrameOutputs::Color, &mut frame)
                    .expect("frame")
            })
        });
    }
    group.finish();
}

criterion_group!(benches, pvrr);
criterion_main!(benches);
