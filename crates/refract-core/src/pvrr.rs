//! Kakimoto et al. 2007, per-vertex reflection and refraction (PVRR): the geometry of one
//! reflection (or refraction) map.
//!
//! Per frame and per reflector, every vertex's exact ray is traced (by the caller, with a BVH:
//! §3.1 step 3.1); from those rays this module finds the **virtual viewpoint** nearest to all
//! their lines (§3.2), the **view volume** of the map rendered from it (§3.3), and each
//! vertex's **texture coordinates**, the projection of its ray's end into that map (§3.4).
//! Drawn with those coordinates interpolated perspective-correctly, the reflector shows at
//! every vertex exactly what its ray hits, and between vertices the map's view from the
//! virtual viewpoint.
//!
//! Texture coordinates here are map **pixel** positions (`(0, 0)` the top-left corner, texel
//! centres at `i + 0.5`), not `[0, 1]`: maps have the aspect of their view volume.

use glam::{DMat3, DVec3, Vec2, Vec3};

use crate::camera::{Camera, CameraDesc, CameraError};
use crate::lanes::{Mask, Vec2x8, Vec3x8};
use crate::real::{Real, Vector3};

/// Where a vertex's exact ray ends: a scene point, or a direction to the environment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RayEnd {
    /// The nearest scene intersection `P` (§3.1 step 3.1).
    Hit(Vec3),
    /// The ray leaves the scene along this unit direction (a point at infinity: its map
    /// position is the direction's projection from the viewpoint).
    Escape(Vec3),
}

/// One vertex's exact ray after the reflector: the line it leaves along and where it ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexRay {
    /// Where the ray leaves the reflector (the vertex of a mirror, the back-surface exit
    /// point of a lens).
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
    /// Where it ends.
    pub end: RayEnd,
}

/// A vertex's state in a map (the per-vertex code both backends interpolate; a pixel whose
/// triangle has a vertex in any state but [`STATE_MAPPED`] is not looked up).
pub const STATE_MAPPED: u32 = 0;
/// The ray's end lies outside the map: in the "zooming region" between a concave mirror (or
/// a convex lens) and the virtual viewpoint, which the paper leaves out (§4.2, Fig. 8), or
/// outside the widest field of view a map may have.
pub const STATE_ZOOM: u32 = 1;
/// The lens ray has no exit (still inside after [`MAX_INTERNAL_BOUNCES`] total internal
/// reflections, or the back surface was not found).
pub const STATE_TRAPPED: u32 = 2;
/// The map was not rendered: the reflector is seen at the last level of the stack (§4.4).
pub const STATE_DEPTH: u32 = 3;

/// Total internal reflections a lens ray may take inside before it counts as trapped.
pub const MAX_INTERNAL_BOUNCES: u32 = 8;

/// The widest half field of view of a map (either axis): rays beyond it are [`STATE_ZOOM`].
pub const MAX_HALF_FOV: f32 = 80.0 * core::f32::consts::PI / 180.0;

/// The near plane never comes closer to the viewpoint than this fraction of the scene radius
/// (the reversed-region maps of concave mirrors and convex lenses, where the reflector lies
/// behind the viewpoint).
pub const NEAR_FLOOR: f32 = 1e-3;

/// §3.2: the point `c` nearest, in least squares, to every line `(p, d)` (`d` unit):
/// `[Σ (I − d dᵀ)] c = Σ (I − d dᵀ) p`, solved in `f64`. `None` when the system is singular
/// (fewer than two lines, or all of them parallel: the determinant below `1e-9` of the cube
/// of the mean eigenvalue). A planar mirror's reflected lines all pass through the mirrored
/// eye, which is then the exact solution.
pub fn virtual_viewpoint(lines: impl IntoIterator<Item = (Vec3, Vec3)>) -> Option<Vec3> {
    let mut a = DMat3::ZERO;
    let mut b = DVec3::ZERO;
    let mut count = 0usize;
    for (p, d) in lines {
        let (p, d) = (p.as_dvec3(), d.as_dvec3());
        let m = DMat3::IDENTITY - DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        a += m;
        b += m * p;
        count += 1;
    }
    let scale = (a.x_axis.x + a.y_axis.y + a.z_axis.z) / 3.0;
    let det = a.determinant();
    if count < 2
        || scale.is_nan()
        || scale <= 0.0
        || det.is_nan()
        || det <= 1e-9 * scale * scale * scale
    {
        return None;
    }
    let c = a.inverse() * b;
    c.is_finite().then(|| c.as_vec3())
}

