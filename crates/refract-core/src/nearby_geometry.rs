//! Refraction of nearby geometry (Wyman 2005b §4): where the ray `P~2 + t T~2` leaving the
//! refractor meets the opaque objects that a separate pass rendered from the eye into the
//! nearby-geometry ("NG") texture. Four lookups, one per method:
//!
//! - [`NearbyLookup::KayGreenberg`] (§4.1): project `P~2` itself into the NG texture.
//! - [`NearbyLookup::RayPlane`] (§4.2): intersect the ray with a few planes that stand for the
//!   objects and project the nearest hit.
//! - [`NearbyLookup::Iterative`] (§4.3, Ohbuchi 2003): start at the plane hit and re-estimate the
//!   distance from the surface the NG texture shows there, a few times.
//! - [`NearbyLookup::Seeded`] (§4.3): sample the ray at `K` points, start the iteration at the
//!   sample whose depth best matches the NG depth.
//!
//! The NG texture is read through [`NearbyGeometryTexture`] (nearest texel, the surface position
//! stored per texel, "empty" explicit) and addressed through the camera that rendered it
//! (the eye's camera, or a wider one with a guard band). Everything here is per pixel and
//! allocation-free.

use glam::{UVec2, Vec3, Vec4};

use crate::camera::{Camera, CameraDesc};
use crate::lanes::{F32x8, I32x8, LANES, Mask, Vec3x8, mask_from_lanes};
use crate::math;
use crate::real::{Msk, Real, Vector3};

/// The camera of an NG texture with a guard band (beyond Wyman 2005b, which renders the NG
/// texture with the eye's camera): `percent` of the image's width and height added on each
/// side, `pad = round(percent/100 · (W, H))`, resolution `(W + 2 pad_x, H + 2 pad_y)` and
/// `tan(fov'/2) = tan(fov/2) · H'/H`, so the texel size is the pixel size and texel
/// `(x + pad_x, y + pad_y)` is pixel `(x, y)`. Returns the camera description and `pad`.
///
/// ```
/// use refract_core::CameraDesc;
/// use refract_core::nearby_geometry::guard_band_camera;
/// let eye = CameraDesc { width: 200, height: 100, ..CameraDesc::default() };
/// let (ng, pad) = guard_band_camera(&eye, 10);
/// assert_eq!((ng.width, ng.height, pad.x, pad.y), (240, 120, 20, 10));
/// ```
pub fn guard_band_camera(desc: &CameraDesc, percent: u32) -> (CameraDesc, UVec2) {
    let fraction = percent as f32 / 100.0;
    // Round half up (both are ≥ 0), with the no_std-safe floor.
    let round = |x: f32| math::floor(x + 0.5) as u32;
    let pad = UVec2::new(
        round(fraction * desc.width as f32),
        round(fraction * desc.height as f32),
    );
    if pad == UVec2::ZERO {
        return (*desc, pad);
    }
    let height = desc.height + 2 * pad.y;
    let scale = height as f32 / desc.height as f32;
    let tan_half = math::tan(0.5 * desc.fov_y) * scale;
    let fov_y = 2.0 * math::atan2(tan_half, 1.0);
    (
        CameraDesc {
            width: desc.width + 2 * pad.x,
            height,
            fov_y,
            ..*desc
        },
        pad,
    )
}

/// The most planes a ray-plane lookup tests (the GPU keeps them in a small uniform array).
pub const MAX_PLANES: usize = 8;
/// The most seeds `K` of [`NearbyLookup::Seeded`].
pub const MAX_SEEDS: u32 = 64;
/// The most iterations of [`NearbyLookup::Iterative`] and [`NearbyLookup::Seeded`].
pub const MAX_ITERATIONS: u32 = 32;

/// The plane `{x : n · x = d}` standing for a nearby object in the ray-plane lookup (§4.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Unit normal (either orientation).
    pub normal: Vec3,
    /// `n · x` of its points.
    pub offset: f32,
}

impl Plane {
    /// The plane through `point` with unit normal `normal`.
    pub fn through(point: Vec3, normal: Vec3) -> Self {
        Self {
            normal,
            offset: normal.dot(point),
        }
    }

    /// The ray parameter `t > 0` where `origin + t dir` meets the plane,
    /// `t = (d − n·o) / (n·dir)`; `None` for rays parallel to it or meeting it behind `origin`.
    ///
    /// ```
    /// use glam::Vec3;
    /// use refract_core::nearby_geometry::Plane;
    /// let floor = Plane::through(Vec3::new(0.0, -1.0, 0.0), Vec3::Y);
    /// assert_eq!(floor.intersect(Vec3::ZERO, -Vec3::Y), Some(1.0));
    /// assert_eq!(floor.intersect(Vec3::ZERO, Vec3::Y), None);
    /// ```
    #[inline]
    pub fn intersect(&self, origin: Vec3, dir: Vec3) -> Option<f32> {
        let denom = self.normal.dot(dir);
        let t = (self.offset - self.normal.dot(origin)) / denom;
        (denom != 0.0 && t > 0.0 && t.is_finite()).then_some(t)
    }
}

