//! The lane twin of [`crate::kernel`]: [`one_interface`] and [`two_interface`] for eight
//! pixels at once, the same formulas on eight SIMD lanes ([`crate::lanes`]).
//!
//! Every lane computes exactly the bits the scalar kernel computes for that pixel (the tests
//! below compare them bit for bit on random inputs). The rare cases (a degenerate input, a
//! vector too long or too short for the one-division normalisation, total internal reflection
//! at the entry point, a non-finite result) are not written twice: those lanes are handed to
//! the scalar kernel. Back-face lookups are made lane by lane through the same
//! [`BackFaceSampler`].

use glam::{Vec2, Vec3};

use crate::camera::Camera;
use crate::exit::{ExitNormalSource, TirPolicy};
use crate::interpolated_distance::{DistanceMode, NORMAL_INCIDENCE_ANGLE};
use crate::kernel::{
    BackFaceSampler, DegenerateInput, FrontSurface, ImageSpaceParams, OneInterfacePath,
    TwoInterfacePath, one_interface, two_interface,
};
use crate::lanes::{F32x8, LANES, Mask, Vec2x8, Vec3x8, atan2, le, lt, mask_lanes};
use crate::optics::FACE_FORWARD_EPSILON;
use crate::vector::{UNIT_TOLERANCE, robust_normalize};

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

/// [`robust_normalize`]'s two common paths (already unit: `v`; otherwise `v · (1/√(v·v))`) and
/// the lanes they cover; the other lanes need the scaled path of the scalar function.
#[inline]
fn normalize_common(v: Vec3x8) -> (Vec3x8, Mask) {
    let length_squared = v.dot(v);
    let unit = (length_squared - F32x8::ONE)
        .abs()
        .simd_le(F32x8::splat(UNIT_TOLERANCE));
    // Most groups are all unit already (normals from the rasteriser, Snell's `T`): the square
    // root and division are only spent when some lane needs them.
    if unit.all() {
        return (v, unit);
    }
    let in_range = le(F32x8::splat(1e-30), length_squared) & le(length_squared, F32x8::MAX);
    let scaled = v * (F32x8::ONE / length_squared.sqrt());
    (Vec3x8::select(unit, v, scaled), unit | in_range)
}

/// [`crate::optics::face_forward_shading_normal`].
#[inline]
fn face_forward(normal: Vec3x8, incident: Vec3x8) -> Vec3x8 {
    let n_dot_i = normal.dot(incident);
    let facing = lt(n_dot_i, F32x8::ZERO);
    if facing.all() {
        return normal; // the common case: no lane needs turning
    }
    let (turned, ok) =
        (normal - (n_dot_i + F32x8::splat(FACE_FORWARD_EPSILON)) * incident).try_normalize();
    let turned = Vec3x8::select(ok, turned, -incident);
    Vec3x8::select(facing, normal, turned)
}

/// [`crate::optics::refract`]: the zero vector where `k < 0`.
#[inline]
pub(crate) fn refract(incident: Vec3x8, normal: Vec3x8, eta: F32x8) -> Vec3x8 {
    let n_dot_i = normal.dot(incident);
    let eta2 = eta * eta;
    let k = (F32x8::ONE - eta2) + eta2 * n_dot_i * n_dot_i;
    let t = eta * incident - (eta * n_dot_i + k.sqrt()) * normal;
    Vec3x8::select(lt(k, F32x8::ZERO), Vec3x8::ZERO, t)
}

/// [`crate::vector::angle_between`].
#[inline]
fn angle_between(a: Vec3x8, b: Vec3x8) -> F32x8 {
    atan2(a.cross(b).length(), a.dot(b))
}

/// The entry refraction of eight pixels: view, shading normal, `T1`, and the lanes the scalar
/// kernel must take (degenerate or long/short vectors, TIR at the entry).
struct Entry {
    view: Vec3x8,
    n1: Vec3x8,
    t1: Vec3x8,
    scalar: Mask,
}

