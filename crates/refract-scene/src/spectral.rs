//! What the exact tracers of both backends need to render a dispersive scene spectrally: the
//! uplift table every renderer shares (Jakob and Hanika's sigmoid coefficients at Mitsuba 3's
//! resolution, built once per process on first use, in parallel: 2 s on two cores), and a
//! scene's emitters as spectra ([`SpectralLighting`]: the environment per texel as Mitsuba 3's
//! spectral `envmap` holds it, the light).

use std::sync::OnceLock;

use glam::Vec3;
use rayon::prelude::*;
use refract_core::environment::{Atan2, latlong_bilinear_taps};
use refract_core::procedural_sky::procedural_radiance;
use refract_core::spectral::uplift::{
    MITSUBA_RESOLUTION, UpliftSolver, emission, emission_coefficients, table_scale,
};
use refract_core::spectral::{UpliftTable, WAVELENGTHS, d65, sigmoid_spectrum};

use crate::environment::Environment;
use crate::scene::Scene;

/// An owned uplift table (`refract_core::spectral::UpliftTable` borrows one).
#[derive(Clone, Debug)]
pub struct UpliftTables {
    res: usize,
    scale: Vec<f32>,
    data: Vec<f32>,
}

impl UpliftTables {
    /// Solves a table of resolution `res` (≥ 2), its `3 · res` slices in parallel.
    pub fn build(res: usize) -> Self {
        let res = res.max(2);
        let solver = UpliftSolver::new();
        let slices: Vec<Vec<f32>> = (0..3 * res)
            .into_par_iter()
            .map(|t| {
                let mut slice = vec![0.0; res * res * 3];
                solver.solve_slice(res, t / res, t % res, &mut slice);
                slice
            })
            .collect();
        let mut data = vec![0.0; 3 * res * res * res * 3];
        for (t, slice) in slices.iter().enumerate() {
            let (l, j) = (t / res, t % res);
            for k in 0..res {
                for i in 0..res {
                    let cell = ((l * res + k) * res + j) * res + i;
                    data[cell * 3..][..3].copy_from_slice(&slice[(k * res + i) * 3..][..3]);
                }
            }
        }
        Self {
            res,
            scale: (0..res).map(table_scale(res)).collect(),
            data,
        }
    }

    /// The table, borrowed.
    pub fn table(&self) -> UpliftTable<'_> {
        UpliftTable {
            res: self.res,
            scale: &self.scale,
            data: &self.data,
        }
    }

    /// Resolution per axis.
    pub fn res(&self) -> usize {
        self.res
    }

    /// The `3 · res³ · 3` coefficients, laid out as [`UpliftTable::data`] (for GPU upload).
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// The brightness axis, `res` values.
    pub fn scale(&self) -> &[f32] {
        &self.scale
    }
}

/// The process's table at Mitsuba 3's resolution (64), built on first call.
pub fn uplift_tables() -> &'static UpliftTables {
    static TABLES: OnceLock<UpliftTables> = OnceLock::new();
    TABLES.get_or_init(|| UpliftTables::build(MITSUBA_RESOLUTION))
}

/// An emitter's spectrum: sigmoid coefficients `c` and scale `f`, the radiance at `λ` being
/// `f · S_c(λ) · D65(λ)` ([`refract_core::spectral::uplift::emission`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterSpectrum {
    /// Sigmoid coefficients of `λ` in nm.
    pub coefficients: [f32; 3],
    /// Scale, `2 max(rgb)`.
    pub scale: f32,
}

impl EmitterSpectrum {
    /// The spectrum of linear-sRGB radiance `rgb`.
    pub fn new(table: &UpliftTable<'_>, rgb: Vec3) -> Self {
        let (coefficients, scale) = emission_coefficients(table, rgb);
        Self {
            coefficients,
            scale,
        }
    }

    /// The radiance at `lambda` without the D65 factor.
    #[inline]
    fn unlit(&self, lambda: f32) -> f32 {
        self.scale * sigmoid_spectrum(self.coefficients, lambda)
    }

    /// The radiance at the wavelengths `lambda`.
    #[inline]
    pub fn at(&self, lambda: &[f32; WAVELENGTHS]) -> [f32; WAVELENGTHS] {
        lambda.map(|l| self.unlit(l) * d65(l))
    }
}

/// A scene's emitters as spectra: the environment (a lat-long map per texel, the others by
/// their colour) and the directional light's two terms.
#[derive(Clone, Debug)]
pub struct SpectralLighting {
    /// Per texel of a lat-long environment (empty otherwise), row-major as the map.
    pub texels: Vec<EmitterSpectrum>,
    /// The light's ambient term.
    pub ambient: EmitterSpectrum,
    /// The light's directional term.
    pub directional: EmitterSpectrum,
}

