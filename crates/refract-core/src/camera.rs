//! The pinhole camera every backend shares: world ↔ view ↔ clip ↔ pixel transforms and
//! pixel-centre rays.
//!
//! Conventions (design.md): right-handed world and view space (the camera looks down `−z_vs`,
//! `y` up), glam's `look_at_mat4` and DirectX-style `perspective` (NDC `z ∈ [0, 1]`, which is what
//! wgpu expects), pixel coordinates `uv_px` with the origin at the top-left corner of the image,
//! `y` pointing down, and pixel `(x, y)` sampled at its centre `(x + ½, y + ½)`.

use core::fmt;

use glam::camera::rh::{proj::directx::perspective, view::look_at_mat4};
use glam::{Mat4, Vec2, Vec3, Vec4Swizzles};

use crate::lanes::{Vec2x8, Vec3x8};
use crate::real::{Msk, Real, Vector3};

/// A ray `origin + t · dir`, `dir` unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts (world space).
    pub origin: Vec3,
    /// Unit direction (world space).
    pub dir: Vec3,
}

impl Ray {
    /// The point `origin + t · dir`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// What a [`Camera`] is built from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    /// Eye position (world space).
    pub eye: Vec3,
    /// The point looked at (world space).
    pub target: Vec3,
    /// Approximate up direction (world space); must not be parallel to `target − eye`.
    pub up: Vec3,
    /// Vertical field of view in radians, in `(0, π)`.
    pub fov_y: f32,
    /// Near plane distance, `> 0`.
    pub near: f32,
    /// Far plane distance, `> near`.
    pub far: f32,
    /// Image width in pixels, `≥ 1`.
    pub width: u32,
    /// Image height in pixels, `≥ 1`.
    pub height: u32,
    /// Mirror the image horizontally (NDC `x → −x`): what a cube-map face needs (see
    /// [`Camera::cube_face`]). A mirrored camera sees counter-clockwise triangles clockwise on
    /// screen, so rasterisers flip their facing test ([`Camera::is_mirrored`]).
    pub mirror_x: bool,
}

impl Default for CameraDesc {
    /// The camera of the built-in scenes: 3 units in front of the unit bounding sphere on `+z`,
    /// looking at the origin with a 40° vertical field of view, 512².
    fn default() -> Self {
        Self {
            eye: Vec3::new(0.0, 0.0, 3.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: 40f32.to_radians(),
            near: 0.05,
            far: 100.0,
            width: 512,
            height: 512,
            mirror_x: false,
        }
    }
}

/// The six faces of a cube map, in the layer order of wgpu/WebGPU (and D3D, Vulkan):
/// `+X, −X, +Y, −Y, +Z, −Z`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CubeFace {
    /// Layer 0, `+X`.
    PosX,
    /// Layer 1, `−X`.
    NegX,
    /// Layer 2, `+Y`.
    PosY,
    /// Layer 3, `−Y`.
    NegY,
    /// Layer 4, `+Z`.
    PosZ,
    /// Layer 5, `−Z`.
    NegZ,
}

impl CubeFace {
    /// Every face, in layer order.
    pub const ALL: [CubeFace; 6] = [
        CubeFace::PosX,
        CubeFace::NegX,
        CubeFace::PosY,
        CubeFace::NegY,
        CubeFace::PosZ,
        CubeFace::NegZ,
    ];

    /// The face's view direction.
    pub const fn forward(self) -> Vec3 {
        match self {
            CubeFace::PosX => Vec3::X,
            CubeFace::NegX => Vec3::NEG_X,
            CubeFace::PosY => Vec3::Y,
            CubeFace::NegY => Vec3::NEG_Y,
            CubeFace::PosZ => Vec3::Z,
            CubeFace::NegZ => Vec3::NEG_Z,
        }
    }

    /// The face's up direction (texel rows run against it): `+Y` for the side faces, `−Z` for
    /// `+Y` and `+Z` for `−Y`, so that with a mirrored right-handed view (a left-handed one)
    /// texel `(s, t)` of a face is the direction [`CubeFace::of_direction`] maps to it.
    pub const fn up(self) -> Vec3 {
        match self {
            CubeFace::PosY => Vec3::NEG_Z,
            CubeFace::NegY => Vec3::Z,
            _ => Vec3::Y,
        }
    }

