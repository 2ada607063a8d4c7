//! The engine family's WGSL (`src/methods/engine_path.wgsl`, the models' leaves in core.wgsl)
//! against refract-core, through the family's own conformance module
//! (`src/methods/engine_conformance.wgsl`): the models' leaves on proptest-generated inputs,
//! and the whole path (`engine_path`: the model's exit, the projection, the clamping, the depth
//! tests, the fallbacks) over an analytic screen, for every engine method.

use glam::{UVec2, Vec2, Vec3, Vec4};
use proptest::prelude::*;
use refract_core::engine::{
    ENGINE_PROXY_BOX, ENGINE_PROXY_SPHERE, ENGINE_PROXY_THIN, ENGINE_SCREEN_OFFSET,
    ENGINE_VOLUME_THICKNESS, EngineModel, EngineUniforms, OpaqueDepth, ProxyLookup, ProxyShape,
    bevy_blurred, engine_path, hdrp_edge_fade, proxy_box_exit, proxy_sphere_exit, screen_offset_px,
    smoothstep01, volume_exit,
};
use refract_core::screen_mips::{ScreenMips, sample_threejs, sample_trilinear};
use refract_core::{Camera, CameraDesc};
use refract_gpu::conformance::{FamilyEvaluation, evaluate_family};

#[macro_use]
mod common;
use common::{ROWS, close, close3, config, context, unit};

/// An evaluation of the engine's conformance module in a frame of `camera` and `ior`.
fn engine_evaluation<'a>(
    camera: &'a Camera,
    ior: f32,
    uniforms: &'a [(u32, &'a [u8])],
    constants: &'a [(&'a str, f64)],
) -> FamilyEvaluation<'a> {
    FamilyEvaluation {
        module: "engine-conformance",
        entry: "",
        camera,
        ior,
        uniforms,
        constants,
    }
}

/// `engine_conformance.wgsl`'s analytic screen: the environment on every fifth column, an
/// opaque surface at view depth `1.5 + 0.25 (y mod 7)` elsewhere.
struct AnalyticScreen;

impl OpaqueDepth for AnalyticScreen {
    fn view_depth(&self, texel: UVec2) -> f32 {
        if texel.x.is_multiple_of(5) {
            f32::INFINITY
        } else {
            1.5 + 0.25 * (texel.y % 7) as f32
        }
    }
}

/// Every engine method's model as the registry builds it (both settings of each switch), with
/// its `ENGINE_MODEL` code.
fn models(thickness: f32) -> Vec<(u32, EngineModel)> {
    let mut models = Vec::new();
    for switch in [false, true] {
        models.push((
            ENGINE_SCREEN_OFFSET,
            EngineModel::ScreenOffset {
                scale: 0.05,
                depth_guard: switch,
            },
        ));
        models.push((
            ENGINE_VOLUME_THICKNESS,
            EngineModel::VolumeThickness {
                thickness,
                reject_nearer: switch,
            },
        ));
        let lookup = if switch {
            ProxyLookup::Filament
        } else {
            ProxyLookup::Hdrp
        };
        for (code, shape) in [
            (ENGINE_PROXY_SPHERE, ProxyShape::Sphere),
            (ENGINE_PROXY_BOX, ProxyShape::Box),
            (ENGINE_PROXY_THIN, ProxyShape::Thin),
        ] {
            models.push((
                code,
                EngineModel::Proxy {
                    shape,
                    thickness,
                    lookup,
                },
            ));
        }
    }
    models
}

