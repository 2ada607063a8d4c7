//! The refraction today's engines ship (`../shared/engine-methods.md` restates each engine's
//! shader as formulas, with its public source files): one interface at most, an exit point or a
//! screen offset from a constant thickness, then a lookup in the screen texture of the opaque
//! objects (colour and depth of everything drawn before the glass, the environment where
//! nothing was drawn).
//!
//! * [`EngineModel::ScreenOffset`]: Godot 4 `BaseMaterial3D` refraction (Unreal's IOR offset
//!   mode has the same shape): `uv' = uv − n_view.xy · scale`, with Godot's depth guard.
//! * [`EngineModel::VolumeThickness`]: three.js `MeshPhysicalMaterial` and Bevy specular
//!   transmission (glTF `KHR_materials_volume`): `X = P + T d`, `uv' = proj(X)`; Bevy rejects
//!   samples in front of the glass and falls back to the environment.
//! * [`EngineModel::Proxy`]: Unity HDRP's refraction models (sphere, box, thin; Filament's
//!   `solid` is the sphere): an exit point `P1` and direction `R2` from a proxy shape, then
//!   HDRP's proxy ray to the sky (`P1 + 65504 R2`, edge fade, depth check, environment
//!   fallback) or Filament's screen-space lookup `proj(P1)`.
//!
//! Per pixel, [`engine_path`] returns which screen texel is read, with which weight, and where
//! the rest comes from ([`EnginePath`]); the backends read the texel's colour. Conventions:
//! `I` the unit eye ray toward `P`, `N` the outward normal at `P`, `T = refract(I, N, 1/ior)`,
//! `cos θt = −N·T`, pixel coordinates `uv_px` with `y` down (as [`Camera::world_to_pixel`]),
//! depths along the look direction (`view_depth`, `+∞` where the screen shows the environment).

use glam::{UVec2, Vec2, Vec3};

use crate::camera::Camera;
use crate::engine_dispersion::EngineDispersion;
use crate::lanes::{F32x8, LANES, Vec2x8, Vec3x8, mask_lanes};
use crate::math;
use crate::optics::refract;
use crate::real::{LaneMask, Msk, Real, Vector3};
use crate::screen_mips::{self, ScreenMips};

/// HDRP's thin refraction model: the slab thickness (5 mm), `REFRACTION_THIN_DISTANCE`.
pub const THIN_THICKNESS: f32 = 0.005;
/// HDRP's distance to the sky when no reflection probe's proxy is found (`65504`, the largest
/// half float): the hit is the direction's vanishing point.
pub const HDRP_SKY_DISTANCE: f32 = 65504.0;
/// HDRP's edge-of-screen fade width in UV (`EdgeOfScreenFade`, default 0.1).
pub const HDRP_EDGE_FADE: f32 = 0.1;
/// HDRP's box model: `dist = d / max(cos θt, 1e-5)`.
pub const HDRP_MIN_COS: f32 = 1e-5;

/// The shape HDRP's refraction model assumes behind the entry point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ProxyShape {
    /// `REFRACTION_MODEL_SPHERE` (and Filament's `solid`): a sphere of diameter `d` tangent at
    /// `P`; the exit is the chord's end, the direction refracted there.
    Sphere,
    /// `REFRACTION_MODEL_BOX` (`_REFRACTION_PLANE`): a slab of thickness `d`; the exit is shifted
    /// sideways, the direction unchanged (`R2 = I`).
    Box,
    /// `REFRACTION_MODEL_THIN`: the box with `d` = [`THIN_THICKNESS`].
    Thin,
}

/// How a proxy model finds what is behind its exit point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ProxyLookup {
    /// Unity HDRP (`EvaluateBSDF_ScreenspaceRefraction` without a probe): the ray `P1 + t R2`
    /// to the sky at [`HDRP_SKY_DISTANCE`], projected; faded to the environment along `R2`
    /// near the screen's edges; the fragment's own texel where the hit's depth is in front.
    Hdrp,
    /// Filament's `screenspace` refraction: `proj(P1)`, clamped to the screen, no depth test,
    /// the exit direction unused.
    Filament,
}

/// One engine's refraction, with its parameters in scene units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EngineModel {
    /// Godot 4: `uv' = SCREEN_UV − n_view.xy · scale` (`SCREEN_UV` in `[0, 1]`, `y` down;
    /// `n_view` the view-space normal, `y` up), and with `depth_guard` the 4.x guard
    /// `uv = mix(SCREEN_UV, uv', smoothstep(0, 1, depth(uv') − depth(P)))`.
    ScreenOffset {
        /// `refraction_scale` (Godot's default 0.05).
        scale: f32,
        /// Godot 4.x's depth guard against foreground objects.
        depth_guard: bool,
    },
    /// three.js / Bevy: `X = P + T d`, `uv' = proj(X)`, clamped to the screen.
    VolumeThickness {
        /// `d`, the material's thickness already scaled to world units.
        thickness: f32,
        /// Bevy's depth rejection: a sample nearer than the fragment is replaced by the
        /// environment along `normalize(I + d T)` (three.js has none).
        reject_nearer: bool,
    },
    /// Unity HDRP's models (Filament's `solid` is [`ProxyShape::Sphere`]).
    Proxy {
        /// Sphere, box or thin slab.
        shape: ProxyShape,
        /// `d`: the sphere's diameter or the slab's thickness (ignored by [`ProxyShape::Thin`]).
        thickness: f32,
        /// HDRP's or Filament's lookup.
        lookup: ProxyLookup,
    },
}

impl EngineModel {
    /// How this model disperses on glass of index `ior` and Abbe number `abbe`
    /// ([`EngineDispersion`]): three.js's model by its three indices, Filament's `solid` model
    /// (the sphere with Filament's lookup) by its four wavelengths; Bevy, Godot, HDRP and
    /// Filament's box and thin models not at all.
    pub fn dispersion(&self, ior: f32, abbe: f32) -> EngineDispersion {
        match self {
            Self::VolumeThickness {
                reject_nearer: false,
                ..
            } => EngineDispersion::threejs(ior, abbe),
            Self::Proxy {
                shape: ProxyShape::Sphere,
                lookup: ProxyLookup::Filament,
                ..
            } => EngineDispersion::filament(ior, abbe),
            _ => EngineDispersion::None,
        }
    }

