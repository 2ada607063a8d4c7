//! The GPU's BVH traversal (`refract-gpu/shaders/bvh.wgsl` over `refract_geometry::FlatBvh`) against the
//! CPU's (`MeshBvh`, obvhs's wide BVH): the first building block of the exact reference in WGSL
//! (issue 32). Both test the same watertight Möller–Trumbore; the trees differ, so only ties
//! (a ray through a shared edge) may pick different triangles, at the same distance.

use glam::Vec3;
use refract_core::Ray;
use refract_geometry::{FlatBvh, Mesh, MeshBvh, shapes};
use refract_gpu::GpuContext;
use refract_gpu::bvh::GpuBvh;
use refract_tests::shared_data;

/// `count` rays from points on a sphere of radius 2·r around the mesh's centre toward random
/// points inside its bounding sphere (most hit), and a tenth aimed away (they miss); a fixed
/// linear congruential sequence, so every run tests the same rays.
fn rays(mesh: &Mesh, count: usize) -> Vec<Ray> {
    let sphere = mesh.bounding_sphere();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut unit = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 40) as f32) / ((1u64 << 24) as f32)
    };
    let direction = |unit: &mut dyn FnMut() -> f32| {
        let z = 2.0 * unit() - 1.0;
        let phi = std::f32::consts::TAU * unit();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    };
    (0..count)
        .map(|i| {
            let origin = sphere.center + 2.0 * sphere.radius * direction(&mut unit);
            let target = sphere.center + sphere.radius * unit() * direction(&mut unit);
            let dir = if i % 10 == 0 {
                (origin - sphere.center).normalize()
            } else {
                (target - origin).normalize()
            };
            Ray { origin, dir }
        })
        .collect()
}

fn check(name: &str, mesh: &Mesh, context: &GpuContext) {
    let flat = FlatBvh::build(mesh).expect("flat BVH");
    let gpu = GpuBvh::upload(context, &flat).expect("upload");
    let cpu = MeshBvh::build(mesh);
    let rays = rays(mesh, 20_000);
    let hits = gpu
        .closest_hits(context, &rays, 0.0, f32::INFINITY)
        .expect("trace");
    let (mut agree, mut hit, mut missed) = (0usize, 0usize, 0usize);
    for (ray, gpu_hit) in rays.iter().zip(&hits) {
        let cpu_hit = cpu.closest_hit(ray, 0.0, f32::INFINITY);
        match (cpu_hit, gpu_hit) {
            (None, None) => {
                agree += 1;
                missed += 1;
            }
            (Some(c), Some(g)) => {
                hit += 1;
                assert!(
                    (c.t - g.t).abs() <= 1e-5 * (1.0 + c.t),
                    "{name}: t {} (CPU) vs {} (GPU) for {ray:?}",
                    c.t,
                    g.t
                );
                agree += usize::from(c.triangle == g.triangle);
            }
            (c, g) => panic!("{name}: CPU {c:?}, GPU {g:?} for {ray:?}"),
        }
    }
    let share = agree as f64 / rays.len() as f64;
    println!(
        "{name}: {} triangles, depth {}, {hit} hits and {missed} misses, the same triangle on {:.3} %",
        mesh.triangles.len(),
        flat.depth,
        100.0 * share
    );
    assert!(
        hit > rays.len() / 2 && missed >= rays.len() / 10,
        "{name}: {hit} / {missed}"
    );
    assert!(share >= 0.999, "{name}: the same first hit on {share}");
}

#[test]
fn gpu_bvh_closest_hits_match_the_cpu_bvh() {
    let Some(context) = GpuContext::for_tests() else {
        return;
    };
    check(
        "uv sphere",
        &shapes::uv_sphere(40, 20, 1.0).expect("sphere"),
        &context,
    );
    check(
        "torus",
        &shapes::torus(1.0, 0.35, 48, 24).expect("torus"),
        &context,
    );
    if let Some(data) = shared_data() {
        let mesh = refract_eval::load_mesh(
            &data.join("meshes/cow.obj"),
            &refract_eval::LoadOptions::default(),
        )
        .expect("cow")
        .mesh;
        check("cow", &mesh, &context);
    }
}

#[test]
fn an_empty_bvh_misses_everything() {
    let Some(context) = GpuContext::for_tests() else {
        return;
    };
    let gpu = GpuBvh::upload(&context, &FlatBvh::default()).expect("upload");
    let ray = Ray {
        origin: Vec3::ZERO,
        dir: Vec3::X,
    };
    assert_eq!(
        gpu.closest_hits(&context, &[ray], 0.0, 1.0).expect("trace"),
        vec![None]
    );
}
