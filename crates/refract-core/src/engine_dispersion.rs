//! The engines' own dispersion (glTF `KHR_materials_dispersion`, `dispersion = 20 / V_d`): a
//! pixel of dispersive glass is a few lookups of the engine's path, each at its own index, and
//! each lookup's read is mapped to the pixel's colour by a 3 × 3 matrix
//! ([`EngineDispersion::lookup`]).
//!
//! * three.js (r163 on, `transmission_pars_fragment`, `USE_DISPERSION`): three lookups at
//!   `n − s`, `n`, `n + s`, `s = (n − 1) · 0.025 · 20 / V_d`; red from the first, green from the
//!   second, blue from the third.
//! * Filament (commit 53a8fd9, `light_indirect.fs`, `calculateDispersion`, `solid` refraction
//!   only, here [`crate::engine::ProxyShape::Sphere`] with Filament's lookup): four lookups at
//!   `n_j = n + f o_j + ξ`, `f = (n − 1) / V_d` (`P (n − 1)` with `P = dispersion / 20`),
//!   `o = (0.708, 0.248, 0, −0.292)` (486.1, 546.1, 589.3 and 656.3 nm), and a per-pixel jitter
//!   `ξ = (IGN(frag) − ½) · 0.35 f` (Jimenez's interleaved gradient noise, frame 0, no TAA);
//!   the colour is `max(Σ_j K_j s_j, 0)` with Filament's four colour-matching matrices `K_j`
//!   (its `tools/specgen`), which map white reads to white within 4e-4.
//!
//! Bevy, Godot and Unity HDRP have no dispersion ([`EngineDispersion::None`]).

use glam::{Mat3, Vec2, Vec3};

use crate::engine::interleaved_gradient_noise;

/// Filament's index offsets `o_j` in units of `(n − 1) / V_d`, at 486.1, 546.1, 589.3 and
/// 656.3 nm (`calculateDispersion`'s `offsets`).
pub const FILAMENT_OFFSETS: [f32; 4] = [0.707_952_15, 0.247_909_8, 0.0, -0.292_047_85];

/// Filament's per-pixel jitter amplitude, in units of `(n − 1) / V_d`: "roughly the distance
/// between the Gaussian sample points".
pub const FILAMENT_JITTER: f32 = 0.35;

/// Filament's colour-matching matrices `K_j`, column-major as its GLSL `mat3(...)` lists them:
/// lookup `j`'s read `s_j` adds `K_j s_j` to the pixel's linear colour. Filament's digits as it
/// writes them (some past `f32`'s precision).
#[allow(clippy::excessive_precision)]
pub const FILAMENT_MATRICES: [[f32; 9]; 4] = [
    [
        0.005_816_37,
        0.023_128_51,
        0.016_896_31,
        -0.117_822_36,
        0.113_162_02,
        0.110_981_48,
        -0.454_220_13,
        0.044_935_17,
        0.982_497_98,
    ],
    [
        0.142_917_03,
        0.104_297_78,
        -0.015_565_22,
        -0.275_601_48,
        0.576_785_41,
        -0.064_122_44,
        0.068_398_11,
        0.027_328_91,
        0.016_020_64,
    ],
    [
        0.701_061_2,
        -0.094_404_02,
        -0.002_416_99,
        0.295_456_74,
        0.299_318_52,
        -0.043_519_61,
        0.318_844,
        -0.056_270_69,
        0.000_838_08,
    ],
    [
        0.150_205_22,
        -0.033_022_13,
        0.001_085_89,
        0.097_967_15,
        0.010_734_1,
        -0.003_339_46,
        0.066_978_07,
        -0.015_993_41,
        0.000_643_33,
    ],
];

/// How an engine model splits a pixel of dispersive glass into lookups.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EngineDispersion {
    /// One lookup at the glass's index: the model has no dispersion, or the glass none.
    None,
    /// three.js: three lookups, `n − s`, `n`, `n + s`, one channel each.
    ThreeJs {
        /// `s = (n − 1) · 0.025 · 20 / V_d`.
        half_spread: f32,
    },
    /// Filament: four lookups at `n + f o_j + ξ`, mixed by [`FILAMENT_MATRICES`].
    Filament {
        /// `f = (n − 1) / V_d`.
        factor: f32,
    },
}

impl EngineDispersion {
    /// three.js's scheme on glass of index `ior` and Abbe number `abbe` (`None` where
    /// `abbe` is infinite: no dispersion).
    pub fn threejs(ior: f32, abbe: f32) -> Self {
        if abbe.is_finite() {
            Self::ThreeJs {
                half_spread: (ior - 1.0) * 0.025 * (20.0 / abbe),
            }
        } else {
            Self::None
        }
    }

    /// Filament's scheme on glass of index `ior` and Abbe number `abbe` (`None` where `abbe` is
    /// infinite).
    pub fn filament(ior: f32, abbe: f32) -> Self {
        if abbe.is_finite() {
            Self::Filament {
                factor: (ior - 1.0) / abbe,
            }
        } else {
            Self::None
        }
    }