/// The nearest plane hit `t > 0` of `origin + t dir` among `planes` (§4.2).
#[inline]
pub fn nearest_plane_hit(planes: &[Plane], origin: Vec3, dir: Vec3) -> Option<f32> {
    planes
        .iter()
        .filter_map(|p| p.intersect(origin, dir))
        .min_by(f32::total_cmp)
}

/// How the seeds of [`NearbyLookup::Seeded`] are spread over the ray segment inside the NG
/// camera's view. §4.3 leaves it open; the feature-size argument of Fig. 9 (screen length / K)
/// holds for [`SeedSpacing::Screen`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SeedSpacing {
    /// Evenly in screen space (evenly in `1/depth`): seed `i` at screen fraction
    /// `s = (i + ½)/K` of the segment's projection.
    #[default]
    Screen,
    /// Evenly in world distance `α` along the ray.
    World,
}

/// Which lookup a nearby-geometry method does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NearbyLookup {
    /// Wyman 2005b §4.1: the texel under `P~2`.
    KayGreenberg,
    /// §4.2: the texel under the nearest plane hit.
    RayPlane,
    /// §4.3 (Ohbuchi): the plane hit refined `iterations` times.
    Iterative {
        /// Distance updates at most (1..=[`MAX_ITERATIONS`]).
        iterations: u32,
    },
    /// §4.3: the best of `seeds` samples, refined `iterations` times.
    Seeded {
        /// Distance updates at most (0..=[`MAX_ITERATIONS`]).
        iterations: u32,
        /// `K`, samples along the ray (1..=[`MAX_SEEDS`]).
        seeds: u32,
        /// Where the samples go.
        spacing: SeedSpacing,
    },
}

/// What the NG texture stores per texel for the lookups: the nearest opaque surface the NG pass
/// saw there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearbySurface {
    /// World position (the lookups' `S`).
    pub p_ws: Vec3,
    /// Its view depth in the NG camera, `(p_ws − eye) · look` (the NG z-buffer of §4.3,
    /// linear, as a float target stores it).
    pub depth: f32,
}

/// The NG texture as the lookups read it: per texel the nearest opaque surface the NG pass
/// saw, or `None` where it saw nothing (the environment).
pub trait NearbyGeometryTexture {
    /// The surface at texel `(x, y)` (inside the texture; the lookups check bounds).
    fn surface(&self, texel: UVec2) -> Option<NearbySurface>;

    /// [`Self::surface`] at eight texels `(x[i], y[i])`, for the lanes set in `read` (each
    /// inside the texture); the other lanes are not read and come back not found. The lane
    /// lookups ([`crate::nearby_geometry_x8`]) read through this; the default reads lane by
    /// lane.
    #[inline]
    fn surfaces_x8(&self, x: I32x8, y: I32x8, read: Mask) -> NearbySurfaceLanes {
        let (x, y, read) = (x.to_array(), y.to_array(), read.to_bitmask());
        let mut p = [[0.0; LANES]; 3];
        let mut depth = [0.0; LANES];
        let mut found = [false; LANES];
        for i in 0..LANES {
            if read & (1 << i) == 0 {
                continue;
            }
            if let Some(s) = self.surface(UVec2::new(x[i] as u32, y[i] as u32)) {
                (p[0][i], p[1][i], p[2][i]) = (s.p_ws.x, s.p_ws.y, s.p_ws.z);
                depth[i] = s.depth;
                found[i] = true;
            }
        }
        NearbySurfaceLanes {
            p_ws: Vec3x8 {
                x: F32x8::new(p[0]),
                y: F32x8::new(p[1]),
                z: F32x8::new(p[2]),
            },
            depth: F32x8::new(depth),
            found: mask_from_lanes(found),
        }
    }
}

/// Eight reads of the NG texture ([`NearbyGeometryTexture::surfaces_x8`]).
#[derive(Clone, Copy, Debug)]
pub struct NearbySurfaceLanes {
    /// [`NearbySurface::p_ws`] per lane (unspecified where not found).
    pub p_ws: Vec3x8,
    /// [`NearbySurface::depth`] per lane (unspecified where not found).
    pub depth: F32x8,
    /// The lanes read whose texel holds a surface.
    pub found: Mask,
}

