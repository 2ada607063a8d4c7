//! Kakimoto et al. 2007 (`pvrr`) on the CPU backend against the exact reference: at every
//! vertex the map lookup lands on the exact ray's hit within one map texel (the paper's "red
//! balls", Fig. 1, 14); a flat mirror's virtual viewpoint is the mirrored eye and its image
//! the reference's; adjacent mirrors agree at their shared vertices (Fig. 7); a stack of maps
//! brings the multiple reflection to the reference (Fig. 11); a concave mirror seen from beyond
//! its focal point marks its zooming region (Fig. 8(b)); a convex lens far from the eye
//! reverses the image (Fig. 13); three indices share one map (Fig. 15); the per-vertex work is
//! kept while the eye is fixed (§5). The CPU-vs-GPU agreement is in `gpu_backend.rs`.

use std::sync::Arc;

use glam::{Vec2, Vec3};
use refract_core::Camera;
use refract_core::optics::{face_forward_shading_normal, reflect};
use refract_core::pvrr::{STATE_MAPPED, sample_bilinear};
use refract_cpu::pvrr::PvrrPasses;
use refract_cpu::{CpuFamily, FrameCx};
use refract_eval::{load_scene, load_scene_str};
use refract_scene::pvrr::PvrrPlanner;
use refract_scene::{
    Aov, Frame, FrameOutputs, MethodId, MethodParams, PvrrParams, Scene, SceneMesh,
};
use refract_tests::scenes::{covered_radiance, method, render, white_furnace};
use refract_trace::ReferenceRenderer;

fn builtin(name: &str) -> Arc<Scene> {
    Arc::new(load_scene(name).expect("built-in").scene)
}

fn scene(toml: &str) -> Arc<Scene> {
    Arc::new(
        load_scene_str("test", toml, std::path::Path::new("."), "test.toml")
            .expect("scene")
            .scene,
    )
}

fn params(settings: &[(&str, &str)]) -> PvrrParams {
    let mut p = method(MethodId::Pvrr);
    for (name, value) in settings {
        p.set(name, value, "test").expect(name);
    }
    let MethodParams::Pvrr(p) = p else {
        unreachable!("pvrr parameters")
    };
    p
}

fn pvrr(scene: &Arc<Scene>, camera: &Camera, p: &PvrrParams) -> (PvrrPasses, Frame) {
    let mut passes = PvrrPasses::default();
    passes.prepare(scene);
    let mut frame = Frame::default();
    let cx = FrameCx {
        scene,
        camera,
        method: MethodId::Pvrr,
        outputs: FrameOutputs::ColorAndAovs,
        lambda_nm: None,
        repeat: false,
    };
    passes.render(&cx, p, &mut frame).expect("pvrr frame");
    (passes, frame)
}

fn reference(scene: &Arc<Scene>, camera: &Camera, mode: &str) -> Frame {
    let mut params = method(MethodId::Reference);
    params.set("mode", mode, "test").expect("mode");
    render(&mut ReferenceRenderer::new(), scene, camera, &params)
}

/// Mean absolute colour difference over the pixels `covered` marks.
fn mean_error_on(a: &Frame, b: &Frame, covered: &[bool]) -> f64 {
    let (sum, n) = a
        .color
        .iter()
        .zip(&b.color)
        .zip(covered)
        .filter(|(_, c)| **c)
        .fold((0.0, 0usize), |(s, n), ((x, y), _)| {
            (s + f64::from((*x - *y).abs().element_sum()) / 3.0, n + 1)
        });
    sum / n.max(1) as f64
}

/// The exact ray of mirror vertex `v` seen from `eye`, traced to the scene (the mirror
/// excluded), independently of the plan.
fn exact_mirror_hit(
    scene: &Scene,
    mirror: SceneMesh,
    eye: Vec3,
    v: Vec3,
    n: Vec3,
) -> Option<(Vec3, SceneMesh)> {
    let incident = (v - eye).normalize();
    let dir = reflect(incident, face_forward_shading_normal(n, incident));
    let ray = refract_core::Ray { origin: v, dir };
    let mut best = (f32::INFINITY, SceneMesh::Refractor);
    for (k, o) in scene.objects.iter().enumerate() {
        if mirror == SceneMesh::Object(k) {
            continue;
        }
        if let Some(h) = o.bvh().closest_hit(&ray, 1e-3, best.0) {
            best = (h.t, SceneMesh::Object(k));
        }
    }
    if mirror != SceneMesh::Refractor
        && let Some(h) = scene.refractor.bvh().closest_hit(&ray, 1e-3, best.0)
    {
        best = (h.t, SceneMesh::Refractor);
    }
    best.0.is_finite().then(|| (ray.at(best.0), best.1))
}

