//! refract-core's per-pixel kernels over precomputed buffers of an analytic sphere (1024²):
//! the cost of the math alone, without rasterisation; the `pvrr` map lookup; and the
//! distance-map search over
//! analytic layers, and its cube-map texel location.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use refract_core::kernel::{one_interface, two_interface};
use refract_core::kernel_x8::{FrontLanes, one_interface_lanes, two_interface_lanes};
use refract_core::{
    BackFaceSample, BackFaceSampler, Camera, CameraDesc, DistanceMode, FrontSurface,
    ImageSpaceParams, TirPolicy,
};

const RES: u32 = 1024;

/// A back-face buffer sampled at the nearest texel.
struct Buffer {
    width: u32,
    height: u32,
    texels: Vec<Option<BackFaceSample>>,
}

impl BackFaceSampler for Buffer {
    fn back_face(&self, uv_px: Vec2) -> Option<BackFaceSample> {
        if !(uv_px.x >= 0.0 && uv_px.y >= 0.0) {
            return None;
        }
        let (x, y) = (uv_px.x as u32, uv_px.y as u32);
        if x >= self.width || y >= self.height {
            return None;
        }
        self.texels[(y * self.width + x) as usize]
    }
}

fn sphere_buffers(camera: &Camera) -> (Vec<Option<FrontSurface>>, Buffer) {
    let (mut front, mut back) = (Vec::new(), Vec::new());
    for y in 0..camera.height() {
        for x in 0..camera.width() {
            let ray = camera.pixel_ray(Camera::pixel_center(x, y));
            let b = ray.origin.dot(ray.dir);
            let disc = b * b - (ray.origin.length_squared() - 1.0);
            if disc < 0.0 {
                front.push(None);
                back.push(None);
                continue;
            }
            let (near, far) = (-b - disc.sqrt(), -b + disc.sqrt());
            let p1 = ray.at(near);
            front.push(Some(FrontSurface {
                p1_ws: p1,
                n1_ws: p1,
                d_n: 2.0,
            }));
            back.push(Some(BackFaceSample {
                n_ws: ray.at(far),
                distance: far,
            }));
        }
    }
    (
        front,
        Buffer {
            width: camera.width(),
            height: camera.height(),
            texels: back,
        },
    )
}