    /// WebGPU's (D3D's, Vulkan's) cube-face selection: the face of the major axis of `dir`
    /// (ties go to `x`, then `y`) and the face coordinates `(s, t) ∈ [0, 1]²`,
    /// `s = (sc / |ma| + 1) / 2`, `t = (tc / |ma| + 1) / 2`, with `(sc, tc, ma)` =
    /// `(−z, −y, x)`, `(z, −y, x)`, `(x, z, y)`, `(x, −z, y)`, `(x, −y, z)`, `(−x, −y, z)` for
    /// `+X … −Z`. Texel column `s·N`, row `t·N` of an `N × N` face. `None` for a zero or
    /// non-finite direction.
    pub fn of_direction(dir: Vec3) -> Option<(CubeFace, Vec2)> {
        let c = cube_coordinates(dir);
        c.valid
            .then(|| (CubeFace::ALL[c.face as usize], Vec2::new(c.s, c.t)))
    }
}

/// [`CubeFace::of_direction`] of one direction or eight: the face's index in
/// [`CubeFace::ALL`], `(s, t)`, and the lanes with a finite non-zero direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubeCoordinates<R: Real> {
    /// The face's index in [`CubeFace::ALL`] (a whole number).
    pub face: R,
    /// `s ∈ [0, 1]`.
    pub s: R,
    /// `t ∈ [0, 1]`.
    pub t: R,
    /// Finite and non-zero directions (elsewhere the other fields are meaningless).
    pub valid: R::Mask,
}

/// [`CubeFace::of_direction`] for one direction or eight, the face chosen by selects.
#[inline]
pub fn cube_coordinates<V: Vector3>(dir: V) -> CubeCoordinates<V::Real> {
    let zero = V::Real::ZERO;
    let (x, y, z) = (dir.x(), dir.y(), dir.z());
    let (ax, ay, az) = (x.abs(), y.abs(), z.abs());
    let valid = dir.is_finite() & ax.max(ay).max(az).gt(zero);
    // The major axis, ties to x, then y.
    let x_major = ax.ge(ay) & ax.ge(az);
    let y_major = !x_major & ay.ge(az);
    let (pos_x, pos_y, pos_z) = (x.ge(zero), y.ge(zero), z.ge(zero));
    let pick = |m: Msk<V>, a: V::Real, b: V::Real| V::Real::select(m, a, b);
    let sc = pick(
        x_major,
        pick(pos_x, -z, z),
        pick(y_major, x, pick(pos_z, x, -x)),
    );
    let tc = pick(x_major, -y, pick(y_major, pick(pos_y, z, -z), -y));
    let ma = pick(x_major, ax, pick(y_major, ay, az));
    let splat = V::Real::splat;
    let face = pick(
        x_major,
        pick(pos_x, splat(0.0), splat(1.0)),
        pick(
            y_major,
            pick(pos_y, splat(2.0), splat(3.0)),
            pick(pos_z, splat(4.0), splat(5.0)),
        ),
    );
    let half = splat(0.5);
    CubeCoordinates {
        face,
        s: (sc / ma + V::Real::ONE) * half,
        t: (tc / ma + V::Real::ONE) * half,
        valid,
    }
}

/// Why a [`CameraDesc`] was rejected.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraError {
    /// Width or height is zero.
    ZeroResolution {
        /// The requested width.
        width: u32,
        /// The requested height.
        height: u32,
    },
    /// The vertical field of view is not in `(0, π)` radians.
    FieldOfView(f32),
    /// Near and far planes must satisfy `0 < near < far`, both finite.
    ClipPlanes {
        /// The requested near distance.
        near: f32,
        /// The requested far distance.
        far: f32,
    },
    /// Eye, target or up is not finite, the eye equals the target, or up is parallel to the view.
    Orientation,
}

impl fmt::Display for CameraError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::ZeroResolution { width, height } => {
                write!(
                    f,
                    "camera resolution {width}x{height}: width and height must be at least 1"
                )
            }
            Self::FieldOfView(fov) => write!(
                f,
                "camera fov_y {:.3}°: expected a vertical field of view strictly between 0° and 180°",
                fov.to_degrees()
            ),
            Self::ClipPlanes { near, far } => {
                write!(
                    f,
                    "camera clip planes near={near} far={far}: expected 0 < near < far, finite"
                )
            }
            Self::Orientation => write!(
                f,
                "camera eye/target/up: expected finite vectors, eye ≠ target, up not parallel to the view direction"
            ),
        }
    }
}

