//! The lane twin of [`crate::kernel`]: [`one_interface`] and [`two_interface`] for eight
//! pixels at once, the same formulas on eight SIMD lanes ([`crate::lanes`]).
//!
//! Both kernels call the same leaves ([`crate::optics`], [`crate::exit`],
//! [`crate::interpolated_distance`], [`crate::vector`]), written once over [`crate::real`]; only
//! the control flow differs (masks here, early returns there). Every lane computes exactly the
//! bits the scalar kernel computes for that pixel (the tests below compare them bit for bit on
//! random inputs). The rare cases (a degenerate input, total internal reflection at the entry
//! point, a non-finite result) are handed to the scalar kernel. Back-face lookups go through
//! [`BackFaceSampler::back_faces_x8`].

use glam::{Vec2, Vec3};

use crate::camera::Camera;
use crate::exit::{ExitNormalSource, exit_normal_outside_silhouette, refract_exit};
use crate::interpolated_distance::{
    approximate_distance, exit_point, incidence_angle, transmission_angle,
};
use crate::kernel::{
    BackFaceSampler, DegenerateInput, FrontSurface, ImageSpaceParams, OneInterfacePath,
    one_interface, two_interface,
};
use crate::lanes::{F32x8, LANES, Mask, Vec2x8, Vec3x8, mask_lanes};
use crate::optics::{face_forward_shading_normal, refract};
use crate::real::Vector3;
use crate::vector::{robust_normalize_masked, robust_normalize_where};

/// Eight front surfaces as lanes (structure of arrays): `P1`, `N1` and `d_N` of each pixel,
/// as a rasteriser that resolves eight texels at once produces them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrontLanes {
    /// `P1`, world space.
    pub p1_ws: Vec3x8,
    /// `N1` (any length; normalised by the kernel).
    pub n1_ws: Vec3x8,
    /// `d_N`.
    pub d_n: F32x8,
}

impl FrontLanes {
    /// The surfaces of eight pixels as lanes (plain loops: `array::map` and `from_fn` are not
    /// always inlined, and this runs per pixel).
    #[inline]
    pub fn from_surfaces(front: &[FrontSurface; LANES]) -> Self {
        let (mut p1, mut n1, mut d_n) = ([Vec3::ZERO; LANES], [Vec3::ZERO; LANES], [0.0; LANES]);
        for (i, f) in front.iter().enumerate() {
            (p1[i], n1[i], d_n[i]) = (f.p1_ws, f.n1_ws, f.d_n);
        }
        Self {
            p1_ws: Vec3x8::from_lanes(&p1),
            n1_ws: Vec3x8::from_lanes(&n1),
            d_n: F32x8::new(d_n),
        }
    }

    /// The surface of lane `i` (`i < LANES`).
    pub fn surface(&self, i: usize) -> FrontSurface {
        FrontSurface {
            p1_ws: self.p1_ws.lane(i),
            n1_ws: self.n1_ws.lane(i),
            d_n: self.d_n.to_array()[i],
        }
    }
}

/// Every lane set.
const ALL_LANES: Mask = F32x8::splat(f32::from_bits(u32::MAX));

/// The entry refraction of eight pixels: view, shading normal, `T1`, and the lanes the scalar
/// kernel must take (degenerate inputs, TIR at the entry).
struct Entry {
    view: Vec3x8,
    n1: Vec3x8,
    t1: Vec3x8,
    scalar: Mask,
}

/// The scalar kernel's `entry_frame` and entry refraction, on lanes, through the same leaves.
#[inline]
fn entry(camera: &Camera, p1: Vec3x8, n1: Vec3x8, eta: F32x8) -> Entry {
    let (view, view_ok) = robust_normalize_masked(p1 - Vec3x8::splat(camera.eye()));
    let (n1, n1_ok) = robust_normalize_masked(n1);
    let n1 = face_forward_shading_normal(n1, view);
    let refracted = refract(view, n1, eta);
    let tir_entry = refracted.is_zero();
    let (t1, t1_ok) = robust_normalize_where(refracted, !tir_entry);
    Entry {
        view,
        n1,
        t1,
        scalar: !(view_ok & n1_ok & t1_ok) | tir_entry,
    }
}