    /// The LOD at which this model reads the mip-mapped screen texture
    /// ([`crate::screen_mips`]) for a surface of roughness `roughness` on glass of index `ior`
    /// seen through `camera` (its frame's size and field of view; 0: one nearest texel, as for
    /// smooth glass): three.js's [`screen_mips::threejs_lod`], Godot's
    /// [`screen_mips::godot_lod`], HDRP's [`screen_mips::hdrp_mip`], Filament's
    /// [`screen_mips::filament_lod`]; for Bevy, whose taps are not a LOD, the roughness itself
    /// ([`bevy_blurred`]). Where Filament's LOD comes to 0 on a rough surface (a roughness below
    /// `2^(−offset/2)`, 0.14 at 256 × 256 under 45°) its model reads the nearest texel, as at
    /// roughness 0, where Filament reads level 0 bilinearly.
    pub fn rough_lod(&self, camera: &Camera, roughness: f32, ior: f32) -> f32 {
        let size = UVec2::new(camera.width(), camera.height());
        match self {
            Self::VolumeThickness {
                reject_nearer: true,
                ..
            } => roughness,
            Self::VolumeThickness {
                reject_nearer: false,
                ..
            } => screen_mips::threejs_lod(size.x, roughness, ior),
            Self::ScreenOffset { .. } => screen_mips::godot_lod(roughness),
            Self::Proxy {
                lookup: ProxyLookup::Hdrp,
                ..
            } => screen_mips::hdrp_mip(roughness, screen_mips::level_count(size)),
            Self::Proxy {
                lookup: ProxyLookup::Filament,
                ..
            } => screen_mips::filament_lod(size, camera.desc().fov_y, roughness, ior),
        }
    }

    /// How many levels of a `size` screen pyramid (from level 0) this model reads at a rough
    /// `lod` ([`Self::rough_lod`]; 0: none, the one-texel read of smooth glass): Bevy's taps
    /// read level 0 only; a LOD's reads touch levels `⌊lod⌋` and `⌈lod⌉`
    /// ([`screen_mips::sample_trilinear`], [`screen_mips::sample_threejs`]), so
    /// `min(⌈lod⌉ + 1, levels)`. A frame builds the most any of its refractors reads.
    pub fn rough_levels(&self, lod: f32, size: UVec2) -> u32 {
        if lod <= 0.0 {
            return 0;
        }
        match self {
            Self::VolumeThickness {
                reject_nearer: true,
                ..
            } => 1,
            _ => (-math::floor(-lod) as u32 + 1).min(screen_mips::level_count(size)),
        }
    }

    /// The blurred screen this model reads for `path` (the pixel at `uv_px`, its front surface
    /// at `p1_ws`) at a rough `lod` (> 0, [`Self::rough_lod`]), and the
    /// share of the pixel it takes (the rest is the environment along the model's fallback):
    /// three.js's B-spline reads ([`screen_mips::sample_threejs`]) at the projected exit point
    /// `proj(P + T d)` (the texel's centre behind the eye); Bevy's taps around the same point
    /// ([`bevy_blurred`]; the share is the accepted taps'); Godot's trilinear read at the centre
    /// of the texel its smooth lookup reads; HDRP's trilinear read at `lerp(fragment, texel,
    /// k)`, `k = `[`screen_mips::hdrp_hit_share`]`(lod)` (the fragment's own texel where the
    /// depth test refused the hit); Filament's trilinear read at the projected exit point
    /// `proj(P1)` (its texel's centre behind the eye). Godot and HDRP read the texel's centre,
    /// not their continuous position: within half a texel of level 0. Except Bevy's, the share and the
    /// fallback are the path's ([`EnginePath::screen_weight`], [`EnginePath::environment_dir`]);
    /// Bevy's fallback is [`bevy_fallback_dir`].
    #[allow(clippy::too_many_arguments)]
    pub fn read_rough<M: ScreenMips, S: OpaqueDepth>(
        &self,
        camera: &Camera,
        mips: &M,
        screen: &S,
        uv_px: Vec2,
        p1_ws: Vec3,
        path: &EnginePath,
        lod: f32,
    ) -> RoughRead {
        let size = mips.size().as_vec2();
        let texel_px = path.texel.as_vec2() + Vec2::splat(0.5);
        let exit_px = || {
            camera
                .world_to_pixel(path.p2)
                .map_or(texel_px, |p| Vec2::new(p.x, p.y))
        };
        let of_path = |color| RoughRead {
            color,
            screen_weight: path.screen_weight,
            environment_dir: path.environment_dir,
        };
        match *self {
            Self::VolumeThickness {
                reject_nearer: true,
                thickness,
            } => {
                let from_eye = p1_ws - camera.eye();
                let fragment_depth = from_eye.dot(camera.look_dir());
                let (color, screen_weight) =
                    bevy_blurred(mips, screen, uv_px, exit_px() / size, lod, fragment_depth);
                RoughRead {
                    color,
                    screen_weight,
                    environment_dir: bevy_fallback_dir(
                        from_eye.normalize_or_zero(),
                        path.t2,
                        thickness,
                    ),
                }
            }
            Self::VolumeThickness { .. } => {
                of_path(screen_mips::sample_threejs(mips, exit_px() / size, lod))
            }
            Self::Proxy {
                lookup: ProxyLookup::Hdrp,
                ..
            } => {
                let k = screen_mips::hdrp_hit_share(lod);
                let read = uv_px.lerp(texel_px, k) / size;
                of_path(screen_mips::sample_trilinear(mips, read, lod))
            }
            Self::Proxy {
                lookup: ProxyLookup::Filament,
                ..
            } => of_path(screen_mips::sample_trilinear(mips, exit_px() / size, lod)),
            Self::ScreenOffset { .. } => {
                of_path(screen_mips::sample_trilinear(mips, texel_px / size, lod))
            }
        }
    }
}