impl core::error::Error for CameraError {}

/// A validated pinhole camera with its matrices precomputed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    desc: CameraDesc,
    world_to_view: Mat4,
    view_to_world: Mat4,
    view_to_clip: Mat4,
    world_to_clip: Mat4,
    clip_to_world: Mat4,
    look_dir: Vec3,
    tan_half_fov_y: f32,
    aspect: f32,
    /// View-space ray direction per pixel position: `dir_vs.xy = uv_px · ray_scale + ray_offset`.
    ray_scale: Vec2,
    ray_offset: Vec2,
}

impl Camera {
    /// Validates `desc` and precomputes `world_to_view = look_at_mat4(eye, target, up)`,
    /// `view_to_clip = perspective(fov_y, width/height, near, far)` and their inverses.
    pub fn new(desc: CameraDesc) -> Result<Self, CameraError> {
        if desc.width == 0 || desc.height == 0 {
            return Err(CameraError::ZeroResolution {
                width: desc.width,
                height: desc.height,
            });
        }
        if !(desc.fov_y > 0.0 && desc.fov_y < core::f32::consts::PI) {
            return Err(CameraError::FieldOfView(desc.fov_y));
        }
        if !(desc.near > 0.0 && desc.far > desc.near && desc.far.is_finite()) {
            return Err(CameraError::ClipPlanes {
                near: desc.near,
                far: desc.far,
            });
        }
        let forward = (desc.target - desc.eye).try_normalize();
        let up = desc.up.try_normalize();
        let (Some(look_dir), Some(up)) = (forward, up) else {
            return Err(CameraError::Orientation);
        };
        if !desc.eye.is_finite() || look_dir.cross(up).length() < 1e-6 {
            return Err(CameraError::Orientation);
        }
        let aspect = desc.width as f32 / desc.height as f32;
        let world_to_view = look_at_mat4(desc.eye, desc.target, up);
        let mirror = if desc.mirror_x { -1.0 } else { 1.0 };
        let view_to_clip = Mat4::from_scale(Vec3::new(mirror, 1.0, 1.0))
            * perspective(desc.fov_y, aspect, desc.near, desc.far);
        let world_to_clip = view_to_clip * world_to_view;
        let tan_half_fov_y = crate::math::tan(0.5 * desc.fov_y);
        Ok(Self {
            desc,
            world_to_view,
            view_to_world: world_to_view.inverse(),
            view_to_clip,
            world_to_clip,
            clip_to_world: world_to_clip.inverse(),
            look_dir,
            tan_half_fov_y,
            aspect,
            // x_vs = (2u/W − 1)·aspect·tan(fov/2), y_vs = (1 − 2v/H)·tan(fov/2).
            // Mirrored: x_vs = −(2u/W − 1)·aspect·tan(fov/2).
            ray_scale: Vec2::new(
                mirror * 2.0 * aspect * tan_half_fov_y / desc.width as f32,
                -2.0 * tan_half_fov_y / desc.height as f32,
            ),
            ray_offset: Vec2::new(-mirror * aspect * tan_half_fov_y, tan_half_fov_y),
        })
    }

    /// The camera of one face of a cube map of `size × size` texels around `center`: 90° field
    /// of view, aspect 1, looking along [`CubeFace::forward`] with [`CubeFace::up`], mirrored, so
    /// that pixel `(s·size, t·size)` sees the direction that [`CubeFace::of_direction`] (and a
    /// wgpu `texture_cube` lookup) maps to `(face, s, t)`.
    ///
    /// # Example
    ///
    /// ```
    /// use glam::Vec3;
    /// use refract_core::{Camera, CubeFace};
    /// let dir = Vec3::new(0.2, -0.3, 1.0);
    /// let (face, st) = CubeFace::of_direction(dir).expect("a direction");
    /// assert_eq!(face, CubeFace::PosZ);
    /// let camera = Camera::cube_face(Vec3::ZERO, face, 128, 0.01, 10.0)?;
    /// let px = camera.world_to_pixel(dir).expect("in front");
    /// assert!((px.truncate() - st * 128.0).length() < 1e-3);
    /// # Ok::<(), refract_core::CameraError>(())
    /// ```
    pub fn cube_face(
        center: Vec3,
        face: CubeFace,
        size: u32,
        near: f32,
        far: f32,
    ) -> Result<Self, CameraError> {
        Self::new(CameraDesc {
            eye: center,
            target: center + face.forward(),
            up: face.up(),
            fov_y: core::f32::consts::FRAC_PI_2,
            near,
            far,
            width: size,
            height: size,
            mirror_x: true,
        })
    }