/// Fig. 1: at every vertex the map position is the projection of the exact hit (within one
/// map texel), and the map shows there the mesh the exact ray hits.
#[test]
fn every_vertex_looks_up_its_exact_hit_within_one_texel() {
    let scene = builtin("convex-mirror");
    let camera = scene.camera(160, 160).expect("camera");
    let p = params(&[("res", "512")]);
    let (passes, _) = pvrr(&scene, &camera, &p);
    let plan = passes.last_plan();
    let draw = &plan.views[0].draws[0];
    let map_view = draw.map.expect("a map");
    let map_camera = plan.views[map_view].camera;
    let mesh = scene.refractor.mesh();
    let (mut checked, mut hits_shown) = (0, 0);
    for (i, vertex) in draw.vertices.iter().enumerate() {
        assert_eq!(vertex.state, STATE_MAPPED as f32, "vertex {i} is mapped");
        let st = Vec2::from_array(vertex.st[1]);
        let Some((hit, hit_mesh)) = exact_mirror_hit(
            &scene,
            SceneMesh::Refractor,
            camera.eye(),
            mesh.positions[i],
            mesh.normals[i],
        ) else {
            continue;
        };
        let projected = map_camera.world_to_pixel(hit).expect("in front").truncate();
        assert!(
            projected.distance(st) <= 1.0,
            "vertex {i}: map position {st} vs the exact hit's projection {projected}"
        );
        checked += 1;
        // The map's surface at that texel is the surface the exact ray hits (no occluder on
        // the line from the virtual viewpoint: Fig. 16 would break this).
        if passes.map_mesh_at(map_view, st) == Some(hit_mesh) {
            hits_shown += 1;
        }
    }
    assert!(
        checked >= 30,
        "{checked} of 49 vertices hit the scene (the rest see the sky)"
    );
    assert!(
        hits_shown * 10 >= checked * 9,
        "{hits_shown} of {checked} vertices show their hit's mesh"
    );
}

const FLAT_MIRROR: &str = r#"
[camera]
eye = [0.0, 0.35, 3.2]
target = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
near = 0.05
far = 40.0

[refractor]
mesh = "builtin:mirror-flat"
material = "mirror"
normalize = false
rotate_deg = [0.0, 30.0, 0.0]

[[objects]]
mesh = "builtin:plane"
texture = "checker"
scale = 14.0
translate = [0.0, -1.0, 0.0]

[[objects]]
mesh = "builtin:sphere"
color = [0.8, 0.1, 0.08]
scale = 0.35
translate = [1.3, -0.65, 1.9]
"#;

/// §3.2: a planar mirror's lines meet at the mirrored eye, and its image is the reference's.
#[test]
fn a_flat_mirror_sees_from_the_mirrored_eye_and_matches_the_reference() {
    let scene = scene(FLAT_MIRROR);
    let camera = scene.camera(96, 96).expect("camera");
    let (passes, frame) = pvrr(&scene, &camera, &params(&[("res", "256")]));
    let plan = passes.last_plan();
    let view = &plan.views[plan.views[0].draws[0].map.expect("a map")];
    // The mirror plane: normal (sin 30°, 0, cos 30°) through the origin.
    let n = Vec3::new(0.5, 0.0, 0.75f32.sqrt());
    let eye = camera.eye();
    let mirrored = eye - 2.0 * eye.dot(n) * n;
    assert!(
        view.camera.eye().distance(mirrored) < 1e-3,
        "{} vs {mirrored}",
        view.camera.eye()
    );
    let truth = reference(&scene, &camera, "transmission");
    let covered = frame.flag(Aov::Covered).expect("covered").to_vec();
    assert!(covered.iter().filter(|c| **c).count() > 500);
    let error = mean_error_on(&frame, &truth, &covered);
    assert!(error < 0.02, "mean error on the mirror {error}");
}