/// The screen texture of the opaque objects, as an engine's lookup reads it: the view depth of
/// what texel `(x, y)` shows (`f32::INFINITY` where it shows the environment).
pub trait OpaqueDepth {
    /// View depth (along the look direction) of the nearest opaque surface at `texel`.
    fn view_depth(&self, texel: UVec2) -> f32;
}

/// What an engine reads for one refractor pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnginePath {
    /// The screen texel read (clamped to the frame).
    pub texel: UVec2,
    /// The share of the colour from that texel, in `[0, 1]`; the rest is the environment along
    /// [`Self::environment_dir`] (HDRP's edge fade, Bevy's rejected samples).
    pub screen_weight: f32,
    /// The fallback direction (`NaN` where the model has none: its weight is then 1).
    pub environment_dir: Vec3,
    /// The model's exit point (`NaN` for the screen offset, which has none).
    pub p2: Vec3,
    /// The model's direction behind the glass: `R2` for the proxies, `T` for the volume
    /// thickness (no refraction at the exit), `NaN` for the screen offset.
    pub t2: Vec3,
    /// The lookup position fell outside the frame (or behind the eye): clamped to the edge, or
    /// faded to the environment (HDRP).
    pub off_screen: bool,
}

/// What a rough refractor's pixel reads ([`EngineModel::read_rough`]): the blurred screen's
/// colour, its share of the pixel, and the environment's direction for the rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughRead {
    /// The blurred screen colour.
    pub color: Vec3,
    /// Its share of the pixel, in `[0, 1]`.
    pub screen_weight: f32,
    /// The environment's direction for `1 − screen_weight` (`NaN` where that is 0).
    pub environment_dir: Vec3,
}

/// `T = refract(I, N, 1/ior)` and `cos θt = −N·T` (never TIR when entering glass, `ior ≥ 1`).
#[inline]
fn entry<V: Vector3>(incident: V, n1: V, ior: V::Real) -> (V, V::Real) {
    let t = refract(incident, n1, V::Real::ONE / ior);
    (t, -n1.dot(t))
}

/// HDRP's sphere model (`RefractionModelSphere`; Filament's `refractionSolidSphere`): the
/// tangent sphere of diameter `d` has its centre at `C = P − N d/2`; the chord along `T` has
/// length `d cos θt`, so `P1 = P + T d cos θt`; `N1 = normalize(C − P1)` (inward) and
/// `R2 = refract(T, N1, ior)`. The chord's symmetry makes the exit angle `θt`: no TIR (should
/// rounding report one, `R2 = T`). Returns `(P1, R2)`. One pixel (glam types) or eight lanes.
#[inline]
pub fn proxy_sphere_exit<V: Vector3>(p: V, n: V, incident: V, ior: V::Real, d: V::Real) -> (V, V) {
    let (t, cos_t) = entry(incident, n, ior);
    let p1 = p + t * (d * cos_t);
    let center = p - n * (V::Real::splat(0.5) * d);
    let n1 = (center - p1).normalize_or_zero();
    let r2 = refract(t, n1, ior);
    (p1, V::select(r2.is_zero(), t, r2))
}

/// HDRP's box model (`RefractionModelBox`): a slab of thickness `d`, `P1 = P + T d / max(cos
/// θt, 1e-5)` and `R2 = I` (exact for a parallel slab). Returns `(P1, R2)`.
#[inline]
pub fn proxy_box_exit<V: Vector3>(p: V, n: V, incident: V, ior: V::Real, d: V::Real) -> (V, V) {
    let (t, cos_t) = entry(incident, n, ior);
    (
        p + t * (d / cos_t.max(V::Real::splat(HDRP_MIN_COS))),
        incident,
    )
}

/// three.js / Bevy: `X = P + T d` (the exit at distance `d` along `T`, not `d / cos θt`).
/// Returns `(X, T)`.
#[inline]
pub fn volume_exit<V: Vector3>(p: V, n: V, incident: V, ior: V::Real, d: V::Real) -> (V, V) {
    let (t, _) = entry(incident, n, ior);
    (p + t * d, t)
}

/// Bevy's environment fallback direction `−normalize(V + d refract(V, −N, 1/ior))`, which is
/// `normalize(I + d T)` (`refract(V, −N, η) = −refract(I, N, η)`).
#[inline]
pub fn bevy_fallback_dir(incident: Vec3, t: Vec3, d: f32) -> Vec3 {
    (incident + t * d).normalize_or_zero()
}

/// Bevy's blur taps (`screen_space_specular_transmission_quality` Medium, its default).
pub const BEVY_TAPS: u32 = 8;

/// Jimenez's spiral offset `k` (*Next Generation Post Processing in Call of Duty: Advanced
/// Warfare*, 2014, Bevy's `SPIRAL_OFFSET_k_`): `(1 − k/8) (cos, sin)(135° (k + 1))`.
#[inline]
pub fn spiral_offset(k: u32) -> Vec2 {
    let (sin, cos) = math::sin_cos(core::f32::consts::FRAC_PI_4 * 3.0 * (k + 1) as f32);
    Vec2::new(cos, sin) * (1.0 - k as f32 / 8.0)
}

/// Jimenez's interleaved gradient noise at pixel position `frag_px` (frame 0):
/// `fract(52.9829189 fract(0.06711056 x + 0.00583715 y))`.
#[inline]
pub fn interleaved_gradient_noise(frag_px: Vec2) -> f32 {
    let fract = |v: f32| v - math::floor(v);
    fract(52.982_918 * fract(0.067_110_56 * frag_px.x + 0.005_837_15 * frag_px.y))
}