#[inline]
fn entry(camera: &Camera, p1: Vec3x8, n1: Vec3x8, eta: F32x8) -> Entry {
    let (view, view_ok) = normalize_common(p1 - Vec3x8::splat(camera.eye()));
    let (n1, n1_ok) = normalize_common(n1);
    let n1 = face_forward(n1, view);
    let refracted = refract(view, n1, eta);
    let tir_entry = refracted.is_zero();
    let (t1, t1_ok) = normalize_common(refracted);
    Entry {
        view,
        n1,
        t1,
        scalar: !(view_ok & n1_ok & t1_ok) | tir_entry,
    }
}

/// [`one_interface`] for eight pixels: lane `i` is `one_interface(camera, &front[i], params)`.
///
/// ```
/// use glam::Vec3;
/// use refract_core::kernel::{FrontSurface, ImageSpaceParams, one_interface};
/// use refract_core::kernel_x8::one_interface_x8;
/// use refract_core::{Camera, CameraDesc, DistanceMode, TirPolicy};
/// let camera = Camera::new(CameraDesc::default())?;
/// let params = ImageSpaceParams::new(1.33, DistanceMode::Interpolated, TirPolicy::default())?;
/// let front: [FrontSurface; 8] = core::array::from_fn(|i| FrontSurface {
///     p1_ws: Vec3::new(0.1 * i as f32, 0.0, 1.0),
///     n1_ws: Vec3::new(0.05 * i as f32, 0.0, 1.0),
///     d_n: 1.0,
/// });
/// let lanes = one_interface_x8(&camera, &front, &params);
/// for (lane, surface) in lanes.iter().zip(&front) {
///     let scalar = one_interface(&camera, surface, &params);
///     assert_eq!(format!("{lane:?}"), format!("{scalar:?}"));
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn one_interface_x8(
    camera: &Camera,
    front: &[FrontSurface; LANES],
    params: &ImageSpaceParams,
) -> [Result<OneInterfacePath, DegenerateInput>; LANES] {
    one_interface_lanes(camera, &FrontLanes::from_surfaces(front), params)
}

/// [`one_interface_x8`] with the surfaces as lanes (the CPU backend's per-pixel path): lane `i`
/// is `one_interface(camera, &front.surface(i), params)`, bit for bit.
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

/// Every value of eight two-interface paths, as lanes; `scalar` marks the lanes the scalar
/// kernel must redo (their other values are meaningless).
struct TwoInterfaceSoa {
    view: Vec3x8,
    n1: Vec3x8,
    t1: Vec3x8,
    /// `d_V` where `d_v_ok`.
    d_v: F32x8,
    d_v_ok: Mask,
    d_tilde: F32x8,
    p2: Vec3x8,
    n2: Vec3x8,
    n2_from_back_face: [bool; LANES],
    t2: Vec3x8,
    tir_exit: Mask,
    scalar: [bool; LANES],
}