    /// The scheme's one number (three.js's half spread, Filament's factor; 0 for none), as the
    /// GPU's refractor table carries it: the model says which scheme it is.
    pub fn amount(&self) -> f32 {
        match *self {
            Self::None => 0.0,
            Self::ThreeJs { half_spread } => half_spread,
            Self::Filament { factor } => factor,
        }
    }

    /// The number of lookups a pixel takes: 1, 3 (three.js) or 4 (Filament).
    pub fn lookups(&self) -> usize {
        match self {
            Self::None => 1,
            Self::ThreeJs { .. } => 3,
            Self::Filament { .. } => 4,
        }
    }

    /// The lookup whose path gives the pixel's AOVs: the one at the base index's offset (the
    /// middle one; Filament's at 589.3 nm, offset 0 plus the jitter).
    pub fn aov_lookup(&self) -> usize {
        match self {
            Self::None => 0,
            Self::ThreeJs { .. } => 1,
            Self::Filament { .. } => 2,
        }
    }

    /// Lookup `j`'s index on glass of index `ior` for the pixel at `frag_px` (its centre, `y`
    /// down), and the matrix its read is multiplied by before it is added to the pixel.
    pub fn lookup(&self, ior: f32, j: usize, frag_px: Vec2) -> (f32, Mat3) {
        match *self {
            Self::None => (ior, Mat3::IDENTITY),
            Self::ThreeJs { half_spread } => {
                let mut channel = Vec3::ZERO;
                channel[j] = 1.0;
                (
                    ior + (j as f32 - 1.0) * half_spread,
                    Mat3::from_diagonal(channel),
                )
            }
            Self::Filament { factor } => {
                let jitter = (interleaved_gradient_noise(frag_px) - 0.5) * FILAMENT_JITTER * factor;
                (
                    ior + factor * FILAMENT_OFFSETS[j] + jitter,
                    Mat3::from_cols_array(&FILAMENT_MATRICES[j]),
                )
            }
        }
    }

    /// Whether the sum of the lookups is clamped at 0 (Filament's `max(…, 0)`: its matrices
    /// have negative entries).
    pub fn clamps(&self) -> bool {
        matches!(self, Self::Filament { .. })
    }

    /// Whether each lookup feeds one channel (a diagonal matrix), so that its read can be
    /// weighted channel by channel.
    pub fn is_diagonal(&self) -> bool {
        !matches!(self, Self::Filament { .. })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Filament's matrices map four white reads to white, and each maps a read to the colours
    /// of its wavelength (the blue end's to blue, the red end's to red).
    #[test]
    fn filament_matrices_keep_white() {
        let white = (0..4)
            .map(|j| Mat3::from_cols_array(&FILAMENT_MATRICES[j]) * Vec3::ONE)
            .fold(Vec3::ZERO, |a, b| a + b);
        assert!((white - Vec3::ONE).abs().max_element() < 4e-4, "{white}");
        let blue = Mat3::from_cols_array(&FILAMENT_MATRICES[0]) * Vec3::ONE;
        let red = Mat3::from_cols_array(&FILAMENT_MATRICES[3]) * Vec3::ONE;
        assert!(blue.z > blue.x && red.x > red.z, "{blue} {red}");
    }

    /// The indices: three.js's `n ∓ s`; Filament's offsets plus a jitter within ±0.175 f, the
    /// same for every lookup of a pixel; no dispersion at an infinite Abbe number.
    #[test]
    fn lookup_indices() {
        let frag = Vec2::new(10.5, 3.5);
        let three = EngineDispersion::threejs(1.5, 30.0);
        let s = 0.5 * 0.025 * 20.0 / 30.0;
        assert!((three.lookup(1.5, 0, frag).0 - (1.5 - s)).abs() < 1e-7);
        assert_eq!(three.lookup(1.5, 2, frag).1, Mat3::from_diagonal(Vec3::Z));
        let filament = EngineDispersion::filament(1.5, 30.0);
        let f = 0.5 / 30.0;
        let jitter = filament.lookup(1.5, 2, frag).0 - 1.5;
        assert!(jitter.abs() <= 0.175 * f + 1e-7, "{jitter}");
        for (j, offset) in FILAMENT_OFFSETS.iter().enumerate() {
            let n = filament.lookup(1.5, j, frag).0;
            assert!((n - (1.5 + f * offset + jitter)).abs() < 1e-6, "{j}: {n}");
        }
        // The noise moves the jitter from pixel to pixel.
        let other = filament.lookup(1.5, 2, Vec2::new(11.5, 3.5)).0 - 1.5;
        assert_ne!(jitter, other);
        assert_eq!(
            EngineDispersion::filament(1.5, f32::INFINITY),
            EngineDispersion::None
        );
        assert_eq!(EngineDispersion::threejs(1.5, f32::INFINITY).lookups(), 1);
    }
}
