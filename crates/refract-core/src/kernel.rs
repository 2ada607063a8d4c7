//! The per-pixel kernels of image-space refraction (Wyman 2005a §3–4), generic over a
//! [`BackFaceSampler`] so that the CPU backend, the GPU twin's tests and your own renderer can
//! all drive them.
//!
//! A backend rasterises the refractor twice (Wyman 2005a §4): back faces into a normal +
//! distance buffer (read through [`BackFaceSampler`]), then front faces, calling
//! [`two_interface`] (method `wyman` and its ablations) or [`one_interface`] (method `single`)
//! for every covered pixel with the interpolated [`FrontSurface`].

use core::fmt;

use glam::{Vec2, Vec3};

use crate::camera::Camera;
use crate::exit::{ExitNormalSource, TirPolicy, exit_normal_outside_silhouette, refract_exit};
use crate::interpolated_distance::{
    DistanceMode, approximate_distance, exit_point, incidence_angle, transmission_angle,
};
use crate::lanes::{F32x8, LANES, Mask, Vec2x8, Vec3x8, mask_from_lanes, mask_lanes};
use crate::optics::{face_forward_shading_normal, reflect, refract};
use crate::vector::robust_normalize;

/// One texel of the back-face buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BackFaceSample {
    /// The back surface's outward shading normal (world space; normalised by the kernel).
    pub n_ws: Vec3,
    /// Distance from the eye to the back surface along the pixel ray, `‖P_back − eye‖`.
    pub distance: f32,
}

/// Reads the back-face buffer (Wyman 2005a §3.2, "BackfaceNormals" and "BackfaceZBuf").
///
/// # Example
///
/// A sampler over an analytic sphere, driving [`two_interface`]:
///
/// ```
/// use glam::{Vec2, Vec3};
/// use refract_core::kernel::{BackFaceSample, BackFaceSampler, FrontSurface, ImageSpaceParams};
/// use refract_core::{Camera, CameraDesc, DistanceMode, TirPolicy};
///
/// /// Your renderer's back-face buffer; here the far side of a unit sphere, exactly.
/// struct SphereBackFaces(Camera);
///
/// impl BackFaceSampler for SphereBackFaces {
///     fn back_face(&self, uv_px: Vec2) -> Option<BackFaceSample> {
///         let ray = self.0.pixel_ray(uv_px);
///         let b = ray.origin.dot(ray.dir);
///         let disc = b * b - (ray.origin.length_squared() - 1.0);
///         (disc >= 0.0).then(|| {
///             let t = -b + disc.sqrt();
///             BackFaceSample { n_ws: ray.at(t), distance: t }
///         })
///     }
/// }
///
/// let camera = Camera::new(CameraDesc { width: 64, height: 64, ..CameraDesc::default() })?;
/// let uv = Camera::pixel_center(40, 32);
/// // Your rasteriser's front-face buffer at that pixel: P1, N1 and the interpolated d_N.
/// let ray = camera.pixel_ray(uv);
/// let b = ray.origin.dot(ray.dir);
/// let p1 = ray.at(-b - (b * b - (ray.origin.length_squared() - 1.0)).sqrt());
/// let front = FrontSurface { p1_ws: p1, n1_ws: p1, d_n: 2.0 };
/// let params = ImageSpaceParams::new(1.5, DistanceMode::Interpolated, TirPolicy::ClampToCritical)?;
/// let path = refract_core::kernel::two_interface(&camera, uv, &front, &SphereBackFaces(camera), &params)?;
/// assert!(path.n2_source == refract_core::ExitNormalSource::BackFace);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub trait BackFaceSampler {
    /// The back surface seen through pixel position `uv_px` (pixels, origin top-left, `y` down,
    /// pixel `(x, y)` covering `[x, x+1) × [y, y+1)`), or `None` where the buffer is empty
    /// (outside the refractor's silhouette, or outside the image).
    fn back_face(&self, uv_px: Vec2) -> Option<BackFaceSample>;

    /// [`Self::back_face`] at eight positions at once (the lane kernels' lookups): lane `i`
    /// holds `back_face(uv_px[i])` where `active` is set, nothing (not `found`) where it is
    /// not. The default looks the lanes up one by one; a sampler may override it, giving the
    /// same lanes.
    #[inline]
    fn back_faces_x8(&self, uv_px: Vec2x8, active: Mask) -> BackFaceLanes {
        let (uv_px, active) = (uv_px.to_lanes(), mask_lanes(active));
        let (mut n_ws, mut distance, mut found) =
            ([Vec3::ZERO; LANES], [0.0; LANES], [false; LANES]);
        for i in (0..LANES).filter(|i| active[*i]) {
            if let Some(sample) = self.back_face(uv_px[i]) {
                (n_ws[i], distance[i], found[i]) = (sample.n_ws, sample.distance, true);
            }
        }
        BackFaceLanes {
            n_ws: Vec3x8::from_lanes(&n_ws),
            distance: F32x8::new(distance),
            found: mask_from_lanes(found),
        }
    }
}