/// Bevy's rough transmission (`fetch_transmissive_background`): [`BEVY_TAPS`] bilinear taps of
/// the screen texture's level 0 around `read_uv` (the projected exit point, `[0, 1]²`), on
/// Jimenez's spiral (offsets taken in the order 0, 2, 4, 6, 1, 3, 5, 7, shrunk by
/// `1 − ½ (j + 1)/S` for spiral `j` of `S = ⌈taps/8⌉`) rotated by
/// `2π (`[`interleaved_gradient_noise`]`(frag_px) + j/S)`, scaled by `(1, W/H)` and by
/// `b (1 − 0.1 c)`, `c = (x + y) mod 2` the pixel's checkerboard, with
/// `b = r² / z_view`: Bevy's `view_z` is the view-space `z`, negative in front of the camera, so
/// `b = −r² / fragment_depth` (the spiral turned half a turn; Bevy's firefly clamp
/// `min(rgb, normalize(rgb) / saturate(b/2))` then divides by 0 and never clamps). A tap whose
/// texel holds an opaque surface nearer than the fragment (`fragment_depth`) is rejected (its
/// colour and alpha 0, Bevy's prepass test). Returns `(Σ accepted colours / taps, accepted /
/// taps)`: Bevy mixes the environment in by `1 − alpha` and keeps the sum as it is.
pub fn bevy_blurred<M: ScreenMips, S: OpaqueDepth>(
    mips: &M,
    screen: &S,
    frag_px: Vec2,
    read_uv: Vec2,
    roughness: f32,
    fragment_depth: f32,
) -> (Vec3, f32) {
    const ORDER: [u32; 8] = [0, 2, 4, 6, 1, 3, 5, 7];
    let size = mips.size();
    let aspect = size.x as f32 / size.y as f32;
    let blur = -(roughness * roughness) / fragment_depth;
    let spirals = BEVY_TAPS.div_ceil(8);
    let noise = interleaved_gradient_noise(frag_px);
    let checker = ((frag_px.x as i32 + frag_px.y as i32) % 2) as f32;
    let (mut sum, mut accepted) = (Vec3::ZERO, 0u32);
    for i in 0..BEVY_TAPS {
        let spiral = i >> 3;
        let angle = (noise + spiral as f32 / spirals as f32) * core::f32::consts::TAU;
        let (sin, cos) = math::sin_cos(angle);
        let offset = spiral_offset(ORDER[(i & 7) as usize])
            * (1.0 - 0.5 * (spiral + 1) as f32 / spirals as f32);
        // Bevy's `mat2x2(m.y, −m.x, m.x, m.y) * offset` with m = (sin, cos).
        let rotated = Vec2::new(
            cos * offset.x + sin * offset.y,
            -sin * offset.x + cos * offset.y,
        );
        let uv = read_uv + rotated * Vec2::new(1.0, aspect) * blur * (1.0 - checker * 0.1);
        let texel = (uv * size.as_vec2())
            .floor()
            .max(Vec2::ZERO)
            .min((size - UVec2::ONE).as_vec2())
            .as_uvec2();
        if screen.view_depth(texel) < fragment_depth {
            continue;
        }
        sum += screen_mips::sample_bilinear(mips, uv, 0);
        accepted += 1;
    }
    (sum / BEVY_TAPS as f32, accepted as f32 / BEVY_TAPS as f32)
}

/// Godot's offset in pixels: `−n_view.xy · scale` of `SCREEN_UV`, i.e.
/// `(−n_x scale W, −n_y scale H)` in `y`-down pixels (`n_view` `y` up: Godot 4's `SCREEN_UV`
/// is `y` down while `NORMAL` is `y` up, so the sample moves against the normal in `x` and
/// with it in `y`, as the engine's formula does; the same scale on both axes, not
/// aspect-corrected).
#[inline]
pub fn screen_offset_px(n_view: Vec3, scale: f32, size: Vec2) -> Vec2 {
    -Vec2::new(n_view.x, n_view.y) * scale * size
}

/// `smoothstep(0, 1, x)`: `3x² − 2x³` of `x` clamped to `[0, 1]`.
#[inline]
pub fn smoothstep01(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// HDRP's `EdgeOfScreenFade` of a position `uv ∈ [0, 1]²`: per axis
/// `smoothstep01(saturate((1 − |2 uv − 1|) / fade))`, the product of both (0 off screen).
#[inline]
pub fn hdrp_edge_fade(uv: Vec2) -> f32 {
    let f = |u: f32| smoothstep01(((1.0 - (2.0 * u - 1.0).abs()) / HDRP_EDGE_FADE).clamp(0.0, 1.0));
    f(uv.x) * f(uv.y)
}

/// The texel a position in pixels reads (nearest, clamped to the frame) and whether it was
/// outside the frame.
#[inline]
pub fn clamp_to_screen(uv_px: Vec2, size: UVec2) -> (UVec2, bool) {
    let (w, h) = (size.x as f32, size.y as f32);
    let inside = uv_px.x >= 0.0 && uv_px.y >= 0.0 && uv_px.x < w && uv_px.y < h;
    let x = uv_px.x.clamp(0.0, w - 1.0) as u32;
    let y = uv_px.y.clamp(0.0, h - 1.0) as u32;
    (UVec2::new(x, y), !inside)
}

/// What [`engine_path`] computes before it reads the screen, for one pixel (`Vec3`) or eight
/// ([`engine_path_x8`]): one body, so the same bits.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Geometry<V: Vector3> {
    incident: V,
    fragment_depth: V::Real,
    p2: V,
    t2: V,
    /// The screen offset's shifted position; for the others the projected lookup point (the
    /// exit, or HDRP's hit on the sky), valid where `in_front`.
    lookup_px: (V::Real, V::Real),
    in_front: Msk<V>,
}

impl Geometry<Vec3> {
    /// The lookup position, `None` behind the eye.
    #[inline]
    fn projected(&self) -> Option<Vec2> {
        self.in_front
            .then(|| Vec2::new(self.lookup_px.0, self.lookup_px.1))
    }
}