/// The viewpoint when [`virtual_viewpoint`] has no solution (parallel rays: a view from
/// infinitely far): the centroid of the ray origins moved back along the mean direction by
/// `100 ×` their spread (at least `100 ×` `scale`).
pub fn parallel_viewpoint(rays: &[VertexRay], scale: f32) -> Option<Vec3> {
    let n = rays.len() as f32;
    if rays.is_empty() {
        return None;
    }
    let centroid = rays.iter().map(|r| r.origin).sum::<Vec3>() / n;
    let dir = mean_direction(rays)?;
    let spread = rays
        .iter()
        .map(|r| r.origin.distance(centroid))
        .fold(scale, f32::max);
    Some(centroid - dir * (100.0 * spread))
}

/// §3.3: the viewing direction, the normalised mean of the ray directions.
pub fn mean_direction(rays: &[VertexRay]) -> Option<Vec3> {
    rays.iter().map(|r| r.dir).sum::<Vec3>().try_normalize()
}

/// The scene a map must contain: an axis-aligned box (the far plane contains it, §3.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneBounds {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl SceneBounds {
    /// Half the diagonal.
    pub fn radius(&self) -> f32 {
        0.5 * (self.max - self.min).length()
    }

    fn farthest_along(&self, origin: Vec3, dir: Vec3) -> f32 {
        let mut far = f32::NEG_INFINITY;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            );
            far = far.max((corner - origin).dot(dir));
        }
        far
    }
}

/// Why a map's view volume could not be built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ViewVolumeError {
    /// No ray of the reflector ends inside any map from the viewpoint (every end is in the
    /// zooming region or behind the viewpoint).
    NoMappedRay,
    /// The camera of the volume was rejected (degenerate numbers).
    Camera(CameraError),
}

impl core::fmt::Display for ViewVolumeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NoMappedRay => write!(
                f,
                "no per-vertex ray ends inside a map from the virtual viewpoint"
            ),
            Self::Camera(err) => write!(f, "map camera: {err}"),
        }
    }
}

impl core::error::Error for ViewVolumeError {}

/// The view volume of one map (§3.3) and the camera that renders it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewVolume {
    /// The map camera: eye at the virtual viewpoint, symmetric frustum around its axis.
    pub camera: Camera,
    /// Near plane: just beyond the reflector's farthest vertex along the axis (which excludes
    /// the reflector and everything behind it), but before the nearest vertex hit, and at
    /// least [`NEAR_FLOOR`] × the scene radius.
    pub near: f32,
}

/// An orthonormal frame `(u, v)` across `w` (`u` horizontal when `w` is not vertical).
fn across(w: Vec3) -> (Vec3, Vec3) {
    let up = if w.y.abs() < 0.99 { Vec3::Y } else { Vec3::Z };
    let u = w.cross(up).normalize();
    (u, u.cross(w))
}

/// The near plane along `w` from `c`: just beyond every reflector vertex (§3.3), pulled in
/// to just before the nearest hit in front of the viewpoint so that every vertex's hit is in
/// the map (a tilted mirror's nearer edge reflects points nearer than its farther edge); never
/// nearer than `floor`.
fn near_plane(c: Vec3, w: Vec3, reflector: &[Vec3], ends: &[RayEnd], floor: f32) -> f32 {
    let farthest = reflector
        .iter()
        .map(|p| (*p - c).dot(w))
        .fold(f32::NEG_INFINITY, f32::max);
    let nearest_hit = ends
        .iter()
        .filter_map(|e| match e {
            RayEnd::Hit(p) => Some((*p - c).dot(w)),
            RayEnd::Escape(_) => None,
        })
        .filter(|z| *z >= floor)
        .fold(f32::INFINITY, f32::min);
    let beyond = farthest + 1e-3 * floor.max(farthest.abs() * 1e-3);
    beyond.min(0.99 * nearest_hit).max(floor)
}

/// A ray end's position on the plane at unit distance along `w` from `c`, in `(u, v)`; `None`
/// when it lies nearer than `near` (or behind `c`) or beyond [`MAX_HALF_FOV`].
fn tangent(c: Vec3, w: Vec3, (u, v): (Vec3, Vec3), near: f32, end: RayEnd) -> Option<Vec2> {
    let limit = crate::math::tan(MAX_HALF_FOV);
    let (offset, z) = match end {
        RayEnd::Hit(p) => {
            let d = p - c;
            let z = d.dot(w);
            if z.is_nan() || z < near {
                return None;
            }
            (d, z)
        }
        RayEnd::Escape(d) => {
            let z = d.dot(w);
            if z.is_nan() || z <= 0.0 {
                return None;
            }
            (d, z)
        }
    };
    let t = Vec2::new(offset.dot(u), offset.dot(v)) / z;
    (t.x.abs() <= limit && t.y.abs() <= limit).then_some(t)
}