/// Where a lookup found nearby geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearbyHit {
    /// The NG texel whose colour the pixel shows.
    pub texel: UVec2,
    /// The surface stored there: the method's `P_geom`.
    pub p_geom: Vec3,
}

/// The outcome of a lookup: a hit, or a miss (the pixel shows the environment along `T~2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearbyResult {
    /// The texel found, `None` for a miss.
    pub hit: Option<NearbyHit>,
    /// Distance updates done (iterative lookups; 0 otherwise).
    pub iterations: u32,
    /// The iteration reached a fixed point: the same texel twice in a row. Lookups that do not
    /// iterate report `true` for a hit.
    pub converged: bool,
}

impl NearbyResult {
    /// No geometry found.
    pub const MISS: Self = Self {
        hit: None,
        iterations: 0,
        converged: false,
    };
}

/// The NG texel under `p_ws`: `floor` of its pixel position in `camera` when it lies in front of
/// the eye, between the near and far planes and inside the texture; `None` otherwise.
#[inline]
pub fn texel_of(camera: &Camera, p_ws: Vec3) -> Option<UVec2> {
    let q = camera.world_to_pixel(p_ws)?;
    let (w, h) = (camera.width() as f32, camera.height() as f32);
    let inside = q.x >= 0.0 && q.x < w && q.y >= 0.0 && q.y < h && q.z >= 0.0 && q.z <= 1.0;
    inside.then(|| UVec2::new(q.x as u32, q.y as u32))
}

/// The view depth of `p_ws` in `camera` (distance along the look direction; > 0 in front).
#[inline]
pub fn view_depth(camera: &Camera, p_ws: Vec3) -> f32 {
    (p_ws - camera.eye()).dot(camera.look_dir())
}

/// The ray `origin + t dir` in a camera's clip space, `clip(t) = c0 + t c1` (affine in `t`):
/// a point of the ray projects with four multiply-adds and one division, and its view depth is
/// `clip.w` (the perspective projection's `w = −z_view`). One ray (`ClipRay`, glam types) or
/// eight (`ClipRay<Vec3x8>`, [`ClipRay::from_rays`]); the methods on `ClipRay<V>` are the one
/// body both run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipRay<V: Vector3 = Vec3> {
    origin: V,
    dir: V,
    c0: [V::Real; 4],
    c1: [V::Real; 4],
    width: V::Real,
    height: V::Real,
}

/// The texels under the points of [`ClipRay::texel_lanes`]: their coordinates (whole numbers)
/// and the lanes inside the view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexelLanes<R: Real> {
    /// Column (a whole number where `inside`).
    pub x: R,
    /// Row.
    pub y: R,
    /// Inside the view and its depth range.
    pub inside: R::Mask,
}

impl ClipRay {
    /// The ray `origin + t dir` seen by `camera`.
    #[inline]
    pub fn new(camera: &Camera, origin: Vec3, dir: Vec3) -> Self {
        let m = camera.world_to_clip();
        Self {
            origin,
            dir,
            c0: (m * origin.extend(1.0)).to_array(),
            c1: (m * dir.extend(0.0)).to_array(),
            width: camera.width() as f32,
            height: camera.height() as f32,
        }
    }

    /// `(c0, c1)` of `clip(t) = c0 + t c1`.
    #[inline]
    pub fn clip(&self) -> (Vec4, Vec4) {
        (Vec4::from_array(self.c0), Vec4::from_array(self.c1))
    }

    /// The pixel position and window depth of the point at `t` (as
    /// [`Camera::world_to_pixel`]), `None` on or behind the eye plane.
    #[inline]
    pub fn pixel(&self, t: f32) -> Option<Vec3> {
        let (x, y, z, in_front) = self.pixel_lanes(t);
        in_front.then(|| Vec3::new(x, y, z))
    }

    /// The texel under the point at `t` ([`texel_of`]).
    #[inline]
    pub fn texel(&self, t: f32) -> Option<UVec2> {
        let texel = self.texel_lanes(t);
        texel
            .inside
            .then(|| UVec2::new(texel.x as u32, texel.y as u32))
    }

    /// The part `[t0, t1]`, `t ≥ 0`, inside the view frustum ([`frustum_segment`]).
    pub fn segment(&self) -> Option<(f32, f32)> {
        let (t0, t1, ok) = self.segment_lanes(true);
        ok.then_some((t0, t1))
    }

    /// The ray parameter of seed `i` of `k` over `segment` ([`seed_parameter`]).
    #[inline]
    pub fn seed(&self, segment: (f32, f32), i: u32, k: u32, spacing: SeedSpacing) -> f32 {
        self.seed_lanes(segment, i, k, spacing)
    }
}