fn kernels(c: &mut Criterion) {
    let camera = Camera::new(CameraDesc {
        width: RES,
        height: RES,
        ..CameraDesc::default()
    })
    .expect("camera");
    let (front, back) = sphere_buffers(&camera);
    let params = ImageSpaceParams::new(1.5, DistanceMode::Interpolated, TirPolicy::ClampToCritical)
        .expect("params");
    let pixels: Vec<(Vec2, FrontSurface)> = front
        .iter()
        .enumerate()
        .filter_map(|(i, f)| f.map(|f| (Camera::pixel_center(i as u32 % RES, i as u32 / RES), f)))
        .collect();
    // Correctness before timing: the centre pixel goes straight through.
    let centre = Camera::pixel_center(RES / 2, RES / 2);
    let centre_front = front[(RES / 2 * RES + RES / 2) as usize].expect("sphere covers the centre");
    let path = two_interface(&camera, centre, &centre_front, &back, &params).expect("path");
    assert!(path.t2.angle_between(path.entry.view) < 1e-2);

    let mut group = c.benchmark_group("core_kernel/sphere_1024");
    group.throughput(Throughput::Elements(pixels.len() as u64));
    group.bench_function("two_interface", |b| {
        b.iter(|| {
            pixels
                .par_iter()
                .map(|(uv, f)| {
                    two_interface(&camera, *uv, f, &back, &params).map_or(0.0, |p| p.t2.x)
                })
                .sum::<f32>()
        })
    });
    group.bench_function("one_interface", |b| {
        b.iter(|| {
            pixels
                .par_iter()
                .map(|(_, f)| one_interface(&camera, black_box(f), &params).map_or(0.0, |p| p.t1.x))
                .sum::<f32>()
        })
    });
    // The lane twins, eight pixels per call (the CPU backend's path).
    let groups: Vec<([Vec2; 8], FrontLanes)> = pixels
        .chunks_exact(8)
        .map(|chunk| {
            let front: [FrontSurface; 8] = core::array::from_fn(|i| chunk[i].1);
            (
                core::array::from_fn(|i| chunk[i].0),
                FrontLanes::from_surfaces(&front),
            )
        })
        .collect();
    let (uv, f) = &groups[groups.len() / 2];
    let lanes = two_interface_lanes(&camera, uv, f, &back, &params);
    for (i, &uv_px) in uv.iter().enumerate() {
        let scalar = two_interface(&camera, uv_px, &f.surface(i), &back, &params);
        assert_eq!(lanes.ok[i], scalar.is_ok());
        assert_eq!(lanes.t2.lane(i), scalar.map_or(Vec3::ZERO, |p| p.t2));
    }
    group.throughput(Throughput::Elements(8 * groups.len() as u64));
    group.bench_function("two_interface_lanes", |b| {
        b.iter(|| {
            groups
                .par_iter()
                .map(|(uv, f)| {
                    let lanes = two_interface_lanes(&camera, uv, f, &back, &params);
                    lanes.t2.to_lanes().iter().map(|t2| t2.x).sum::<f32>()
                })
                .sum::<f32>()
        })
    });
    group.bench_function("one_interface_lanes", |b| {
        b.iter(|| {
            groups
                .par_iter()
                .map(|(_, f)| {
                    one_interface_lanes(&camera, black_box(f), &params)
                        .iter()
                        .map(|p| p.as_ref().map_or(0.0, |p| p.t1.x))
                        .sum::<f32>()
                })
                .sum::<f32>()
        })
    });
    group.finish();
}

/// The distance-map search alone (`refract_core::distance_map::hit`, Listing 17-1 on eight
/// lanes and the secant steps) over the analytic room's 512² layers: 64k rays from points
/// inside the mirror sphere's shell in directions spread over the sphere, with and without
/// min-max.
fn distance_search(c: &mut Criterion) {
    use glam::Vec3;
    use refract_core::distance_map::{AnalyticRoom, SearchParams, hit};
    let layers = AnalyticRoom { size: 512 };
    let rays: Vec<(Vec3, Vec3)> = (0..65_536u32)
        .map(|k| {
            let z = (k as f32 + 0.5) / 65_536.0 * 2.0 - 1.0;
            let phi = k as f32 * 2.399_963;
            let r = Vec3::new(
                (1.0 - z * z).sqrt() * phi.cos(),
                z,
                (1.0 - z * z).sqrt() * phi.sin(),
            );
            (Vec3::new(0.3, -0.2, 0.5), r)
        })
        .collect();
    let mut group = c.benchmark_group("core/distance_search");
    group.sample_size(10);
    group.throughput(Throughput::Elements(rays.len() as u64));
    for min_max in [false, true] {
        let params = SearchParams {
            min_max,
            ..SearchParams::default()
        };
        // Correctness before timing: every ray meets the room's walls.
        assert!(
            rays.iter()
                .all(|(x, r)| hit(&layers, *x, *r, None, &params).0.is_some())
        );
        group.bench_function(format!("hit/minmax={min_max}"), |b| {
            b.iter(|| {
                rays.par_iter()
                    .map(|(x, r)| {
                        hit(&layers, black_box(*x), *r, None, &params)
                            .1
                            .linear_steps
                    })
                    .sum::<u32>()
            })
        });
    }
    group.finish();
}

