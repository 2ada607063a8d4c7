//! Geometry precompute: BVH build, d_N, and closest-hit throughput on 1024² camera rays.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rayon::prelude::*;
use refract_core::{Camera, CameraDesc};
use refract_geometry::{MeshBvh, normal_distances};

const RES: u32 = 1024;

fn geometry(c: &mut Criterion) {
    let camera = Camera::new(CameraDesc {
        width: RES,
        height: RES,
        ..CameraDesc::default()
    })
    .expect("camera");
    for (label, file) in refract_benches::BENCH_MESHES {
        let Some(mesh) = refract_benches::load_shared_mesh(file) else {
            continue;
        };
        let bvh = MeshBvh::build(&mesh);
        // Correctness before timing: closed meshes have almost no d_N misses.
        let d_n = normal_distances(&mesh, &bvh);
        assert!(
            d_n.miss_rate() < 0.05,
            "{label}: d_N miss rate {}",
            d_n.miss_rate()
        );

        let mut group = c.benchmark_group(format!("geometry/{label}"));
        group.sample_size(10);
        group.throughput(Throughput::Elements(mesh.triangles.len() as u64));
        group.bench_function("bvh_build", |b| b.iter(|| MeshBvh::build(black_box(&mesh))));
        group.throughput(Throughput::Elements(mesh.positions.len() as u64));
        group.bench_function("d_n", |b| {
            b.iter(|| normal_distances(black_box(&mesh), &bvh))
        });
        group.bench_function("bvh_build_plus_d_n", |b| {
            b.iter(|| {
                let bvh = MeshBvh::build(black_box(&mesh));
                normal_distances(&mesh, &bvh)
            })
        });

        let rays: Vec<_> = (0..RES * RES)
            .map(|i| camera.pixel_ray(Camera::pixel_center(i % RES, i / RES)))
            .collect();
        let hits = rays
            .par_iter()
            .filter(|r| bvh.closest_hit(r, 0.0, f32::INFINITY).is_some())
            .count();
        assert!(
            hits > (RES * RES / 10) as usize,
            "{label}: only {hits} camera rays hit"
        );
        group.throughput(Throughput::Elements(rays.len() as u64));
        group.bench_function("closest_hit_camera_rays_1024", |b| {
            b.iter(|| {
                rays.par_iter()
                    .map(|r| bvh.closest_hit(r, 0.0, f32::INFINITY).map_or(0.0, |h| h.t))
                    .sum::<f32>()
            })
        });
        group.finish();
    }
}

criterion_group!(benches, geometry);
criterion_main!(benches);