/// §3.3: the view volume from viewpoint `c`. The axis starts as `direction` (the mean ray
/// direction) and is re-aimed, three times, at the centre of the ends' angular bounds so that
/// the frustum can be symmetric (our [`Camera`] has symmetric frusta); the near plane lies just
/// beyond the `reflector`'s vertices, the far plane contains `scene`, and the sides contain
/// every ray end `ends` that lies between them, with a margin of one texel: the map holds every
/// vertex's hit (the paper bounds whole ray segments between near and far, a superset that
/// spends texels on what no lookup reads). The longer side of the map has `resolution` texels.
pub fn view_volume(
    c: Vec3,
    direction: Vec3,
    reflector: &[Vec3],
    ends: &[RayEnd],
    scene: SceneBounds,
    resolution: u32,
) -> Result<ViewVolume, ViewVolumeError> {
    let floor = NEAR_FLOOR * scene.radius().max(f32::MIN_POSITIVE);
    let mut w = direction
        .try_normalize()
        .ok_or(ViewVolumeError::NoMappedRay)?;
    let mut bounds = (Vec2::ZERO, Vec2::ZERO);
    for _ in 0..4 {
        let frame = across(w);
        let near = near_plane(c, w, reflector, ends, floor);
        let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
        for t in ends.iter().filter_map(|e| tangent(c, w, frame, near, *e)) {
            lo = lo.min(t);
            hi = hi.max(t);
        }
        if lo.x.is_nan() || lo.x > hi.x {
            return Err(ViewVolumeError::NoMappedRay);
        }
        bounds = (lo, hi);
        let centre = 0.5 * (lo + hi);
        w = (w + centre.x * frame.0 + centre.y * frame.1).normalize();
    }
    // The last re-aiming moved the axis by the centre of the final bounds: measure once more.
    let frame = across(w);
    let near = near_plane(c, w, reflector, ends, floor);
    let mut half = Vec2::ZERO;
    for t in ends.iter().filter_map(|e| tangent(c, w, frame, near, *e)) {
        half = half.max(t.abs());
    }
    if half == Vec2::ZERO && bounds.0.x > bounds.1.x {
        return Err(ViewVolumeError::NoMappedRay);
    }
    let half = half.max(Vec2::splat(1e-4)) * (1.0 + 2.0 / resolution as f32);
    let (width, height) = if half.x >= half.y {
        (
            resolution,
            ((crate::math::floor(resolution as f32 * half.y / half.x + 0.5)) as u32).max(1),
        )
    } else {
        (
            ((crate::math::floor(resolution as f32 * half.x / half.y + 0.5)) as u32).max(1),
            resolution,
        )
    };
    // Rounding the texel counts changes the aspect: widen the vertical extent to keep both.
    let tan_half_y = half.y.max(half.x * height as f32 / width as f32);
    let far = scene.farthest_along(c, w).max(near * 2.0) * 1.01;
    let camera = Camera::new(CameraDesc {
        eye: c,
        target: c + w,
        up: frame.1,
        fov_y: 2.0 * crate::math::atan2(tan_half_y, 1.0),
        near,
        far,
        width,
        height,
        mirror_x: false,
    })
    .map_err(ViewVolumeError::Camera)?;
    Ok(ViewVolume { camera, near })
}

/// §3.4: the map position of a ray's end, the projection of `P` (or of the direction) from
/// the viewpoint; `None` ([`STATE_ZOOM`]) when it lies nearer than the near plane, behind the
/// viewpoint or outside the map.
pub fn texcoord(volume: &ViewVolume, end: RayEnd) -> Option<Vec2> {
    let camera = &volume.camera;
    let c = camera.eye();
    let point = match end {
        RayEnd::Hit(p) => {
            let z = (p - c).dot(camera.look_dir());
            if z.is_nan() || z < volume.near {
                return None;
            }
            p
        }
        RayEnd::Escape(d) => {
            let z = d.dot(camera.look_dir());
            if z.is_nan() || z <= 0.0 {
                return None;
            }
            c + d
        }
    };
    let px = camera.world_to_pixel(point)?.truncate();
    let size = Vec2::new(camera.width() as f32, camera.height() as f32);
    let inside = px.x >= -1e-3 && px.y >= -1e-3 && px.x <= size.x + 1e-3 && px.y <= size.y + 1e-3;
    inside.then_some(px)
}

