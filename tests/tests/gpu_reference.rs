//! The exact reference's transmission mode on the GPU (`refract_gpu::reference`, WGSL) against
//! the CPU reference (`refract_trace`), pixel by pixel on every built-in scene: the same first
//! hits, the same path records and colours but for f32 noise (issue 32's conformance bounds).

use std::sync::Arc;

use glam::Vec3;
use refract_eval::load_scene;
use refract_gpu::GpuContext;
use refract_gpu::reference::GpuReference;
use refract_scene::{Aov, Frame, FrameOutputs, MethodId, MethodParams, Scene, TraceSettings};

const RES: u32 = 96;

fn vectors(frame: &Frame, aov: Aov) -> &[Vec3] {
    frame
        .vec3(aov)
        .unwrap_or_else(|| panic!("no {aov:?} layer"))
}

fn flags(frame: &Frame, aov: Aov) -> &[bool] {
    frame
        .flag(aov)
        .unwrap_or_else(|| panic!("no {aov:?} layer"))
}

/// Two points are the same hit: both absent (NaN), or within 10⁻⁴ of the scene's scale.
fn same_point(a: Vec3, b: Vec3) -> bool {
    (a.is_nan() && b.is_nan()) || (a - b).length() <= 1e-4 * (1.0 + a.length())
}

/// Per scene: (share of pixels with the same first hit, share with the same colour within
/// 10⁻³ relative, mean absolute colour difference).
fn compare(name: &str, scene: &Arc<Scene>, context: &GpuContext) -> (f64, f64, f64) {
    let camera = scene.camera(RES, RES).expect("camera");
    let settings = TraceSettings::default();
    let cpu = refract_trace::render(scene, &camera, &settings);
    let mut gpu = Frame::default();
    GpuReference::new(context, scene)
        .expect("upload")
        .render(
            context,
            &camera,
            &settings,
            FrameOutputs::ColorAndAovs,
            &mut gpu,
        )
        .expect("GPU reference");
    // Exactly the layers of the reference row, as the CPU writes them.
    let mut expected: Vec<Aov> = MethodId::Reference.info().aovs.to_vec();
    let mut written: Vec<Aov> = gpu.aovs().collect();
    expected.sort();
    written.sort();
    assert_eq!(written, expected, "{name}");
    // The same rays traced: one per closest-hit query, counted on both.
    assert!(
        gpu.rays.abs_diff(cpu.rays) * 1000 <= cpu.rays,
        "{name}: {} rays on the GPU, {} on the CPU",
        gpu.rays,
        cpu.rays
    );
    let n = (RES * RES) as usize;
    let (cpu_p1, gpu_p1) = (vectors(&cpu, Aov::P1), vectors(&gpu, Aov::P1));
    let (cpu_cov, gpu_cov) = (flags(&cpu, Aov::Covered), flags(&gpu, Aov::Covered));
    let same_hit = (0..n)
        .filter(|&i| cpu_cov[i] == gpu_cov[i] && same_point(cpu_p1[i], gpu_p1[i]))
        .count();
    let same_color = (0..n)
        .filter(|&i| {
            let (a, b) = (cpu.color[i], gpu.color[i]);
            (a - b).abs().max_element() <= 1e-3 * (1.0 + a.abs().max_element())
        })
        .count();
    let mean = (0..n)
        .map(|i| f64::from((cpu.color[i] - gpu.color[i]).abs().max_element()))
        .sum::<f64>()
        / n as f64;
    let covered = cpu_cov.iter().filter(|c| **c).count();
    println!(
        "{name}: {covered} covered pixels; same first hit on {:.2} %, same colour on {:.2} %, mean |Δ| {mean:.2e}",
        100.0 * same_hit as f64 / n as f64,
        100.0 * same_color as f64 / n as f64
    );
    (
        same_hit as f64 / n as f64,
        same_color as f64 / n as f64,
        mean,
    )
}

#[test]
fn gpu_reference_matches_the_cpu_reference_on_every_built_in_scene() {
    let Some(context) = GpuContext::for_tests() else {
        return;
    };
    for name in [
        "sphere",
        "torus",
        "lens",
        "chart",
        "engine-failures",
        "mirror-room",
        "glass-room",
        "convex-mirror",
        "concave-mirror",
        "adjacent-mirrors",
        "mirror-stack",
        "spectacles",
    ] {
        let scene = Arc::new(load_scene(name).expect("built-in").scene);
        let (hits, colors, mean) = compare(name, &scene, &context);
        assert!(hits >= 0.999, "{name}: the same first hit on {hits}");
        assert!(colors >= 0.99, "{name}: the same colour on {colors}");
        assert!(mean <= 2e-3, "{name}: mean colour difference {mean}");
    }
}

#[test]
fn full_mode_and_supersampling_are_refused_with_a_message() {
    let Some(context) = GpuContext::for_tests() else {
        return;
    };
    let scene = Arc::new(load_scene("sphere").expect("built-in").scene);
    let camera = scene.camera(8, 8).expect("camera");
    let reference = GpuReference::new(&context, &scene).expect("upload");
    for setting in [("mode", "full"), ("spp", "4")] {
        let mut params = MethodParams::defaults(MethodId::Reference);
        params.set(setting.0, setting.1, "test").expect("setting");
        let MethodParams::Reference(settings) = params else {
            unreachable!()
        };
        let err = reference
            .render(
                &context,
                &camera,
                &settings,
                FrameOutputs::Color,
                &mut Frame::default(),
            )
            .expect_err("refused");
        assert!(err.to_string().contains("transmission mode"), "{err}");
    }
}