/// The per-pixel geometry of `model` at the front surface `(p1_ws, n1_ws)` of the pixel at
/// `uv_px` (its `x` and `y`), for one pixel or eight.
#[inline]
fn geometry<V: Vector3>(
    camera: &Camera,
    uv_px: (V::Real, V::Real),
    p1_ws: V,
    n1_ws: V,
    ior: V::Real,
    model: EngineModel,
) -> Geometry<V> {
    let splat = V::Real::splat;
    let from_eye = p1_ws - V::constant(camera.eye());
    let incident = from_eye.normalize_or_zero();
    // `view_depth`: along the look direction.
    let fragment_depth = from_eye.dot(V::constant(camera.look_dir()));
    let geometry = |p2: V, t2: V, lookup: V| {
        let (x, y, in_front) = camera.world_to_pixel_xy(lookup);
        Geometry {
            incident,
            fragment_depth,
            p2,
            t2,
            lookup_px: (x, y),
            in_front,
        }
    };
    match model {
        EngineModel::ScreenOffset { scale, .. } => {
            // `screen_offset_px`: (−n_x scale W, −n_y scale H).
            let n_view = V::transform_vector3(&camera.world_to_view(), n1_ws);
            let (w, h) = (splat(camera.width() as f32), splat(camera.height() as f32));
            let x = uv_px.0 + -n_view.x() * splat(scale) * w;
            let y = uv_px.1 + -n_view.y() * splat(scale) * h;
            let nan = V::constant(Vec3::NAN);
            Geometry {
                incident,
                fragment_depth,
                p2: nan,
                t2: nan,
                lookup_px: (x, y),
                in_front: LaneMask::splat(true),
            }
        }
        EngineModel::VolumeThickness { thickness, .. } => {
            let (x, t) = volume_exit(p1_ws, n1_ws, incident, ior, splat(thickness));
            geometry(x, t, x)
        }
        EngineModel::Proxy {
            shape,
            thickness,
            lookup,
        } => {
            let (p1, r2) = match shape {
                ProxyShape::Sphere => {
                    proxy_sphere_exit(p1_ws, n1_ws, incident, ior, splat(thickness))
                }
                ProxyShape::Box => proxy_box_exit(p1_ws, n1_ws, incident, ior, splat(thickness)),
                ProxyShape::Thin => {
                    proxy_box_exit(p1_ws, n1_ws, incident, ior, splat(THIN_THICKNESS))
                }
            };
            let point = match lookup {
                ProxyLookup::Filament => p1,
                ProxyLookup::Hdrp => p1 + r2 * splat(HDRP_SKY_DISTANCE),
            };
            geometry(p1, r2, point)
        }
    }
}

/// The lookup of a pixel whose geometry is `g`: which texel, with which weight, what else.
#[inline]
fn finish<S: OpaqueDepth>(
    size: UVec2,
    screen: &S,
    uv_px: Vec2,
    g: &Geometry<Vec3>,
    model: EngineModel,
) -> EnginePath {
    let own_texel = clamp_to_screen(uv_px, size).0;
    let screen_only = |texel: UVec2, off_screen: bool| EnginePath {
        texel,
        screen_weight: 1.0,
        environment_dir: Vec3::NAN,
        p2: g.p2,
        t2: g.t2,
        off_screen,
    };
    let projected = |q: Option<Vec2>| match q {
        Some(q) => clamp_to_screen(q, size),
        None => (own_texel, true),
    };
    match model {
        EngineModel::ScreenOffset { depth_guard, .. } => {
            let offset = g.projected().unwrap_or(uv_px);
            let (texel, off_screen) = clamp_to_screen(offset, size);
            let texel = if depth_guard {
                let w = smoothstep01(screen.view_depth(texel) - g.fragment_depth);
                clamp_to_screen(uv_px.lerp(offset, w), size).0
            } else {
                texel
            };
            screen_only(texel, off_screen)
        }
        EngineModel::VolumeThickness {
            thickness,
            reject_nearer,
        } => {
            let (texel, off_screen) = projected(g.projected());
            if reject_nearer && screen.view_depth(texel) < g.fragment_depth {
                return EnginePath {
                    screen_weight: 0.0,
                    environment_dir: bevy_fallback_dir(g.incident, g.t2, thickness),
                    ..screen_only(texel, off_screen)
                };
            }
            screen_only(texel, off_screen)
        }
        EngineModel::Proxy {
            lookup: ProxyLookup::Filament,
            ..
        } => {
            let (texel, off_screen) = projected(g.projected());
            screen_only(texel, off_screen)
        }
        EngineModel::Proxy {
            lookup: ProxyLookup::Hdrp,
            ..
        } => {
            let Some(hit) = g.projected() else {
                return EnginePath {
                    screen_weight: 0.0,
                    environment_dir: g.t2,
                    ..screen_only(own_texel, true)
                };
            };
            let weight = hdrp_edge_fade(hit / size.as_vec2());
            let (hit_texel, off_screen) = clamp_to_screen(hit, size);
            let texel = if screen.view_depth(hit_texel) > g.fragment_depth {
                hit_texel
            } else {
                own_texel
            };
            EnginePath {
                screen_weight: weight,
                environment_dir: g.t2,
                ..screen_only(texel, off_screen)
            }
        }
    }
}

/// What `model` reads for the refractor pixel at `uv_px` (its centre) whose nearest front
/// surface is `(p1_ws, n1_ws)` (`n1_ws` unit, outward), from `screen`. `ior ≥ 1`.
pub fn engine_path<S: OpaqueDepth>(
    camera: &Camera,
    screen: &S,
    uv_px: Vec2,
    p1_ws: Vec3,
    n1_ws: Vec3,
    ior: f32,
    model: EngineModel,
) -> EnginePath {
    let g = geometry(camera, (uv_px.x, uv_px.y), p1_ws, n1_ws, ior, model);
    let size = UVec2::new(camera.width(), camera.height());
    finish(size, screen, uv_px, &g, model)
}