/// The texels of a map's longer side chosen from its reflector's screen footprint (issue 33:
/// a map needs about as many texels as the pixels that look it up, not a fixed 1024). The
/// footprint is the longer side, in pixels, of the bounding rectangle of `points` (the
/// reflector's vertices) projected by `view` (the view that draws the reflector: the eye, or
/// for a stack the parent map's camera), clipped to `view`'s image; the result is
/// `ceil(footprint · texels_per_pixel)` kept within `range` (inclusive). A point behind `view`'s
/// eye makes the footprint the whole image (the projection of the rest says nothing then).
pub fn footprint_resolution(
    view: &Camera,
    points: &[Vec3],
    texels_per_pixel: f32,
    range: (u32, u32),
) -> u32 {
    let size = Vec2::new(view.width() as f32, view.height() as f32);
    let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for &p in points {
        match view.world_to_pixel(p) {
            Some(px) => {
                lo = lo.min(px.truncate());
                hi = hi.max(px.truncate());
            }
            None => {
                lo = Vec2::ZERO;
                hi = size;
                break;
            }
        }
    }
    let extent = (hi.min(size) - lo.max(Vec2::ZERO)).max(Vec2::ZERO);
    let footprint = extent.x.max(extent.y);
    let texels = -crate::math::floor(-(footprint * texels_per_pixel));
    if texels.is_nan() {
        return range.1;
    }
    (texels.min(range.1 as f32) as u32).clamp(range.0, range.1)
}

/// A rendered map's texels.
pub trait MapTexels {
    /// Width and height in texels.
    fn size(&self) -> (u32, u32);
    /// Radiance of texel `(x, y)` (row-major from the top).
    fn texel(&self, x: u32, y: u32) -> Vec3;
    /// A hint that texel `(x, y)` (inside the map) is about to be read: an implementation may
    /// prefetch its memory. The default does nothing.
    #[inline]
    fn prefetch(&self, _x: u32, _y: u32) {}
}

/// Bilinear lookup of `map` at pixel position `st` (texel centres at `i + 0.5`), clamped to the
/// edge texels: the texture filtering of the paper's second pass.
pub fn sample_bilinear<M: MapTexels + ?Sized>(map: &M, st: Vec2) -> Vec3 {
    sample_bilinear_at(map, st.x, st.y)
}

/// [`sample_bilinear`] at one position `(s, t)` or eight. The footprints (clamp, floor,
/// fractions) are computed on lanes; each lane's four texels are weighed as they are loaded
/// (gathering them into lanes first cost a transpose through memory).
#[inline]
pub fn sample_bilinear_at<M: MapTexels + ?Sized, V: Vector3>(map: &M, s: V::Real, t: V::Real) -> V {
    let (w, h) = map.size();
    let clamp =
        |v: V::Real, size: u32| Real::clamp(v, V::Real::ZERO, V::Real::splat((size - 1) as f32));
    let x = clamp(s - V::Real::splat(0.5), w);
    let y = clamp(t - V::Real::splat(0.5), h);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (x0, y0) = (x0.to_lane_array(), y0.to_lane_array());
    let (fx, fy) = (fx.to_lane_array(), fy.to_lane_array());
    V::gather(|i| {
        let (x0, y0) = (x0.as_ref()[i] as u32, y0.as_ref()[i] as u32);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (fx, fy) = (fx.as_ref()[i], fy.as_ref()[i]);
        let top = map.texel(x0, y0) * (1.0 - fx) + map.texel(x1, y0) * fx;
        let bottom = map.texel(x0, y1) * (1.0 - fx) + map.texel(x1, y1) * fx;
        top * (1.0 - fy) + bottom * fy
    })
}

/// The second pass at one pixel: channel `k` of the map at `st[k]` (one set of coordinates per
/// channel: chromatic aberration with three indices sharing one map, §4.5 Fig. 15), times the
/// reflector's `tint`.
pub fn lookup<M: MapTexels + ?Sized>(map: &M, st: [Vec2; 3], tint: Vec3) -> Vec3 {
    let r = sample_bilinear(map, st[0]);
    if st[1] == st[0] && st[2] == st[0] {
        return r * tint;
    }
    let g = sample_bilinear(map, st[1]);
    let b = sample_bilinear(map, st[2]);
    Vec3::new(r.x, g.y, b.z) * tint
}