    /// Whether the image is mirrored ([`CameraDesc::mirror_x`]): counter-clockwise triangles
    /// appear clockwise on screen.
    pub fn is_mirrored(&self) -> bool {
        self.desc.mirror_x
    }

    /// The description this camera was built from.
    pub fn desc(&self) -> &CameraDesc {
        &self.desc
    }
    /// Eye position (world space).
    pub fn eye(&self) -> Vec3 {
        self.desc.eye
    }
    /// Unit look-at direction `L = normalize(target − eye)` (Wyman 2005a §3.3 `L_at`).
    pub fn look_dir(&self) -> Vec3 {
        self.look_dir
    }
    /// Image width in pixels.
    pub fn width(&self) -> u32 {
        self.desc.width
    }
    /// Image height in pixels.
    pub fn height(&self) -> u32 {
        self.desc.height
    }
    /// The view matrix (world → view).
    pub fn world_to_view(&self) -> Mat4 {
        self.world_to_view
    }
    /// The inverse view matrix (view → world).
    pub fn view_to_world(&self) -> Mat4 {
        self.view_to_world
    }
    /// The projection matrix (view → clip, NDC depth in `[0, 1]`).
    pub fn view_to_clip(&self) -> Mat4 {
        self.view_to_clip
    }
    /// `view_to_clip · world_to_view`.
    pub fn world_to_clip(&self) -> Mat4 {
        self.world_to_clip
    }
    /// The exact inverse of [`Self::world_to_clip`].
    pub fn clip_to_world(&self) -> Mat4 {
        self.clip_to_world
    }

    /// The centre of pixel `(x, y)`: `uv_px = (x + ½, y + ½)`.
    #[inline]
    pub fn pixel_center(x: u32, y: u32) -> Vec2 {
        Vec2::new(x as f32 + 0.5, y as f32 + 0.5)
    }

    /// Pixel coordinates to NDC: `x_ndc = 2 u/W − 1`, `y_ndc = 1 − 2 v/H` (NDC `y` points up).
    #[inline]
    pub fn pixel_to_ndc(&self, uv_px: Vec2) -> Vec2 {
        Vec2::new(
            2.0 * uv_px.x / self.desc.width as f32 - 1.0,
            1.0 - 2.0 * uv_px.y / self.desc.height as f32,
        )
    }

    /// Projects a world point to `(u_px, v_px, depth)` with `depth ∈ [0, 1]` between the near and
    /// far planes, or `None` when the point is on or behind the eye plane (`w_clip ≤ 0`).
    #[inline]
    pub fn world_to_pixel(&self, p_ws: Vec3) -> Option<Vec3> {
        let clip = self.world_to_clip * p_ws.extend(1.0);
        if clip.w.is_nan() || clip.w <= 0.0 {
            return None;
        }
        let ndc = clip.xyz() * clip.w.recip();
        Some(Vec3::new(
            0.5 * (ndc.x + 1.0) * self.desc.width as f32,
            0.5 * (1.0 - ndc.y) * self.desc.height as f32,
            ndc.z,
        ))
    }