proptest! {
    #![proptest_config(config())]

    /// The engine exit models (HDRP sphere and box, three.js/Bevy volume) and Godot's offset
    /// with HDRP's edge fade: incidence kept 3° off grazing, where `cos θt` is well defined.
    #[test]
    fn engine_models_agree(rows in prop::collection::vec((unit(), unit(), 1.0f32..2.5, 0.0f32..3.0, 0.0f32..1.0, 0.0f32..1.0, -0.5f32..1.5), ROWS)) {
        let context = gpu_or_skip!();
        let camera = Camera::new(CameraDesc::default()).expect("camera");
        let leaf = |entry, a: &[Vec4], b: &[Vec4]| {
            let evaluation = FamilyEvaluation { entry, ..engine_evaluation(&camera, 1.5, &[], &[]) };
            evaluate_family(context, &evaluation, a, b)
        };
        let rows: Vec<_> = rows.into_iter()
            .map(|(n, i, ior, d, u, v, x)| (n, if n.dot(i) > 0.0 { -i } else { i }, ior, d, u, v, x))
            .filter(|(n, i, ..)| n.dot(*i) < -0.05)
            .collect();
        let a: Vec<Vec4> = rows.iter().map(|r| r.0.extend(r.2)).collect();
        let b: Vec<Vec4> = rows.iter().map(|r| r.1.extend(r.3)).collect();
        let sphere_p = leaf("test_proxy_sphere_point", &a, &b).expect("gpu");
        let sphere_dir = leaf("test_proxy_sphere_dir", &a, &b).expect("gpu");
        let slab = leaf("test_proxy_box", &a, &b).expect("gpu");
        let volume = leaf("test_volume_exit", &a, &b).expect("gpu");
        let screen_a: Vec<Vec4> = rows.iter().map(|r| r.0.extend(0.05 * r.3)).collect();
        let screen_b: Vec<Vec4> = rows.iter().map(|r| Vec4::new(r.4, r.5, r.6, 0.0)).collect();
        let screen = leaf("test_engine_screen", &screen_a, &screen_b).expect("gpu");
        for (k, &(n, i, ior, d, u, v, x)) in rows.iter().enumerate() {
            let (p1, r2) = proxy_sphere_exit(Vec3::ZERO, n, i, ior, d);
            prop_assert!(close3(sphere_p[k], p1, 2e-5), "{} vs {}", sphere_p[k], p1);
            prop_assert!(close3(sphere_dir[k], r2, 2e-5), "{} vs {}", sphere_dir[k], r2);
            prop_assert!(close3(slab[k], proxy_box_exit(Vec3::ZERO, n, i, ior, d).0, 2e-5));
            prop_assert!(close3(volume[k], volume_exit(Vec3::ZERO, n, i, ior, d).0, 2e-5));
            let offset = screen_offset_px(n, 0.05 * d, Vec2::new(640.0, 480.0));
            prop_assert!(close(screen[k].x, offset.x, 1e-5) && close(screen[k].y, offset.y, 1e-5));
            prop_assert!(close(screen[k].z, hdrp_edge_fade(Vec2::new(u, v)), 1e-5));
            prop_assert!(close(screen[k].w, smoothstep01(x), 1e-5));
        }
    }


    /// The whole engine path (`engine_path.wgsl`) against `refract_core::engine::engine_path`
    /// over the same analytic screen, for every engine model and both settings of its switch,
    /// on front pixels of a unit sphere seen by a 64 × 48 camera (normals turned and scaled as
    /// the image-space kernel's test turns them). The texel read must be the same; the weight,
    /// the exit point and directions within 1e-4. A texel is decided by a floor of a projected
    /// point, so a row whose point projects within rounding of a texel edge may read the
    /// neighbour: at most 3 % of the rows may differ.
    #[test]
    fn engine_path_agrees(
        rows in prop::collection::vec((0u32..64, 0u32..48, unit(), 0.0f32..0.6, 0.5f32..2.0), ROWS),
        ior in prop::sample::select(vec![1.5f32, 1.33, 2.4, 0.8]),
        thickness in 0.05f32..2.0,
    ) {
        let context = gpu_or_skip!();
        let camera = Camera::new(CameraDesc { width: 64, height: 48, ..CameraDesc::default() })
            .expect("camera");
        let mut pixels = Vec::new();
        for (x, y, turn, amount, scale) in rows {
            let uv = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let ray = camera.pixel_ray(uv);
            let b = ray.origin.dot(ray.dir);
            let disc = b * b - (ray.origin.length_squared() - 1.0);
            if disc < 0.0 {
                continue;
            }
            let p1 = ray.at(-b - disc.sqrt());
            pixels.push((x, y, uv, p1, ((p1 + turn * amount) * scale).normalize()));
        }
        prop_assume!(pixels.len() > 40);
        let a: Vec<Vec4> = pixels.iter().map(|p| p.3.extend(0.0)).collect();
        let b: Vec<Vec4> = pixels.iter().map(|p| p.4.extend((p.0 + 4096 * p.1) as f32)).collect();
        let mut outcomes = [0usize; 3];
        for (code, model) in models(thickness) {
            let uniforms = EngineUniforms::new(&camera, &model, true);
            let blocks = [(16, bytemuck::bytes_of(&uniforms))];
            let constants = [("ENGINE_MODEL", f64::from(code))];
            let eval = |entry| {
                let evaluation = FamilyEvaluation {
                    entry,
                    ..engine_evaluation(&camera, ior, &blocks, &constants)
                };
                evaluate_family(context, &evaluation, &a, &b).expect("gpu")
            };
            let (texel, p2, t2, environment) = (
                eval("test_engine_path_texel"),
                eval("test_engine_path_p2"),
                eval("test_engine_path_t2"),
                eval("test_engine_path_environment"),
            );
            let mut mismatches = Vec::new();
            for (k, &(_, _, uv, p1, n1)) in pixels.iter().enumerate() {
                let path = engine_path(&camera, &AnalyticScreen, uv, p1, n1, ior, model);
                let flags = texel[k].w as u32;
                // NaN on the CPU where the model has no such vector: the GPU's value is unused.
                let same3 = |gpu: Vec4, cpu: Vec3| cpu.is_nan() || close3(gpu, cpu, 1e-4);
                let same = texel[k].x == path.texel.x as f32
                    && texel[k].y == path.texel.y as f32
                    && close(texel[k].z, path.screen_weight, 1e-4)
                    && (flags & 1 == 1) == path.off_screen
                    && same3(p2[k], path.p2)
                    && same3(t2[k], path.t2)
                    && (path.screen_weight == 1.0 || same3(environment[k], path.environment_dir));
                if !same {
                    mismatches.push(k);
                }
                outcomes[0] += usize::from(path.screen_weight == 0.0);
                outcomes[1] += usize::from(path.screen_weight > 0.0 && path.screen_weight < 1.0);
                outcomes[2] += usize::from(path.off_screen);
            }
            prop_assert!(
                mismatches.len() * 100 <= 3 * pixels.len(),
                "{model:?}: {} of {} rows differ (first: {:?}, GPU {:?}, CPU {:?})",
                mismatches.len(),
                pixels.len(),
                mismatches.first().map(|&k| pixels[k]),
                mismatches.first().map(|&k| (texel[k], p2[k], t2[k])),
                mismatches.first().map(|&k| {
                    let (_, _, uv, p1, n1) = pixels[k];
                    engine_path(&camera, &AnalyticScreen, uv, p1, n1, ior, model)
                }),
            );
        }
        // The screen's depth tests and fallbacks are exercised: environment-only pixels
        // (Bevy's rejection, HDRP's hit behind the eye), blends (Godot's guard, HDRP's fade).
        prop_assert!(outcomes[0] > 0 && outcomes[1] > 0, "{outcomes:?}");
    }
}