/// A mirror's reflectance at one pixel: Schlick's approximation per channel from the
/// conductor's normal-incidence reflectance `f0` (the distance-map method's choice too):
/// `F = F0 + (1 − F0)(1 − |N·V|)⁵`; a perfect mirror (`F0 = 1`) gives 1.
/// One pixel (glam types) or eight lanes.
#[inline]
pub fn mirror_tint<V: Vector3>(f0: Vec3, n: V, v: V) -> V {
    let m = V::Real::ONE - n.dot(v).abs().min(V::Real::ONE);
    let m5 = m * m * m * m * m;
    V::constant(f0) + V::constant(Vec3::ONE - f0) * m5
}

/// [`lookup`] at eight pixels: lane `i` is `lookup(map, [st[0]_i, st[1]_i, st[2]_i], tint_i)`,
/// bit for bit; the second and third channels' lookups are made only when some lane's
/// coordinates differ per channel.
///
/// The lookups wait on memory (a map is megabytes, read along the curves a reflector's rows
/// trace through it), so the texels the next eight pixels of a row will read, extrapolated
/// linearly from these eight lanes' positions, are announced first ([`MapTexels::prefetch`]).
#[inline]
pub fn lookup_x8<M: MapTexels + ?Sized>(map: &M, st: [Vec2x8; 3], tint: Vec3x8) -> Vec3x8 {
    let equal = |a: Vec2x8, b: Vec2x8| a.x.simd_eq(b.x) & a.y.simd_eq(b.y);
    let shared: Mask = equal(st[1], st[0]) & equal(st[2], st[0]);
    prefetch_ahead(map, st[0]);
    if !shared.all() {
        prefetch_ahead(map, st[1]);
        prefetch_ahead(map, st[2]);
    }
    let r: Vec3x8 = sample_bilinear_at(map, st[0].x, st[0].y);
    if shared.all() {
        return r * tint;
    }
    let g: Vec3x8 = sample_bilinear_at(map, st[1].x, st[1].y);
    let b: Vec3x8 = sample_bilinear_at(map, st[2].x, st[2].y);
    let split = Vec3x8 {
        x: r.x,
        y: g.y,
        z: b.z,
    };
    Vec3x8::select(shared, r, split) * tint
}

/// Announces the map rows the next eight pixels' lookups will likely read: lanes 8, 12 and
/// 16 of the line through lane 0 and lane 7's positions (a hint; nothing is read).
#[inline]
fn prefetch_ahead<M: MapTexels + ?Sized>(map: &M, st: Vec2x8) {
    let (w, h) = map.size();
    let (x, y) = (st.x.to_array(), st.y.to_array());
    let (dx, dy) = ((x[7] - x[0]) / 7.0, (y[7] - y[0]) / 7.0);
    for lane in [8.0, 12.0, 16.0] {
        // The texel whose centre is at or left of and above the position, as the lookup's.
        let (px, py) = (x[0] + dx * lane - 0.5, y[0] + dy * lane - 0.5);
        if px >= 0.0 && py >= 0.0 && px < w as f32 && py < h as f32 {
            let (px, py) = (px as u32, py as u32);
            map.prefetch(px, py);
            map.prefetch(px, (py + 1).min(h - 1));
        }
    }
}

/// One vertex of a reflector as both backends draw it: its map position per channel (R, G, B)
/// and its state (`refract-gpu/src/methods/pvrr.wgsl`, `struct PvrrVertex`; the second vertex buffer of the
/// reflector pass).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PvrrVertex {
    /// Map pixel positions of the R, G and B rays.
    pub st: [[f32; 2]; 3],
    /// [`STATE_MAPPED`], [`STATE_ZOOM`], [`STATE_TRAPPED`] or [`STATE_DEPTH`], as a float so
    /// the rasteriser interpolates it: a pixel is looked up only where it interpolates to 0.
    pub state: f32,
    /// Padding to 32 bytes.
    pub _padding: f32,
}

impl PvrrVertex {
    /// A vertex mapped at `st` (one position per channel).
    pub fn mapped(st: [Vec2; 3]) -> Self {
        Self {
            st: st.map(|s| s.to_array()),
            state: STATE_MAPPED as f32,
            _padding: 0.0,
        }
    }

