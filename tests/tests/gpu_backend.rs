//! Whole frames: the GPU backend against the CPU backend, every method, on the built-in sphere
//! and the cow at 256². Both run the same math on the same kind of buffers; they differ by
//! rasterisation rounding (which triangle owns a pixel centre on an edge, interpolation order)
//! and by transcendental-function ulps, which matter where the result is discontinuous:
//! silhouettes, TIR boundaries, texel edges of the back-face lookup.

use refract_core::exit::TirPolicy;
use refract_core::vector::angle_between;
use refract_core::{BackSurface, Method};
use refract_cpu::{MethodFrame, MethodParams, render_method};
use refract_gpu::{GpuContext, GpuRenderer, GpuScene};
use refract_tests::scenes::{TestScene, camera};
use refract_tests::shared_data;
use refract_trace::tonemap::to_srgb8;

struct Agreement {
    coverage: f64,
    t2_differs: f64,
    color_differs: f64,
}

fn agreement(cpu: &MethodFrame, gpu: &MethodFrame) -> Agreement {
    let (mut union, mut same_coverage, mut both, mut t2_differs, mut color_differs) =
        (0, 0, 0, 0, 0);
    for i in 0..cpu.aov.len() {
        let (c, g) = (&cpu.aov[i], &gpu.aov[i]);
        if c.covered || g.covered {
            union += 1;
            same_coverage += usize::from(c.covered == g.covered);
        }
        if c.covered && g.covered {
            both += 1;
            let angle = angle_between(c.t2, g.t2);
            t2_differs += usize::from(angle.is_nan() || angle > 1e-3);
            let (a, b) = (to_srgb8(cpu.color[i]), to_srgb8(gpu.color[i]));
            color_differs += usize::from(a.iter().zip(b).any(|(x, y)| x.abs_diff(y) > 1));
        }
    }
    Agreement {
        coverage: same_coverage as f64 / union as f64,
        t2_differs: t2_differs as f64 / both as f64,
        color_differs: color_differs as f64 / both as f64,
    }
}

/// Bounds from the measured values printed below (lavapipe: T2 differs on at most 0.8 % of the
/// cow's refractor pixels, colours on at most 0.7 %), with margin: coverage agrees on ≥ 99.5 %
/// of the refractor pixels; T2 differs by more than 1e-3 rad on at most 2 % and colours by more
/// than 1/255 (after the tonemap) on at most 2 % of them.
fn check(label: &str, scene: &TestScene, context: &GpuContext, renderer: &GpuRenderer) {
    let cam = camera(256);
    let gpu_scene = GpuScene::new(
        context,
        &scene.scene.refractor.mesh,
        &scene.d_n,
        &scene.scene.environment,
    );
    let ior = scene.scene.refractor.ior();
    let mut methods = Method::ALL.to_vec();
    methods.push(Method::ALL[1].with_back_surface(BackSurface::Second));
    for method in methods {
        for tir_policy in [TirPolicy::ClampToCritical, TirPolicy::Black] {
            let params = MethodParams {
                method,
                ior,
                tir_policy,
            };
            let cpu = render_method(&scene.prepared(), &scene.scene.environment, &cam, &params)
                .expect("cpu");
            let (gpu, timing) =
                refract_gpu::render_method(context, renderer, &gpu_scene, &cam, &params)
                    .expect("gpu");
            let a = agreement(&cpu, &gpu);
            let back = match method {
                Method::TwoInterface { back, .. } => Some(back),
                Method::Single => None,
            };
            println!(
                "{label} {method} ({back:?}) {tir_policy:?}: coverage {:.5}, T2 > 1e-3 rad on {:.3} %, colour > 1/255 on {:.3} % ({:.2} ms GPU)",
                a.coverage,
                100.0 * a.t2_differs,
                100.0 * a.color_differs,
                timing.ms
            );
            assert!(
                a.coverage >= 0.995,
                "{label} {method}: coverage {}",
                a.coverage
            );
            assert!(
                a.t2_differs <= 0.02,
                "{label} {method}: T2 {}",
                a.t2_differs
            );
            assert!(
                a.color_differs <= 0.02,
                "{label} {method}: colour {}",
                a.color_differs
            );
        }
    }
}

#[test]
fn gpu_frames_agree_with_cpu_frames() {
    let Some(context) = GpuContext::for_tests() else {
        return;
    };
    let renderer = GpuRenderer::new(&context).expect("pipelines");
    println!(
        "adapter: {} ({:?}), timestamps: {}",
        context.info.name, context.info.backend, context.timestamps
    );
    check(
        "sphere",
        &TestScene::builtin("sphere", 1.5),
        &context,
        &renderer,
    );
    if let Some(data) = shared_data() {
        check(
            "cow",
            &TestScene::shared(&data, "cow.obj", 1.2),
            &context,
            &renderer,
        );
    }
}

/// Bad parameters and impossible resolutions are errors, not panics.
#[test]
fn gpu_errors_are_reported() {
    let Some(context) = GpuContext::for_tests() else {
        return;
    };
    let renderer = GpuRenderer::new(&context).expect("pipelines");
    let scene = TestScene::builtin("sphere", 1.5);
    let gpu_scene = GpuScene::new(
        &context,
        &scene.scene.refractor.mesh,
        &scene.d_n,
        &scene.scene.environment,
    );
    let params = MethodParams {
        method: Method::ALL[1],
        ior: f32::NAN,
        tir_policy: TirPolicy::ClampToCritical,
    };
    assert!(
        refract_gpu::render_method(&context, &renderer, &gpu_scene, &camera(16), &params).is_err()
    );
    let params = MethodParams { ior: 1.5, ..params };
    let huge = refract_core::Camera::new(refract_core::CameraDesc {
        width: 100_000,
        height: 4,
        ..Default::default()
    })
    .expect("camera");
    let err = refract_gpu::render_method(&context, &renderer, &gpu_scene, &huge, &params)
        .expect_err("too large");
    assert!(err.to_string().contains("100000x4"), "{err}");
}

/// A colour-only frame (`WRITE_AOVS = false`) has the colours of the full frame and no AOVs.
#[test]
fn gpu_colour_only_frames_have_the_same_colours() {
    let Some(context) = GpuContext::for_tests() else {
        return;
    };
    let renderer = GpuRenderer::new(&context).expect("pipelines");
    let scene = TestScene::builtin("torus", 1.33);
    let cam = camera(64);
    let gpu_scene = GpuScene::new(
        &context,
        &scene.scene.refractor.mesh,
        &scene.d_n,
        &scene.scene.environment,
    );
    for method in Method::ALL {
        let params = MethodParams {
            method,
            ior: 1.33,
            tir_policy: TirPolicy::ClampToCritical,
        };
        let frame = |outputs| {
            let frame = refract_gpu::GpuFrame::with_outputs(
                &context, &renderer, &gpu_scene, &cam, &params, outputs,
            )
            .expect("frame");
            frame
                .execute(&context, &renderer, &gpu_scene, true)
                .expect("execute");
            frame.read(&context).expect("read")
        };
        let full = frame(refract_cpu::FrameOutputs::ColorAndAovs);
        let colour = frame(refract_cpu::FrameOutputs::Color);
        assert!(colour.aov.is_empty() && full.aov.len() == 64 * 64);
        let worst = full
            .color
            .iter()
            .zip(&colour.color)
            .map(|(a, b)| (*a - *b).abs().max_element())
            .fold(0.0f32, f32::max);
        assert!(worst <= 1e-5, "{method}: colours differ by {worst}");
    }
}
