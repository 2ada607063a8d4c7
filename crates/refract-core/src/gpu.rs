//! The data the WGSL twin shares with Rust: the `#[repr(C)]` uniform block of a frame and the
//! integer codes of enums and per-pixel flags, defined once here. `refract-gpu` generates the WGSL constant header
//! from [`wgsl_constants`], and its tests compare [`FrameUniforms`]' offsets with the WGSL
//! struct's (as naga lays it out).

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;

use bytemuck::{Pod, Zeroable};

use crate::exit::{ExitNormalSource, TirPolicy};
use crate::interpolated_distance::{DistanceMode, NORMAL_INCIDENCE_ANGLE};
use crate::nearby_geometry::{MAX_PLANES, NearbyLookup, SeedSpacing};
use crate::optics::FACE_FORWARD_EPSILON;
use crate::vector::UNIT_TOLERANCE;

/// Per-frame uniforms of the GPU passes (`refract-gpu/shaders/frame.wgsl`, `struct FrameUniforms`).
/// Matrices are column-major, as glam and WGSL store them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct FrameUniforms {
    /// `Camera::world_to_clip`.
    pub world_to_clip: [[f32; 4]; 4],
    /// `Camera::view_to_world`.
    pub view_to_world: [[f32; 4]; 4],
    /// Eye position, `w` unused.
    pub eye: [f32; 4],
    /// Unit look direction, `w` unused.
    pub look_dir: [f32; 4],
    /// Radiance of a constant environment, `w` unused.
    pub environment_constant: [f32; 4],
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// `tan(fov_y / 2)`.
    pub tan_half_fov_y: f32,
    /// `width / height`, negated for a mirrored camera (the `x` scale of view-space rays).
    pub aspect: f32,
    /// Index of refraction.
    pub ior: f32,
    /// [`tir_policy_code`].
    pub tir_policy: u32,
    /// [`ENVIRONMENT_PROCEDURAL`], [`ENVIRONMENT_LATLONG`] or [`ENVIRONMENT_CONSTANT`].
    pub environment_kind: u32,
    /// Lat-long map width.
    pub environment_width: u32,
    /// Lat-long map height.
    pub environment_height: u32,
    /// Lat-long map intensity.
    pub environment_intensity: f32,
    /// Padding to a multiple of 16 bytes.
    pub _padding: [u32; 2],
}

/// Uniforms of the nearby-geometry pass (`refract-gpu/shaders/object_surfaces.wgsl`,
/// `struct NearbyUniforms`): the NG camera, the light of the opaque objects, the planes of the
/// ray-plane lookup and the lookup's counts.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct NearbyUniforms {
    /// The NG camera's `world_to_clip`.
    pub world_to_clip: [[f32; 4]; 4],
    /// The NG camera's eye, `w` unused.
    pub eye: [f32; 4],
    /// The NG camera's unit look direction, `w` unused.
    pub look_dir: [f32; 4],
    /// Unit direction toward the light, `w` unused.
    pub light_direction: [f32; 4],
    /// Light radiance, `w` unused.
    pub light_radiance: [f32; 4],
    /// Ambient term, `w` unused.
    pub light_ambient: [f32; 4],
    /// Planes `(n, d)` with `n · x = d`; the first `plane_count` are used.
    pub planes: [[f32; 4]; MAX_PLANES],
    /// NG texture width.
    pub width: u32,
    /// NG texture height.
    pub height: u32,
    /// Guard band in texels, `x`.
    pub pad_x: u32,
    /// Guard band in texels, `y`.
    pub pad_y: u32,
    /// Planes used.
    pub plane_count: u32,
    /// Iterations of the iterative lookups.
    pub iterations: u32,
    /// Seeds `K`.
    pub seeds: u32,
    /// [`seed_spacing_code`].
    pub spacing: u32,
}