impl ClipRay<Vec3x8> {
    /// Eight rays as lanes: `rays[i]` is the ray `origin + t dir` of lane `i` (as lanes too).
    pub fn from_rays(rays: &[ClipRay; LANES], origin: Vec3x8, dir: Vec3x8) -> Self {
        let (mut c0, mut c1) = ([[0.0; LANES]; 4], [[0.0; LANES]; 4]);
        for (i, ray) in rays.iter().enumerate() {
            for k in 0..4 {
                (c0[k][i], c1[k][i]) = (ray.c0[k], ray.c1[k]);
            }
        }
        Self {
            origin,
            dir,
            c0: c0.map(F32x8::new),
            c1: c1.map(F32x8::new),
            width: F32x8::splat(rays[0].width),
            height: F32x8::splat(rays[0].height),
        }
    }
}

impl<V: Vector3> ClipRay<V> {
    /// The point at `t`.
    #[inline]
    pub fn at(&self, t: V::Real) -> V {
        self.origin + self.dir * t
    }

    /// The view depth of the point at `t`: `c0.w + t c1.w`.
    #[inline]
    pub fn depth(&self, t: V::Real) -> V::Real {
        self.c0[3] + t * self.c1[3]
    }

    /// `(u_px, v_px, z/w)` of the point at `t` and the lanes in front of the eye (`w > 0`, false
    /// for NaN): `(½(x/w + 1)·W, ½(1 − y/w)·H)`.
    #[inline]
    pub fn pixel_lanes(&self, t: V::Real) -> (V::Real, V::Real, V::Real, Msk<V>) {
        let clip = |k: usize| self.c0[k] + t * self.c1[k];
        let w = clip(3);
        let rcp_w = V::Real::ONE / w;
        let (ndc_x, ndc_y, ndc_z) = (clip(0) * rcp_w, clip(1) * rcp_w, clip(2) * rcp_w);
        let (half, one) = (V::Real::splat(0.5), V::Real::ONE);
        let u_px = half * (ndc_x + one) * self.width;
        let v_px = half * (one - ndc_y) * self.height;
        (u_px, v_px, ndc_z, w.gt(V::Real::ZERO))
    }

    /// The texel under the point at `t`: the floor of its pixel position, inside where `w > 0`,
    /// `0 ≤ x < W`, `0 ≤ y < H` and `0 ≤ z ≤ 1` (NaN: outside).
    #[inline]
    pub fn texel_lanes(&self, t: V::Real) -> TexelLanes<V::Real> {
        let (q_x, q_y, q_z, in_front) = self.pixel_lanes(t);
        let zero = V::Real::ZERO;
        let inside = in_front
            & q_x.ge(zero)
            & q_x.lt(self.width)
            & q_y.ge(zero)
            & q_y.lt(self.height)
            & q_z.ge(zero)
            & q_z.le(V::Real::ONE);
        TexelLanes {
            x: q_x.floor(),
            y: q_y.floor(),
            inside,
        }
    }

    /// The clip-space Liang–Barsky clip of `t ≥ 0` against `−w ≤ x, y ≤ w` and `0 ≤ z ≤ w`,
    /// each constraint `a0 + t a1 ≥ 0`: `(t0, t1)` and the lanes of `live` where the segment
    /// exists (finite, `t0 < t1`).
    #[inline]
    pub fn segment_lanes(&self, live: Msk<V>) -> (V::Real, V::Real, Msk<V>) {
        let (c0, c1) = (&self.c0, &self.c1);
        let constraints = [
            (c0[3] + c0[0], c1[3] + c1[0]),
            (c0[3] - c0[0], c1[3] - c1[0]),
            (c0[3] + c0[1], c1[3] + c1[1]),
            (c0[3] - c0[1], c1[3] - c1[1]),
            (c0[2], c1[2]),
            (c0[3] - c0[2], c1[3] - c1[2]),
        ];
        // The far end is bounded by the far plane when the ray heads away from the eye; rays
        // heading back toward the camera leave through the near plane or a side, so t stays
        // finite.
        let zero = V::Real::ZERO;
        let (mut t0, mut t1) = (zero, V::Real::splat(f32::INFINITY));
        let mut ok = live;
        for (a0, a1) in constraints {
            // Parallel to this plane: inside everywhere or nowhere (NaN: nowhere).
            ok = ok & !(a1.eq(zero) & !a0.ge(zero));
            let t = -a0 / a1;
            t0 = V::Real::select(a1.gt(zero), t0.max(t), t0);
            t1 = V::Real::select(a1.lt(zero), t1.min(t), t1);
        }
        let ok = ok & t0.is_finite() & t1.is_finite() & t0.lt(t1);
        (t0, t1, ok)
    }

