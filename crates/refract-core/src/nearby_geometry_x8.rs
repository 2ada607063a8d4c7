//! The nearby-geometry lookups of Wyman 2005b §4 ([`crate::nearby_geometry::find_nearby`]) for
//! eight refractor pixels at a time.
//!
//! A seeded lookup is a chain of about a dozen dependent NG-texel reads (the `K` seeds, then
//! the iteration), each a projection with a division and a read whose address the previous
//! read decided: one pixel at a time the CPU mostly waits for memory. Eight pixels per
//! instruction keep eight such chains in flight. Every lane performs the IEEE operations of
//! the scalar [`find_nearby`](crate::nearby_geometry::find_nearby) in the same order (the seed
//! parameters, the projections `c0 + t c1`, `1/w`, the texel floors, the depth errors and the
//! strict `<` that keeps the first best seed, the distance updates `‖S − P~2‖`), so each lane
//! returns the scalar result bit for bit; the tests hold it to that.

use glam::UVec2;

use crate::camera::Camera;
use crate::lanes::{F32x8, LANES, Mask, Vec3x8, mask_lanes};
use crate::nearby_geometry::{
    ClipRay, NearbyGeometryTexture, NearbyHit, NearbyLookup, NearbyResult, Plane, SeedSpacing,
    TexelLanes, nearest_plane_hit,
};
use crate::real::Vector3;

/// Eight rays in clip space.
type ClipRayLanes = ClipRay<Vec3x8>;

/// Eight lookups: the texel read and what it holds, in the lanes where it holds a surface.
struct Found {
    texel: TexelLanes<F32x8>,
    p_ws: Vec3x8,
    depth: F32x8,
    found: Mask,
}

/// The texture read at the texels under `rays` at `t`, in the lanes of `live`. (Always
/// inlined: returned through memory its result cost about a sixth of the lookups'
/// instructions.)
#[inline(always)]
fn lookup<T: NearbyGeometryTexture + ?Sized>(
    rays: &ClipRayLanes,
    texture: &T,
    t: F32x8,
    live: Mask,
) -> Found {
    let texel = rays.texel_lanes(t);
    let read = live & texel.inside;
    let s = texture.surfaces_x8(texel.x.trunc_int(), texel.y.trunc_int(), read);
    Found {
        texel,
        p_ws: s.p_ws,
        depth: s.depth,
        found: s.found & read,
    }
}

/// Per lane, a hit at `texel` with its surface `p_geom`.
#[inline]
fn hit(texel: &TexelLanes<F32x8>, p_geom: &Vec3x8, i: usize) -> NearbyHit {
    NearbyHit {
        texel: UVec2::new(texel.x.to_array()[i] as u32, texel.y.to_array()[i] as u32),
        p_geom: p_geom.lane(i),
    }
}

/// [`find_nearby`](crate::nearby_geometry::find_nearby) for the eight rays `p2 + t t2` (unit
/// `t2`) in the lanes of `active`; the other lanes come back [`NearbyResult::MISS`] and are
/// never read. Lane `i` is bit for bit the scalar `find_nearby(camera, texture, planes,
/// lookup, p2[i], t2[i])`.
pub fn find_nearby_x8<T: NearbyGeometryTexture + ?Sized>(
    camera: &Camera,
    texture: &T,
    planes: &[Plane],
    lookup: NearbyLookup,
    p2: &Vec3x8,
    t2: &Vec3x8,
    active: Mask,
) -> [NearbyResult; LANES] {
    let (p2_lanes, t2_lanes) = (p2.to_lanes(), t2.to_lanes());
    let scalar_rays: [ClipRay; LANES] =
        core::array::from_fn(|i| ClipRay::new(camera, p2_lanes[i], t2_lanes[i]));
    let rays = ClipRayLanes::from_rays(&scalar_rays, *p2, *t2);
    let active_lanes = mask_lanes(active);
    // Per lane the ray parameter the lookup starts from (or `None`: a miss).
    let plane_starts = || -> [Option<f32>; LANES] {
        core::array::from_fn(|i| {
            active_lanes[i]
                .then(|| nearest_plane_hit(planes, p2_lanes[i], t2_lanes[i]))
                .flatten()
        })
    };
    match lookup {
        NearbyLookup::KayGreenberg => single(&rays, texture, starts(&[Some(0.0); LANES], active)),
        NearbyLookup::RayPlane => single(&rays, texture, starts(&plane_starts(), active)),
        NearbyLookup::Iterative { iterations } => iterate(
            &rays,
            texture,
            p2,
            starts(&plane_starts(), active),
            iterations,
        ),
        NearbyLookup::Seeded {
            iterations,
            seeds,
            spacing,
        } => {
            let start = best_seed(&rays, texture, active, seeds, spacing);
            iterate(&rays, texture, p2, start, iterations)
        }
    }
}