/// [`engine_path`] for eight pixels: lane `i` is `engine_path(camera, screen, uv_px[i],
/// p1_ws[i], n1_ws[i], ior[i], model)`, bit for bit (tested). The geometry runs on eight lanes;
/// the reads of the screen's depth run per lane.
pub fn engine_path_x8<S: OpaqueDepth>(
    camera: &Camera,
    screen: &S,
    uv_px: &[Vec2; LANES],
    p1_ws: &[Vec3; LANES],
    n1_ws: &[Vec3; LANES],
    ior: &[f32; LANES],
    model: EngineModel,
) -> [EnginePath; LANES] {
    let uv = Vec2x8::from_lanes(uv_px);
    let (p, n) = (Vec3x8::from_lanes(p1_ws), Vec3x8::from_lanes(n1_ws));
    let g = geometry(camera, (uv.x, uv.y), p, n, F32x8::from(*ior), model);
    let size = UVec2::new(camera.width(), camera.height());
    // Each vector taken apart once, each lane's geometry built where it is finished.
    let (incident, p2, t2) = (g.incident.to_lanes(), g.p2.to_lanes(), g.t2.to_lanes());
    let depth = g.fragment_depth.to_array();
    let (x, y) = (g.lookup_px.0.to_array(), g.lookup_px.1.to_array());
    let in_front = mask_lanes(g.in_front);
    let mut paths = [EnginePath {
        texel: UVec2::ZERO,
        screen_weight: 0.0,
        environment_dir: Vec3::NAN,
        p2: Vec3::NAN,
        t2: Vec3::NAN,
        off_screen: false,
    }; LANES];
    // A loop, not `array::from_fn`: its closure was left as a call per lane.
    for (i, path) in paths.iter_mut().enumerate() {
        let lane = Geometry {
            incident: incident[i],
            fragment_depth: depth[i],
            p2: p2[i],
            t2: t2[i],
            lookup_px: (x[i], y[i]),
            in_front: in_front[i],
        };
        *path = finish(size, screen, uv_px[i], &lane, model);
    }
    paths
}

/// Model code of [`EngineModel::ScreenOffset`].
pub const ENGINE_SCREEN_OFFSET: u32 = 0;
/// Model code of [`EngineModel::VolumeThickness`].
pub const ENGINE_VOLUME_THICKNESS: u32 = 1;
/// Model code of [`ProxyShape::Sphere`].
pub const ENGINE_PROXY_SPHERE: u32 = 2;
/// Model code of [`ProxyShape::Box`].
pub const ENGINE_PROXY_BOX: u32 = 3;
/// Model code of [`ProxyShape::Thin`].
pub const ENGINE_PROXY_THIN: u32 = 4;

/// The per-frame parameters of the engine shader (`refract-gpu/src/methods/engine_path.wgsl`, `EngineUniforms`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct EngineUniforms {
    /// `world_to_view` (column-major), for Godot's view-space normal.
    pub world_to_view: [[f32; 4]; 4],
    /// `d` in world units (the screen offset's `scale` for [`ENGINE_SCREEN_OFFSET`]).
    pub amount: f32,
    /// 1: Godot's depth guard or Bevy's depth rejection.
    pub depth_test: u32,
    /// 1: Filament's lookup, 0: HDRP's.
    pub filament_lookup: u32,
    /// 1 when the scene has opaque objects; 0: the screen texture is the environment
    /// everywhere and is neither drawn nor read.
    pub has_objects: u32,
}

impl EngineUniforms {
    /// The uniforms of `model` seen by `camera`, for a scene with or without opaque objects.
    pub fn new(camera: &Camera, model: &EngineModel, has_objects: bool) -> Self {
        let (amount, depth_test, filament_lookup) = match *model {
            EngineModel::ScreenOffset { scale, depth_guard } => (scale, depth_guard, false),
            EngineModel::VolumeThickness {
                thickness,
                reject_nearer,
            } => (thickness, reject_nearer, false),
            EngineModel::Proxy {
                thickness, lookup, ..
            } => (thickness, false, lookup == ProxyLookup::Filament),
        };
        Self {
            world_to_view: camera.world_to_view().to_cols_array_2d(),
            amount,
            depth_test: u32::from(depth_test),
            filament_lookup: u32::from(filament_lookup),
            has_objects: u32::from(has_objects),
        }
    }
}

#[cfg(test)]
mod tests {

    /// The levels a rough read touches: Bevy's level 0, a LOD's up to `⌈lod⌉`, none when smooth.
    #[test]
    fn rough_reads_touch_the_levels_they_build() {
        let size = UVec2::new(256, 192);
        let bevy = EngineModel::VolumeThickness {
            thickness: 1.0,
            reject_nearer: true,
        };
        let three = EngineModel::VolumeThickness {
            thickness: 1.0,
            reject_nearer: false,
        };
        assert_eq!(bevy.rough_levels(0.6, size), 1);
        assert_eq!(bevy.rough_levels(0.0, size), 0);
        assert_eq!(three.rough_levels(2.0, size), 3);
        assert_eq!(three.rough_levels(2.3, size), 4);
        assert_eq!(three.rough_levels(0.2, size), 2);
        assert_eq!(
            three.rough_levels(40.0, size),
            screen_mips::level_count(size)
        );
    }