    /// The ray parameter of seed `i` of `k` over the segment `(t0, t1)`: at fraction
    /// `s = (i + ½)/k` in `α` or, for [`SeedSpacing::Screen`], on screen
    /// ([`screen_fraction_to_segment`]).
    #[inline]
    pub fn seed_lanes(
        &self,
        (t0, t1): (V::Real, V::Real),
        i: u32,
        k: u32,
        spacing: SeedSpacing,
    ) -> V::Real {
        let s = V::Real::splat((i as f32 + 0.5) / k as f32);
        let lambda = match spacing {
            SeedSpacing::World => s,
            SeedSpacing::Screen => screen_fraction_to_segment(s, self.depth(t0), self.depth(t1)),
        };
        t0 + lambda * (t1 - t0)
    }
}

/// The part `[t0, t1]` of the ray `origin + t dir`, `t ≥ 0`, inside `camera`'s view frustum
/// (between its near and far planes, inside its four sides): clip-space Liang–Barsky against
/// `−w ≤ x, y ≤ w` and `0 ≤ z ≤ w` (WebGPU depth), each linear in `t`. `None` when the ray never
/// enters it. This is the span where the NG texture can hold an answer; §4.3 samples
/// `0 ≤ α ≤ d_far`, which it contains.
pub fn frustum_segment(camera: &Camera, origin: Vec3, dir: Vec3) -> Option<(f32, f32)> {
    ClipRay::new(camera, origin, dir).segment()
}

/// The fraction `λ ∈ [0, 1]` of a segment with view depths `w0` (start) and `w1` (end) whose
/// projection lies at screen fraction `s`: perspective interpolation,
/// `λ = s w0 / ((1 − s) w1 + s w0)`.
///
/// ```
/// use refract_core::nearby_geometry::screen_fraction_to_segment;
/// // A segment from depth 1 to depth 3: halfway on screen is a quarter of the way in space.
/// assert_eq!(screen_fraction_to_segment(0.5, 1.0, 3.0), 0.25);
/// ```
#[inline]
pub fn screen_fraction_to_segment<R: Real>(s: R, w0: R, w1: R) -> R {
    let denom = (R::ONE - s) * w1 + s * w0;
    R::select(denom.gt(R::ZERO), s * w0 / denom, s)
}

/// The ray parameter of seed `i` of `k` over the segment `[t0, t1]` of `origin + t dir`
/// (§4.3: `P~2 + α_i T~2`): at fraction `(i + ½)/k` in screen space or in `α`.
#[inline]
pub fn seed_parameter(
    camera: &Camera,
    origin: Vec3,
    dir: Vec3,
    segment: (f32, f32),
    i: u32,
    k: u32,
    spacing: SeedSpacing,
) -> f32 {
    ClipRay::new(camera, origin, dir).seed(segment, i, k, spacing)
}

/// The guaranteed feature size of Fig. 9 in NG pixels: the largest screen gap a feature can hide
/// in between the `k` seeds of `spacing` on the ray's segment inside the view — the largest
/// distance between consecutive seeds, and twice the distance from each end of the segment to
/// its nearest seed. A feature at least this long on screen contains a seed. For
/// [`SeedSpacing::Screen`] this is the paper's "screen-space distance T~2 travels … divided by
/// the number of intersections". `None` when the ray never enters the view.
pub fn guaranteed_feature_px(
    camera: &Camera,
    origin: Vec3,
    dir: Vec3,
    k: u32,
    spacing: SeedSpacing,
) -> Option<f32> {
    let ray = ClipRay::new(camera, origin, dir);
    let segment = ray.segment()?;
    let screen = |t: f32| ray.pixel(t).map(|q| q.truncate());
    let (start, end) = (screen(segment.0)?, screen(segment.1)?);
    let mut previous = start;
    let mut gap = 0.0f32;
    for i in 0..k {
        let seed = screen(ray.seed(segment, i, k, spacing))?;
        let d = (seed - previous).length();
        gap = gap.max(if i == 0 { 2.0 * d } else { d });
        previous = seed;
    }
    Some(gap.max(2.0 * (end - previous).length()))
}