/// Start parameters `t` as lanes, live where `t` is `Some` and `active`.
#[inline]
fn starts(t: &[Option<f32>; LANES], active: Mask) -> (F32x8, Mask) {
    let mut lanes = [0.0; LANES];
    let mut live = [false; LANES];
    for i in 0..LANES {
        if let Some(t) = t[i] {
            (lanes[i], live[i]) = (t, true);
        }
    }
    (
        F32x8::new(lanes),
        active & crate::lanes::mask_from_lanes(live),
    )
}

/// The seed search of §4.3 on lanes: over `k` seeds on each ray's segment inside the view,
/// the first with the smallest `|depth(p2 + t_i t2) − depth(S(t_i))|` among the non-empty
/// texels; live where some seed found a surface.
fn best_seed<T: NearbyGeometryTexture + ?Sized>(
    rays: &ClipRayLanes,
    texture: &T,
    active: Mask,
    k: u32,
    spacing: SeedSpacing,
) -> (F32x8, Mask) {
    let (starts_t, ends_t, live) = rays.segment_lanes(active);
    let mut best_error = F32x8::ZERO;
    let mut best_t = F32x8::ZERO;
    let mut has_best = F32x8::ZERO;
    for i in 0..k {
        let t = rays.seed_lanes((starts_t, ends_t), i, k, spacing);
        let read = lookup(rays, texture, t, live);
        let error = (rays.depth(t) - read.depth).abs();
        let take = read.found & (!has_best | error.simd_lt(best_error));
        best_error = take.select(error, best_error);
        best_t = take.select(t, best_t);
        has_best |= read.found;
    }
    (best_t, has_best)
}

/// One read per live lane at its start (Kay–Greenberg, ray-plane): a hit where the texel holds
/// a surface, `converged` with it, no iterations.
fn single<T: NearbyGeometryTexture + ?Sized>(
    rays: &ClipRayLanes,
    texture: &T,
    (t, live): (F32x8, Mask),
) -> [NearbyResult; LANES] {
    let read = lookup(rays, texture, t, live);
    let found = mask_lanes(read.found);
    core::array::from_fn(|i| {
        if found[i] {
            NearbyResult {
                hit: Some(hit(&read.texel, &read.p_ws, i)),
                iterations: 0,
                converged: true,
            }
        } else {
            NearbyResult::MISS
        }
    })
}