/// Fig. 7: the shared vertices of two adjacent mirrors read the same colour from both maps.
#[test]
fn adjacent_mirrors_agree_at_their_shared_vertices() {
    let scene = builtin("adjacent-mirrors");
    let camera = scene.camera(128, 128).expect("camera");
    let (passes, _) = pvrr(&scene, &camera, &params(&[("res", "512")]));
    let plan = passes.last_plan();
    let draws = &plan.views[0].draws;
    assert_eq!(draws.len(), 2, "two mirrors");
    let left = scene.refractor.mesh();
    let right = scene.objects.last().expect("the right mirror").mesh();
    let mut differences = Vec::new();
    for (i, p) in left.positions.iter().enumerate() {
        let Some(j) = right.positions.iter().position(|q| q == p) else {
            continue;
        };
        let lookup = |draw: &refract_scene::pvrr::PvrrDraw, v: usize| {
            let map = passes.map(draw.map.expect("a map")).expect("rendered");
            sample_bilinear(map, Vec2::from_array(draw.vertices[v].st[1]))
        };
        differences.push(
            (lookup(&draws[0], i) - lookup(&draws[1], j))
                .abs()
                .max_element(),
        );
    }
    assert_eq!(differences.len(), 7, "the seven shared vertices");
    differences.sort_by(f32::total_cmp);
    assert!(
        differences[3] < 0.02,
        "median colour step at the shared vertices {differences:?}"
    );
}

/// Fig. 11 / §4.4: the flat mirror seen in the convex mirror needs the stack: with one level
/// the convex mirror's map draws it black, three levels bring it to the reference.
#[test]
fn a_stack_of_maps_renders_the_multiple_reflection() {
    let scene = builtin("mirror-stack");
    let camera = scene.camera(96, 96).expect("camera");
    let truth = reference(&scene, &camera, "full");
    let mut errors = Vec::new();
    for depth in ["1", "3"] {
        let (passes, frame) = pvrr(
            &scene,
            &camera,
            &params(&[("res", "256"), ("depth", depth)]),
        );
        let covered = frame.flag(Aov::Covered).expect("covered").to_vec();
        let black = frame
            .color
            .iter()
            .zip(&covered)
            .filter(|(c, k)| **k && **c == Vec3::ZERO)
            .count();
        errors.push((
            mean_error_on(&frame, &truth, &covered),
            black,
            passes.last_plan().views.len(),
        ));
    }
    let (shallow, deep) = (errors[0], errors[1]);
    assert!(
        shallow.1 > 20,
        "depth 1 leaves the inner mirror black: {errors:?}"
    );
    assert!(deep.1 < shallow.1 / 4, "depth 3 fills it: {errors:?}");
    assert!(deep.2 > shallow.2, "more views with depth 3: {errors:?}");
    assert!(deep.0 < 0.25 * shallow.0, "{errors:?}");
}

/// Fig. 8(b): a concave mirror seen from beyond its focal point: the rays converge between
/// the mirror and the objects; what lies before the convergence is the zooming region (marked,
/// black), the rest is looked up.
#[test]
fn a_concave_mirror_marks_its_zooming_region() {
    let toml = FLAT_MIRROR
        .replace("builtin:mirror-flat", "builtin:mirror-concave")
        .replace("eye = [0.0, 0.35, 3.2]", "eye = [0.0, 0.35, 9.0]")
        .replace(
            "rotate_deg = [0.0, 30.0, 0.0]",
            "rotate_deg = [0.0, 10.0, 0.0]",
        );
    let concave = scene(&toml);
    let camera = concave.camera(96, 96).expect("camera");
    let (_, frame) = pvrr(&concave, &camera, &params(&[("res", "256")]));
    let zoom = frame.flag(Aov::Zoom).expect("zoom");
    let covered = frame.flag(Aov::Covered).expect("covered");
    let zoomed = zoom.iter().filter(|z| **z).count();
    assert!(zoomed > 0, "the zooming region is marked");
    assert!(
        zoom.iter().zip(covered).all(|(z, c)| !z || *c),
        "only on the mirror"
    );
    for (i, z) in zoom.iter().enumerate() {
        if *z {
            assert_eq!(frame.color[i], Vec3::ZERO, "left out, as in the paper");
        }
    }
    let flat = scene(FLAT_MIRROR);
    let camera = flat.camera(96, 96).expect("camera");
    let (_, frame) = pvrr(&flat, &camera, &params(&[("res", "256")]));
    assert_eq!(
        frame
            .flag(Aov::Zoom)
            .expect("zoom")
            .iter()
            .filter(|z| **z)
            .count(),
        0
    );
}

