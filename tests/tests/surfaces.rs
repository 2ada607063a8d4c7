//! Rasterising any mesh of the scene from any camera: the refractor and an opaque object, from
//! the default camera and from the six (mirrored) cube-map face cameras. The CPU rasteriser is
//! held to BVH ray casts at every pixel centre, and the GPU pass to the CPU one (positions,
//! normals, uvs, object ids).

use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use refract_core::{Camera, CubeFace};
use refract_cpu::rasterize_surface;
use refract_geometry::shapes;
use refract_gpu::GpuRenderer;
use refract_scene::{Material, Object, Scene, SceneMesh, SurfaceTexel};
use refract_tests::scenes::{builtin, camera};

/// A torus refractor above a 6 × 6 plane (uvs over [0, 1]²) at y = −1.
fn scene() -> Arc<Scene> {
    let mut scene = builtin("torus", 1.33);
    let mut plane = shapes::plane(6.0, 8).expect("plane");
    plane.transform(&Affine3A::from_translation(Vec3::new(0.0, -1.0, 0.0)));
    let albedo = refract_scene::Albedo::Constant(Vec3::splat(0.5));
    Arc::make_mut(&mut scene)
        .objects
        .push(Object::new(plane, Material::Diffuse(albedo)).expect("object"));
    scene
}

/// The default camera and the six faces of a cube map around a point above the torus.
fn cameras() -> Vec<(String, Camera)> {
    let mut cameras = vec![("default".to_owned(), camera(96))];
    for face in CubeFace::ALL {
        let camera =
            Camera::cube_face(Vec3::new(0.1, 1.4, 0.3), face, 48, 0.01, 50.0).expect("cube face");
        cameras.push((format!("{face:?}"), camera));
    }
    cameras
}

const MESHES: [SceneMesh; 2] = [SceneMesh::Refractor, SceneMesh::Object(0)];

/// Coverage agrees with front-facing closest hits on ≥ 99.5 % of the pixels either covers
/// (the rest are pixel centres within rounding of an edge), and where both see the mesh the
/// positions agree within 2e-3 and uvs within 1e-3 (the rasteriser snaps vertices to 1/256 px).
#[test]
fn cpu_surfaces_match_ray_casts_from_any_camera() {
    let scene = scene();
    let mut seen = std::collections::HashMap::new();
    for (label, cam) in cameras() {
        for which in MESHES {
            let texels = rasterize_surface(&scene, which, &cam).expect("mesh");
            let bvh = match which {
                SceneMesh::Refractor => scene.refractor.bvh(),
                SceneMesh::Object(k) => scene.objects[k].bvh(),
            };
            let (mut union, mut agree, mut both) = (0, 0, 0);
            for (i, texel) in texels.iter().enumerate() {
                let (x, y) = (i as u32 % cam.width(), i as u32 / cam.width());
                let ray = cam.pixel_ray(Camera::pixel_center(x, y));
                let hit = bvh
                    .closest_hit(&ray, 0.0, f32::INFINITY)
                    .filter(|h| h.geometric_normal.dot(ray.dir) < 0.0);
                if texel.is_some() || hit.is_some() {
                    union += 1;
                    agree += usize::from(texel.is_some() == hit.is_some());
                }
                if let (Some(t), Some(hit)) = (texel, hit) {
                    both += 1;
                    let p = ray.at(hit.t);
                    assert!((t.p_ws - p).length() < 2e-3, "{label} {which:?} ({x}, {y})");
                    assert_eq!(t.object, which.object_id());
                    if let SceneMesh::Object(_) = which {
                        // The plane's uv is linear in x and z.
                        let uv = Vec2::new(p.x / 6.0 + 0.5, p.z / 6.0 + 0.5);
                        assert!(
                            (t.uv - uv).abs().max_element() < 1e-3,
                            "{label}: {} vs {uv}",
                            t.uv
                        );
                    }
                }
            }
            let coverage = agree as f64 / union.max(1) as f64;
            println!(
                "{label} {which:?}: {union} px, coverage agreement {coverage:.5}, {both} compared"
            );
            assert!(
                union == 0 || coverage >= 0.995,
                "{label} {which:?}: coverage {coverage}"
            );
            *seen
                .entry((label.starts_with("Pos") || label.starts_with("Neg"), which))
                .or_insert(0) += both;
        }
    }
    // Both meshes are seen through the default camera and through some cube faces.
    assert_eq!(seen.len(), 4);
    assert!(seen.values().all(|&n| n > 500), "{seen:?}");
}

fn close(a: &SurfaceTexel, b: &SurfaceTexel) -> bool {
    (a.p_ws - b.p_ws).length() < 1e-3
        && (a.n_ws - b.n_ws).length() < 2e-3
        && (a.uv - b.uv).abs().max_element() < 1e-3
        && a.object == b.object
}

/// The GPU pass sees what the CPU pass sees: coverage on ≥ 99.5 % of the pixels either covers
/// and ≥ 99.5 % of the common pixels within 1e-3 (position, uv) and 2e-3 (normal), same object.
#[test]
fn gpu_surfaces_match_cpu_surfaces_from_any_camera() {
    let Some(mut gpu) = GpuRenderer::for_tests() else {
        return;
    };
    let scene = scene();
    refract_scene::Renderer::prepare(&mut gpu, &scene).expect("prepare");
    for (label, cam) in cameras() {
        for which in MESHES {
            let cpu = rasterize_surface(&scene, which, &cam).expect("mesh");
            let ours = gpu.rasterize_surface(&cam, which).expect("gpu surface");
            let (mut union, mut agree, mut both, mut near) = (0, 0, 0, 0);
            for (c, g) in cpu.iter().zip(&ours) {
                if c.is_some() || g.is_some() {
                    union += 1;
                    agree += usize::from(c.is_some() == g.is_some());
                }
                if let (Some(c), Some(g)) = (c, g) {
                    both += 1;
                    near += usize::from(close(c, g));
                }
            }
            let coverage = agree as f64 / union.max(1) as f64;
            let closeness = near as f64 / both.max(1) as f64;
            println!(
                "{label} {which:?}: coverage {coverage:.5}, attributes {closeness:.5} over {both} px"
            );
            assert!(union == 0 || coverage >= 0.995, "{label} {which:?}");
            assert!(both == 0 || closeness >= 0.995, "{label} {which:?}");
        }
    }
    let err = gpu
        .rasterize_surface(&camera(8), SceneMesh::Object(7))
        .expect_err("no such object");
    assert!(err.to_string().contains("Object(7)"), "{err}");
}