/// Eight [`BackFaceSample`]s as lanes ([`BackFaceSampler::back_faces_x8`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BackFaceLanes {
    /// [`BackFaceSample::n_ws`] (any value where not `found`).
    pub n_ws: Vec3x8,
    /// [`BackFaceSample::distance`] (any value where not `found`).
    pub distance: F32x8,
    /// The lanes that found a sample.
    pub found: Mask,
}

/// The front surface of the refractor at one pixel, as rasterised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrontSurface {
    /// The visible entry point `P1` (world space).
    pub p1_ws: Vec3,
    /// The interpolated outward shading normal `N1` (world space; normalised by the kernel).
    pub n1_ws: Vec3,
    /// The interpolated per-vertex distance along `−N` to the far side, `d_N` (Wyman 2005a §3.1).
    pub d_n: f32,
}

/// The index of refraction was outside [`crate::optics::IOR_RANGE`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InvalidIor(pub f32);

impl fmt::Display for InvalidIor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "index of refraction {}: expected {}",
            self.0,
            crate::optics::IOR_EXPECTED
        )
    }
}

impl core::error::Error for InvalidIor {}

/// Parameters of the image-space methods.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageSpaceParams {
    ior: f32,
    /// How `d~` is approximated (`wyman`, `wyman-dv`, `wyman-dn`).
    pub distance_mode: DistanceMode,
    /// What happens under total internal reflection at the exit surface.
    pub tir_policy: TirPolicy,
}

impl ImageSpaceParams {
    /// Parameters for a refractor of index `ior` in a medium of index 1.
    pub fn new(
        ior: f32,
        distance_mode: DistanceMode,
        tir_policy: TirPolicy,
    ) -> Result<Self, InvalidIor> {
        if !crate::optics::ior_in_range(ior) {
            return Err(InvalidIor(ior));
        }
        Ok(Self {
            ior,
            distance_mode,
            tir_policy,
        })
    }

    /// The refractor's index of refraction `n` (the outside is 1).
    pub fn ior(&self) -> f32 {
        self.ior
    }

    /// `η = n_i / n_t = 1 / n` at the entry interface.
    pub fn eta_in(&self) -> f32 {
        1.0 / self.ior
    }
}

/// Why a kernel could not produce a path for a pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DegenerateInput {
    /// `P1` coincides with the eye or is not finite, so there is no view direction.
    ViewDirection,
    /// `N1` is zero or not finite.
    Normal,
    /// `d_N` is negative or not finite.
    NormalDistance,
    /// The result overflowed `f32` (inputs of magnitude near `f32::MAX`).
    NonFiniteResult,
}

impl fmt::Display for DegenerateInput {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::ViewDirection => "entry point P1 coincides with the eye or is not finite",
            Self::Normal => "normal N1 is zero or not finite",
            Self::NormalDistance => "distance d_N is negative or not finite",
            Self::NonFiniteResult => "the refracted path overflowed f32",
        })
    }
}

impl core::error::Error for DegenerateInput {}

/// The result of [`one_interface`] (method `single`, Wyman 2005a Table 1 "1-sided").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OneInterfacePath {
    /// The view direction `V` (unit).
    pub view: Vec3,
    /// The shading normal used at `P1` (unit, facing the viewer).
    pub n1: Vec3,
    /// The direction looked up in the environment: `T1 = refract(V, N1, 1/n)`, or
    /// `reflect(V, N1)` under total internal reflection (only possible when `n < 1`).
    pub t1: Vec3,
    /// Total internal reflection at the entry point.
    pub tir_entry: bool,
}