impl SpectralLighting {
    /// The spectra of `scene`'s emitters, through `table`.
    pub fn new(scene: &Scene, table: &UpliftTable<'_>) -> Self {
        let texels = match &scene.environment {
            Environment::LatLong { map, .. } => map
                .texels
                .par_iter()
                .map(|&rgb| EmitterSpectrum::new(table, rgb))
                .collect(),
            _ => Vec::new(),
        };
        Self {
            texels,
            ambient: EmitterSpectrum::new(table, scene.light.ambient),
            directional: EmitterSpectrum::new(table, scene.light.radiance),
        }
    }

    /// Spectral radiance of `environment` seen along unit `dir` at the wavelengths `lambda`:
    /// for a lat-long map, Mitsuba 3's spectral `envmap`: the four texels' spectra `S_k(λ)` and
    /// scales `f_k` interpolated separately, `bilerp(S) · bilerp(f) · intensity · D65(λ)`;
    /// a constant or the procedural sky as the emitter of its colour.
    pub fn environment<A: Atan2>(
        &self,
        environment: &Environment,
        table: &UpliftTable<'_>,
        dir: Vec3,
        lambda: &[f32; WAVELENGTHS],
    ) -> [f32; WAVELENGTHS] {
        match environment {
            Environment::LatLong { map, intensity } => {
                let ([a, b, c, d], f) = latlong_bilinear_taps::<A>(map.width, map.height, dir);
                let t = [a, b, c, d].map(|i| self.texels[i]);
                let lerp = |p: f32, q: f32, w: f32| p + (q - p) * w;
                let scale = lerp(
                    lerp(t[0].scale, t[1].scale, f.x),
                    lerp(t[2].scale, t[3].scale, f.x),
                    f.y,
                );
                lambda.map(|l| {
                    let s = t.map(|e| sigmoid_spectrum(e.coefficients, l));
                    let s = lerp(lerp(s[0], s[1], f.x), lerp(s[2], s[3], f.x), f.y);
                    s * scale * intensity * d65(l)
                })
            }
            Environment::Constant(rgb) => emission(table, *rgb, lambda),
            Environment::Procedural => emission(table, procedural_radiance::<A>(dir), lambda),
        }
    }

    /// Spectral radiance leaving a diffuse surface of `albedo` whose shading cosine to the
    /// light is `cos`: the albedo's reflectance spectrum times the light's
    /// `ambient(λ) + directional(λ) · cos` (the RGB shading of [`refract_core::shading`],
    /// spectrally).
    #[inline]
    pub fn diffuse(
        &self,
        table: &UpliftTable<'_>,
        albedo: Vec3,
        cos: f32,
        lambda: &[f32; WAVELENGTHS],
    ) -> [f32; WAVELENGTHS] {
        let reflectance = table.reflectance(albedo, lambda);
        core::array::from_fn(|i| {
            let l = lambda[i];
            reflectance[i] * (self.ambient.unlit(l) + self.directional.unlit(l) * cos) * d65(l)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use refract_core::spectral::{
        CIE_Y_NORMALIZATION, LAMBDA_MAX, LAMBDA_MIN, XYZ_TO_LINEAR_SRGB, cie_1931_xyz, d65, mul3,
        sigmoid_spectrum,
    };

    /// Mitsuba's table reproduces reflectances across the gamut: the colour under D65 of
    /// each fetched spectrum is within 0.01 of the colour asked for (a grid of 6³ colours, the
    /// trilinear lookup between the nodes included).
    #[test]
    fn the_shared_table_reproduces_reflectances() {
        let table = uplift_tables().table();
        let colour = |c: [f32; 3]| {
            let n = 470;
            let h = (LAMBDA_MAX - LAMBDA_MIN) / n as f32;
            let xyz: Vec3 = (0..=n)
                .map(|i| {
                    let l = LAMBDA_MIN + i as f32 * h;
                    let w = if i == 0 || i == n { 0.5 } else { 1.0 };
                    cie_1931_xyz(l) * (sigmoid_spectrum(c, l) * d65(l) * w * h)
                })
                .sum();
            mul3(&XYZ_TO_LINEAR_SRGB, xyz * CIE_Y_NORMALIZATION)
        };
        let mut worst = 0.0f32;
        for r in 0..6 {
            for g in 0..6 {
                for b in 0..6 {
                    let rgb = Vec3::new(r as f32, g as f32, b as f32) * 0.17 + 0.07;
                    worst = worst.max((colour(table.fetch(rgb)) - rgb).abs().max_element());
                }
            }
        }
        assert!(worst < 0.01, "worst channel error {worst}");
    }
}