/// Fig. 13: a convex lens far from the eye reverses the image, and pvrr draws it so: the
/// lens's left shows what lies right of the axis, as in the reference.
#[test]
fn a_far_convex_lens_reverses_the_image() {
    let scene = scene(refract_eval::scene_file::MAGNIFIER_SCENE);
    let camera = scene.camera(96, 96).expect("camera");
    let (_, frame) = pvrr(&scene, &camera, &params(&[("res", "512")]));
    let truth = reference(&scene, &camera, "transmission");
    let covered = frame.flag(Aov::Covered).expect("covered").to_vec();
    let lens_pixels = covered.iter().filter(|c| **c).count();
    assert!(lens_pixels > 1000, "{lens_pixels}");
    let error = mean_error_on(&frame, &truth, &covered);
    assert!(error < 0.05, "mean error through the lens {error}");
    // Reversed: a pixel left of centre on the lens shows the chart colour the direct view has
    // right of centre (the chart is symmetric in no axis, so compare with the reference).
    let row = 48 * 96;
    let (left, right) = (frame.color[row + 40], frame.color[row + 56]);
    let (truth_left, truth_right) = (truth.color[row + 40], truth.color[row + 56]);
    assert!(
        (left - truth_left).abs().max_element() < 0.05,
        "{left} vs {truth_left}"
    );
    assert!(
        (right - truth_right).abs().max_element() < 0.05,
        "{right} vs {truth_right}"
    );
}

/// Fig. 15: three indices share one map; the image matches the reference composed channel by
/// channel from three indices better than one index does.
#[test]
fn three_indices_share_one_map_for_chromatic_aberration() {
    let base = builtin("spectacles");
    let camera = base.camera(96, 96).expect("camera");
    let (passes, chromatic) = pvrr(
        &base,
        &camera,
        &params(&[("res", "512"), ("dispersion", "40")]),
    );
    let plan = passes.last_plan();
    assert_eq!(plan.views.len(), 2, "one map for the three channels");
    let spread = plan.views[0].draws[0]
        .vertices
        .iter()
        .filter(|v| v.state == STATE_MAPPED as f32)
        .map(|v| Vec2::from_array(v.st[0]).distance(Vec2::from_array(v.st[2])))
        .fold(0.0f32, f32::max);
    assert!(spread > 1.0, "R and B land apart somewhere: {spread}");
    let (_, plain) = pvrr(&base, &camera, &params(&[("res", "512")]));
    // The reference per channel: IOR 1.57, 1.61, 1.65.
    let mut composed = Frame::default();
    for (k, ior) in [1.57f32, 1.61, 1.65].into_iter().enumerate() {
        let mut s = (*base).clone();
        s.refractor.set_ior(ior).expect("ior");
        let truth = reference(&Arc::new(s), &camera, "transmission");
        if k == 0 {
            composed = truth.clone();
        }
        for (c, t) in composed.color.iter_mut().zip(&truth.color) {
            c[k] = t[k];
        }
    }
    let covered = chromatic.flag(Aov::Covered).expect("covered").to_vec();
    let with = mean_error_on(&chromatic, &composed, &covered);
    let without = mean_error_on(&plain, &composed, &covered);
    assert!(with < without, "dispersion {with} vs none {without}");
}