/// The `LOOKUP` override constant of a nearby-geometry pipeline.
pub const fn lookup_code(lookup: NearbyLookup) -> u32 {
    match lookup {
        NearbyLookup::KayGreenberg => 0,
        NearbyLookup::RayPlane => 1,
        NearbyLookup::Iterative { .. } => 2,
        NearbyLookup::Seeded { .. } => 3,
    }
}

/// `NearbyUniforms::spacing` of a seed spacing.
pub const fn seed_spacing_code(spacing: SeedSpacing) -> u32 {
    match spacing {
        SeedSpacing::Screen => 0,
        SeedSpacing::World => 1,
    }
}

/// `environment_kind` of the procedural environment.
pub const ENVIRONMENT_PROCEDURAL: u32 = 0;
/// `environment_kind` of a lat-long map.
pub const ENVIRONMENT_LATLONG: u32 = 1;
/// `environment_kind` of a constant environment.
pub const ENVIRONMENT_CONSTANT: u32 = 2;

/// The WGSL code of a [`TirPolicy`].
pub const fn tir_policy_code(policy: TirPolicy) -> u32 {
    match policy {
        TirPolicy::ClampToCritical => 0,
        TirPolicy::ReflectOnce => 1,
        TirPolicy::Black => 2,
    }
}

/// The WGSL code of a [`DistanceMode`].
pub const fn distance_mode_code(mode: DistanceMode) -> u32 {
    match mode {
        DistanceMode::Interpolated => 0,
        DistanceMode::ViewOnly => 1,
        DistanceMode::NormalOnly => 2,
    }
}

/// The WGSL code of an [`ExitNormalSource`] (0 means none).
pub const fn exit_normal_source_code(source: ExitNormalSource) -> u32 {
    match source {
        ExitNormalSource::BackFace => 1,
        ExitNormalSource::SilhouetteFallback => 2,
    }
}

/// The [`ExitNormalSource`] of a WGSL code, the inverse of [`exit_normal_source_code`]
/// (`None` for 0 and unknown codes).
pub fn exit_normal_source_from_code(code: u32) -> Option<ExitNormalSource> {
    [
        ExitNormalSource::BackFace,
        ExitNormalSource::SilhouetteFallback,
    ]
    .into_iter()
    .find(|s| exit_normal_source_code(*s) == code)
}

/// Per-pixel coverage codes of the GPU colour output's `w`: the pixel sees the background.
pub const COVERAGE_BACKGROUND: u32 = 0;
/// The pixel sees the refractor and the kernel produced a path.
pub const COVERAGE_PATH: u32 = 1;
/// The pixel sees the refractor but the kernel reported a degenerate input (black, no path).
pub const COVERAGE_DEGENERATE: u32 = 2;