    /// A vertex in `state` (not looked up).
    pub fn unmapped(state: u32) -> Self {
        Self {
            state: state as f32,
            ..Self::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lanes::LANES;

    fn eye_camera(size: u32) -> Camera {
        Camera::new(CameraDesc {
            eye: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: core::f32::consts::FRAC_PI_2,
            near: 0.1,
            far: 100.0,
            width: size,
            height: size,
            mirror_x: false,
        })
        .expect("camera")
    }

    #[test]
    fn footprint_resolution_is_the_projected_extent_times_the_density() {
        let view = eye_camera(1000);
        // A square of side 1 at distance 5 under a 90° field of view: 1/(2·5·tan 45°) = 1/10
        // of the image, 100 pixels.
        let square =
            [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)].map(|(x, y)| Vec3::new(x, y, 0.0));
        let one = footprint_resolution(&view, &square, 1.0, (16, 4096));
        assert!((99..=101).contains(&one), "{one}");
        let two = footprint_resolution(&view, &square, 2.0, (16, 4096));
        assert!((199..=201).contains(&two), "{two}");
        // Clamped to the range.
        assert_eq!(footprint_resolution(&view, &square, 1.0, (128, 4096)), 128);
        assert_eq!(footprint_resolution(&view, &square, 1.0, (16, 64)), 64);
        // Clipped to the image: a huge square covers 1000 pixels, not more.
        let huge = square.map(|p| p * 100.0);
        assert_eq!(footprint_resolution(&view, &huge, 1.0, (16, 4096)), 1000);
        // A point behind the eye: the whole image.
        let behind = [Vec3::ZERO, Vec3::new(0.0, 0.0, 10.0)];
        assert_eq!(footprint_resolution(&view, &behind, 1.0, (16, 4096)), 1000);
        // Nothing projected: the smallest map.
        assert_eq!(footprint_resolution(&view, &[], 1.0, (16, 4096)), 16);
    }

    fn ray(origin: Vec3, dir: Vec3, end: RayEnd) -> VertexRay {
        VertexRay {
            origin,
            dir: dir.normalize(),
            end,
        }
    }

    #[test]
    fn lines_through_one_point_meet_there() {
        let c = Vec3::new(0.3, -1.2, 2.0);
        let lines: Vec<(Vec3, Vec3)> = [Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 1.0), Vec3::Z]
            .iter()
            .map(|d| (c + 3.0 * d.normalize(), d.normalize()))
            .collect();
        let found = virtual_viewpoint(lines).expect("a solution");
        assert!(found.distance(c) < 1e-5, "{found}");
    }

    #[test]
    fn planar_mirror_gives_the_mirrored_eye() {
        // Mirror y = 0, eye above: every reflected line passes through the mirrored eye.
        let eye = Vec3::new(0.2, 1.5, 3.0);
        let mirrored = Vec3::new(eye.x, -eye.y, eye.z);
        let mut lines = Vec::new();
        for i in 0..7 {
            for j in 0..7 {
                let v = Vec3::new(i as f32 * 0.3 - 1.0, 0.0, j as f32 * 0.3 - 1.0);
                let d = crate::optics::reflect((v - eye).normalize(), Vec3::Y);
                lines.push((v, d));
            }
        }
        let found = virtual_viewpoint(lines).expect("a solution");
        assert!(found.distance(mirrored) < 1e-4, "{found} vs {mirrored}");
    }

    #[test]
    fn parallel_lines_are_singular() {
        let lines = (0..5).map(|i| (Vec3::new(i as f32, 0.0, 0.0), Vec3::Z));
        assert_eq!(virtual_viewpoint(lines), None);
        assert_eq!(virtual_viewpoint([(Vec3::ZERO, Vec3::X)]), None);
        let rays: Vec<VertexRay> = (0..5)
            .map(|i| {
                ray(
                    Vec3::new(i as f32, 0.0, 0.0),
                    Vec3::Z,
                    RayEnd::Escape(Vec3::Z),
                )
            })
            .collect();
        let c = parallel_viewpoint(&rays, 1.0).expect("a point");
        assert!(
            (c.z + 100.0 * 2.0).abs() < 1e-3 && (c.x - 2.0).abs() < 1e-5,
            "{c}"
        );
    }

    fn bounds() -> SceneBounds {
        SceneBounds {
            min: Vec3::splat(-10.0),
            max: Vec3::splat(10.0),
        }
    }