/// A 75 × 46 frame (sides that are not powers of two) and its camera, for the rough lookups.
fn odd_frame() -> (UVec2, Camera) {
    let size = UVec2::new(75, 46);
    let camera = Camera::new(CameraDesc {
        width: size.x,
        height: size.y,
        ..CameraDesc::default()
    })
    .expect("camera");
    (size, camera)
}

/// A rough lookup of `refract_core::screen_mips` over the analytic pyramid.
type Sampler = fn(&AnalyticMips, Vec2, f32) -> Vec3;

/// `engine_conformance.wgsl`'s analytic screen pyramid (`mip_texel`), exact in f32.
struct AnalyticMips(UVec2);

impl ScreenMips for AnalyticMips {
    fn size(&self) -> UVec2 {
        self.0
    }

    fn texel(&self, level: u32, texel: UVec2) -> Vec3 {
        Vec3::new(
            ((texel.x * 7 + texel.y * 3 + level * 5) % 11) as f32,
            0.5 * ((texel.x ^ texel.y) % 13) as f32,
            level as f32 + 0.25 * (texel.x % 4) as f32,
        )
    }
}

proptest! {
    #![proptest_config(config())]

    /// The rough lookups (`screen_mips.wgsl`: the levels' sizes, three.js's B-spline weights and
    /// clamped 4 × 4 sums, Godot's and HDRP's clamped bilinear reads, the mix of two levels)
    /// against `refract_core::screen_mips::{sample_threejs, sample_trilinear}` over an analytic
    /// pyramid of a frame whose sides are not powers of two, at positions inside and outside
    /// the image and LODs from 0 past the top level.
    #[test]
    fn rough_lookups_agree(rows in prop::collection::vec((-0.2f32..1.2, -0.2f32..1.2, 0.0f32..9.0), ROWS)) {
        let context = gpu_or_skip!();
        let (size, camera) = odd_frame();
        let a: Vec<Vec4> = rows.iter().map(|&(u, v, lod)| Vec4::new(u, v, lod, 0.0)).collect();
        let mips = AnalyticMips(size);
        let samplers: [(&str, Sampler); 2] = [
            ("test_sample_threejs", sample_threejs),
            ("test_sample_trilinear", sample_trilinear),
        ];
        for (entry, sample) in samplers {
            let evaluation = FamilyEvaluation {
                entry,
                ..engine_evaluation(&camera, 1.5, &[], &[])
            };
            let gpu = evaluate_family(context, &evaluation, &a, &a).expect("gpu");
            for (k, &(u, v, lod)) in rows.iter().enumerate() {
                let rust = sample(&mips, Vec2::new(u, v), lod);
                prop_assert!(close3(gpu[k], rust, 1e-4), "{entry}: uv ({u}, {v}) lod {lod}: gpu {} rust {rust}", gpu[k]);
            }
        }
    }
}