    /// [`Self::world_to_pixel`]'s `(u_px, v_px)` for one point or eight, and the lanes in front
    /// of the eye (`w_clip > 0`): the same operations (glam's `M · (p, 1)` row by row,
    /// `((m₀ x + m₁ y) + m₂ z) + m₃`), so the same bits.
    #[inline]
    pub fn world_to_pixel_xy<V: Vector3>(&self, p_ws: V) -> (V::Real, V::Real, Msk<V>) {
        let m = &self.world_to_clip;
        let row = |k: usize| {
            let c = |col: glam::Vec4| V::Real::splat(col[k]);
            c(m.x_axis) * p_ws.x() + c(m.y_axis) * p_ws.y() + c(m.z_axis) * p_ws.z() + c(m.w_axis)
        };
        let (x, y, w) = (row(0), row(1), row(3));
        let rcp = V::Real::ONE / w;
        let half = V::Real::splat(0.5);
        let u_px = half * (x * rcp + V::Real::ONE) * V::Real::splat(self.desc.width as f32);
        let v_px = half * (V::Real::ONE - y * rcp) * V::Real::splat(self.desc.height as f32);
        (u_px, v_px, w.gt(V::Real::ZERO))
    }

    /// The world point at pixel position `uv_px` and window depth `depth ∈ [0, 1]`: the exact
    /// inverse of [`Self::world_to_pixel`] through `clip_to_world` (never a linearisation formula
    /// for another depth range).
    #[inline]
    pub fn pixel_to_world(&self, uv_px: Vec2, depth: f32) -> Vec3 {
        let ndc = self.pixel_to_ndc(uv_px);
        self.clip_to_world
            .project_point3(Vec3::new(ndc.x, ndc.y, depth))
    }

    /// View-space `z` (negative in front of the camera) of window depth `depth ∈ [0, 1]`:
    /// `z_vs = −f n / (n + (1 − depth)(f − n))`, the inverse of the DirectX-style projection,
    /// written so that `depth = 1` gives exactly `−f` (no cancellation near the far plane).
    #[inline]
    pub fn view_z_from_depth(&self, depth: f32) -> f32 {
        let (n, f) = (self.desc.near, self.desc.far);
        -f * n / (n + (1.0 - depth) * (f - n))
    }

    /// The primary ray through pixel position `uv_px` (use [`Self::pixel_center`] for pixel
    /// centres): origin at the eye, direction `normalize(view_to_world · (x_ndc·a·tan(fov/2),
    /// y_ndc·tan(fov/2), −1))`, `a = W/H` (the affine map from pixels to view-space `x, y`
    /// precomputed, so that a ray costs no division besides the normalisation).
    #[inline]
    pub fn pixel_ray(&self, uv_px: Vec2) -> Ray {
        Ray {
            origin: self.desc.eye,
            dir: self.pixel_ray_dir(uv_px.x, uv_px.y),
        }
    }

    /// [`Self::pixel_ray`]'s direction for eight pixel positions at once (bit-identical).
    #[inline]
    pub fn pixel_ray_dir_x8(&self, uv_px: Vec2x8) -> Vec3x8 {
        self.pixel_ray_dir(uv_px.x, uv_px.y)
    }

    /// [`Self::pixel_ray`]'s direction at pixel position `(u_px, v_px)`, for one pixel or eight.
    #[inline]
    pub fn pixel_ray_dir<V: Vector3>(&self, u_px: V::Real, v_px: V::Real) -> V {
        let splat = V::Real::splat;
        let x = u_px * splat(self.ray_scale.x) + splat(self.ray_offset.x);
        let y = v_px * splat(self.ray_scale.y) + splat(self.ray_offset.y);
        let dir = V::transform_vector3(&self.view_to_world, V::new(x, y, splat(-1.0)));
        dir * (V::Real::ONE / dir.length())
    }

    /// Euclidean distance from the eye, `‖p − eye‖`: the quantity stored in back-face buffers.
    #[inline]
    pub fn distance_from_eye(&self, p_ws: Vec3) -> f32 {
        (p_ws - self.desc.eye).length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera::new(CameraDesc {
            width: 640,
            height: 480,
            ..CameraDesc::default()
        })
        .expect("valid camera")
    }