/// [`one_interface`] for eight pixels (the CPU backend's per-pixel path): lane `i` is
/// `one_interface(camera, &front.surface(i), params)`, bit for bit.
///
/// ```
/// use glam::Vec3;
/// use refract_core::kernel::{FrontSurface, ImageSpaceParams, one_interface};
/// use refract_core::kernel_x8::{FrontLanes, one_interface_lanes};
/// use refract_core::{Camera, CameraDesc, DistanceMode, TirPolicy};
/// let camera = Camera::new(CameraDesc::default())?;
/// let params = ImageSpaceParams::new(1.33, DistanceMode::Interpolated, TirPolicy::default())?;
/// let front: [FrontSurface; 8] = core::array::from_fn(|i| FrontSurface {
///     p1_ws: Vec3::new(0.1 * i as f32, 0.0, 1.0),
///     n1_ws: Vec3::new(0.05 * i as f32, 0.0, 1.0),
///     d_n: 1.0,
/// });
/// let lanes = one_interface_lanes(&camera, &FrontLanes::from_surfaces(&front), &params);
/// for (lane, surface) in lanes.iter().zip(&front) {
///     let scalar = one_interface(&camera, surface, &params);
///     assert_eq!(format!("{lane:?}"), format!("{scalar:?}"));
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn one_interface_lanes(
    camera: &Camera,
    front: &FrontLanes,
    params: &ImageSpaceParams,
) -> [Result<OneInterfacePath, DegenerateInput>; LANES] {
    let e = entry(
        camera,
        front.p1_ws,
        front.n1_ws,
        F32x8::splat(params.eta_in()),
    );
    let scalar = mask_lanes(e.scalar);
    let (view, n1, t1) = (e.view.to_lanes(), e.n1.to_lanes(), e.t1.to_lanes());
    let mut paths = [Err(DegenerateInput::NonFiniteResult); LANES];
    for (i, path) in paths.iter_mut().enumerate() {
        *path = if scalar[i] {
            one_interface(camera, &front.surface(i), params)
        } else {
            Ok(OneInterfacePath {
                view: view[i],
                n1: n1[i],
                t1: t1[i],
                tir_entry: false,
            })
        };
    }
    paths
}

/// What a renderer needs of eight two-interface paths, as lanes (the CPU backend's per-pixel
/// path). Lane `i` holds the values of `two_interface(camera, uv_px[i], &front.surface(i), back,
/// params)`, bit for bit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoInterfaceLanes {
    /// The lanes with a path (`Ok`); the others reported a [`DegenerateInput`] and their
    /// values are zero.
    pub ok: [bool; LANES],
    /// `d~`, the approximate distance from `P1` to `P~2`.
    pub d_tilde: F32x8,
    /// `T2` (zero where the TIR policy absorbed the ray).
    pub t2: Vec3x8,
    /// `P~2`.
    pub p2: Vec3x8,
    /// `N2`.
    pub n2: Vec3x8,
    /// `N2` came from the back faces (else the silhouette fallback).
    pub n2_from_back_face: [bool; LANES],
    /// Total internal reflection at the entry or the exit.
    pub tir: [bool; LANES],
}