proptest! {
    #![proptest_config(config())]

    /// Bevy's taps (`screen_mips.wgsl`'s `bevy_blurred`: the noise, the spiral, the rotation,
    /// the checkerboard, the per-tap depth test, the bilinear reads) against
    /// `refract_core::engine::bevy_blurred` over the analytic pyramid and screen, with
    /// fragments in front of and behind the screen's surfaces so that taps are both kept and
    /// rejected. Where a tap's texel sits within rounding of a texel edge the two may test
    /// different texels: at most 3 % of the rows may differ.
    #[test]
    fn bevy_taps_agree(rows in prop::collection::vec((0.0f32..1.0, 0.0f32..1.0, 0.05f32..1.0, 0.5f32..4.0, 0u32..75, 0u32..46), ROWS)) {
        let context = gpu_or_skip!();
        let (size, camera) = odd_frame();
        let evaluation = FamilyEvaluation {
            entry: "test_bevy_blurred",
            ..engine_evaluation(&camera, 1.5, &[], &[])
        };
        let frag = |x: u32, y: u32| Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        let a: Vec<Vec4> = rows.iter().map(|&(u, v, r, d, _, _)| Vec4::new(u, v, r, d)).collect();
        let b: Vec<Vec4> = rows.iter().map(|&(.., x, y)| frag(x, y).extend(0.0).extend(0.0)).collect();
        let gpu = evaluate_family(context, &evaluation, &a, &b).expect("gpu");
        let mips = AnalyticMips(size);
        let mut mismatches = 0;
        let mut rejected = 0;
        for (k, &(u, v, r, d, x, y)) in rows.iter().enumerate() {
            let (color, share) = bevy_blurred(&mips, &AnalyticScreen, frag(x, y), Vec2::new(u, v), r, d);
            rejected += usize::from(share < 1.0);
            if !(close3(gpu[k], color, 1e-3) && (gpu[k].w - share).abs() < 1e-6) {
                mismatches += 1;
            }
        }
        prop_assert!(mismatches * 100 <= 3 * rows.len(), "{mismatches} of {} rows differ", rows.len());
        prop_assert!(rejected > 0, "no tap was rejected");
    }
}
