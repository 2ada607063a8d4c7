//! The CPU backend: its rasterised buffers against the reference tracer's hits, and its methods
//! against the reference (Wyman 2005a).

use std::sync::Arc;

use glam::Vec3;
use refract_core::vector::angle_between;
use refract_core::{BackSurface, Camera, Ray};
use refract_cpu::{CpuRenderer, front_faces, render_buffers, shade_into};
use refract_eval::metrics::{MetricsRecord, evaluate};
use refract_geometry::{Hit, shapes};
use refract_scene::{
    Aov, Environment, Family, Frame, FrameOutputs, ImageSpaceMethod, LatLongMap, MethodId,
    MethodParams, Renderer, Scene, TwoInterfaceParams,
};
use refract_tests::scenes::{builtin, camera, method, render, shared, with_mesh};
use refract_tests::shared_data;
use refract_trace::ReferenceRenderer;

/// One CPU frame with colour and AOVs.
fn cpu_frame(scene: &Arc<Scene>, cam: &Camera, params: &MethodParams) -> Frame {
    render(&mut CpuRenderer::new(), scene, cam, params)
}

fn second_surface() -> MethodParams {
    MethodParams::ImageSpace(ImageSpaceMethod::TwoInterface(TwoInterfaceParams {
        back: BackSurface::Second,
        ..TwoInterfaceParams::default()
    }))
}

/// Compares a rasterised buffer with ray-cast hits at every pixel centre: coverage agrees on
/// ≥ 99.5 % of the pixels either covers, and where both cover, ≥ 99.5 % have positions within
/// 1e-3 (unit bounding sphere) and normals within 2e-3. The rasteriser snaps vertices to 1/256
/// pixel like a GPU, which moves a sample by up to 1/512 pixel (≈ 2e-5 at 160²), amplified by
/// 1/cos θ at grazing angles: measured median 1.3e-5, maximum 4.6e-4 on the sphere.
fn check_buffer_against_rays(
    label: &str,
    buffer: &refract_cpu::SurfaceBuffer,
    cam: &Camera,
    mut expected: impl FnMut(&Ray) -> Option<Hit>,
) {
    let (mut union, mut agree, mut both, mut close) = (0, 0, 0, 0);
    let mut errors = Vec::new();
    for y in 0..cam.height() {
        for x in 0..cam.width() {
            let i = (y * cam.width() + x) as usize;
            let ray = cam.pixel_ray(Camera::pixel_center(x, y));
            let hit = expected(&ray);
            let texel = buffer.texel(i);
            let covered = texel.is_some();
            if covered || hit.is_some() {
                union += 1;
                agree += usize::from(covered == hit.is_some());
            }
            if let (Some(texel), Some(hit)) = (texel, hit) {
                both += 1;
                let p_err = (texel.p_ws - ray.at(hit.t)).length();
                let n_err = (texel.n_ws - hit.shading_normal).length();
                errors.push((p_err, n_err));
                close += usize::from(p_err < 1e-3 && n_err < 2e-3);
            }
        }
    }
    let coverage = agree as f64 / union as f64;
    let closeness = close as f64 / both as f64;
    println!(
        "{label}: coverage agreement {coverage:.5} over {union} px, attribute agreement {closeness:.5}"
    );
    errors.sort_by(|a, b| a.0.total_cmp(&b.0));
    let q = |f: f64| errors[((errors.len() - 1) as f64 * f) as usize];
    println!(
        "  p/n err quantiles 50% {:?} 99% {:?} 99.9% {:?} max {:?}",
        q(0.5),
        q(0.99),
        q(0.999),
        q(1.0)
    );
    assert!(coverage >= 0.995, "{label}: coverage agreement {coverage}");
    assert!(
        closeness >= 0.995,
        "{label}: attribute agreement {closeness}"
    );
}