    /// three.js's model disperses by its three indices, Filament's sphere by its four; the
    /// others not at all.
    #[test]
    fn which_models_disperse() {
        let three = EngineModel::VolumeThickness {
            thickness: 1.0,
            reject_nearer: false,
        };
        assert_eq!(
            three.dispersion(1.5, 30.0),
            EngineDispersion::ThreeJs {
                half_spread: 0.5 * 0.025 * 20.0 / 30.0
            }
        );
        assert_eq!(three.dispersion(1.5, f32::INFINITY), EngineDispersion::None);
        let filament = |shape| EngineModel::Proxy {
            shape,
            thickness: 1.0,
            lookup: ProxyLookup::Filament,
        };
        assert_eq!(
            filament(ProxyShape::Sphere).dispersion(1.5, 30.0),
            EngineDispersion::Filament { factor: 0.5 / 30.0 }
        );
        let bevy = EngineModel::VolumeThickness {
            thickness: 1.0,
            reject_nearer: true,
        };
        let godot = EngineModel::ScreenOffset {
            scale: 0.05,
            depth_guard: true,
        };
        let hdrp = EngineModel::Proxy {
            shape: ProxyShape::Sphere,
            thickness: 1.0,
            lookup: ProxyLookup::Hdrp,
        };
        for other in [
            bevy,
            godot,
            hdrp,
            filament(ProxyShape::Box),
            filament(ProxyShape::Thin),
        ] {
            assert_eq!(
                other.dispersion(1.5, 30.0),
                EngineDispersion::None,
                "{other:?}"
            );
        }
    }

    use super::*;
    use crate::camera::CameraDesc;
    use crate::nearby_geometry::view_depth;

    /// A screen with one depth everywhere.
    struct Flat(f32);
    impl OpaqueDepth for Flat {
        fn view_depth(&self, _: UVec2) -> f32 {
            self.0
        }
    }

    fn camera() -> Camera {
        Camera::new(CameraDesc {
            width: 200,
            height: 100,
            ..CameraDesc::default()
        })
        .expect("a valid camera")
    }

    /// A screen whose depth varies per texel, so that depth tests pass and fail across lanes.
    struct Ramp;
    impl OpaqueDepth for Ramp {
        fn view_depth(&self, texel: UVec2) -> f32 {
            if texel.x.is_multiple_of(3) {
                f32::INFINITY
            } else {
                2.0 + 0.05 * texel.y as f32 + 0.01 * texel.x as f32
            }
        }
    }