/// The result of [`two_interface`] (method `wyman` and its ablations).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoInterfacePath {
    /// The entry refraction.
    pub entry: OneInterfacePath,
    /// `d_V`, the front-to-back distance along `V`; `None` when the back-face buffer was empty
    /// at `P1`'s own pixel, in which case `d_N` stood in for it.
    pub d_v: Option<f32>,
    /// The distance used, `d~` (Wyman 2005a §3.1).
    pub d_tilde: f32,
    /// The approximate exit point `P~2 = P1 + d~ T1`.
    pub p2: Vec3,
    /// The exit normal `N2` (outward, unit).
    pub n2: Vec3,
    /// Where `N2` came from.
    pub n2_source: ExitNormalSource,
    /// `T2`, the direction looked up in the environment (unit), or the zero vector when the
    /// [`TirPolicy::Black`] absorbed the ray. Equal to `entry.t1` when the entry was a TIR.
    pub t2: Vec3,
    /// Total internal reflection at the exit surface.
    pub tir_exit: bool,
}

/// The view direction and the viewer-facing shading normal at `P1`.
#[inline]
fn entry_frame(camera: &Camera, front: &FrontSurface) -> Result<(Vec3, Vec3), DegenerateInput> {
    let view =
        robust_normalize(front.p1_ws - camera.eye()).ok_or(DegenerateInput::ViewDirection)?;
    let n1 = robust_normalize(front.n1_ws).ok_or(DegenerateInput::Normal)?;
    Ok((view, face_forward_shading_normal(n1, view)))
}

/// One refraction at `P1` (Wyman 2005a §2; Table 1 "1-sided"): `T1 = refract(V, N1, 1/n)`.
///
/// `V = normalize(P1 − eye)`. Unnormalised or back-facing normals are normalised and turned
/// toward the viewer; zero or non-finite ones are reported, never turned into NaN.
///
/// # Example
///
/// ```
/// use glam::Vec3;
/// use refract_core::kernel::{FrontSurface, ImageSpaceParams, one_interface};
/// use refract_core::{Camera, CameraDesc, DistanceMode, TirPolicy};
/// let camera = Camera::new(CameraDesc::default())?; // eye at (0, 0, 3) looking at the origin
/// // Looking straight at a surface facing the eye: the ray goes straight on.
/// let front = FrontSurface { p1_ws: Vec3::new(0.0, 0.0, 1.0), n1_ws: Vec3::Z, d_n: 2.0 };
/// let params = ImageSpaceParams::new(1.5, DistanceMode::Interpolated, TirPolicy::default())?;
/// let path = one_interface(&camera, &front, &params)?;
/// assert!((path.t1 - Vec3::NEG_Z).length() < 1e-6 && !path.tir_entry);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[inline]
pub fn one_interface(
    camera: &Camera,
    front: &FrontSurface,
    params: &ImageSpaceParams,
) -> Result<OneInterfacePath, DegenerateInput> {
    let (view, n1) = entry_frame(camera, front)?;
    let refracted = refract(view, n1, params.eta_in());
    let tir_entry = refracted == Vec3::ZERO;
    let t1 = if tir_entry {
        reflect(view, n1)
    } else {
        refracted
    };
    // Renormalised: see `refract_exit` on f32 rounding at extreme indices.
    let t1 = robust_normalize(t1).ok_or(DegenerateInput::NonFiniteResult)?;
    Ok(OneInterfacePath {
        view,
        n1,
        t1,
        tir_entry,
    })
}