fn check_rasteriser(label: &str, scene: &Scene) {
    let cam = camera(160);
    let refractor = &scene.refractor;
    let bvh = refractor.bvh();
    let front = front_faces(refractor, &cam);
    check_buffer_against_rays(&format!("{label} front"), &front, &cam, |r| {
        bvh.closest_hit(r, 0.0, f32::INFINITY)
    });
    let mut hits = Vec::new();
    let furthest = render_buffers(scene, &cam, Some(BackSurface::Furthest))
        .back
        .expect("back");
    check_buffer_against_rays(&format!("{label} furthest"), furthest.buffer(), &cam, |r| {
        bvh.all_hits(r, 0.0, f32::INFINITY, &mut hits);
        hits.iter()
            .rev()
            .find(|h| h.geometric_normal.dot(r.dir) > 0.0)
            .copied()
    });
    let second = render_buffers(scene, &cam, Some(BackSurface::Second))
        .back
        .expect("back");
    check_buffer_against_rays(&format!("{label} second"), second.buffer(), &cam, |r| {
        bvh.all_hits(r, 0.0, f32::INFINITY, &mut hits);
        hits.iter()
            .find(|h| h.geometric_normal.dot(r.dir) > 0.0)
            .copied()
    });
}

#[test]
fn rasterised_buffers_match_ray_cast_hits() {
    check_rasteriser("sphere", &builtin("sphere", 1.5));
    check_rasteriser("torus", &builtin("torus", 1.33));
    if let Some(data) = shared_data() {
        check_rasteriser("cow", &shared(&data, "cow.obj", 1.2));
    }
}

/// With IOR 1 nothing bends: every method shows the environment seen straight through.
#[test]
fn index_one_sees_straight_through() {
    // A smooth map (colour = (u, v, ½)), so that colours can be compared without the hard
    // edges of the procedural environment.
    let (w, h) = (64u32, 32u32);
    let texels = (0..w * h)
        .map(|i| Vec3::new((i % w) as f32 / w as f32, (i / w) as f32 / h as f32, 0.5))
        .collect();
    let smooth = Environment::LatLong {
        map: LatLongMap {
            width: w,
            height: h,
            texels,
        },
        intensity: 1.0,
    };
    let scene = with_mesh(shapes::torus(0.7, 0.3, 48, 24).expect("torus"), 1.0, smooth);
    let cam = camera(96);
    // The families with a T2 (the distance-map paths are checked in distance_map.rs), but
    // Godot's screen offset, which does not depend on the IOR (engine-methods.md §3): it shifts
    // the sample at IOR 1 too, which the assertion after the loop holds it to.
    let straight = MethodId::approximations()
        .filter(|id| id.info().aovs.contains(&Aov::T2) && *id != MethodId::ScreenOffset);
    for id in straight {
        let frame = cpu_frame(&scene, &cam, &method(id));
        let covered_layer = frame.flag(Aov::Covered).expect("covered");
        let t2 = frame.vec3(Aov::T2).expect("T2");
        let (mut covered, mut same_color) = (0, 0);
        for i in 0..frame.pixel_count() {
            let view = cam
                .pixel_ray(Camera::pixel_center(i as u32 % 96, i as u32 / 96))
                .dir;
            if covered_layer[i] {
                covered += 1;
                assert!(
                    angle_between(t2[i], view) < 2e-4,
                    "{id}: {} vs {view}",
                    t2[i]
                );
                same_color += usize::from(
                    (frame.color[i] - scene.environment.radiance(view))
                        .abs()
                        .max_element()
                        < 1e-3,
                );
            }
        }
        // P1 is interpolated, so V = normalize(P1 − eye) differs from the pixel ray by rounding
        // (< 2e-4 rad, far below a texel of this map).
        assert_eq!(same_color, covered, "{id}");
        assert!(covered > 1000);
    }
    let offset = cpu_frame(&scene, &cam, &method(MethodId::ScreenOffset));
    let covered = offset.flag(Aov::Covered).expect("covered");
    let shifted = (0..offset.pixel_count())
        .filter(|&i| {
            let view = cam
                .pixel_ray(Camera::pixel_center(i as u32 % 96, i as u32 / 96))
                .dir;
            covered[i] && (offset.color[i] - scene.environment.radiance(view)).length() > 1e-3
        })
        .count();
    assert!(
        shifted > 100,
        "Godot's offset ignores the IOR: {shifted} pixels moved"
    );
}