/// The WGSL `const` declarations every shader module starts with: the numbers the Rust code
/// uses, so that neither side hard-codes them.
pub fn wgsl_constants() -> String {
    let f = |v: f32| format!("{v:e}");
    [
        format!(
            "const FACE_FORWARD_EPSILON: f32 = {};",
            f(FACE_FORWARD_EPSILON)
        ),
        format!(
            "const NORMAL_INCIDENCE_ANGLE: f32 = {};",
            f(NORMAL_INCIDENCE_ANGLE)
        ),
        format!("const UNIT_TOLERANCE: f32 = {};", f(UNIT_TOLERANCE)),
        format!(
            "const TIR_CLAMP_TO_CRITICAL: u32 = {}u;",
            tir_policy_code(TirPolicy::ClampToCritical)
        ),
        format!(
            "const TIR_REFLECT_ONCE: u32 = {}u;",
            tir_policy_code(TirPolicy::ReflectOnce)
        ),
        format!(
            "const TIR_BLACK: u32 = {}u;",
            tir_policy_code(TirPolicy::Black)
        ),
        format!(
            "const DISTANCE_INTERPOLATED: u32 = {}u;",
            distance_mode_code(DistanceMode::Interpolated)
        ),
        format!(
            "const DISTANCE_VIEW_ONLY: u32 = {}u;",
            distance_mode_code(DistanceMode::ViewOnly)
        ),
        format!(
            "const DISTANCE_NORMAL_ONLY: u32 = {}u;",
            distance_mode_code(DistanceMode::NormalOnly)
        ),
        format!("const COVERAGE_BACKGROUND: u32 = {COVERAGE_BACKGROUND}u;"),
        format!("const COVERAGE_PATH: u32 = {COVERAGE_PATH}u;"),
        format!("const COVERAGE_DEGENERATE: u32 = {COVERAGE_DEGENERATE}u;"),
        format!("const ENVIRONMENT_PROCEDURAL: u32 = {ENVIRONMENT_PROCEDURAL}u;"),
        format!("const ENVIRONMENT_LATLONG: u32 = {ENVIRONMENT_LATLONG}u;"),
        format!("const ENVIRONMENT_CONSTANT: u32 = {ENVIRONMENT_CONSTANT}u;"),
        format!(
            "const DM_T_START: f32 = {};",
            f(crate::distance_map::T_START)
        ),
        format!("const DM_T_END: f32 = {};", f(crate::distance_map::T_END)),
        format!(
            "const DM_SECANT_TOLERANCE: f32 = {};",
            f(crate::distance_map::SECANT_TOLERANCE)
        ),
        format!(
            "const DM_MIN_MAX_MARGIN: f32 = {};",
            f(crate::distance_map::MIN_MAX_MARGIN)
        ),
        format!(
            "const DM_START_SKIP_TEXELS: f32 = {};",
            f(crate::distance_map::START_SKIP_TEXELS)
        ),
        format!(
            "const DM_MAX_LAYERS: u32 = {}u;",
            crate::distance_map::MAX_LAYERS
        ),
        format!(
            "const MAX_PEEL_LAYERS: u32 = {}u;",
            crate::depth_peel::MAX_PEEL_LAYERS
        ),
        format!(
            "const PEEL_REFINE_STEPS: u32 = {}u;",
            crate::depth_peel::REFINE_STEPS
        ),
        format!(
            "const PEEL_END_LEFT: u32 = {}u;",
            crate::depth_peel::PeelEnd::Left.code()
        ),
        format!(
            "const PEEL_END_LOST: u32 = {}u;",
            crate::depth_peel::PeelEnd::Lost.code()
        ),
        format!(
            "const PEEL_END_OFF_SCREEN: u32 = {}u;",
            crate::depth_peel::PeelEnd::OffScreen.code()
        ),
        format!(
            "const PEEL_END_BUDGET: u32 = {}u;",
            crate::depth_peel::PeelEnd::Budget.code()
        ),
        format!(
            "const DM_FRESNEL_IGNORE: u32 = {}u;",
            crate::distance_map::fresnel_code(crate::distance_map::DielectricFresnel::Ignore)
        ),
        format!(
            "const DM_FRESNEL_SCHLICK: u32 = {}u;",
            crate::distance_map::fresnel_code(crate::distance_map::DielectricFresnel::Schlick)
        ),
        format!(
            "const DM_FRESNEL_SPLIT: u32 = {}u;",
            crate::distance_map::fresnel_code(crate::distance_map::DielectricFresnel::Split)
        ),
        format!(
            "const EXIT_NORMAL_BACK_FACE: u32 = {}u;",
            exit_normal_source_code(ExitNormalSource::BackFace)
        ),
        format!(
            "const EXIT_NORMAL_FALLBACK: u32 = {}u;",
            exit_normal_source_code(ExitNormalSource::SilhouetteFallback)
        ),
        format!(
            "const LOOKUP_KAY_GREENBERG: u32 = {}u;",
            lookup_code(NearbyLookup::KayGreenberg)
        ),
        format!(
            "const LOOKUP_RAY_PLANE: u32 = {}u;",
            lookup_code(NearbyLookup::RayPlane)
        ),
        format!(
            "const LOOKUP_ITERATIVE: u32 = {}u;",
            lookup_code(NearbyLookup::Iterative { iterations: 1 })
        ),
        format!(
            "const LOOKUP_SEEDED: u32 = {}u;",
            lookup_code(NearbyLookup::Seeded {
                iterations: 0,
                seeds: 1,
                spacing: SeedSpacing::Screen
            })
        ),
        format!(
            "const SPACING_SCREEN: u32 = {}u;",
            seed_spacing_code(SeedSpacing::Screen)
        ),
        format!(
            "const SPACING_WORLD: u32 = {}u;",
            seed_spacing_code(SeedSpacing::World)
        ),
        format!(
            "const ENGINE_SCREEN_OFFSET: u32 = {}u;",
            crate::engine::ENGINE_SCREEN_OFFSET
        ),
        format!(
            "const ENGINE_VOLUME_THICKNESS: u32 = {}u;",
            crate::engine::ENGINE_VOLUME_THICKNESS
        ),
        format!(
            "const ENGINE_PROXY_SPHERE: u32 = {}u;",
            crate::engine::ENGINE_PROXY_SPHERE
        ),
        format!(
            "const ENGINE_PROXY_BOX: u32 = {}u;",
            crate::engine::ENGINE_PROXY_BOX
        ),
        format!(
            "const ENGINE_PROXY_THIN: u32 = {}u;",
            crate::engine::ENGINE_PROXY_THIN
        ),
        format!(
            "const THIN_THICKNESS: f32 = {};",
            f(crate::engine::THIN_THICKNESS)
        ),
        format!(
            "const HDRP_SKY_DISTANCE: f32 = {};",
            f(crate::engine::HDRP_SKY_DISTANCE)
        ),
        format!(
            "const HDRP_EDGE_FADE: f32 = {};",
            f(crate::engine::HDRP_EDGE_FADE)
        ),
        format!(
            "const HDRP_MIN_COS: f32 = {};",
            f(crate::engine::HDRP_MIN_COS)
        ),
        format!(
            "const FILAMENT_JITTER: f32 = {};",
            f(crate::engine_dispersion::FILAMENT_JITTER)
        ),
        format!(
            "const FILAMENT_OFFSETS: array<f32, 4> = array<f32, 4>({});",
            crate::engine_dispersion::FILAMENT_OFFSETS
                .iter()
                .map(|&v| f(v))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        format!(
            "const FILAMENT_MATRICES: array<mat3x3<f32>, 4> = array<mat3x3<f32>, 4>({});",
            crate::engine_dispersion::FILAMENT_MATRICES
                .iter()
                .map(|m| format!(
                    "mat3x3<f32>({})",
                    m.iter().map(|&v| f(v)).collect::<Vec<_>>().join(", ")
                ))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        crate::spectral::wgsl_tables(),
    ]
    .join("\n")
        + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_block_is_tightly_packed_and_16_byte_aligned() {
        assert_eq!(core::mem::size_of::<FrameUniforms>(), 224);
        assert_eq!(core::mem::size_of::<FrameUniforms>() % 16, 0);
        assert_eq!(core::mem::offset_of!(FrameUniforms, eye), 128);
        assert_eq!(core::mem::offset_of!(FrameUniforms, width), 176);
        assert_eq!(
            core::mem::offset_of!(FrameUniforms, environment_intensity),
            212
        );
    }

    #[test]
    fn nearby_uniforms_are_16_byte_aligned() {
        assert_eq!(core::mem::size_of::<NearbyUniforms>(), 304);
        assert_eq!(core::mem::offset_of!(NearbyUniforms, planes), 144);
        assert_eq!(core::mem::offset_of!(NearbyUniforms, width), 272);
    }

    #[test]
    fn exit_normal_codes_round_trip() {
        for s in [
            ExitNormalSource::BackFace,
            ExitNormalSource::SilhouetteFallback,
        ] {
            assert_eq!(
                exit_normal_source_from_code(exit_normal_source_code(s)),
                Some(s)
            );
        }
        assert_eq!(exit_normal_source_from_code(0), None);
    }
}