/// Wyman 2005b §4: finds the nearby geometry the ray `p2 + t t2` (unit `t2`) shows, with the
/// NG texture `texture` rendered by `camera` and, for the ray-plane and iterative lookups, the
/// planes standing for the objects.
///
/// - Kay–Greenberg: the texel under `p2`.
/// - Ray-plane: the texel under `p2 + t_plane t2` (a miss without a plane hit).
/// - Iterative: from `t_plane`, `t ← ‖S(t) − p2‖` where `S(t)` is the surface stored at the texel
///   under `p2 + t t2` (the distance form of Ohbuchi's update, no division by `T~2 · view`, so
///   rays leaving sideways or back toward the camera need no special case), until the texel
///   repeats (converged) or after `iterations` updates.
/// - Seeded: the seed with the smallest `|depth(p2 + t_i t2) − depth(S(t_i))|` over the
///   non-empty texels starts the same iteration.
///
/// An empty texel (or a point outside the view, behind the eye or beyond the far plane) where
/// the answer is read is a miss.
pub fn find_nearby<T: NearbyGeometryTexture + ?Sized>(
    camera: &Camera,
    texture: &T,
    planes: &[Plane],
    lookup: NearbyLookup,
    p2: Vec3,
    t2: Vec3,
) -> NearbyResult {
    let ray = ClipRay::new(camera, p2, t2);
    let lookup_at = |t: f32| -> Option<(UVec2, NearbySurface)> {
        let texel = ray.texel(t)?;
        Some((texel, texture.surface(texel)?))
    };
    let single = |found: Option<(UVec2, NearbySurface)>| NearbyResult {
        hit: found.map(|(texel, s)| NearbyHit {
            texel,
            p_geom: s.p_ws,
        }),
        iterations: 0,
        converged: found.is_some(),
    };
    match lookup {
        NearbyLookup::KayGreenberg => single(lookup_at(0.0)),
        NearbyLookup::RayPlane => single(nearest_plane_hit(planes, p2, t2).and_then(lookup_at)),
        NearbyLookup::Iterative { iterations } => match nearest_plane_hit(planes, p2, t2) {
            None => NearbyResult::MISS,
            Some(t) => iterate(&lookup_at, p2, t, iterations),
        },
        NearbyLookup::Seeded {
            iterations,
            seeds,
            spacing,
        } => {
            let Some(segment) = ray.segment() else {
                return NearbyResult::MISS;
            };
            let mut best: Option<(f32, f32)> = None;
            for i in 0..seeds {
                let t = ray.seed(segment, i, seeds, spacing);
                if let Some((_, surface)) = lookup_at(t) {
                    let error = (ray.depth(t) - surface.depth).abs();
                    if best.is_none_or(|(e, _)| error < e) {
                        best = Some((error, t));
                    }
                }
            }
            match best {
                None => NearbyResult::MISS,
                Some((_, t)) => iterate(&lookup_at, p2, t, iterations),
            }
        }
    }
}