/// A slab facing the camera: front and back faces are parallel, so `wyman` gives T2 = V.
#[test]
fn slab_returns_the_view_direction() {
    let scene = with_mesh(
        shapes::cuboid(Vec3::new(1.5, 1.5, 0.2), 1).expect("slab"),
        1.5,
        Environment::Procedural,
    );
    let cam = camera(96);
    let frame = cpu_frame(&scene, &cam, &method(MethodId::Wyman));
    let (covered, t2) = (
        frame.flag(Aov::Covered).expect("covered"),
        frame.vec3(Aov::T2).expect("T2"),
    );
    let mut checked = 0;
    for i in 0..frame.pixel_count() {
        let (x, y) = (i as u32 % 96, i as u32 / 96);
        if covered[i] && (20..76).contains(&x) && (20..76).contains(&y) {
            let view = cam.pixel_ray(Camera::pixel_center(x, y)).dir;
            assert!(
                angle_between(t2[i], view) < 1e-4,
                "pixel ({x}, {y}): {}",
                t2[i]
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 56 * 56);
}

/// The metrics of `id` on the CPU against the reference (refract-scene's metrics, as the CLI
/// reports them).
fn errors_against_reference(scene: &Arc<Scene>, id: MethodId, res: u32) -> MetricsRecord {
    let cam = camera(res);
    let reference = render(
        &mut ReferenceRenderer::new(),
        scene,
        &cam,
        &method(MethodId::Reference),
    );
    let frame = cpu_frame(scene, &cam, &method(id));
    evaluate(&reference, &frame, &cam, scene.refractor.diameter()).0
}

/// Mean T2 error (degrees) and mean |P~2 − P2| / diameter, without TIR on the reference path.
fn t2_p2(record: &MetricsRecord) -> (f64, f64) {
    (
        record.t2_angle_deg_mean_non_tir.expect("T2 error"),
        record.p2_error_rel_mean_non_tir.unwrap_or(f64::NAN),
    )
}

/// `[single, wyman, wyman-dv, wyman-dn]` as `(T2 error, P2 error)`.
fn compare_methods(label: &str, scene: &Arc<Scene>, res: u32) -> [(f64, f64); 4] {
    let [single, wyman, wyman_dv, wyman_dn] = [
        MethodId::Single,
        MethodId::Wyman,
        MethodId::WymanDv,
        MethodId::WymanDn,
    ]
    .map(|id| t2_p2(&errors_against_reference(scene, id, res)));
    println!(
        "{label} {res}², non-TIR px: mean T2 error single {:.2}° wyman {:.2}° wyman-dv {:.2}° wyman-dn {:.2}°; \
         mean |P~2−P2|/diam wyman {:.4} wyman-dv {:.4} wyman-dn {:.4}",
        single.0, wyman.0, wyman_dv.0, wyman_dn.0, wyman.1, wyman_dv.1, wyman_dn.1
    );
    [single, wyman, wyman_dv, wyman_dn]
}

/// The papers' claim on the sphere (IOR 1.5): two interfaces beat one, and interpolating d~
/// beats either distance alone on the exit point (Wyman 2005a §3.1). Bounds: the measured values
/// (printed) plus ~25 %.
#[test]
fn wyman_beats_single_and_d_v_on_the_sphere() {
    let scene = builtin("sphere", 1.5);
    let [single, wyman, wyman_dv, wyman_dn] = compare_methods("sphere", &scene, 128);
    assert!(wyman.0 < single.0);
    assert!(wyman.1 < wyman_dv.1);
    assert!(wyman.1 < wyman_dn.1, "d~ beats d_N alone on P2");
    assert!(wyman.0 < wyman_dn.0, "d~ beats d_N alone on T2");
    assert!(wyman.0 < 5.0 && wyman.1 < 0.1, "{} {}", wyman.0, wyman.1);
}

/// The same on the cow (IOR 1.2, as in Wyman 2005a's results).
#[test]
fn wyman_beats_single_and_d_v_on_the_cow() {
    let Some(data) = shared_data() else { return };
    let scene = shared(&data, "cow.obj", 1.2);
    let [single, wyman, wyman_dv, wyman_dn] = compare_methods("cow", &scene, 128);
    assert!(wyman.0 < single.0);
    assert!(wyman.1 < wyman_dv.1);
    assert!(wyman.1 < wyman_dn.1, "d~ beats d_N alone on P2");
}

/// Bad parameters are errors, not panics: an index of refraction that is not finite and > 0
/// (rejected by the scene, so no backend ever sees one), a `d_N` shorter than the mesh (rejected
/// by the scene for every backend alike), the reference asked of the CPU backend, a frame before
/// a scene, a zero resolution.
#[test]
fn bad_parameters_are_errors() {
    let mesh = || refract_geometry::builtin::mesh("builtin:sphere").expect("sphere");
    for ior in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let err = refract_scene::Refractor::new(mesh(), ior).expect_err("bad ior");
        assert!(err.to_string().contains("ior"), "{err}");
        let mut scene = builtin("sphere", 1.5);
        let refractor = &mut Arc::make_mut(&mut scene).refractor;
        assert!(refractor.set_ior(ior).is_err());
        assert_eq!(refractor.ior(), 1.5);
    }
    let scene = builtin("sphere", 1.5);
    let mut short = scene.refractor.normal_distances().clone();
    short.values.pop();
    let err =
        refract_scene::Refractor::with_normal_distances(mesh(), short, 1.5).expect_err("short d_N");
    assert!(err.to_string().contains("d_N"), "{err}");

    let cam = camera(16);
    let mut cpu = CpuRenderer::new();
    let mut frame = Frame::default();
    let colour = FrameOutputs::ColorAndAovs;
    let err = cpu
        .render(&cam, &method(MethodId::Wyman), colour, &mut frame)
        .expect_err("not prepared");
    assert!(err.to_string().contains("prepare"), "{err}");
    cpu.prepare(&scene).expect("prepare");
    let err = cpu
        .render(&cam, &method(MethodId::Reference), colour, &mut frame)
        .expect_err("unsupported");
    assert!(
        err.to_string().contains("reference") && err.to_string().contains("cpu"),
        "{err}"
    );
    let zero = refract_core::Camera::new(refract_core::CameraDesc {
        width: 0,
        ..Default::default()
    });
    assert!(zero.is_err());
}

/// What each renderer says it supports is what the registry says, and an unsupported method is
/// an error naming both, never a frame of something else.
#[test]
fn renderers_support_exactly_the_registry_rows() {
    let scene = builtin("sphere", 1.5);
    let cam = camera(8);
    let mut renderers: Vec<Box<dyn Renderer>> = vec![
        Box::new(CpuRenderer::new()),
        Box::new(ReferenceRenderer::new()),
    ];
    for renderer in &mut renderers {
        renderer.prepare(&scene).expect("prepare");
        for row in &refract_scene::REGISTRY {
            let listed = row.backends.contains(&renderer.backend());
            assert_eq!(
                renderer.supports(row.id),
                listed,
                "{} {}",
                renderer.backend(),
                row.name
            );
            let mut frame = Frame::default();
            let result = renderer.render(
                &cam,
                &method(row.id),
                FrameOutputs::ColorAndAovs,
                &mut frame,
            );
            assert_eq!(
                result.is_ok(),
                listed,
                "{} {}",
                renderer.backend(),
                row.name
            );
        }
    }
}

/// A frame's layers are exactly the AOVs of the method's registry row (CPU and reference), and
/// none in a colour-only frame.
#[test]
fn frames_have_the_registry_aovs() {
    let scene = builtin("torus", 1.33);
    let cam = camera(24);
    let mut cpu = CpuRenderer::new();
    let mut reference = ReferenceRenderer::new();
    for row in &refract_scene::REGISTRY {
        let renderer: &mut dyn Renderer = if row.id == MethodId::Reference {
            &mut reference
        } else {
            &mut cpu
        };
        let frame = render(renderer, &scene, &cam, &method(row.id));
        let mut expected = row.aovs.to_vec();
        expected.sort();
        assert_eq!(frame.aovs().collect::<Vec<_>>(), expected, "{}", row.name);
    }
    let mut frame = Frame::default();
    cpu.render(
        &cam,
        &method(MethodId::Wyman),
        FrameOutputs::Color,
        &mut frame,
    )
    .expect("colour");
    assert_eq!(frame.aovs().count(), 0);
}

/// The frame does not depend on the thread count.
#[test]
fn cpu_frames_are_bit_identical_for_any_thread_count() {
    let scene = builtin("torus", 1.33);
    let cam = camera(80);
    let run = || cpu_frame(&scene, &cam, &method(MethodId::Wyman));
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let single = one.install(run);
    let parallel = run();
    let bits = |f: &Frame| {
        f.color
            .iter()
            .flat_map(|c| c.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&single), bits(&parallel));
}

/// The buffer-reusing renderer gives the same frames as a fresh one, across methods and
/// resolutions (its buffers are cleared and resized between frames).
#[test]
fn reusing_renderer_matches_fresh_frames() {
    let scene = builtin("torus", 1.33);
    let mut renderer = CpuRenderer::new();
    renderer.prepare(&scene).expect("prepare");
    let mut reused = Frame::default();
    for (res, id) in [
        (64, MethodId::Wyman),
        (48, MethodId::Single),
        (64, MethodId::WymanDn),
        (80, MethodId::Wyman),
    ] {
        let cam = camera(res);
        let fresh = cpu_frame(&scene, &cam, &method(id));
        renderer
            .render(&cam, &method(id), FrameOutputs::ColorAndAovs, &mut reused)
            .expect("reused");
        assert_eq!(
            format!("{fresh:?}"),
            format!("{reused:?}"),
            "{id} at {res}²"
        );
    }
}

/// The two-step path: buffers stored whole, then the kernel.
fn two_step(scene: &Scene, cam: &Camera, params: &MethodParams) -> Frame {
    let MethodParams::ImageSpace(method) = params else {
        panic!("{} is not an image-space method", params.id())
    };
    let back = method.back_surface();
    let kernel = method.kernel(scene.refractor.ior()).expect("kernel");
    let buffers = render_buffers(scene, cam, back);
    let mut frame = Frame::default();
    shade_into(
        &buffers,
        &scene.environment,
        cam,
        &kernel,
        params.id(),
        FrameOutputs::ColorAndAovs,
        &mut frame,
    )
    .expect("the row's layers");
    frame
}

/// The renderer shades each band right after rasterising it (front faces never stored whole);
/// the two-step path (`render_buffers`, then `shade_into`) stores both buffers first. Same
/// frames, bit for bit, for every method and both back surfaces; and a colour-only frame has the
/// same colours and no AOVs.
#[test]
fn fused_bands_match_the_two_step_path_and_colour_only_frames() {
    // The torus alone, and the engine-failures scene's objects in front of and behind a torus.
    let failures = Arc::new(
        refract_eval::load_scene("engine-failures")
            .expect("engine-failures")
            .scene,
    );
    for scene in [builtin("torus", 1.33), failures] {
        fused_matches_two_step(&scene);
    }
}

fn fused_matches_two_step(scene: &Arc<Scene>) {
    let cam = camera(72);
    let mut renderer = CpuRenderer::new();
    renderer.prepare(scene).expect("prepare");
    // The image-space family (the nearby-geometry methods have no two-step path; their
    // colour-only frames are checked in nearby_geometry.rs).
    let methods = MethodId::approximations()
        .filter(|id| id.info().family == Family::ImageSpace)
        .map(method)
        .chain([second_surface()]);
    for params in methods {
        let two_step = two_step(scene, &cam, &params);
        let mut fused = Frame::default();
        renderer
            .render(&cam, &params, FrameOutputs::ColorAndAovs, &mut fused)
            .expect("fused");
        assert_eq!(format!("{two_step:?}"), format!("{fused:?}"), "{params:?}");
        let mut colour = Frame::default();
        renderer
            .render(&cam, &params, FrameOutputs::Color, &mut colour)
            .expect("colour only");
        assert_eq!(colour.aovs().count(), 0);
        assert_eq!(
            format!("{:?}", colour.color),
            format!("{:?}", two_step.color)
        );
    }
}

/// A scene's opaque objects are drawn by the image-space methods where they are the nearest
/// surface, as the reference shows them (issue 31, item 4: `wyman` on `chart` showed the
/// environment where the reference shows the room): on `engine-failures` (a ball in front of a
/// glass torus, a chart behind, a floor) every pixel outside the refractor in both frames has
/// the reference's colour (within f32 interpolation noise) on ≥ 99 % of those pixels, the ball
/// hides the torus where the reference says it does, and the refraction is the one of the scene
/// without objects, bit for bit, at every pixel the method covers.
#[test]
fn image_space_methods_draw_the_objects_the_reference_sees() {
    let scene = Arc::new(
        refract_eval::load_scene("engine-failures")
            .expect("engine-failures")
            .scene,
    );
    let mut bare = (*scene).clone();
    bare.objects.clear();
    let bare = Arc::new(bare);
    let cam = scene.camera(96, 72).expect("camera");
    let truth = render(
        &mut ReferenceRenderer::new(),
        &scene,
        &cam,
        &method(MethodId::Reference),
    );
    let truth_covered = truth.flag(Aov::Covered).expect("covered");
    let front = front_faces(&scene.refractor, &cam);
    for id in MethodId::approximations().filter(|id| id.info().family == Family::ImageSpace) {
        let frame = cpu_frame(&scene, &cam, &method(id));
        let without = cpu_frame(&bare, &cam, &method(id));
        let covered = frame.flag(Aov::Covered).expect("covered");
        let (mut outside, mut same, mut hidden) = (0, 0, 0);
        for i in 0..frame.pixel_count() {
            if covered[i] {
                assert_eq!(
                    frame.color[i].to_array().map(f32::to_bits),
                    without.color[i].to_array().map(f32::to_bits),
                    "{id}: pixel {i}'s refraction depends on the objects"
                );
                continue;
            }
            hidden += usize::from(front.is_covered(i) && !truth_covered[i]);
            if !truth_covered[i] {
                outside += 1;
                let (a, b) = (frame.color[i], truth.color[i]);
                same += usize::from((a - b).abs().max_element() <= 1e-3 * b.max_element().max(1.0));
            }
        }
        let share = same as f64 / outside as f64;
        println!(
            "{id}: {same} of {outside} pixels outside the refractor as the reference, {hidden} hidden by the ball"
        );
        assert!(
            share >= 0.99,
            "{id}: {share} of the pixels outside the refractor"
        );
        assert!(
            hidden > 20,
            "{id}: the ball hides {hidden} pixels of the torus"
        );
    }
}

/// Eight texels resolved at once equal the scalar resolve bit for bit: on the torus's small
/// triangles (lanes on different triangles) and on the sphere at 640², whose triangles span
/// ~20 pixels (most groups eight neighbours on one triangle: the path that compares their ids in
/// the visibility buffer and looks the triangle up once); with only some
/// attributes asked for, those keep their bits and the others are zero.
#[test]
fn eight_lane_texels_equal_scalar_texels() {
    for (name, size) in [("torus", 96u32), ("sphere", 640)] {
        let scene = builtin(name, 1.33);
        let cam = camera(size);
        let front = front_faces(&scene.refractor, &cam);
        let mut checked = 0;
        for y in 0..size {
            let covered: Vec<u32> = (0..size)
                .filter(|&x| front.is_covered((y * size + x) as usize))
                .collect();
            for chunk in covered.chunks(8) {
                let x: [u32; 8] = core::array::from_fn(|i| chunk[i.min(chunk.len() - 1)]);
                let lanes = front.texels_x8(&x, y);
                // Fewer attributes: the same bits for those asked for, zero for the others.
                let some = front
                    .attribute_lanes::<{ refract_cpu::raster::Attribute::SCALAR }>(&x, y)
                    .to_texels();
                for ((xi, lane), some) in x.iter().zip(lanes).zip(some) {
                    let scalar = front.texel((y * size + xi) as usize).expect("covered");
                    assert_eq!(
                        format!("{lane:?}"),
                        format!("{scalar:?}"),
                        "{name}: ({xi}, {y})"
                    );
                    let expected = refract_cpu::Texel {
                        depth: 0.0,
                        barycentrics: Vec3::ZERO,
                        ..scalar
                    };
                    assert_eq!(format!("{some:?}"), format!("{expected:?}"));
                    checked += 1;
                }
            }
        }
        assert!(checked > 1000, "{name}: {checked}");
    }
}

/// Frames of every size, down to one pixel and with partial bands and partial groups of eight,
/// agree between the fused renderer and the two-step path.
#[test]
fn odd_frame_sizes_render_consistently() {
    let scene = builtin("sphere", 1.5);
    let mut renderer = CpuRenderer::new();
    renderer.prepare(&scene).expect("prepare");
    for (width, height) in [(1, 1), (3, 5), (17, 9), (9, 33), (40, 17)] {
        let cam = refract_core::Camera::new(refract_core::CameraDesc {
            width,
            height,
            ..Default::default()
        })
        .expect("camera");
        for id in [MethodId::Single, MethodId::Wyman] {
            let two_step = two_step(&scene, &cam, &method(id));
            let mut fused = Frame::default();
            renderer
                .render(&cam, &method(id), FrameOutputs::ColorAndAovs, &mut fused)
                .expect("fused");
            assert_eq!(fused.color.len(), (width * height) as usize);
            assert_eq!(
                format!("{two_step:?}"),
                format!("{fused:?}"),
                "{id} {width}×{height}"
            );
        }
    }
}

/// The rasteriser's barycentric weights (carried like the position, through near-plane
/// clipping) locate each texel in its mesh triangle: `Σ wₖ·Pₖ` is the interpolated position and
/// the weights sum to 1. On the sphere seen whole and from a camera whose near plane cuts
/// it (clipped pieces); a weight that ignored the clipping or the corner order would put the
/// point elsewhere on the triangle.
#[test]
fn rasteriser_barycentrics_locate_the_texel_in_its_triangle() {
    let scene = builtin("sphere", 1.5);
    let mesh = scene.refractor.mesh();
    // The eye 1 from the unit sphere and the near plane beyond its nearest point: the plane
    // cuts a hole of radius ~0.3 in the view, rimmed by clipped triangles.
    let near_cut = refract_core::CameraDesc {
        eye: Vec3::new(0.0, 0.0, 2.0),
        target: Vec3::ZERO,
        near: 1.05,
        width: 96,
        height: 96,
        ..Default::default()
    };
    for (label, cam) in [
        ("whole", camera(128)),
        ("near-plane cut", Camera::new(near_cut).expect("camera")),
    ] {
        let buffer = refract_cpu::rasterize(
            &refract_cpu::RasterMesh::new(mesh),
            &cam,
            refract_cpu::Faces::Both,
            refract_cpu::DepthTest::Nearest,
        );
        let (mut checked, mut clipped, mut worst) = (0, 0, 0.0f32);
        let in_front = |p: Vec3| (p - cam.eye()).dot(cam.look_dir()) >= cam.desc().near;
        for index in 0..(cam.width() * cam.height()) as usize {
            let Some(t) = buffer.texel(index) else {
                continue;
            };
            let w = t.barycentrics;
            let [a, b, c] = mesh.triangles[t.triangle as usize].map(|i| mesh.positions[i as usize]);
            clipped += usize::from(![a, b, c].into_iter().all(in_front));
            let p = w.x * a + w.y * b + w.z * c;
            worst = worst.max((p - t.p_ws).length());
            assert!((w.x + w.y + w.z - 1.0).abs() < 1e-5, "{label}: weights {w}");
            assert!(
                w.min_element() > -1e-3,
                "{label}: weights {w} outside the triangle"
            );
            checked += 1;
        }
        println!(
            "{label}: {checked} texels ({clipped} on clipped triangles), worst |Σ wₖ·Pₖ − p| = {worst:e}"
        );
        assert!(checked > 1000, "{label}: {checked} texels");
        if label == "near-plane cut" {
            assert!(
                clipped > 100,
                "{label}: {clipped} texels on clipped triangles"
            );
        }
        assert!(worst < 1e-5, "{label}: worst {worst}");
    }
}

/// A reused renderer clears only what its last frame drew (each row's extent): frames of one
/// size from cameras that move the refractor across the image, and with the back faces' depth
/// test switched between frames (furthest, then second surface), equal fresh frames. A buffer
/// that kept the last frame's fragments outside the new extents would show a ghost torus.
#[test]
fn reused_buffers_forget_the_last_frame() {
    let scene = builtin("torus", 1.33);
    let mut renderer = CpuRenderer::new();
    renderer.prepare(&scene).expect("prepare");
    let mut reused = Frame::default();
    for (k, params) in [
        method(MethodId::Wyman),
        method(MethodId::Wyman),
        second_surface(),
        method(MethodId::Single),
        method(MethodId::Wyman),
    ]
    .iter()
    .enumerate()
    {
        let cam = Camera::new(refract_core::CameraDesc {
            eye: Vec3::new(-2.0 + k as f32, 0.3 * k as f32, 4.0),
            width: 64,
            height: 48,
            ..Default::default()
        })
        .expect("camera");
        let fresh = cpu_frame(&scene, &cam, params);
        renderer
            .render(&cam, params, FrameOutputs::ColorAndAovs, &mut reused)
            .expect("reused");
        assert_eq!(format!("{fresh:?}"), format!("{reused:?}"), "frame {k}");
    }
}