    #[test]
    fn every_end_lands_inside_the_map() {
        let c = Vec3::ZERO;
        let ends: Vec<RayEnd> = (0..40)
            .map(|i| {
                let a = i as f32 * 0.37;
                RayEnd::Hit(Vec3::new(a.sin() * 2.0 + 1.0, a.cos() * 0.7, 5.0 + a.sin()))
            })
            .chain([RayEnd::Escape(Vec3::new(0.3, 0.1, 1.0).normalize())])
            .collect();
        let volume = view_volume(
            c,
            Vec3::Z,
            &[Vec3::new(0.0, 0.0, 1.0)],
            &ends,
            bounds(),
            256,
        )
        .expect("test value");
        let camera = volume.camera;
        assert_eq!(camera.width().max(camera.height()), 256);
        for end in &ends {
            let st = texcoord(&volume, *end).expect("inside");
            assert!(st.x >= 0.0 && st.y >= 0.0, "{st}");
            assert!(st.x <= camera.width() as f32 && st.y <= camera.height() as f32);
        }
        // The frustum is tight: some end lies within two texels of an edge.
        let margin = ends
            .iter()
            .filter_map(|e| texcoord(&volume, *e))
            .map(|st| {
                st.x.min(st.y)
                    .min(camera.width() as f32 - st.x)
                    .min(camera.height() as f32 - st.y)
            })
            .fold(f32::INFINITY, f32::min);
        assert!(margin < 2.0, "{margin}");
    }

    #[test]
    fn a_hit_projects_where_the_map_camera_sees_it() {
        let ends = [
            RayEnd::Hit(Vec3::new(1.0, 2.0, 6.0)),
            RayEnd::Hit(Vec3::new(-1.0, 0.0, 4.0)),
        ];
        let volume =
            view_volume(Vec3::ZERO, Vec3::Z, &[Vec3::Z], &ends, bounds(), 128).expect("test value");
        let st = texcoord(&volume, ends[0]).expect("test value");
        let ray = volume.camera.pixel_ray(st);
        let to_p = (Vec3::new(1.0, 2.0, 6.0) - ray.origin).normalize();
        assert!(ray.dir.dot(to_p) > 1.0 - 1e-6);
    }

    #[test]
    fn ends_before_the_near_plane_are_the_zooming_region() {
        // The reflector lies at depth 3: the near plane lies just beyond it.
        let ends = [
            RayEnd::Hit(Vec3::new(0.0, 0.0, 6.0)),
            RayEnd::Hit(Vec3::new(0.1, 0.0, 5.0)),
        ];
        let volume = view_volume(
            Vec3::ZERO,
            Vec3::Z,
            &[Vec3::new(0.0, 0.0, 3.0)],
            &ends,
            bounds(),
            64,
        )
        .expect("test value");
        // Just beyond the reflector along the (re-aimed) axis.
        assert!(volume.near > 2.99 && volume.near < 3.01, "{}", volume.near);
        assert!(texcoord(&volume, ends[0]).is_some());
        assert_eq!(
            texcoord(&volume, RayEnd::Hit(Vec3::new(0.0, 0.0, 2.0))),
            None
        );
        // A hit nearer than the reflector's far edge pulls the near plane in.
        let tilted = [RayEnd::Hit(Vec3::new(0.0, 0.0, 2.5)), ends[0]];
        let volume = view_volume(
            Vec3::ZERO,
            Vec3::Z,
            &[Vec3::new(0.0, 0.0, 3.0)],
            &tilted,
            bounds(),
            64,
        )
        .expect("test value");
        assert!(texcoord(&volume, tilted[0]).is_some(), "{}", volume.near);
        assert_eq!(texcoord(&volume, RayEnd::Escape(-Vec3::Z)), None);
        let behind = [RayEnd::Hit(Vec3::new(0.0, 0.0, -5.0))];
        assert_eq!(
            view_volume(Vec3::ZERO, Vec3::Z, &[], &behind, bounds(), 64),
            Err(ViewVolumeError::NoMappedRay)
        );
    }

    struct Ramp(u32, u32);
    impl MapTexels for Ramp {
        fn size(&self) -> (u32, u32) {
            (self.0, self.1)
        }
        fn texel(&self, x: u32, y: u32) -> Vec3 {
            Vec3::new(x as f32, y as f32, 1.0)
        }
    }