    /// Direction → face → texel round trip: a cube-face camera's pixel of a direction is where
    /// WebGPU's face selection puts it, and its pixel ray points back along the direction.
    #[test]
    fn cube_face_cameras_match_webgpu_face_selection() {
        let size = 64;
        let center = Vec3::new(0.3, -0.2, 0.5);
        let cameras =
            CubeFace::ALL.map(|f| Camera::cube_face(center, f, size, 0.01, 10.0).expect("face"));
        let mut checked = 0;
        for i in 0..2000u32 {
            // A deterministic spread of directions (golden-angle spiral).
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / 2000.0;
            let phi = i as f32 * 2.399_963;
            let r = (1.0 - z * z).sqrt();
            let dir = Vec3::new(r * phi.cos(), z, r * phi.sin());
            let (face, st) = CubeFace::of_direction(dir).expect("direction");
            let camera = &cameras[face as usize];
            let px = camera.world_to_pixel(center + dir).expect("in front");
            assert!(
                (px.truncate() - st * size as f32).abs().max_element() < 1e-3,
                "{dir}: {face:?} {st} vs {px}"
            );
            let back = camera.pixel_ray(px.truncate()).dir;
            assert!((back - dir.normalize()).length() < 1e-5, "{dir} vs {back}");
            checked += 1;
        }
        assert_eq!(checked, 2000);
        assert!(cameras.iter().all(Camera::is_mirrored));
    }

    #[test]
    fn eight_pixel_rays_equal_the_scalar_rays_bit_for_bit() {
        let cam = camera();
        for row in [0, 1, 239, 479] {
            for first in (0..640).step_by(8) {
                let uv: [Vec2; 8] = core::array::from_fn(|i| {
                    Camera::pixel_center(first + i as u32, row) + Vec2::new(0.1 * i as f32, 0.0)
                });
                let lanes = cam.pixel_ray_dir_x8(Vec2x8::from_lanes(&uv)).to_lanes();
                for i in 0..8 {
                    assert_eq!(lanes[i].to_array(), cam.pixel_ray(uv[i]).dir.to_array());
                }
            }
        }
    }

    #[test]
    fn pixel_ray_hits_the_point_that_projects_to_that_pixel() {
        let cam = camera();
        for (x, y) in [(0, 0), (320, 240), (639, 479), (17, 400)] {
            let uv = Camera::pixel_center(x, y);
            let p = cam.pixel_ray(uv).at(2.5);
            let back = cam.world_to_pixel(p).expect("in front");
            assert!((back.truncate() - uv).length() < 2e-3, "{uv} -> {back}");
        }
    }

    #[test]
    fn depth_round_trips_through_the_exact_inverse() {
        let cam = camera();
        let p = Vec3::new(0.3, -0.2, 0.4);
        let px = cam.world_to_pixel(p).expect("in front");
        let q = cam.pixel_to_world(px.truncate(), px.z);
        assert!((p - q).length() < 1e-5, "{p} vs {q}");
        let z_vs = cam.world_to_view().transform_point3(p).z;
        // One f32 ulp of window depth moves z_vs by about z²/near · 2⁻²⁴ (≈ 1e-5 here).
        let tolerance = 4.0 * z_vs * z_vs / 0.05 * f32::EPSILON;
        assert!((cam.view_z_from_depth(px.z) - z_vs).abs() < tolerance);
        assert!((cam.view_z_from_depth(0.0) + 0.05).abs() < 1e-6);
        assert!((cam.view_z_from_depth(1.0) + 100.0).abs() < 1e-3);
    }

    #[test]
    fn centre_pixel_looks_along_the_look_direction_and_y_points_down() {
        let cam = camera();
        let ray = cam.pixel_ray(Vec2::new(320.0, 240.0));
        assert!((ray.dir - cam.look_dir()).length() < 1e-6);
        let above = cam
            .world_to_pixel(Vec3::new(0.0, 0.5, 0.0))
            .expect("in front");
        assert!(above.y < 240.0, "world +y appears toward the top row");
        assert!(
            cam.world_to_pixel(Vec3::new(0.0, 0.0, 5.0)).is_none(),
            "behind the eye"
        );
    }

    #[test]
    fn bad_descriptions_are_rejected() {
        let ok = CameraDesc::default();
        assert!(Camera::new(CameraDesc { width: 0, ..ok }).is_err());
        assert!(
            Camera::new(CameraDesc {
                fov_y: f32::NAN,
                ..ok
            })
            .is_err()
        );
        assert!(Camera::new(CameraDesc { near: 0.0, ..ok }).is_err());
        assert!(Camera::new(CameraDesc { far: 0.01, ..ok }).is_err());
        assert!(Camera::new(CameraDesc { up: Vec3::Z, ..ok }).is_err());
        assert!(
            Camera::new(CameraDesc {
                target: ok.eye,
                ..ok
            })
            .is_err()
        );
    }
}