    /// `engine_path_x8` is `engine_path` lane by lane, bit for bit, for every model and lookup
    /// (pseudo-random surfaces: grazing normals, points near and far, off-screen lookups).
    #[test]
    fn lanes_equal_the_scalar_path_bit_for_bit() {
        let camera = camera();
        let mut seed = 0x2545_f491_u32;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            (seed as f32) / (u32::MAX as f32)
        };
        let models = [
            EngineModel::ScreenOffset {
                scale: 0.05,
                depth_guard: true,
            },
            EngineModel::ScreenOffset {
                scale: 0.3,
                depth_guard: false,
            },
            EngineModel::VolumeThickness {
                thickness: 0.7,
                reject_nearer: false,
            },
            EngineModel::VolumeThickness {
                thickness: 2.5,
                reject_nearer: true,
            },
            EngineModel::Proxy {
                shape: ProxyShape::Sphere,
                thickness: 1.6,
                lookup: ProxyLookup::Hdrp,
            },
            EngineModel::Proxy {
                shape: ProxyShape::Sphere,
                thickness: 0.4,
                lookup: ProxyLookup::Filament,
            },
            EngineModel::Proxy {
                shape: ProxyShape::Box,
                thickness: 1.0,
                lookup: ProxyLookup::Hdrp,
            },
            EngineModel::Proxy {
                shape: ProxyShape::Thin,
                thickness: 0.0,
                lookup: ProxyLookup::Hdrp,
            },
        ];
        for model in models {
            for _ in 0..64 {
                let uv: [Vec2; LANES] =
                    core::array::from_fn(|_| Vec2::new(next() * 200.0, next() * 100.0));
                let p: [Vec3; LANES] =
                    core::array::from_fn(|i| camera.pixel_to_world(uv[i], 0.2 + 0.79 * next()));
                let n: [Vec3; LANES] = core::array::from_fn(|i| {
                    let toward_eye = (camera.eye() - p[i]).normalize();
                    let jitter = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 2.5;
                    (toward_eye + jitter).normalize()
                });
                let lanes = engine_path_x8(&camera, &Ramp, &uv, &p, &n, &[1.5; LANES], model);
                for i in 0..LANES {
                    let scalar = engine_path(&camera, &Ramp, uv[i], p[i], n[i], 1.5, model);
                    assert_eq!(
                        format!("{:?}", lanes[i]),
                        format!("{scalar:?}"),
                        "{model:?} lane {i}"
                    );
                }
            }
        }
    }

    /// A sphere of radius r at the origin: the sphere model with d = 2r is exact, so its exit
    /// point lies on the sphere and its direction is the exact two-refraction direction.
    #[test]
    fn sphere_model_is_exact_on_a_sphere() {
        let r = 1.3;
        let ior = 1.5;
        for k in 0..50 {
            let a = k as f32 * 0.03;
            let n = Vec3::new(a.sin(), 0.2 * a.cos(), a.cos()).normalize();
            let p = n * r;
            let i = Vec3::new(0.1, -0.2, -1.0).normalize();
            if i.dot(n) >= -0.05 {
                continue;
            }
            let (p1, r2) = proxy_sphere_exit(p, n, i, ior, 2.0 * r);
            assert!((p1.length() - r).abs() < 1e-4, "exit off the sphere: {p1}");
            let t = refract(i, n, 1.0 / ior);
            let exact = refract(t, -p1.normalize(), ior);
            assert!(r2.angle_between(exact) < 1e-3, "{r2} vs {exact}");
            // The exit angle equals the entry's refraction angle.
            let cos_exit = r2.dot(p1.normalize());
            let cos_entry = -n.dot(i);
            assert!((cos_exit - cos_entry).abs() < 1e-3);
        }
    }

    /// A slab of thickness d along z: the box model's exit lies on its back plane, the direction
    /// is the incident one (exact for parallel faces).
    #[test]
    fn box_model_is_exact_on_a_slab() {
        let d = 0.4;
        let i = Vec3::new(0.5, 0.1, -1.0).normalize();
        let (p1, r2) = proxy_box_exit(Vec3::ZERO, Vec3::Z, i, 1.5, d);
        assert!((p1.z + d).abs() < 1e-5);
        assert_eq!(r2, i);
        // Lateral shift from Snell: tan θt · d.
        let sin_t = (1.0 - i.z * i.z).sqrt() / 1.5;
        let tan_t = sin_t / (1.0 - sin_t * sin_t).sqrt();
        assert!((p1.truncate().length() - tan_t * d).abs() < 1e-5);
    }

    #[test]
    fn volume_exit_walks_d_along_t_not_d_over_cos() {
        let i = Vec3::new(0.6, 0.0, -0.8);
        let (x, t) = volume_exit(Vec3::ZERO, Vec3::Z, i, 1.5, 2.0);
        assert!((x.length() - 2.0).abs() < 1e-5);
        assert!((t.length() - 1.0).abs() < 1e-5);
        assert!((bevy_fallback_dir(i, t, 0.0) - i).length() < 1e-6);
    }

    #[test]
    fn edge_fade_is_one_inside_and_zero_outside() {
        assert_eq!(hdrp_edge_fade(Vec2::splat(0.5)), 1.0);
        assert_eq!(hdrp_edge_fade(Vec2::new(1.2, 0.5)), 0.0);
        assert_eq!(hdrp_edge_fade(Vec2::new(0.5, -0.01)), 0.0);
        let near_edge = hdrp_edge_fade(Vec2::new(0.02, 0.5));
        assert!(near_edge > 0.0 && near_edge < 1.0);
    }

    /// Zero thickness means no offset at all (three.js and Bevy's default): the pixel's own
    /// texel; the screen offset with scale 0 too.
    #[test]
    fn zero_thickness_reads_the_pixel_behind() {
        let camera = camera();
        let uv = Camera::pixel_center(37, 61);
        let p = camera.pixel_to_world(uv, 0.5);
        let n = (camera.eye() - p).normalize() + Vec3::new(0.3, 0.2, 0.0);
        for model in [
            EngineModel::VolumeThickness {
                thickness: 0.0,
                reject_nearer: false,
            },
            EngineModel::ScreenOffset {
                scale: 0.0,
                depth_guard: true,
            },
        ] {
            let path = engine_path(
                &camera,
                &Flat(f32::INFINITY),
                uv,
                p,
                n.normalize(),
                1.5,
                model,
            );
            assert_eq!(path.texel, UVec2::new(37, 61), "{model:?}");
            assert!(!path.off_screen);
        }
    }

    /// Bevy rejects a sample in front of the glass; three.js reads it (the foreground leak).
    #[test]
    fn bevy_rejects_foreground_samples_three_js_leaks_them() {
        let camera = camera();
        let uv = Camera::pixel_center(100, 50);
        let p = camera.pixel_to_world(uv, 0.9);
        let n = (camera.eye() - p).normalize();
        let depth = view_depth(&camera, p);
        let near = Flat(0.5 * depth);
        let model = |reject_nearer| EngineModel::VolumeThickness {
            thickness: 0.3,
            reject_nearer,
        };
        let bevy = engine_path(&camera, &near, uv, p, n, 1.5, model(true));
        assert_eq!(bevy.screen_weight, 0.0);
        assert!(bevy.environment_dir.is_finite());
        let three = engine_path(&camera, &near, uv, p, n, 1.5, model(false));
        assert_eq!(three.screen_weight, 1.0);
    }

    /// Godot's guard keeps the pixel's own texel when the offset sample is in front.
    #[test]
    fn godot_guard_falls_back_to_the_unshifted_texel() {
        let camera = camera();
        let uv = Camera::pixel_center(100, 50);
        let p = camera.pixel_to_world(uv, 0.9);
        let n = ((camera.eye() - p).normalize() + Vec3::X).normalize();
        let depth = view_depth(&camera, p);
        let model = |depth_guard| EngineModel::ScreenOffset {
            scale: 0.05,
            depth_guard,
        };
        let guarded = engine_path(&camera, &Flat(depth - 1.0), uv, p, n, 1.5, model(true));
        assert_eq!(guarded.texel, UVec2::new(100, 50));
        let shifted = engine_path(&camera, &Flat(depth - 1.0), uv, p, n, 1.5, model(false));
        assert!(
            shifted.texel.x < 100,
            "the normal's +x moves the sample left"
        );
        let behind = engine_path(&camera, &Flat(depth + 2.0), uv, p, n, 1.5, model(true));
        assert_eq!(behind.texel, shifted.texel);
    }

    /// HDRP with the exit direction straight ahead reads the vanishing point, faded near the
    /// edges and the environment beyond them.
    #[test]
    fn hdrp_lookup_reads_the_vanishing_point_and_fades_off_screen() {
        let camera = camera();
        let uv = Camera::pixel_center(100, 50);
        let p = camera.pixel_to_world(uv, 0.9);
        let n = (camera.eye() - p).normalize();
        let model = EngineModel::Proxy {
            shape: ProxyShape::Box,
            thickness: 0.1,
            lookup: ProxyLookup::Hdrp,
        };
        let path = engine_path(&camera, &Flat(f32::INFINITY), uv, p, n, 1.5, model);
        assert!(path.screen_weight > 0.99);
        assert!(
            path.texel
                .as_ivec2()
                .distance_squared(glam::IVec2::new(100, 50))
                <= 2
        );
        // A grazing normal sends the exit direction (R2 = I for the box) off screen only when
        // I itself leaves it: at the corner pixel the fade is partial.
        let corner = Camera::pixel_center(1, 1);
        let q = camera.pixel_to_world(corner, 0.9);
        let path = engine_path(
            &camera,
            &Flat(f32::INFINITY),
            corner,
            q,
            (camera.eye() - q).normalize(),
            1.5,
            model,
        );
        assert!(path.screen_weight < 0.2, "{}", path.screen_weight);
    }
}