/// The distance-form iteration of §4.3 from `p2 + t t2` in the live lanes: `t ← ‖S(t) − p2‖`
/// until the texel repeats (converged), a read finds nothing (a miss) or after `iterations`.
fn iterate<T: NearbyGeometryTexture + ?Sized>(
    rays: &ClipRayLanes,
    texture: &T,
    p2: &Vec3x8,
    (t, live): (F32x8, Mask),
    iterations: u32,
) -> [NearbyResult; LANES] {
    let mut out = [NearbyResult::MISS; LANES];
    let first = lookup(rays, texture, t, live);
    let mut live = first.found;
    let (mut texel, mut p_ws) = (first.texel, first.p_ws);
    for k in 0..iterations {
        if !live.any() {
            return out;
        }
        let t = (p_ws - *p2).length();
        let next = lookup(rays, texture, t, live);
        let lost = mask_lanes(live & !next.found);
        let stay = live & next.found;
        let repeated = stay & next.texel.x.simd_eq(texel.x) & next.texel.y.simd_eq(texel.y);
        texel = TexelLanes {
            x: stay.select(next.texel.x, texel.x),
            y: stay.select(next.texel.y, texel.y),
            inside: texel.inside,
        };
        p_ws = Vec3x8::select(stay, next.p_ws, p_ws);
        let repeated_lanes = mask_lanes(repeated);
        for i in 0..LANES {
            if lost[i] {
                out[i].iterations = k + 1;
            } else if repeated_lanes[i] {
                out[i] = NearbyResult {
                    hit: Some(hit(&texel, &p_ws, i)),
                    iterations: k + 1,
                    converged: true,
                };
            }
        }
        live = stay & !repeated;
    }
    for (i, live) in mask_lanes(live).into_iter().enumerate() {
        if live {
            out[i] = NearbyResult {
                hit: Some(hit(&texel, &p_ws, i)),
                iterations,
                converged: false,
            };
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::camera::CameraDesc;
    use crate::lanes::mask_from_lanes;
    use crate::nearby_geometry::{NearbySurface, find_nearby, view_depth};

    /// An analytic NG texture: a wall `z = z_wall` seen by `camera`, empty outside
    /// `|x| < half` and on a checkerboard of holes (so reads find gaps mid-iteration).
    struct Wall<'a> {
        camera: &'a Camera,
        z_wall: f32,
        half: f32,
    }

    impl NearbyGeometryTexture for Wall<'_> {
        fn surface(&self, texel: UVec2) -> Option<NearbySurface> {
            let cell = texel.x / 8 + texel.y / 8;
            if cell.is_multiple_of(5) {
                return None;
            }
            // A band of texels whose depth is so far off that every seed's depth error
            // rounds to the same number: ties, which the first seed wins.
            let far = cell % 5 == 2;
            let ray = self
                .camera
                .pixel_ray(Camera::pixel_center(texel.x, texel.y));
            let t = (self.z_wall - ray.origin.z) / ray.dir.z;
            let p = ray.at(t);
            // A bumpy wall, so the iteration takes several steps.
            let p = p + Vec3::Z * (0.3 * (3.0 * p.x).sin() * (2.0 * p.y).cos());
            (t > 0.0 && p.x.abs() < self.half).then(|| NearbySurface {
                p_ws: p,
                depth: if far {
                    1e30
                } else {
                    view_depth(self.camera, p)
                },
            })
        }
    }

    fn camera(width: u32, height: u32) -> Camera {
        Camera::new(CameraDesc {
            width,
            height,
            eye: Vec3::new(0.0, 0.3, 3.0),
            target: Vec3::ZERO,
            near: 0.1,
            far: 12.0,
            ..CameraDesc::default()
        })
        .expect("camera")
    }

    /// Direction `i` of `n` on a golden-angle spiral over the sphere.
    fn spiral(i: usize, n: usize) -> Vec3 {
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = i as f32 * 2.399_963;
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    /// Each lane of `find_nearby_x8` is the scalar `find_nearby` bit for bit (hits, texels,
    /// positions, iteration counts, convergence), for every lookup and setting, over rays in
    /// every direction from points inside, beside and behind the view (hits, misses, empty
    /// texels mid-iteration, rays leaving the view), with lanes switched off.
    #[test]
    fn eight_lane_lookups_equal_the_scalar_lookups() {
        let lookups = [
            NearbyLookup::KayGreenberg,
            NearbyLookup::RayPlane,
            NearbyLookup::Iterative { iterations: 0 },
            NearbyLookup::Iterative { iterations: 5 },
            NearbyLookup::Seeded {
                iterations: 5,
                seeds: 7,
                spacing: SeedSpacing::Screen,
            },
            NearbyLookup::Seeded {
                iterations: 1,
                seeds: 3,
                spacing: SeedSpacing::World,
            },
            NearbyLookup::Seeded {
                iterations: 8,
                seeds: 16,
                spacing: SeedSpacing::Screen,
            },
        ];
        let origins = [
            Vec3::new(0.2, 0.0, 0.0),
            Vec3::new(-0.5, 0.4, 0.8),
            Vec3::new(2.5, -0.2, -1.0),
            Vec3::new(0.0, 0.0, 4.0),
        ];
        let mut counts = [0usize; 4];
        for (width, height) in [(128, 96), (37, 61)] {
            let cam = camera(width, height);
            let wall = Wall {
                camera: &cam,
                z_wall: -1.5,
                half: 1.2,
            };
            let planes = [
                Plane::through(Vec3::new(0.0, 0.0, -1.5), Vec3::Z),
                Plane::through(Vec3::new(0.0, -0.7, 0.0), Vec3::Y),
            ];
            for lookup in lookups {
                for &p2 in &origins {
                    let n = 400;
                    for group in 0..n / LANES {
                        let t2: [Vec3; LANES] =
                            core::array::from_fn(|i| spiral(group * LANES + i, n));
                        let active: [bool; LANES] = core::array::from_fn(|i| (group + i) % 7 != 3);
                        let lanes = find_nearby_x8(
                            &cam,
                            &wall,
                            &planes,
                            lookup,
                            &Vec3x8::splat(p2),
                            &Vec3x8::from_lanes(&t2),
                            mask_from_lanes(active),
                        );
                        for i in 0..LANES {
                            let scalar = if active[i] {
                                find_nearby(&cam, &wall, &planes, lookup, p2, t2[i])
                            } else {
                                NearbyResult::MISS
                            };
                            assert_eq!(
                                lanes[i], scalar,
                                "{lookup:?}, p2 {p2}, t2 {}, {width}×{height}",
                                t2[i]
                            );
                            if active[i] {
                                let kind = match scalar {
                                    NearbyResult { hit: None, .. } => 0,
                                    NearbyResult {
                                        converged: true, ..
                                    } => 1,
                                    NearbyResult { iterations: 0, .. } => 2,
                                    _ => 3,
                                };
                                counts[kind] += 1;
                            }
                        }
                    }
                }
            }
        }
        // Every outcome is exercised: misses, converged hits, unconverged hits without and
        // with iterations.
        assert!(counts.iter().all(|&c| c > 50), "{counts:?}");
    }

    /// The lane projection is the scalar `ClipRay::texel` bit for bit: inside or not, and the
    /// texel, at the ends of each ray's segment inside the view (on the near, far and side
    /// planes), between them, before and past them and behind the eye.
    #[test]
    fn lane_texels_equal_the_scalar_texels() {
        let cam = camera(64, 48);
        let mut inside = [0usize; 2];
        for origin in [Vec3::new(0.1, 0.2, 0.5), Vec3::new(0.0, 0.3, 3.0)] {
            for group in 0..100 {
                let dirs: [Vec3; LANES] = core::array::from_fn(|i| spiral(group * LANES + i, 800));
                let scalar: [ClipRay; LANES] =
                    core::array::from_fn(|i| ClipRay::new(&cam, origin, dirs[i]));
                let lanes = ClipRayLanes::from_rays(
                    &scalar,
                    Vec3x8::splat(origin),
                    Vec3x8::from_lanes(&dirs),
                );
                let segment = scalar.map(|r| r.segment().unwrap_or((0.0, 1.0)));
                for f in [-1.0, 0.0, 0.25, 0.5, 0.999, 1.0, 1.5, 100.0] {
                    let t: [f32; LANES] =
                        core::array::from_fn(|i| segment[i].0 + f * (segment[i].1 - segment[i].0));
                    let texels = lanes.texel_lanes(F32x8::new(t));
                    let (x, y) = (texels.x.to_array(), texels.y.to_array());
                    let lane_inside = mask_lanes(texels.inside);
                    for i in 0..LANES {
                        let expected = scalar[i].texel(t[i]);
                        let got = lane_inside[i].then(|| UVec2::new(x[i] as u32, y[i] as u32));
                        assert_eq!(got, expected, "ray {origin} + t {}, t = {}", dirs[i], t[i]);
                        inside[usize::from(got.is_some())] += 1;
                    }
                }
            }
        }
        assert!(inside.iter().all(|&n| n > 500), "{inside:?}");
    }

    /// The lane segments are the scalar `ClipRay::segment`s: the same lanes have one and the
    /// same ends, for rays in every direction, rays parallel to the frustum's planes (the axes
    /// seen by a camera looking down −z, the zero direction), and origins inside, outside and
    /// behind the view and not a number.
    #[test]
    fn lane_segments_equal_the_scalar_segments() {
        let axis_camera = Camera::new(CameraDesc {
            width: 64,
            height: 64,
            eye: Vec3::new(0.0, 0.0, 3.0),
            target: Vec3::ZERO,
            near: 0.1,
            far: 12.0,
            ..CameraDesc::default()
        })
        .expect("camera");
        let axes = [
            Vec3::X,
            -Vec3::X,
            Vec3::Y,
            -Vec3::Y,
            Vec3::Z,
            -Vec3::Z,
            Vec3::ZERO,
        ];
        let mut found = [0usize; 2];
        for cam in [camera(64, 48), axis_camera] {
            for origin in [
                Vec3::new(0.1, 0.2, 0.5),
                Vec3::new(0.0, 0.0, 3.0),
                Vec3::new(30.0, 0.0, 0.0),
                Vec3::new(0.0, 0.0, 20.0),
                Vec3::new(f32::NAN, 0.0, 0.0),
            ] {
                for group in 0..60 {
                    let dirs: [Vec3; LANES] = core::array::from_fn(|i| {
                        let k = group * LANES + i;
                        if k.is_multiple_of(5) {
                            axes[k / 5 % axes.len()]
                        } else {
                            spiral(k, 480)
                        }
                    });
                    let scalar: [ClipRay; LANES] =
                        core::array::from_fn(|i| ClipRay::new(&cam, origin, dirs[i]));
                    let (t0, t1, ok) = ClipRayLanes::from_rays(
                        &scalar,
                        Vec3x8::splat(origin),
                        Vec3x8::from_lanes(&dirs),
                    )
                    .segment_lanes(F32x8::splat(f32::from_bits(u32::MAX)));
                    let (t0, t1, ok) = (t0.to_array(), t1.to_array(), mask_lanes(ok));
                    for i in 0..LANES {
                        let lanes = ok[i].then_some((t0[i], t1[i]));
                        let expected = scalar[i].segment();
                        assert_eq!(
                            lanes.map(|(a, b)| (a.to_bits(), b.to_bits())),
                            expected.map(|(a, b)| (a.to_bits(), b.to_bits())),
                            "ray {origin} + t {}",
                            dirs[i]
                        );
                        found[usize::from(ok[i])] += 1;
                    }
                }
            }
        }
        assert!(found.iter().all(|&n| n > 300), "{found:?}");
    }
}