/// The lane computation shared by [`two_interface_x8`] and [`two_interface_lanes`].
#[inline]
fn two_interface_soa<S: BackFaceSampler + ?Sized>(
    camera: &Camera,
    uv_px: &[Vec2; LANES],
    front: &FrontLanes,
    back: &S,
    params: &ImageSpaceParams,
) -> TwoInterfaceSoa {
    let FrontLanes {
        p1_ws: p1,
        n1_ws: n1,
        d_n,
    } = *front;
    let eta = F32x8::splat(params.eta_in());
    let e = entry(camera, p1, n1, eta);
    let d_n_ok = d_n.simd_ge(F32x8::ZERO) & d_n.is_finite();

    // d_V at P1's own pixel (Wyman 2005a §3.1); `‖P1 − eye‖` on lanes, as
    // `Camera::distance_from_eye`.
    let own = back.back_faces_x8(Vec2x8::from_lanes(uv_px), ALL_LANES);
    let d_v = own.distance - (p1 - Vec3x8::splat(camera.eye())).length();
    let d_v_ok = own.found & d_v.simd_ge(F32x8::ZERO) & d_v.is_finite();
    let d_v_or_n = d_v_ok.select(d_v, d_n);

    // d~ (Wyman 2005a §3.1).
    let theta_i = angle_between(-e.view, e.n1);
    let theta_t = angle_between(e.t1, -e.n1);
    let d_tilde = match params.distance_mode {
        DistanceMode::Interpolated => {
            let ratio = theta_i
                .simd_gt(F32x8::splat(NORMAL_INCIDENCE_ANGLE))
                .select(theta_t / theta_i, eta);
            // f32::clamp(0, 1): NaN stays NaN.
            let ratio = lt(ratio, F32x8::ZERO).select(F32x8::ZERO, ratio);
            let w = ratio.simd_gt(F32x8::ONE).select(F32x8::ONE, ratio);
            w * d_v_or_n + (F32x8::ONE - w) * d_n
        }
        DistanceMode::ViewOnly => d_v_or_n,
        DistanceMode::NormalOnly => d_n,
    };
    let p2 = p1 + d_tilde * e.t1;

    // N2 from the back faces at P~2's pixel (§3.2), else the silhouette fallback (§3.3).
    let (px, py, in_front) = world_to_pixel_xy(camera, p2);
    let far = back.back_faces_x8(Vec2x8 { x: px, y: py }, in_front);
    // `robust_normalize` of each sampled normal: its two common paths on lanes, the rare
    // lanes (too long, too short, not finite) one by one.
    let (mut sampled_n2, common) = normalize_common(far.n_ws);
    let mut sampled_mask = far.found & common;
    let rare = far.found & !common;
    if rare.any() {
        let (rare, raw) = (mask_lanes(rare), far.n_ws.to_lanes());
        let (mut n2, mut sampled) = (sampled_n2.to_lanes(), mask_lanes(sampled_mask));
        for i in (0..LANES).filter(|i| rare[*i]) {
            if let Some(n) = robust_normalize(raw[i]) {
                (n2[i], sampled[i]) = (n, true);
            }
        }
        sampled_n2 = Vec3x8::from_lanes(&n2);
        sampled_mask = crate::lanes::mask_from_lanes(sampled);
    }
    let sampled = mask_lanes(sampled_mask);
    let n2 = if sampled_mask.all() {
        sampled_n2
    } else {
        let look = Vec3x8::splat(camera.look_dir());
        let (fallback, fallback_ok) = (e.t1 - look.dot(e.t1) * look).try_normalize();
        let fallback = Vec3x8::select(fallback_ok, fallback, e.t1);
        Vec3x8::select(sampled_mask, sampled_n2, fallback)
    };

    // T2 = refract(T1, −N2, n) with the TIR policy (§3.3), as `refract_exit`.
    let inward = face_forward(-n2, e.t1);
    let refracted = refract(e.t1, inward, F32x8::splat(params.ior()));
    let tir_exit = refracted.is_zero();
    let (normalized, t2_ok) = normalize_common(refracted);
    let t2 = if tir_exit.any() {
        let tir_t2 = match params.tir_policy {
            TirPolicy::ClampToCritical => {
                let (tangent, ok) = (e.t1 - e.t1.dot(inward) * inward).try_normalize();
                Vec3x8::select(ok, tangent, e.t1)
            }
            TirPolicy::ReflectOnce => e.t1 - (F32x8::splat(2.0) * inward.dot(e.t1)) * inward,
            TirPolicy::Black => Vec3x8::ZERO,
        };
        Vec3x8::select(tir_exit, tir_t2, normalized)
    } else {
        normalized
    };

    let finite = p2.is_finite() & d_tilde.is_finite() & t2.is_finite();
    TwoInterfaceSoa {
        view: e.view,
        n1: e.n1,
        t1: e.t1,
        d_v,
        d_v_ok,
        d_tilde,
        p2,
        n2,
        n2_from_back_face: sampled,
        t2,
        tir_exit,
        scalar: mask_lanes(e.scalar | !d_n_ok | !(finite & (t2_ok | tir_exit))),
    }
}

