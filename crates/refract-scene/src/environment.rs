//! Distant lighting: lat-long HDR maps (loaded by refract-eval), a constant colour, and the
//! procedural default environment that needs no file.

use glam::Vec3;
use refract_core::environment::{Atan2, Exact, Polynomial, sample_latlong_bilinear};
use refract_core::lanes::{F32x8, Vec3x8};
use refract_core::procedural_sky::{procedural_radiance, procedural_radiance_x8};

/// A lat-long (equirectangular) map of linear RGB radiance, row 0 at the zenith.
#[derive(Clone, Debug, PartialEq)]
pub struct LatLongMap {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width × height` texels, row-major from the top.
    pub texels: Vec<Vec3>,
}

/// What loading a map had to fix.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EnvironmentReport {
    /// Negative channel values clamped to 0 (down-sampling ringing in real HDRIs).
    pub negative_clamped: usize,
    /// NaN or infinite channel values replaced by 0.
    pub non_finite_replaced: usize,
}

/// Radiance arriving from infinitely far away, by direction.
#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    /// A lat-long map scaled by an intensity, looked up bilinearly (Mitsuba's convention).
    LatLong {
        /// The map.
        map: LatLongMap,
        /// Radiance scale.
        intensity: f32,
    },
    /// The same radiance from every direction (the white furnace).
    Constant(Vec3),
    /// The built-in procedural sky and checkered ground, see [`procedural_radiance`].
    Procedural,
}

impl Environment {
    /// Radiance arriving along `-dir` (i.e. seen when looking along unit `dir`), with `atan2`
    /// evaluated by `A`.
    #[inline]
    pub fn radiance_with<A: Atan2>(&self, dir: Vec3) -> Vec3 {
        match self {
            Self::LatLong { map, intensity } => {
                *intensity
                    * sample_latlong_bilinear::<A, _>(&map.texels, map.width, map.height, dir)
            }
            Self::Constant(c) => *c,
            Self::Procedural => procedural_radiance::<A>(dir),
        }
    }

    /// The backends' lookup: [`Self::radiance_with`] the polynomial `atan2` that the WGSL twin
    /// is held to.
    #[inline]
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        self.radiance_with::<Polynomial>(dir)
    }

    /// The reference's lookup: [`Self::radiance_with`] libm's `atan2f`, no approximation.
    #[inline]
    pub fn radiance_exact(&self, dir: Vec3) -> Vec3 {
        self.radiance_with::<Exact>(dir)
    }

    /// [`Self::radiance`] for eight unit directions at once (bit-identical per lane).
    #[inline]
    pub fn radiance_x8(&self, dir: Vec3x8) -> Vec3x8 {
        match self {
            Self::Procedural => procedural_radiance_x8(dir),
            Self::Constant(c) => Vec3x8::splat(*c),
            Self::LatLong { map, intensity } => {
                let texels = &map.texels;
                sample_latlong_bilinear::<Polynomial, _>(texels, map.width, map.height, dir)
                    * F32x8::splat(*intensity)
            }
        }
    }
}