/// The distance-form iteration of §4.3 from `p2 + t t2`.
#[inline]
fn iterate(
    lookup_at: &impl Fn(f32) -> Option<(UVec2, NearbySurface)>,
    p2: Vec3,
    t: f32,
    iterations: u32,
) -> NearbyResult {
    let Some(mut hit) = lookup_at(t) else {
        return NearbyResult::MISS;
    };
    let result = |(texel, s): (UVec2, NearbySurface), iterations, converged| NearbyResult {
        hit: Some(NearbyHit {
            texel,
            p_geom: s.p_ws,
        }),
        iterations,
        converged,
    };
    for k in 0..iterations {
        let t = (hit.1.p_ws - p2).length();
        let Some(next) = lookup_at(t) else {
            return NearbyResult {
                iterations: k + 1,
                ..NearbyResult::MISS
            };
        };
        let repeated = next.0 == hit.0;
        hit = next;
        if repeated {
            return result(hit, k + 1, true);
        }
    }
    result(hit, iterations, false)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraDesc;

    /// An analytic NG texture: a wall `z = z_wall` seen by `camera`, empty outside `|x| < half`.
    struct Wall<'a> {
        camera: &'a Camera,
        z_wall: f32,
        half: f32,
    }

    impl NearbyGeometryTexture for Wall<'_> {
        fn surface(&self, texel: UVec2) -> Option<NearbySurface> {
            let ray = self
                .camera
                .pixel_ray(Camera::pixel_center(texel.x, texel.y));
            let t = (self.z_wall - ray.origin.z) / ray.dir.z;
            let p = ray.at(t);
            (t > 0.0 && p.x.abs() < self.half).then(|| NearbySurface {
                p_ws: p,
                depth: view_depth(self.camera, p),
            })
        }
    }

    fn camera() -> Camera {
        Camera::new(CameraDesc {
            width: 128,
            height: 128,
            eye: Vec3::new(0.0, 0.0, 3.0),
            target: Vec3::ZERO,
            near: 0.1,
            far: 20.0,
            ..CameraDesc::default()
        })
        .expect("camera")
    }

    #[test]
    fn guard_band_texels_are_screen_pixels() {
        let desc = CameraDesc {
            width: 96,
            height: 64,
            ..CameraDesc::default()
        };
        let (ng_desc, pad) = guard_band_camera(&desc, 25);
        let (eye, ng) = (
            Camera::new(desc).expect("eye"),
            Camera::new(ng_desc).expect("ng"),
        );
        for p in [
            Vec3::ZERO,
            Vec3::new(0.4, -0.3, 0.2),
            Vec3::new(-0.7, 0.5, -1.0),
        ] {
            let a = eye.world_to_pixel(p).expect("in front");
            let b = ng.world_to_pixel(p).expect("in front");
            let offset = b.truncate() - a.truncate();
            assert!(
                (offset - pad.as_vec2()).abs().max_element() < 1e-3,
                "{offset}"
            );
        }
    }

    #[test]
    fn plane_hits_are_nearest_and_in_front() {
        let planes = [
            Plane::through(Vec3::new(0.0, 0.0, -2.0), Vec3::Z),
            Plane::through(Vec3::new(0.0, 0.0, -1.0), -Vec3::Z),
            Plane::through(Vec3::new(0.0, 0.0, 5.0), Vec3::Z),
        ];
        assert_eq!(nearest_plane_hit(&planes, Vec3::ZERO, -Vec3::Z), Some(1.0));
        assert_eq!(nearest_plane_hit(&planes, Vec3::ZERO, Vec3::Z), Some(5.0));
        assert_eq!(nearest_plane_hit(&planes, Vec3::ZERO, Vec3::X), None);
    }

    #[test]
    fn frustum_segment_ends_on_the_far_plane_and_near_plane() {
        let cam = camera();
        // Straight ahead from the eye: from the near plane to the far plane.
        let (t0, t1) = frustum_segment(&cam, cam.eye(), -Vec3::Z).expect("inside");
        assert!(
            (t0 - 0.1).abs() < 1e-5 && (t1 - 20.0).abs() < 1e-3,
            "{t0} {t1}"
        );
        // Back toward the camera from the origin: ends at the near plane.
        let (t0, t1) = frustum_segment(&cam, Vec3::ZERO, Vec3::Z).expect("inside");
        assert!(t0 == 0.0 && (t1 - 2.9).abs() < 1e-4, "{t0} {t1}");
        // Sideways out of the view.
        let (_, t1) = frustum_segment(&cam, Vec3::ZERO, Vec3::X).expect("inside");
        let edge = Vec3::X * t1;
        let q = cam.world_to_pixel(edge).expect("in front");
        assert!((q.x - 128.0).abs() < 1e-2, "{q}");
        // Behind the eye, looking away: never inside.
        assert_eq!(
            frustum_segment(&cam, Vec3::new(0.0, 0.0, 4.0), Vec3::Z),
            None
        );
    }

    #[test]
    fn screen_spaced_seeds_are_evenly_spaced_on_screen() {
        let cam = camera();
        let (p2, t2) = (
            Vec3::new(0.0, 0.0, 0.5),
            Vec3::new(0.3, 0.0, -1.0).normalize(),
        );
        let segment = frustum_segment(&cam, p2, t2).expect("inside");
        let k = 7;
        let xs: Vec<f32> = (0..k)
            .map(|i| {
                let t = seed_parameter(&cam, p2, t2, segment, i, k, SeedSpacing::Screen);
                cam.world_to_pixel(p2 + t * t2).expect("in view").x
            })
            .collect();
        let steps: Vec<f32> = xs.windows(2).map(|w| w[1] - w[0]).collect();
        for s in &steps {
            assert!((s - steps[0]).abs() < 1e-2 * steps[0].abs(), "{steps:?}");
        }
        // World spacing crowds the screen near P~2: its first step on screen is the largest.
        let world: Vec<f32> = (0..k)
            .map(|i| {
                let t = seed_parameter(&cam, p2, t2, segment, i, k, SeedSpacing::World);
                cam.world_to_pixel(p2 + t * t2).expect("in view").x
            })
            .collect();
        assert!(
            world[1] - world[0] > 2.0 * (world[6] - world[5]),
            "{world:?}"
        );
    }

    #[test]
    fn lookups_on_a_wall_find_it_and_iteration_converges() {
        let cam = camera();
        let wall = Wall {
            camera: &cam,
            z_wall: -2.0,
            half: 10.0,
        };
        let planes = [Plane::through(Vec3::new(0.0, 0.0, -2.0), Vec3::Z)];
        let (p2, t2) = (
            Vec3::new(0.2, 0.0, 0.0),
            Vec3::new(0.4, 0.1, -1.0).normalize(),
        );
        let exact = p2 + planes[0].intersect(p2, t2).expect("hit") * t2;
        let exact_texel = texel_of(&cam, exact).expect("in view");
        for lookup in [
            NearbyLookup::RayPlane,
            NearbyLookup::Iterative { iterations: 5 },
            NearbyLookup::Seeded {
                iterations: 5,
                seeds: 7,
                spacing: SeedSpacing::Screen,
            },
        ] {
            let r = find_nearby(&cam, &wall, &planes, lookup, p2, t2);
            let hit = r.hit.expect("hit");
            assert!(
                (hit.texel.as_ivec2() - exact_texel.as_ivec2())
                    .abs()
                    .max_element()
                    <= 1,
                "{lookup:?}: {:?} vs {exact_texel}",
                hit.texel
            );
            assert!(r.converged, "{lookup:?}");
        }
        // Kay–Greenberg reads the wall behind P~2, not where the ray goes.
        let kg = find_nearby(&cam, &wall, &planes, NearbyLookup::KayGreenberg, p2, t2);
        let kg_texel = kg.hit.expect("the wall is behind P~2").texel;
        assert!(
            (kg_texel.as_ivec2() - exact_texel.as_ivec2())
                .abs()
                .max_element()
                > 3
        );
    }

    #[test]
    fn iterative_misses_what_seeding_finds() {
        // A narrow wall off to the side, with its plane far behind it: the plane hit lands on
        // empty texels (Ohbuchi's miss), the seeds find the wall.
        let cam = camera();
        let wall = Wall {
            camera: &cam,
            z_wall: -1.0,
            half: 0.6,
        };
        let planes = [Plane::through(Vec3::new(0.0, 0.0, -8.0), Vec3::Z)];
        let (p2, t2) = (Vec3::ZERO, Vec3::new(0.35, 0.0, -1.0).normalize());
        let iterative = find_nearby(
            &cam,
            &wall,
            &planes,
            NearbyLookup::Iterative { iterations: 5 },
            p2,
            t2,
        );
        assert_eq!(iterative.hit, None);
        let seeded = find_nearby(
            &cam,
            &wall,
            &planes,
            NearbyLookup::Seeded {
                iterations: 5,
                seeds: 7,
                spacing: SeedSpacing::Screen,
            },
            p2,
            t2,
        );
        let hit = seeded.hit.expect("seeded finds the wall");
        assert!((hit.p_geom.z + 1.0).abs() < 1e-4);
        let exact = p2 + t2 * (1.0 / -t2.z);
        assert!((hit.p_geom - exact).length() < 0.05, "{hit:?} vs {exact}");
    }

    #[test]
    fn clip_rays_project_like_the_camera() {
        let cam = camera();
        let (p, d) = (
            Vec3::new(0.3, -0.2, 0.5),
            Vec3::new(-0.2, 0.1, -1.0).normalize(),
        );
        let ray = ClipRay::new(&cam, p, d);
        for t in [0.0, 0.5, 2.0, 7.5] {
            let a = ray.pixel(t).expect("in front");
            let b = cam.world_to_pixel(p + t * d).expect("in front");
            assert!((a - b).abs().max_element() < 1e-3, "{a} vs {b}");
            assert!((ray.depth(t) - view_depth(&cam, p + t * d)).abs() < 1e-4);
            assert_eq!(ray.texel(t), texel_of(&cam, p + t * d));
        }
    }

    #[test]
    fn points_outside_the_view_are_empty() {
        let cam = camera();
        assert_eq!(texel_of(&cam, Vec3::new(0.0, 0.0, 5.0)), None, "behind");
        assert_eq!(texel_of(&cam, Vec3::new(100.0, 0.0, 0.0)), None, "outside");
        assert_eq!(
            texel_of(&cam, Vec3::new(0.0, 0.0, -30.0)),
            None,
            "beyond far"
        );
        assert!(texel_of(&cam, Vec3::ZERO).is_some());
    }

    #[test]
    fn feature_size_divides_the_screen_length_by_k() {
        let cam = camera();
        let screen = SeedSpacing::Screen;
        // A ray straight away from the eye projects to one point.
        let along = guaranteed_feature_px(&cam, Vec3::ZERO, -Vec3::Z, 7, screen).expect("in view");
        assert!(along < 1e-3, "{along}");
        let side = guaranteed_feature_px(&cam, Vec3::ZERO, Vec3::X, 7, screen).expect("in view");
        assert!((side - 64.0 / 7.0).abs() < 1e-2, "{side}");
        // Away from the camera and sideways: world spacing leaves a larger gap on screen.
        let dir = Vec3::new(0.3, 0.0, -1.0).normalize();
        let p = Vec3::new(0.0, 0.0, 1.0);
        let s = guaranteed_feature_px(&cam, p, dir, 7, screen).expect("in view");
        let w = guaranteed_feature_px(&cam, p, dir, 7, SeedSpacing::World).expect("in view");
        assert!(w > 1.5 * s, "world {w} vs screen {s}");
    }
}