/// [`two_interface`] for eight pixels: lane `i` is
/// `two_interface(camera, uv_px[i], &front[i], back, params)`, bit for bit.
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
/// use refract_core::kernel_x8::two_interface_x8;
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
/// let lanes = two_interface_x8(&camera, &uv, &front, &back, &params);
/// for i in 0..8 {
///     let scalar = two_interface(&camera, uv[i], &front[i], &back, &params)?;
///     assert_eq!(format!("{:?}", lanes[i]), format!("{:?}", Ok::<_, ()>(scalar)));
///     // Parallel faces: the ray leaves in the direction it came.
///     assert!((scalar.t2 - camera.pixel_ray(uv[i]).dir).length() < 1e-5);
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn two_interface_x8<S: BackFaceSampler + ?Sized>(
    camera: &Camera,
    uv_px: &[Vec2; LANES],
    front: &[FrontSurface; LANES],
    back: &S,
    params: &ImageSpaceParams,
) -> [Result<TwoInterfacePath, DegenerateInput>; LANES] {
    let soa = two_interface_soa(
        camera,
        uv_px,
        &FrontLanes::from_surfaces(front),
        back,
        params,
    );
    let (view, n1, t1) = (soa.view.to_lanes(), soa.n1.to_lanes(), soa.t1.to_lanes());
    let (p2, n2, t2) = (soa.p2.to_lanes(), soa.n2.to_lanes(), soa.t2.to_lanes());
    let (d_tilde, tir_exit) = (soa.d_tilde.to_array(), mask_lanes(soa.tir_exit));
    let (d_v, d_v_ok) = (soa.d_v.to_array(), mask_lanes(soa.d_v_ok));
    let mut paths = [Err(DegenerateInput::NonFiniteResult); LANES];
    for (i, path) in paths.iter_mut().enumerate() {
        if soa.scalar[i] {
            *path = two_interface(camera, uv_px[i], &front[i], back, params);
            continue;
        }
        *path = Ok(TwoInterfacePath {
            entry: OneInterfacePath {
                view: view[i],
                n1: n1[i],
                t1: t1[i],
                tir_entry: false,
            },
            d_v: d_v_ok[i].then_some(d_v[i]),
            d_tilde: d_tilde[i],
            p2: p2[i],
            n2: n2[i],
            n2_source: if soa.n2_from_back_face[i] {
                ExitNormalSource::BackFace
            } else {
                ExitNormalSource::SilhouetteFallback
            },
            t2: t2[i],
            tir_exit: tir_exit[i],
        });
    }
    paths
}

/// What a renderer needs of eight two-interface paths, as lanes: [`two_interface_x8`] without
/// the per-lane structs (the CPU backend's per-pixel path). Lane `i` holds the values of
/// `two_interface(camera, uv_px[i], &front[i], back, params)`, bit for bit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoInterfaceLanes {
    /// The lanes with a path (`Ok`); the others reported a [`DegenerateInput`] and their
    /// vectors are zero.
    pub ok: [bool; LANES],
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

/// [`two_interface_x8`] as [`TwoInterfaceLanes`].
pub fn two_interface_lanes<S: BackFaceSampler + ?Sized>(
    camera: &Camera,
    uv_px: &[Vec2; LANES],
    front: &FrontLanes,
    back: &S,
    params: &ImageSpaceParams,
) -> TwoInterfaceLanes {
    let soa = two_interface_soa(camera, uv_px, front, back, params);
    let mut lanes = TwoInterfaceLanes {
        ok: [true; LANES],
        t2: soa.t2,
        p2: soa.p2,
        n2: soa.n2,
        n2_from_back_face: soa.n2_from_back_face,
        tir: mask_lanes(soa.tir_exit),
    };
    if soa.scalar.iter().any(|s| *s) {
        // The rare lanes, from the scalar kernel.
        let (mut t2, mut p2, mut n2) = (soa.t2.to_lanes(), soa.p2.to_lanes(), soa.n2.to_lanes());
        for i in (0..LANES).filter(|i| soa.scalar[*i]) {
            match two_interface(camera, uv_px[i], &front.surface(i), back, params) {
                Ok(path) => {
                    (t2[i], p2[i], n2[i]) = (path.t2, path.p2, path.n2);
                    lanes.n2_from_back_face[i] = path.n2_source == ExitNormalSource::BackFace;
                    lanes.tir[i] = path.tir_exit || path.entry.tir_entry;
                }
                Err(_) => {
                    (t2[i], p2[i], n2[i]) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
                    lanes.ok[i] = false;
                    lanes.n2_from_back_face[i] = false;
                    lanes.tir[i] = false;
                }
            }
        }
        (lanes.t2, lanes.p2, lanes.n2) = (
            Vec3x8::from_lanes(&t2),
            Vec3x8::from_lanes(&p2),
            Vec3x8::from_lanes(&n2),
        );
    }
    lanes
}

