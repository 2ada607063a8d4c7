//! The CPU backend: its rasterised buffers against the reference tracer's hits, and its methods
//! against the reference (Wyman 2005a).

use glam::Vec3;
use refract_core::exit::TirPolicy;
use refract_core::vector::angle_between;
use refract_core::{BackSurface, Camera, Method, Ray};
use refract_cpu::{MethodParams, front_faces, render_buffers, render_method};
use refract_geometry::{Hit, shapes};
use refract_tests::scenes::{TestScene, camera};
use refract_tests::shared_data;
use refract_trace::{Environment, LatLongMap, TraceSettings, render};

fn params(method: Method, ior: f32) -> MethodParams {
    MethodParams {
        method,
        ior,
        tir_policy: TirPolicy::ClampToCritical,
    }
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

fn check_rasteriser(label: &str, scene: &TestScene) {
    let cam = camera(160);
    let prepared = scene.prepared();
    let bvh = &scene.scene.refractor.bvh;
    let front = front_faces(&prepared, &cam);
    check_buffer_against_rays(&format!("{label} front"), &front, &cam, |r| {
        bvh.closest_hit(r, 0.0, f32::INFINITY)
    });
    let mut hits = Vec::new();
    let method = Method::ALL[1];
    let furthest = render_buffers(&prepared, &cam, method)
        .expect("buffers")
        .back
        .expect("back");
    check_buffer_against_rays(&format!("{label} furthest"), furthest.buffer(), &cam, |r| {
        bvh.all_hits(r, 0.0, f32::INFINITY, &mut hits);
        hits.iter()
            .rev()
            .find(|h| h.geometric_normal.dot(r.dir) > 0.0)
            .copied()
    });
    let second = render_buffers(
        &prepared,
        &cam,
        method.with_back_surface(BackSurface::Second),
    )
    .expect("buffers")
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
    check_rasteriser("sphere", &TestScene::builtin("sphere", 1.5));
    check_rasteriser("torus", &TestScene::builtin("torus", 1.33));
    if let Some(data) = shared_data() {
        check_rasteriser("cow", &TestScene::shared(&data, "cow.obj", 1.2));
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
    let scene = TestScene::new(shapes::torus(0.7, 0.3, 48, 24).expect("torus"), 1.0, smooth);
    let cam = camera(96);
    for method in Method::ALL {
        let frame = render_method(
            &scene.prepared(),
            &scene.scene.environment,
            &cam,
            &params(method, 1.0),
        )
        .expect("frame");
        let (mut covered, mut same_color) = (0, 0);
        for (i, aov) in frame.aov.iter().enumerate() {
            let view = cam
                .pixel_ray(Camera::pixel_center(i as u32 % 96, i as u32 / 96))
                .dir;
            if aov.covered {
                covered += 1;
                assert!(
                    angle_between(aov.t2, view) < 2e-4,
                    "{method}: {} vs {view}",
                    aov.t2
                );
                same_color += usize::from(
                    (frame.color[i] - scene.scene.environment.radiance(view))
                        .abs()
                        .max_element()
                        < 1e-3,
                );
            }
        }
        // P1 is interpolated, so V = normalize(P1 − eye) differs from the pixel ray by rounding
        // (< 2e-4 rad, far below a texel of this map).
        assert_eq!(same_color, covered, "{method}");
        assert!(covered > 1000);
    }
}

/// A slab facing the camera: front and back faces are parallel, so `wyman` gives T2 = V.
#[test]
fn slab_returns_the_view_direction() {
    let scene = TestScene::new(
        shapes::cuboid(Vec3::new(1.5, 1.5, 0.2), 1).expect("slab"),
        1.5,
        Environment::Procedural,
    );
    let cam = camera(96);
    let frame = render_method(
        &scene.prepared(),
        &scene.scene.environment,
        &cam,
        &params(Method::ALL[1], 1.5),
    )
    .expect("frame");
    let mut checked = 0;
    for (i, aov) in frame.aov.iter().enumerate() {
        let (x, y) = (i as u32 % 96, i as u32 / 96);
        if aov.covered && (20..76).contains(&x) && (20..76).contains(&y) {
            let view = cam.pixel_ray(Camera::pixel_center(x, y)).dir;
            assert!(
                angle_between(aov.t2, view) < 1e-4,
                "pixel ({x}, {y}): {aov:?}"
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 56 * 56);
}

struct Errors {
    t2_deg: f64,
    p2_rel: f64,
    pixels: usize,
}

/// Mean T2 angle error and mean |P~2 − P2| / diameter over the pixels both see, where the
/// reference has no TIR on its path.
fn errors_against_reference(scene: &TestScene, method: Method, res: u32) -> Errors {
    let cam = camera(res);
    let ior = scene.scene.refractor.ior();
    let reference = render(&scene.scene, &cam, &TraceSettings::default());
    let frame = render_method(
        &scene.prepared(),
        &scene.scene.environment,
        &cam,
        &params(method, ior),
    )
    .expect("frame");
    let diameter = 2.0 * f64::from(scene.scene.refractor.mesh.bounding_sphere().radius);
    let (mut t2, mut p2, mut n, mut n_p2) = (0.0, 0.0, 0, 0);
    for (ours, truth) in frame.aov.iter().zip(&reference.aov) {
        if !(ours.covered && truth.covers_refractor()) || truth.tir || truth.t2.is_nan() {
            continue;
        }
        t2 += f64::from(angle_between(ours.t2, truth.t2).to_degrees());
        n += 1;
        if !ours.p2.is_nan() && !truth.p2.is_nan() {
            p2 += f64::from((ours.p2 - truth.p2).length()) / diameter;
            n_p2 += 1;
        }
    }
    Errors {
        t2_deg: t2 / n as f64,
        p2_rel: if n_p2 > 0 { p2 / n_p2 as f64 } else { f64::NAN },
        pixels: n,
    }
}

fn compare_methods(label: &str, scene: &TestScene, res: u32) -> [Errors; 3] {
    let single = errors_against_reference(scene, Method::ALL[0], res);
    let wyman = errors_against_reference(scene, Method::ALL[1], res);
    let wyman_dv = errors_against_reference(scene, Method::ALL[2], res);
    let wyman_dn = errors_against_reference(scene, Method::ALL[3], res);
    println!(
        "{label} {res}², {} non-TIR px: mean T2 error single {:.2}° wyman {:.2}° wyman-dv {:.2}° wyman-dn {:.2}°; \
         mean |P~2−P2|/diam wyman {:.4} wyman-dv {:.4} wyman-dn {:.4}",
        wyman.pixels,
        single.t2_deg,
        wyman.t2_deg,
        wyman_dv.t2_deg,
        wyman_dn.t2_deg,
        wyman.p2_rel,
        wyman_dv.p2_rel,
        wyman_dn.p2_rel
    );
    [single, wyman, wyman_dv]
}

/// The papers' claim on the sphere (IOR 1.5): two interfaces beat one, and interpolating d~
/// beats d_V alone on the exit point. Bounds: the measured values (printed) plus ~25 %.
#[test]
fn wyman_beats_single_and_d_v_on_the_sphere() {
    let scene = TestScene::builtin("sphere", 1.5);
    let [single, wyman, wyman_dv] = compare_methods("sphere", &scene, 128);
    assert!(wyman.t2_deg < single.t2_deg);
    assert!(wyman.p2_rel < wyman_dv.p2_rel);
    assert!(
        wyman.t2_deg < 5.0 && wyman.p2_rel < 0.1,
        "{} {}",
        wyman.t2_deg,
        wyman.p2_rel
    );
}

/// The same on the cow (IOR 1.2, as in Wyman 2005a's results).
#[test]
fn wyman_beats_single_and_d_v_on_the_cow() {
    let Some(data) = shared_data() else { return };
    let scene = TestScene::shared(&data, "cow.obj", 1.2);
    let [single, wyman, wyman_dv] = compare_methods("cow", &scene, 128);
    assert!(wyman.t2_deg < single.t2_deg);
    assert!(wyman.p2_rel < wyman_dv.p2_rel);
}

/// Bad parameters are errors, not panics.
#[test]
fn bad_parameters_are_errors() {
    let scene = TestScene::builtin("sphere", 1.5);
    let cam = camera(16);
    for ior in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let result = render_method(
            &scene.prepared(),
            &scene.scene.environment,
            &cam,
            &params(Method::ALL[1], ior),
        );
        assert!(result.is_err(), "ior {ior}");
    }
    let short_d_n = refract_cpu::PreparedRefractor {
        mesh: &scene.scene.refractor.mesh,
        d_n: &scene.d_n[1..],
    };
    assert!(
        render_method(
            &short_d_n,
            &scene.scene.environment,
            &cam,
            &params(Method::ALL[1], 1.5)
        )
        .is_err()
    );
    let zero = refract_core::Camera::new(refract_core::CameraDesc {
        width: 0,
        ..Default::default()
    });
    assert!(zero.is_err());
}

/// The frame does not depend on the thread count.
#[test]
fn cpu_frames_are_bit_identical_for_any_thread_count() {
    let scene = TestScene::builtin("torus", 1.33);
    let cam = camera(80);
    let run = || {
        render_method(
            &scene.prepared(),
            &scene.scene.environment,
            &cam,
            &params(Method::ALL[1], 1.33),
        )
        .expect("frame")
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let single = one.install(run);
    let parallel = run();
    let bits = |f: &refract_cpu::MethodFrame| {
        f.color
            .iter()
            .flat_map(|c| c.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&single), bits(&parallel));
}

/// The buffer-reusing renderer gives the same frames as the allocating path, across methods and
/// resolutions (its buffers are cleared and resized between frames).
#[test]
fn reusing_renderer_matches_fresh_frames() {
    let scene = TestScene::builtin("torus", 1.33);
    let mut renderer = refract_cpu::CpuRenderer::default();
    for (res, method) in [
        (64, Method::ALL[1]),
        (48, Method::ALL[0]),
        (64, Method::ALL[3]),
        (80, Method::ALL[1]),
    ] {
        let cam = camera(res);
        let params = params(method, 1.33);
        let fresh = render_method(&scene.prepared(), &scene.scene.environment, &cam, &params)
            .expect("fresh");
        let reused = renderer
            .render(&scene.prepared(), &scene.scene.environment, &cam, &params)
            .expect("reused");
        assert_eq!(
            format!("{fresh:?}"),
            format!("{reused:?}"),
            "{method} at {res}²"
        );
    }
}

/// The renderer shades each band right after rasterising it (front faces never stored whole);
/// the two-step path (`render_buffers`, then `shade`) stores both buffers first. Same frames,
/// bit for bit, for every method and both back surfaces; and a colour-only frame has the same
/// colours and no AOVs.
#[test]
fn fused_bands_match_the_two_step_path_and_colour_only_frames() {
    let scene = TestScene::builtin("torus", 1.33);
    let cam = camera(72);
    let mut renderer = refract_cpu::CpuRenderer::default();
    let mut colour_only = refract_cpu::CpuRenderer::new(refract_cpu::FrameOutputs::Color);
    let methods = Method::ALL
        .into_iter()
        .chain([Method::ALL[1].with_back_surface(BackSurface::Second)]);
    for method in methods {
        let params = params(method, 1.33);
        let prepared = scene.prepared();
        let buffers = render_buffers(&prepared, &cam, method).expect("buffers");
        let two_step =
            refract_cpu::shade(&buffers, &scene.scene.environment, &cam, &params).expect("shade");
        let fused = renderer
            .render(&prepared, &scene.scene.environment, &cam, &params)
            .expect("fused");
        assert_eq!(format!("{two_step:?}"), format!("{fused:?}"), "{method}");
        let colour = colour_only
            .render(&prepared, &scene.scene.environment, &cam, &params)
            .expect("colour only");
        assert!(colour.aov.is_empty());
        assert_eq!(
            format!("{:?}", colour.color),
            format!("{:?}", two_step.color)
        );
    }
}

/// Eight texels resolved at once equal the scalar resolve bit for bit.
#[test]
fn eight_lane_texels_equal_scalar_texels() {
    let scene = TestScene::builtin("torus", 1.33);
    let cam = camera(96);
    let prepared = scene.prepared();
    let front = front_faces(&prepared, &cam);
    let mut checked = 0;
    for y in 0..96u32 {
        let covered: Vec<u32> = (0..96)
            .filter(|&x| front.is_covered((y * 96 + x) as usize))
            .collect();
        for chunk in covered.chunks(8) {
            let x: [u32; 8] = core::array::from_fn(|i| chunk[i.min(chunk.len() - 1)]);
            let lanes = front.texels_x8(&x, y);
            for (xi, lane) in x.iter().zip(lanes) {
                let scalar = front.texel((y * 96 + xi) as usize).expect("covered");
                assert_eq!(format!("{lane:?}"), format!("{scalar:?}"), "({xi}, {y})");
                checked += 1;
            }
        }
    }
    assert!(checked > 1000);
}

/// Frames of every size, down to one pixel and with partial bands and partial groups of eight,
/// agree between the fused renderer and the two-step path.
#[test]
fn odd_frame_sizes_render_consistently() {
    let scene = TestScene::builtin("sphere", 1.5);
    let mut renderer = refract_cpu::CpuRenderer::default();
    for (width, height) in [(1, 1), (3, 5), (17, 9), (9, 33), (40, 17)] {
        let cam = refract_core::Camera::new(refract_core::CameraDesc {
            width,
            height,
            ..Default::default()
        })
        .expect("camera");
        for method in [Method::ALL[0], Method::ALL[1]] {
            let params = params(method, 1.5);
            let prepared = scene.prepared();
            let buffers = render_buffers(&prepared, &cam, method).expect("buffers");
            let two_step = refract_cpu::shade(&buffers, &scene.scene.environment, &cam, &params)
                .expect("shade");
            let fused = renderer
                .render(&prepared, &scene.scene.environment, &cam, &params)
                .expect("fused");
            assert_eq!(fused.color.len(), (width * height) as usize);
            assert_eq!(
                format!("{two_step:?}"),
                format!("{fused:?}"),
                "{method} {width}×{height}"
            );
        }
    }
}