/// Locating the linear search's samples in a cube map: `cube_texel` + `cube_texel_index` one
/// direction at a time against `cube_texel_indices_x8`, eight (the same texels), over 1M
/// directions spread over every face, one thread.
fn cube_texels(c: &mut Criterion) {
    use glam::Vec3;
    use refract_core::distance_map::{cube_texel, cube_texel_index, cube_texel_indices_x8};
    use refract_core::lanes::{LANES, Vec3x8};
    const SIZE: u32 = 512;
    let dirs: Vec<Vec3> = (0..1u32 << 20)
        .map(|k| {
            let z = (k as f32 + 0.5) / (1u32 << 20) as f32 * 2.0 - 1.0;
            let phi = k as f32 * 2.399_963;
            let s = (1.0 - z * z).sqrt();
            Vec3::new(s * phi.cos(), z, s * phi.sin())
        })
        .collect();
    let lanes: Vec<Vec3x8> = dirs
        .chunks_exact(LANES)
        .map(|d| Vec3x8::from_lanes(d.try_into().expect("eight")))
        .collect();
    let mut group = c.benchmark_group("core/cube_texels");
    group.throughput(Throughput::Elements(dirs.len() as u64));
    group.bench_function("scalar", |b| {
        b.iter(|| {
            dirs.iter()
                .filter_map(|d| cube_texel(black_box(*d), SIZE))
                .map(|(f, t)| cube_texel_index(f, t, SIZE))
                .fold(0u32, u32::wrapping_add)
        })
    });
    group.bench_function("x8", |b| {
        b.iter(|| {
            lanes
                .iter()
                .flat_map(|d| cube_texel_indices_x8(black_box(*d), SIZE))
                .flatten()
                .fold(0u32, u32::wrapping_add)
        })
    });
    group.finish();
}

/// The `pvrr` map lookup alone (`refract_core::pvrr::lookup`, one pixel at a time, and
/// `lookup_x8`, eight): a 1024 × 1024 map read bilinearly at the positions a convex mirror's
/// 512 × 512 pixels would read, a smooth magnified warp of the map (each map row read along a
/// curve), as the eye view of `convex-mirror` does; one thread, the CPU backend's map type.
fn pvrr_lookup(c: &mut Criterion) {
    use glam::{Vec2, Vec3};
    use refract_core::lanes::{LANES, Vec2x8, Vec3x8};
    use refract_core::pvrr::{lookup, lookup_x8};
    use refract_cpu::pvrr::Image;
    let map = Image {
        width: 1024,
        height: 1024,
        texels: (0..1024 * 1024)
            .map(|i| Vec3::new((i % 1024) as f32, (i / 1024) as f32, 1.0))
            .collect(),
    };
    let side = 512;
    let positions: Vec<Vec2> = (0..side * side)
        .map(|i| {
            let (u, v) = (
                (i % side) as f32 / side as f32,
                (i / side) as f32 / side as f32,
            );
            let (du, dv) = (u - 0.5, v - 0.5);
            let bulge = 1.0 - 0.6 * (du * du + dv * dv);
            Vec2::new(
                512.0 + 1000.0 * du * bulge,
                512.0 + 1000.0 * dv * bulge + 80.0 * du * du,
            )
        })
        .collect();
    let mut group = c.benchmark_group("core/pvrr_lookup");
    group.sample_size(10);
    group.throughput(Throughput::Elements(positions.len() as u64));
    group.bench_function("lookup", |b| {
        b.iter(|| {
            positions
                .iter()
                .map(|st| lookup(&map, [black_box(*st); 3], Vec3::ONE).x)
                .sum::<f32>()
        })
    });
    group.bench_function("lookup_x8", |b| {
        b.iter(|| {
            positions
                .chunks_exact(LANES)
                .map(|st| {
                    let st = Vec2x8::from_lanes(black_box(st.try_into().expect("eight")));
                    let tint = Vec3x8::splat(Vec3::ONE);
                    lookup_x8(&map, [st; 3], tint).x.reduce_add()
                })
                .sum::<f32>()
        })
    });
    group.finish();
}

criterion_group!(benches, kernels, distance_search, cube_texels, pvrr_lookup);
criterion_main!(benches);