/// [`Camera::world_to_pixel`]'s `(u_px, v_px)` and the lanes in front of the eye (`w > 0`).
#[inline]
pub(crate) fn world_to_pixel_xy(camera: &Camera, p: Vec3x8) -> (F32x8, F32x8, Mask) {
    let m = camera.world_to_clip();
    let row = |c: glam::Vec4| Vec3x8::splat(c.truncate());
    // glam's Mat4 · Vec4: ((c0·x + c1·y) + c2·z) + c3·1, lane-wise per output row.
    let (c0, c1, c2) = (row(m.x_axis), row(m.y_axis), row(m.z_axis));
    let c3 = m.w_axis;
    let clip = c0 * p.x + c1 * p.y + c2 * p.z + Vec3x8::splat(c3.truncate());
    let w = F32x8::splat(m.x_axis.w) * p.x
        + F32x8::splat(m.y_axis.w) * p.y
        + F32x8::splat(m.z_axis.w) * p.z
        + F32x8::splat(c3.w);
    let rcp = F32x8::ONE / w;
    let (ndc_x, ndc_y) = (clip.x * rcp, clip.y * rcp);
    let half = F32x8::splat(0.5);
    let px = half * (ndc_x + F32x8::ONE) * F32x8::splat(camera.width() as f32);
    let py = half * (F32x8::ONE - ndc_y) * F32x8::splat(camera.height() as f32);
    (px, py, w.simd_gt(F32x8::ZERO))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraDesc;
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
                let lanes = two_interface_x8(&camera, &uv, &front, &Field, &params);
                let lean = two_interface_lanes(
                    &camera,
                    &uv,
                    &FrontLanes::from_surfaces(&front),
                    &Field,
                    &params,
                );
                let (t2, p2, n2) = (lean.t2.to_lanes(), lean.p2.to_lanes(), lean.n2.to_lanes());
                let single = one_interface_x8(&camera, &front, &params);
                for i in 0..LANES {
                    let scalar = two_interface(&camera, uv[i], &front[i], &Field, &params);
                    assert_eq!(lean.ok[i], scalar.is_ok());
                    if let Ok(path) = &scalar {
                        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                        assert_eq!(bits(t2[i]), bits(path.t2));
                        assert_eq!(bits(p2[i]), bits(path.p2));
                        assert_eq!(bits(n2[i]), bits(path.n2));
                        assert_eq!(
                            lean.n2_from_back_face[i],
                            path.n2_source == ExitNormalSource::BackFace
                        );
                        assert_eq!(lean.tir[i], path.tir_exit || path.entry.tir_entry);
                    }
                    assert_eq!(
                        format!("{:?}", lanes[i]),
                        format!("{scalar:?}"),
                        "two_interface lane {i}, {params:?}"
                    );
                    let scalar = one_interface(&camera, &front[i], &params);
                    assert_eq!(
                        format!("{:?}", single[i]),
                        format!("{scalar:?}"),
                        "one_interface lane {i}"
                    );
                    lanes_checked += 1;
                    scalar_lanes += usize::from(lanes[i].is_err());
                }
            }
        }
        // The paths taken must include errors and successes of every kind.
        assert!(scalar_lanes > 100 && scalar_lanes < lanes_checked / 2);
    }
}