    #[test]
    fn bilinear_is_exact_on_a_ramp_and_clamps_at_edges() {
        let map = Ramp(8, 4);
        assert_eq!(
            sample_bilinear(&map, Vec2::new(3.5, 2.5)),
            Vec3::new(3.0, 2.0, 1.0)
        );
        let v = sample_bilinear(&map, Vec2::new(2.25, 1.75));
        assert!((v - Vec3::new(1.75, 1.25, 1.0)).length() < 1e-6, "{v}");
        assert_eq!(
            sample_bilinear(&map, Vec2::new(-5.0, 99.0)),
            Vec3::new(0.0, 3.0, 1.0)
        );
    }

    #[test]
    fn chromatic_lookup_takes_one_channel_per_position() {
        let map = Ramp(8, 8);
        let st = [
            Vec2::new(1.5, 0.5),
            Vec2::new(4.5, 0.5),
            Vec2::new(0.5, 6.5),
        ];
        // Blue of the ramp is 1 everywhere; red from the first, green (= y) from the second.
        assert_eq!(lookup(&map, st, Vec3::ONE), Vec3::new(1.0, 0.0, 1.0));
        assert_eq!(mirror_tint(Vec3::ONE, Vec3::Z, Vec3::X), Vec3::ONE);
        let f = mirror_tint(Vec3::splat(0.5), Vec3::Z, Vec3::Z);
        assert!((f - Vec3::splat(0.5)).length() < 1e-6);
    }

    /// A map whose texels differ in every bit pattern (no two neighbours alike).
    struct Noise(u32, u32);
    impl MapTexels for Noise {
        fn size(&self) -> (u32, u32) {
            (self.0, self.1)
        }
        fn texel(&self, x: u32, y: u32) -> Vec3 {
            let h = (x.wrapping_mul(73_856_093) ^ y.wrapping_mul(19_349_663)) % 10_007;
            Vec3::new(
                h as f32 / 997.0,
                (h % 101) as f32 * 0.37,
                1.0 / (1.0 + h as f32),
            )
        }
    }

    /// Lane `i` of the eight-lane lookup, tint and bilinear sample is the scalar function's,
    /// bit for bit: inside the map, past its edges, on texel centres, with one position for
    /// the three channels and with three (chromatic aberration), NaN positions included.
    #[test]
    fn eight_lane_lookups_equal_the_scalar_ones_bit_for_bit() {
        let map = Noise(37, 23);
        let mut state = 11u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 40) as f32) / (1u64 << 24) as f32
        };
        let bits = |v: Vec3| {
            v.to_array()
                .map(|c| if c.is_nan() { u32::MAX } else { c.to_bits() })
        };
        for round in 0..2000 {
            let mut position = || match (next() * 12.0) as u32 {
                0 => Vec2::new(-3.0 + 50.0 * next(), 40.0 * next() - 8.0),
                1 => Vec2::new((next() * 37.0).floor() + 0.5, (next() * 23.0).floor() + 0.5),
                2 => Vec2::new(f32::NAN, 3.0),
                _ => Vec2::new(37.0 * next(), 23.0 * next()),
            };
            let st: [[Vec2; 3]; LANES] = core::array::from_fn(|_| {
                let first = position();
                if round % 2 == 0 {
                    [first; 3]
                } else {
                    [first, position(), position()]
                }
            });
            let n: [Vec3; LANES] = core::array::from_fn(|_| {
                Vec3::new(next() - 0.5, next() - 0.5, next()).normalize_or_zero()
            });
            let v: [Vec3; LANES] = core::array::from_fn(|_| {
                Vec3::new(next() - 0.5, next() - 0.5, -next()).normalize_or_zero()
            });
            let f0 = Vec3::new(0.9, 0.6 * next(), 0.3);
            let tint = mirror_tint(f0, Vec3x8::from_lanes(&n), Vec3x8::from_lanes(&v));
            let channels = [0, 1, 2].map(|c| Vec2x8::from_lanes(&st.map(|s| s[c])));
            let looked_up = lookup_x8(&map, channels, tint).to_lanes();
            let sampled: Vec3x8 = sample_bilinear_at(&map, channels[1].x, channels[1].y);
            let sampled = sampled.to_lanes();
            let tint = tint.to_lanes();
            for i in 0..LANES {
                let scalar_tint = mirror_tint(f0, n[i], v[i]);
                assert_eq!(bits(tint[i]), bits(scalar_tint), "tint, lane {i}");
                assert_eq!(bits(sampled[i]), bits(sample_bilinear(&map, st[i][1])));
                let scalar = lookup(&map, st[i], scalar_tint);
                assert_eq!(bits(looked_up[i]), bits(scalar), "{:?}", st[i]);
            }
        }
    }
}