/// §5: with `update=on-change` the per-vertex work runs once while the camera stays, and the
/// frames are identical; a moved camera rebuilds.
#[test]
fn a_fixed_eye_keeps_the_per_vertex_work() {
    let scene = builtin("spectacles");
    let camera = scene.camera(64, 64).expect("camera");
    for (update, builds) in [("every-frame", 3), ("on-change", 1)] {
        let p = params(&[("res", "128"), ("update", update)]);
        let mut planner = PvrrPlanner::default();
        planner.prepare(&scene);
        let first = planner.plan(&scene, &camera, &p).expect("plan").clone();
        for _ in 0..2 {
            assert_eq!(planner.plan(&scene, &camera, &p).expect("plan"), &first);
        }
        assert_eq!(planner.builds(), builds, "{update}");
        let mut desc = *camera.desc();
        desc.eye.x += 0.1;
        let moved = Camera::new(desc).expect("camera");
        planner.plan(&scene, &moved, &p).expect("plan");
        assert_eq!(
            planner.builds(),
            builds + 1,
            "{update}: a moved eye rebuilds"
        );
    }
}

/// The longer side of the first map of a `size²` frame of `scene` with `settings`.
fn map_side(scene: &Scene, size: u32, settings: &[(&str, &str)]) -> u32 {
    let camera = scene.camera(size, size).expect("camera");
    let mut planner = PvrrPlanner::default();
    let plan = planner
        .plan(scene, &camera, &params(settings))
        .expect("plan");
    let map = &plan.views.get(1).expect("a map").camera;
    map.width().max(map.height())
}

/// The registry's parameters reach the plan: under `sizing=fixed` the map's longer side is
/// `res` whatever the frame.
#[test]
fn the_map_resolution_is_the_parameter() {
    let scene = builtin("convex-mirror");
    for size in [32, 128] {
        let side = map_side(&scene, size, &[("res", "200"), ("sizing", "fixed")]);
        assert_eq!(side, 200, "{size}²");
    }
}

/// Under `sizing=footprint` (the default) the map follows the mirror's footprint: 8 texels per
/// pixel of the frame it is seen in (the mirror covers about 44 % of the default view's
/// width), so twice the frame gives twice the map, and `res` caps it.
#[test]
fn the_map_follows_the_reflector_footprint() {
    let scene = builtin("convex-mirror");
    let small = map_side(&scene, 32, &[]);
    let large = map_side(&scene, 64, &[]);
    assert!((8 * 8..=8 * 32).contains(&small), "{small}");
    assert!(
        large.abs_diff(2 * small) <= 16,
        "32²: {small} texels, 64²: {large} texels"
    );
    assert_eq!(map_side(&scene, 64, &[("res", "100")]), 100);
    // At 1024² the footprint asks for more than the default cap: the paper's 1024 texels.
    assert_eq!(map_side(&scene, 1024, &[]), 1024);
}

/// The exact ray through the lens of vertex `v` seen from `eye`, independently of the plan:
/// refracted in at `v`, out at the first back-surface hit (no TIR in these tests), traced to the
/// objects.
fn exact_lens_hit(scene: &Scene, eye: Vec3, v: Vec3, n: Vec3, ior: f32) -> Option<Vec3> {
    use refract_core::optics::refract;
    let incident = (v - eye).normalize();
    let inside = refract(
        incident,
        face_forward_shading_normal(n, incident),
        1.0 / ior,
    );
    let ray = refract_core::Ray {
        origin: v,
        dir: inside.try_normalize()?,
    };
    let back = scene
        .refractor
        .bvh()
        .closest_hit(&ray, 1e-3, f32::INFINITY)?;
    let out = refract(
        ray.dir,
        face_forward_shading_normal(-back.shading_normal, ray.dir),
        ior,
    )
    .try_normalize()?;
    let exit = refract_core::Ray {
        origin: ray.at(back.t),
        dir: out,
    };
    let t = scene
        .objects
        .iter()
        .filter_map(|o| o.bvh().closest_hit(&exit, 1e-3, f32::INFINITY))
        .map(|h| h.t)
        .min_by(f32::total_cmp)?;
    Some(exit.at(t))
}