/// Wyman 2005a §3–4, the two-interface fragment program, one pixel:
///
/// ```text
/// T1  = refract(V, N1, 1/n)
/// d_V = back.distance(P1's pixel) − ‖P1 − eye‖                    (§3.1; d_N where empty)
/// d~  = (θt/θi) d_V + (1 − θt/θi) d_N                               (§3.1, or an ablation)
/// P~2 = P1 + d~ T1
/// N2  = back.normal(project(P~2))  or  normalize(T1 − (L·T1) L)     (§3.2, §3.3 outside)
/// T2  = refract(T1, −N2, n)  with the TIR policy                     (§3.3)
/// ```
///
/// `uv_px` is the pixel position of `P1` (its pixel centre when rasterised). Every finite input
/// gives either a path whose vectors are all finite and unit (or `T2 = 0` for
/// [`TirPolicy::Black`]) or a [`DegenerateInput`].
///
/// # Example
///
/// On a unit sphere the exact exit distance is `2 cos θt`; `d~` lands within a few percent:
///
/// ```
/// use glam::{Vec2, Vec3};
/// use refract_core::kernel::{BackFaceSample, BackFaceSampler, FrontSurface, ImageSpaceParams};
/// use refract_core::{Camera, CameraDesc, DistanceMode, TirPolicy};
///
/// /// Your renderer's back-face buffer; here the far side of a unit sphere, exactly.
/// struct SphereBackFaces(Camera);
///
/// impl BackFaceSampler for SphereBackFaces {
///     fn back_face(&self, uv_px: Vec2) -> Option<BackFaceSample> {
///         let ray = self.0.pixel_ray(uv_px);
///         let b = ray.origin.dot(ray.dir);
///         let disc = b * b - (ray.origin.length_squared() - 1.0);
///         (disc >= 0.0).then(|| {
///             let t = -b + disc.sqrt();
///             BackFaceSample { n_ws: ray.at(t), distance: t }
///         })
///     }
/// }
///
/// let camera = Camera::new(CameraDesc { width: 64, height: 64, ..CameraDesc::default() })?;
/// let uv = Camera::pixel_center(40, 32);
/// // Your rasteriser's front-face buffer at that pixel: P1, N1 and the interpolated d_N.
/// let ray = camera.pixel_ray(uv);
/// let b = ray.origin.dot(ray.dir);
/// let p1 = ray.at(-b - (b * b - (ray.origin.length_squared() - 1.0)).sqrt());
/// let front = FrontSurface { p1_ws: p1, n1_ws: p1, d_n: 2.0 };
/// let params = ImageSpaceParams::new(1.5, DistanceMode::Interpolated, TirPolicy::ClampToCritical)?;
/// let path = refract_core::kernel::two_interface(&camera, uv, &front, &SphereBackFaces(camera), &params)?;
/// let theta_t = refract_core::interpolated_distance::transmission_angle(path.entry.t1, path.entry.n1);
/// assert!((path.d_tilde - 2.0 * theta_t.cos()).abs() < 0.05 * 2.0 * theta_t.cos());
/// assert!((path.t2.length() - 1.0).abs() < 1e-5 && !path.tir_exit);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn two_interface<S: BackFaceSampler + ?Sized>(
    camera: &Camera,
    uv_px: Vec2,
    front: &FrontSurface,
    back: &S,
    params: &ImageSpaceParams,
) -> Result<TwoInterfacePath, DegenerateInput> {
    let entry = one_interface(camera, front, params)?;
    if !(front.d_n >= 0.0 && front.d_n.is_finite()) {
        return Err(DegenerateInput::NormalDistance);
    }
    let d_v = back
        .back_face(uv_px)
        .map(|b| b.distance - camera.distance_from_eye(front.p1_ws))
        .filter(|d| *d >= 0.0 && d.is_finite());

    if entry.tir_entry {
        // Nothing entered the refractor: the reflected direction is the answer.
        return Ok(TwoInterfacePath {
            entry,
            d_v,
            d_tilde: 0.0,
            p2: front.p1_ws,
            n2: entry.n1,
            n2_source: ExitNormalSource::SilhouetteFallback,
            t2: entry.t1,
            tir_exit: false,
        });
    }

    let theta_i = incidence_angle(entry.view, entry.n1);
    let theta_t = transmission_angle(entry.t1, entry.n1);
    let d_tilde = approximate_distance(
        params.distance_mode,
        theta_i,
        theta_t,
        params.eta_in(),
        d_v.unwrap_or(front.d_n),
        front.d_n,
    );
    let p2 = exit_point(front.p1_ws, entry.t1, d_tilde);

    let sampled_n2 = camera
        .world_to_pixel(p2)
        .and_then(|px| back.back_face(px.truncate()))
        .and_then(|b| robust_normalize(b.n_ws));
    let (n2, n2_source) = match sampled_n2 {
        Some(n2) => (n2, ExitNormalSource::BackFace),
        None => (
            exit_normal_outside_silhouette(entry.t1, camera.look_dir()),
            ExitNormalSource::SilhouetteFallback,
        ),
    };
    let exit = refract_exit(entry.t1, n2, params.ior, params.tir_policy);

    let path = TwoInterfacePath {
        entry,
        d_v,
        d_tilde,
        p2,
        n2,
        n2_source,
        t2: exit.t2,
        tir_exit: exit.tir,
    };
    if path.p2.is_finite() && path.d_tilde.is_finite() && path.t2.is_finite() {
        Ok(path)
    } else {
        Err(DegenerateInput::NonFiniteResult)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraDesc;

    /// An analytic sphere of radius `r` at the origin, seen from the default camera: the back
    /// face at a pixel is the far intersection of its primary ray.
    struct SphereBack {
        camera: Camera,
        radius: f32,
    }

    impl BackFaceSampler for SphereBack {
        fn back_face(&self, uv_px: Vec2) -> Option<BackFaceSample> {
            let ray = self.camera.pixel_ray(uv_px);
            let b = ray.origin.dot(ray.dir);
            let c = ray.origin.length_squared() - self.radius * self.radius;
            let disc = b * b - c;
            if disc < 0.0 {
                return None;
            }
            let t = -b + disc.sqrt();
            Some(BackFaceSample {
                n_ws: ray.at(t) / self.radius,
                distance: t,
            })
        }
    }

    fn front_of_sphere(camera: &Camera, uv_px: Vec2, radius: f32) -> FrontSurface {
        let ray = camera.pixel_ray(uv_px);
        let b = ray.origin.dot(ray.dir);
        let c = ray.origin.length_squared() - radius * radius;
        let t = -b - (b * b - c).sqrt();
        let p1 = ray.at(t);
        FrontSurface {
            p1_ws: p1,
            n1_ws: p1 / radius,
            d_n: 2.0 * radius,
        }
    }

    #[test]
    fn centre_pixel_of_a_sphere_goes_straight_through() {
        let camera = Camera::new(CameraDesc {
            width: 65,
            height: 65,
            ..CameraDesc::default()
        })
        .expect("camera");
        let back = SphereBack {
            camera,
            radius: 1.0,
        };
        let uv = Camera::pixel_center(32, 32);
        let front = front_of_sphere(&camera, uv, 1.0);
        let params = ImageSpaceParams::new(1.5, DistanceMode::Interpolated, TirPolicy::default())
            .expect("params");
        let path = two_interface(&camera, uv, &front, &back, &params).expect("path");
        assert!((path.t2 - path.entry.view).length() < 1e-5);
        assert!((path.d_tilde - 2.0).abs() < 1e-4, "d~ {}", path.d_tilde);
        assert_eq!(path.n2_source, ExitNormalSource::BackFace);
    }

    #[test]
    fn on_a_sphere_the_exit_point_is_close_to_the_exact_one() {
        // For a sphere, d = 2 r cos θt exactly; d~ interpolates 2r cos-ish d_V and d_N = 2r.
        let camera = Camera::new(CameraDesc {
            width: 65,
            height: 65,
            ..CameraDesc::default()
        })
        .expect("camera");
        let back = SphereBack {
            camera,
            radius: 1.0,
        };
        let params = ImageSpaceParams::new(1.5, DistanceMode::Interpolated, TirPolicy::default())
            .expect("params");
        let uv = Camera::pixel_center(45, 32);
        let front = front_of_sphere(&camera, uv, 1.0);
        let path = two_interface(&camera, uv, &front, &back, &params).expect("path");
        let theta_t = transmission_angle(path.entry.t1, path.entry.n1);
        let exact = 2.0 * theta_t.cos();
        assert!(
            (path.d_tilde - exact).abs() / exact < 0.05,
            "{} vs {exact}",
            path.d_tilde
        );
    }

    #[test]
    fn invalid_ior_is_an_error() {
        for ior in [0.0, -1.5, f32::NAN, f32::INFINITY] {
            assert!(
                ImageSpaceParams::new(ior, DistanceMode::Interpolated, TirPolicy::Black).is_err()
            );
        }
    }

    /// The kernels take exactly `IOR_RANGE`: both ends, not one step past either, and not the
    /// 1e-20 that issue 54 found turning the reference's radiance into +inf; the error says
    /// the range.
    #[test]
    fn the_ior_range_is_the_one_range() {
        use crate::optics::{IOR_RANGE, MAX_IOR, MIN_IOR};
        let params = |ior| ImageSpaceParams::new(ior, DistanceMode::Interpolated, TirPolicy::Black);
        assert_eq!(IOR_RANGE, MIN_IOR..=MAX_IOR);
        assert!(params(MIN_IOR).is_ok() && params(MAX_IOR).is_ok() && params(1.5).is_ok());
        for ior in [MIN_IOR.next_down(), MAX_IOR.next_up(), 1e-20, 5e-20] {
            let err = params(ior).expect_err("outside the range");
            assert!(err.to_string().contains("from 0.01 to 1000"), "{err}");
        }
    }
}