/// [`two_interface`] for eight pixels, as [`TwoInterfaceLanes`].
///
/// # Example
///
/// Eight pixels of a slab facing the camera, each lane bit for bit the scalar kernel's:
///
/// ```
/// use glam::{Vec2, Vec3};
/// use refract_core::kernel::{
///     BackFaceSample, BackFaceSampler, FrontSurface, ImageSpaceParams, two_interface,
/// };
/// use refract_core::kernel_x8::{FrontLanes, two_interface_lanes};
/// use refract_core::{Camera, CameraDesc, DistanceMode, TirPolicy};
///
/// /// The slab's back face, the plane z = −0.2, seen through every pixel.
/// struct SlabBack(Camera);
/// impl BackFaceSampler for SlabBack {
///     fn back_face(&self, uv_px: Vec2) -> Option<BackFaceSample> {
///         let ray = self.0.pixel_ray(uv_px);
///         let t = (-0.2 - ray.origin.z) / ray.dir.z;
///         Some(BackFaceSample { n_ws: Vec3::NEG_Z, distance: t })
///     }
/// }
///
/// let camera = Camera::new(CameraDesc { width: 16, height: 16, ..CameraDesc::default() })?;
/// let params = ImageSpaceParams::new(1.5, DistanceMode::Interpolated, TirPolicy::default())?;
/// let uv: [Vec2; 8] = core::array::from_fn(|i| Camera::pixel_center(4 + i as u32, 8));
/// let front: [FrontSurface; 8] = core::array::from_fn(|i| {
///     let ray = camera.pixel_ray(uv[i]);
///     let t = (0.2 - ray.origin.z) / ray.dir.z; // the front face, z = 0.2
///     FrontSurface { p1_ws: ray.at(t), n1_ws: Vec3::Z, d_n: 0.4 }
/// });
/// let back = SlabBack(camera);
/// let lanes = two_interface_lanes(&camera, &uv, &FrontLanes::from_surfaces(&front), &back, &params);
/// let (t2, p2) = (lanes.t2.to_lanes(), lanes.p2.to_lanes());
/// for i in 0..8 {
///     let scalar = two_interface(&camera, uv[i], &front[i], &back, &params)?;
///     assert!(lanes.ok[i]);
///     assert_eq!((t2[i], p2[i]), (scalar.t2, scalar.p2));
///     // Parallel faces: the ray leaves in the direction it came.
///     assert!((scalar.t2 - camera.pixel_ray(uv[i]).dir).length() < 1e-5);
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn two_interface_lanes<S: BackFaceSampler + ?Sized>(
    camera: &Camera,
    uv_px: &[Vec2; LANES],
    front: &FrontLanes,
    back: &S,
    params: &ImageSpaceParams,
) -> TwoInterfaceLanes {
    let FrontLanes {
        p1_ws: p1,
        n1_ws: n1,
        d_n,
    } = *front;
    let eta = F32x8::splat(params.eta_in());
    let e = entry(camera, p1, n1, eta);
    let d_n_ok = d_n.simd_ge(F32x8::ZERO) & d_n.is_finite();

    // d_V at P1's own pixel (Wyman 2005a §3.1), `‖P1 − eye‖` as `Camera::distance_from_eye`.
    let own = back.back_faces_x8(Vec2x8::from_lanes(uv_px), ALL_LANES);
    let d_v = own.distance - (p1 - Vec3x8::splat(camera.eye())).length();
    let d_v_ok = own.found & d_v.simd_ge(F32x8::ZERO) & d_v.is_finite();

    let theta_i = incidence_angle(e.view, e.n1);
    let theta_t = transmission_angle(e.t1, e.n1);
    let d_v_or_n = d_v_ok.select(d_v, d_n);
    let d_tilde = approximate_distance(params.distance_mode, theta_i, theta_t, eta, d_v_or_n, d_n);
    let p2 = exit_point(p1, e.t1, d_tilde);

    // N2 from the back faces at P~2's pixel (§3.2), else the silhouette fallback (§3.3).
    let (px, py, in_front) = camera.world_to_pixel_xy(p2);
    let far = back.back_faces_x8(Vec2x8 { x: px, y: py }, in_front);
    // Empty lanes are replaced by the fallback.
    let (sampled_n2, normal_ok) = robust_normalize_where(far.n_ws, far.found);
    let sampled = far.found & normal_ok;
    let n2 = if sampled.all() {
        sampled_n2
    } else {
        let fallback = exit_normal_outside_silhouette(e.t1, Vec3x8::splat(camera.look_dir()));
        Vec3x8::select(sampled, sampled_n2, fallback)
    };

    let exit = refract_exit(e.t1, n2, F32x8::splat(params.ior()), params.tir_policy);
    let finite = p2.is_finite() & d_tilde.is_finite() & exit.t2.is_finite();
    let mut lanes = TwoInterfaceLanes {
        ok: [true; LANES],
        d_tilde,
        t2: exit.t2,
        p2,
        n2,
        n2_from_back_face: mask_lanes(sampled),
        tir: mask_lanes(exit.tir),
    };
    let scalar = mask_lanes(e.scalar | !d_n_ok | !finite);
    if scalar.contains(&true) {
        // The rare lanes (degenerate inputs, TIR at the entry, non-finite results), from the
        // scalar kernel.
        let mut d_tilde = d_tilde.to_array();
        let (mut t2, mut p2, mut n2) = (exit.t2.to_lanes(), p2.to_lanes(), n2.to_lanes());
        for i in (0..LANES).filter(|&i| scalar[i]) {
            let path = two_interface(camera, uv_px[i], &front.surface(i), back, params);
            lanes.ok[i] = path.is_ok();
            let Ok(path) = path else {
                (d_tilde[i], t2[i], p2[i], n2[i]) = (0.0, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
                (lanes.n2_from_back_face[i], lanes.tir[i]) = (false, false);
                continue;
            };
            (d_tilde[i], t2[i], p2[i], n2[i]) = (path.d_tilde, path.t2, path.p2, path.n2);
            lanes.n2_from_back_face[i] = path.n2_source == ExitNormalSource::BackFace;
            lanes.tir[i] = path.tir_exit || path.entry.tir_entry;
        }
        lanes.d_tilde = F32x8::new(d_tilde);
        (lanes.t2, lanes.p2, lanes.n2) = (
            Vec3x8::from_lanes(&t2),
            Vec3x8::from_lanes(&p2),
            Vec3x8::from_lanes(&n2),
        );
    }
    lanes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraDesc;
    use crate::exit::TirPolicy;
    use crate::interpolated_distance::DistanceMode;
    use crate::kernel::BackFaceSample;

    /// A back-face buffer made of a smooth analytic field, so that lookups vary per pixel
    /// and miss outside a disc (silhouette fallbacks) as real buffers do.
    struct Field;

    impl BackFaceSampler for Field {
        fn back_face(&self, uv: Vec2) -> Option<BackFaceSample> {
            let d = (uv - Vec2::splat(48.0)) / 40.0;
            if d.length_squared() > 1.0 {
                return None;
            }
            let n_ws = Vec3::new(d.x, -d.y, -0.8 - 0.1 * d.x * d.y);
            let distance = 6.0 + 0.5 * d.length_squared();
            // Scattered texels the normalisation and the d_V filter must treat apart: normals
            // too short or too long for the one-division path, zero normals, back faces in
            // front of the front surface (a negative d_V).
            let (n_ws, distance) = match (uv.x as u32 + 7 * uv.y as u32) % 23 {
                0 => (n_ws * 1e-20, distance),
                1 => (n_ws * 1e20, distance),
                2 => (Vec3::ZERO, distance),
                3 => (n_ws, 2.0),
                _ => (n_ws, distance),
            };
            Some(BackFaceSample { n_ws, distance })
        }
    }

    /// A tiny deterministic generator (no dependency for unit tests).
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((self.0 >> 40) as f32) / (1u64 << 24) as f32
        }
        fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.next()
        }
    }

    fn camera() -> Camera {
        Camera::new(CameraDesc {
            width: 96,
            height: 96,
            ..CameraDesc::default()
        })
        .expect("camera")
    }

    #[test]
    fn lanes_equal_the_scalar_kernel_bit_for_bit() {
        let camera = camera();
        let mut rng = Lcg(7);
        let (mut lanes_checked, mut scalar_lanes) = (0, 0);
        for (ior, mode, policy) in [
            (1.5, DistanceMode::Interpolated, TirPolicy::ClampToCritical),
            (1.33, DistanceMode::ViewOnly, TirPolicy::ReflectOnce),
            (2.4, DistanceMode::NormalOnly, TirPolicy::Black),
            (0.7, DistanceMode::Interpolated, TirPolicy::ReflectOnce),
        ] {
            let params = ImageSpaceParams::new(ior, mode, policy).expect("params");
            for _ in 0..400 {
                let uv: [Vec2; LANES] =
                    core::array::from_fn(|_| Vec2::new(rng.range(0.0, 96.0), rng.range(0.0, 96.0)));
                let front: [FrontSurface; LANES] = core::array::from_fn(|i| {
                    // Points on a unit sphere seen through each pixel, with perturbed,
                    // unnormalised normals; a few degenerate inputs.
                    let ray = camera.pixel_ray(uv[i]);
                    let p1 = ray.at(rng.range(3.5, 4.5));
                    let mut n1 =
                        (p1 + Vec3::new(rng.range(-0.5, 0.5), 0.0, 0.3)) * rng.range(0.5, 1.5);
                    let mut d_n = rng.range(0.0, 2.0);
                    match (rng.next() * 40.0) as u32 {
                        0 => n1 = Vec3::ZERO,
                        1 => d_n = -1.0,
                        2 => n1 = -n1, // back-facing: turned by face-forward
                        3 => n1 = n1.normalize(),
                        _ => {}
                    }
                    FrontSurface {
                        p1_ws: p1,
                        n1_ws: n1,
                        d_n,
                    }
                });
                let lean = two_interface_lanes(
                    &camera,
                    &uv,
                    &FrontLanes::from_surfaces(&front),
                    &Field,
                    &params,
                );
                let (t2, p2, n2) = (lean.t2.to_lanes(), lean.p2.to_lanes(), lean.n2.to_lanes());
                let d_tilde = lean.d_tilde.to_array();
                let single =
                    one_interface_lanes(&camera, &FrontLanes::from_surfaces(&front), &params);
                for i in 0..LANES {
                    let scalar = two_interface(&camera, uv[i], &front[i], &Field, &params);
                    assert_eq!(lean.ok[i], scalar.is_ok(), "lane {i}, {params:?}");
                    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                    match &scalar {
                        Ok(path) => {
                            assert_eq!(d_tilde[i].to_bits(), path.d_tilde.to_bits());
                            assert_eq!(bits(t2[i]), bits(path.t2));
                            assert_eq!(bits(p2[i]), bits(path.p2));
                            assert_eq!(bits(n2[i]), bits(path.n2));
                            assert_eq!(
                                lean.n2_from_back_face[i],
                                path.n2_source == ExitNormalSource::BackFace
                            );
                            assert_eq!(lean.tir[i], path.tir_exit || path.entry.tir_entry);
                        }
                        Err(_) => {
                            assert_eq!((t2[i], p2[i], n2[i]), (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO));
                            assert!(!lean.n2_from_back_face[i] && !lean.tir[i]);
                        }
                    }
                    let scalar = one_interface(&camera, &front[i], &params);
                    assert_eq!(
                        format!("{:?}", single[i]),
                        format!("{scalar:?}"),
                        "one_interface lane {i}"
                    );
                    lanes_checked += 1;
                    scalar_lanes += usize::from(!lean.ok[i]);
                }
            }
        }
        // The paths taken must include errors and successes of every kind.
        assert!(scalar_lanes > 100 && scalar_lanes < lanes_checked / 2);
    }
}