/// Fig. 14: through a lens too, every ray-issuing vertex looks up its exact double-refracted
/// hit within one map texel; the concave spectacle lens as well as the convex one.
#[test]
fn every_lens_vertex_looks_up_its_exact_hit_within_one_texel() {
    let convex = builtin("spectacles");
    let toml = r#"
[camera]
eye = [0.0, 0.0, 1.1]
target = [0.0, 0.0, 0.0]
fov_y_deg = 70.0
near = 0.05
far = 40.0

[refractor]
mesh = "builtin:lens-concave"
ior = 1.61
scale = 0.9

[[objects]]
mesh = "builtin:plane"
texture = "color-chart"
scale = 4.0
rotate_deg = [90.0, 0.0, 0.0]
translate = [0.0, 0.0, -2.0]
"#;
    for scene in [convex, scene(toml)] {
        let camera = scene.camera(64, 64).expect("camera");
        let (passes, frame) = pvrr(&scene, &camera, &params(&[("res", "512")]));
        let plan = passes.last_plan();
        let draw = &plan.views[0].draws[0];
        let map_camera = plan.views[draw.map.expect("a map")].camera;
        let mesh = scene.refractor.mesh();
        let mut checked = 0;
        for (i, vertex) in draw.vertices.iter().enumerate() {
            if vertex.state != STATE_MAPPED as f32 {
                continue;
            }
            let Some(hit) = exact_lens_hit(
                &scene,
                camera.eye(),
                mesh.positions[i],
                mesh.normals[i],
                scene.refractor.ior(),
            ) else {
                continue;
            };
            let projected = map_camera.world_to_pixel(hit).expect("in front").truncate();
            let st = Vec2::from_array(vertex.st[1]);
            assert!(
                projected.distance(st) <= 1.0,
                "{}: vertex {i}: {st} vs {projected}",
                mesh.name
            );
            checked += 1;
        }
        assert!(
            checked >= 100,
            "{}: {checked} ray-issuing vertices checked",
            mesh.name
        );
        // And the image through the lens is the reference's where it is looked up (the
        // concave lens spreads its rim's rays beyond the widest map: the zoom flag, black).
        let truth = reference(&scene, &camera, "transmission");
        let zoom = frame.flag(Aov::Zoom).expect("zoom");
        let looked_up: Vec<bool> = frame
            .flag(Aov::Covered)
            .expect("covered")
            .iter()
            .zip(zoom)
            .map(|(c, z)| *c && !z)
            .collect();
        assert!(
            looked_up.iter().filter(|l| **l).count() > 500,
            "{}",
            mesh.name
        );
        let error = mean_error_on(&frame, &truth, &looked_up);
        assert!(
            error < 0.05,
            "{}: mean error through the lens {error}",
            mesh.name
        );
    }
}

/// The specular object and every conductor object are reflectors; a glass specular object is
/// a lens.
#[test]
fn the_specular_object_and_conductor_objects_are_reflectors() {
    use refract_scene::pvrr::{ReflectorKind, reflectors};
    let scene = load_scene("mirror-room").expect("built-in").scene;
    let all = reflectors(&scene);
    assert_eq!(all[0].mesh, SceneMesh::Refractor);
    assert!(matches!(all[0].kind, ReflectorKind::Mirror { .. }));
    assert!(
        all.len() >= 2,
        "the planar mirror is a conductor object too"
    );
    let glass = load_scene("sphere").expect("built-in").scene;
    assert!(matches!(
        reflectors(&glass)[0].kind,
        ReflectorKind::Lens { .. }
    ));
}

/// White furnace (no energy from nowhere): the convex mirror (its scene's objects removed)
/// and the spectacle lens in a constant white environment: every pixel of the mirror or lens
/// is at most the environment's radiance (1 + 1e-4 for f32 rounding), since a conductor's
/// Fresnel reflectance and a dielectric's transmittance are at most one; and not black (the
/// view of the environment through them is kept).
#[test]
fn a_white_furnace_gains_no_energy() {
    for name in ["convex-mirror", "spectacles"] {
        let s = white_furnace(name);
        let camera = s.camera(64, 64).expect("camera");
        let (_, frame) = pvrr(&s, &camera, &params(&[]));
        let (max, mean, count) = covered_radiance(&frame);
        println!("{name}: furnace radiance max {max}, mean {mean} over {count} values");
        assert!(count > 300, "{name}: the specular object is seen");
        assert!(max <= 1.0 + 1e-4, "{name}: energy from nowhere: {max}");
        assert!(mean >= 0.5, "{name}: mean {mean}");
    }
}
