//! Spectral rendering as Mitsuba 3's spectral variants do it, for dispersive glass: wavelengths
//! drawn in 360–830 nm by Mitsuba's RGB importance density (Radziszewski et al. 2009), four per
//! sample shifted in sample space (hero wavelengths, Wilkie et al. 2014, *Hero Wavelength
//! Spectral Sampling*), linear sRGB values turned into spectra by Jakob and Hanika's sigmoid
//! polynomials ([`uplift`]; emitters times the D65 illuminant), spectra to linear sRGB through
//! the CIE 1931 2° observer, and the glTF `KHR_materials_dispersion` index of refraction per
//! wavelength ([`dispersive_ior`]).
//!
//! Wavelengths are in nanometres; every function here is pure and allocation-free.

mod bins;
mod tables;
pub mod uplift;

use glam::Vec3;

use crate::math;

pub use bins::{MAX_WAVELENGTH_BINS, WavelengthBin, WavelengthBins};
pub use uplift::{UpliftSolver, UpliftTable};

/// The shortest wavelength rendered, nm (Mitsuba's `MI_CIE_MIN`).
pub const LAMBDA_MIN: f32 = 360.0;
/// The longest wavelength rendered, nm (Mitsuba's `MI_CIE_MAX`).
pub const LAMBDA_MAX: f32 = 830.0;
/// Samples of the CIE tables (5 nm apart).
pub const CIE_SAMPLES: usize = 95;
/// Wavelengths per spectral sample (Mitsuba's `MI_WAVELENGTH_SAMPLES`).
pub const WAVELENGTHS: usize = 4;
/// `1 / ∫ ȳ(λ) dλ`: a spectrum of constant 1 has luminance 1 (Mitsuba's
/// `MI_CIE_Y_NORMALIZATION`).
pub const CIE_Y_NORMALIZATION: f32 = 1.0 / 106.750_26;
/// Scales the tabulated D65 so that it has luminance 1 (Mitsuba's `MI_CIE_D65_NORMALIZATION`).
pub const D65_NORMALIZATION: f32 = 1.0 / 98.997_42;

/// Linear interpolation in a table sampled at 5 nm from [`LAMBDA_MIN`]; `None` outside
/// [[`LAMBDA_MIN`], [`LAMBDA_MAX`]] (and for NaN).
#[inline]
fn table_position(lambda: f32) -> Option<(usize, f32)> {
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda) {
        return None;
    }
    let t = (lambda - LAMBDA_MIN) * ((CIE_SAMPLES - 1) as f32 / (LAMBDA_MAX - LAMBDA_MIN));
    let i0 = (t as usize).min(CIE_SAMPLES - 2);
    Some((i0, t - i0 as f32))
}

/// The CIE 1931 2° colour matching functions `(x̄, ȳ, z̄)` at `lambda`, linearly interpolated
/// from the 5 nm table; zero outside 360–830 nm.
#[inline]
pub fn cie_1931_xyz(lambda: f32) -> Vec3 {
    let Some((i, w1)) = table_position(lambda) else {
        return Vec3::ZERO;
    };
    let w0 = 1.0 - w1;
    let (a, b) = (tables::CIE_1931_XYZ[i], tables::CIE_1931_XYZ[i + 1]);
    Vec3::new(
        w0 * a[0] + w1 * b[0],
        w0 * a[1] + w1 * b[1],
        w0 * a[2] + w1 * b[2],
    )
}

/// The D65 illuminant at `lambda` times [`D65_NORMALIZATION`] (luminance 1); zero outside
/// 360–830 nm.
#[inline]
pub fn d65(lambda: f32) -> f32 {
    let Some((i, w1)) = table_position(lambda) else {
        return 0.0;
    };
    ((1.0 - w1) * tables::D65[i] + w1 * tables::D65[i + 1]) * D65_NORMALIZATION
}

/// The WGSL declarations of the CIE tables (`CIE_1931_XYZ`, `CIE_D65`) that
/// `wgsl/spectral.wgsl` reads, written from the Rust tables (shortest round-trip `f32` digits:
/// the same values), for [`crate::gpu::wgsl_constants`].
pub fn wgsl_tables() -> alloc::string::String {
    use alloc::format;
    use alloc::vec::Vec;
    let xyz: Vec<_> = tables::CIE_1931_XYZ
        .iter()
        .map(|[x, y, z]| format!("vec3<f32>({x:e}, {y:e}, {z:e})"))
        .collect();
    let d65: Vec<_> = tables::D65.iter().map(|v| format!("{v:e}")).collect();
    format!(
        "const CIE_1931_XYZ = array<vec3<f32>, {CIE_SAMPLES}>({});\nconst CIE_D65 = array<f32, {CIE_SAMPLES}>({});",
        xyz.join(", "),
        d65.join(", ")
    )
}

/// `tanh⁻¹ x` for `|x| < 1`.
#[inline]
fn atanh(x: f32) -> f32 {
    0.5 * math::ln((1.0 + x) / (1.0 - x))
}

/// `cosh x`.
#[inline]
fn cosh(x: f32) -> f32 {
    let e = math::exp(x);
    0.5 * (e + 1.0 / e)
}

/// One wavelength drawn from `u ∈ [0, 1)` by the density
/// `p(λ) ∝ sech²(0.0072 (λ − 538))` on 360–830 nm, which follows the sum of the CIE curves
/// (Mitsuba 3's `sample_rgb_spectrum`): `λ = 538 − 138.9 tanh⁻¹(0.85691 − 1.82750 u)`, with
/// its weight `1 / p(λ) = 253.82 cosh²(0.0072 (λ − 538))`.
#[inline]
pub fn sample_rgb_spectrum(u: f32) -> (f32, f32) {
    let lambda = 538.0 - atanh(0.856_910_6 - 1.827_502 * u) * 138.888_89;
    let c = cosh(0.0072 * (lambda - 538.0));
    (lambda, 253.82 * c * c)
}

/// The density of [`sample_rgb_spectrum`] per nm (zero outside 360–830 nm).
#[inline]
pub fn pdf_rgb_spectrum(lambda: f32) -> f32 {
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda) {
        return 0.0;
    }
    let c = 1.0 / cosh(0.0072 * (lambda - 538.0));
    0.003_939_804 * c * c
}

/// CIE XYZ to linear sRGB (ITU-R BT.709 primaries, D65 white), the matrix Mitsuba 3 and
/// `rgb2spec` use.
pub const XYZ_TO_LINEAR_SRGB: [[f32; 3]; 3] = [
    [3.240_479, -1.537_15, -0.498_535],
    [-0.969_256, 1.875_991, 0.041_556],
    [0.055_648, -0.204_043, 1.057_311],
];

/// Linear sRGB to CIE XYZ, the inverse of [`XYZ_TO_LINEAR_SRGB`] as Mitsuba 3 tabulates it.
pub const LINEAR_SRGB_TO_XYZ: [[f32; 3]; 3] = [
    [0.412_453, 0.357_580, 0.180_423],
    [0.212_671, 0.715_160, 0.072_169],
    [0.019_334, 0.119_193, 0.950_227],
];

/// `m · v` for a row-major 3 × 3 matrix.
#[inline]
pub fn mul3(m: &[[f32; 3]; 3], v: Vec3) -> Vec3 {
    Vec3::new(
        m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
        m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
        m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z,
    )
}

/// Jakob and Hanika's sigmoid spectrum (2019, *A Low-Dimensional Function Space for Efficient
/// Spectral Upsampling*, eq. 3) of coefficients `c` (of `λ` in nm, as [`UpliftTable::fetch`]
/// returns them): `S(λ) = ½ + x / (2 √(1 + x²))` with `x = (c₀ λ + c₁) λ + c₂`, a value in
/// [0, 1] (Mitsuba 3's `srgb_model_eval`; an infinite `c₂` is the constant 0 or 1).
#[inline]
pub fn sigmoid_spectrum(c: [f32; 3], lambda: f32) -> f32 {
    if c[2].is_infinite() {
        return if c[2] > 0.0 { 1.0 } else { 0.0 };
    }
    let x = (c[0] * lambda + c[1]) * lambda + c[2];
    (0.5 * x / math::sqrt(x * x + 1.0) + 0.5).max(0.0)
}

/// The wavelength at which glTF's `KHR_materials_dispersion` and the Abbe number are defined,
/// the helium d line, nm.
pub const LAMBDA_D: f32 = 587.56;

/// Abbe numbers the reference accepts: from 1 (extremely dispersive) up; glass is 20–90.
pub const ABBE_MIN: f32 = 1.0;

/// The index of refraction at `lambda` (nm) of a glass of index `ior` at the d line and Abbe
/// number `abbe`, as `KHR_materials_dispersion` defines it (Cauchy's two-term law fitted
/// through `n_d` and `V_d = (n_d − 1) / (n_F − n_C)`):
/// `n(λ) = n_d + (n_d − 1) / V_d · (523 655 / λ² − 1.5168)`, with `λ` in nm. An infinite
/// Abbe number is no dispersion (`n(λ) = n_d`).
#[inline]
pub fn dispersive_ior(ior: f32, abbe: f32, lambda: f32) -> f32 {
    if abbe.is_infinite() {
        return ior;
    }
    ior + (ior - 1.0) / abbe * (523_655.0 / (lambda * lambda) - 1.5168)
}

/// The Abbe number of glTF's `dispersion` parameter: `V_d = 20 / dispersion` (infinite for
/// 0: no dispersion).
#[inline]
pub fn abbe_from_dispersion(dispersion: f32) -> f32 {
    if dispersion == 0.0 {
        f32::INFINITY
    } else {
        20.0 / dispersion
    }
}

/// The [`WAVELENGTHS`] wavelengths of one spectral sample, with their weights `1 / p(λᵢ)`
/// (0 for a terminated wavelength). The first one is the hero: where the path's direction
/// depends on the wavelength (a dispersive interface), the others are terminated
/// ([`Self::terminate_secondary`]) and the hero carries the estimate alone, as pbrt-v4's
/// `SampledWavelengths::TerminateSecondary` does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wavelengths {
    /// Wavelengths, nm; `lambda[0]` is the hero.
    pub lambda: [f32; WAVELENGTHS],
    /// `1 / p(λᵢ)` (nm), or 0 where terminated.
    pub weight: [f32; WAVELENGTHS],
}

impl Wavelengths {
    /// The wavelengths of sample `u ∈ [0, 1)`: `uᵢ = frac(u + i / 4)` through
    /// [`sample_rgb_spectrum`] (Mitsuba 3's `sample_wavelength` with `sample_shifted`).
    #[inline]
    pub fn sample(u: f32) -> Self {
        let mut lambda = [0.0; WAVELENGTHS];
        let mut weight = [0.0; WAVELENGTHS];
        for i in 0..WAVELENGTHS {
            let mut ui = u + i as f32 / WAVELENGTHS as f32;
            if ui >= 1.0 {
                ui -= 1.0;
            }
            (lambda[i], weight[i]) = sample_rgb_spectrum(ui);
        }
        Self { lambda, weight }
    }

    /// The hero wavelength, nm.
    #[inline]
    pub fn hero(&self) -> f32 {
        self.lambda[0]
    }

    /// Whether the secondary wavelengths were terminated.
    #[inline]
    pub fn is_terminated(&self) -> bool {
        self.weight[1] == 0.0
    }

    /// Terminates the secondary wavelengths: their weights become 0 and the hero's is
    /// multiplied by [`WAVELENGTHS`], so the estimate stays unbiased. Idempotent.
    #[inline]
    pub fn terminate_secondary(&mut self) {
        if self.is_terminated() {
            return;
        }
        self.weight[0] *= WAVELENGTHS as f32;
        for w in &mut self.weight[1..] {
            *w = 0.0;
        }
    }

    /// The linear sRGB estimate of spectral radiance `values` at these wavelengths:
    /// `M_XYZ→sRGB · (1/4) Σᵢ (x̄, ȳ, z̄)(λᵢ) values[i] / p(λᵢ) · CIE_Y_NORMALIZATION` (Mitsuba 3's
    /// `spectrum_to_xyz` then `xyz_to_srgb`).
    #[inline]
    pub fn to_linear_srgb(&self, values: [f32; WAVELENGTHS]) -> Vec3 {
        let mut xyz = Vec3::ZERO;
        for (i, value) in values.iter().enumerate() {
            if self.weight[i] != 0.0 {
                xyz += cie_1931_xyz(self.lambda[i]) * (value * self.weight[i]);
            }
        }
        mul3(
            &XYZ_TO_LINEAR_SRGB,
            xyz * (CIE_Y_NORMALIZATION / WAVELENGTHS as f32),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫ f(λ) dλ` over 360–830 nm by the trapezoid rule at 0.1 nm.
    fn integrate(f: impl Fn(f32) -> f64) -> f64 {
        let n = 4700;
        let h = f64::from(LAMBDA_MAX - LAMBDA_MIN) / n as f64;
        (0..=n)
            .map(|i| {
                let w = if i == 0 || i == n { 0.5 } else { 1.0 };
                w * f(LAMBDA_MIN + (i as f64 * h) as f32)
            })
            .sum::<f64>()
            * h
    }

    /// Mitsuba's constants: the linearly interpolated 5 nm table integrates `ȳ` to 106.857,
    /// 0.1 % above Mitsuba's 106.750 (from the 1 nm table).
    #[test]
    fn normalisations_give_unit_luminance() {
        let y = integrate(|l| f64::from(cie_1931_xyz(l).y));
        assert!(
            (y * f64::from(CIE_Y_NORMALIZATION) - 1.0).abs() < 1.5e-3,
            "{y}"
        );
        let d65_y = integrate(|l| f64::from(d65(l) * cie_1931_xyz(l).y));
        assert!(
            (d65_y * f64::from(CIE_Y_NORMALIZATION) - 1.0).abs() < 2e-3,
            "{d65_y}"
        );
    }

    /// D65 is sRGB's white: its spectrum goes to linear sRGB (1, 1, 1).
    #[test]
    fn d65_is_srgb_white() {
        let xyz = Vec3::new(
            integrate(|l| f64::from(d65(l) * cie_1931_xyz(l).x)) as f32,
            integrate(|l| f64::from(d65(l) * cie_1931_xyz(l).y)) as f32,
            integrate(|l| f64::from(d65(l) * cie_1931_xyz(l).z)) as f32,
        ) * CIE_Y_NORMALIZATION;
        let rgb = mul3(&XYZ_TO_LINEAR_SRGB, xyz);
        assert!((rgb - Vec3::ONE).abs().max_element() < 5e-3, "{rgb}");
    }

    #[test]
    fn wavelength_density_integrates_to_one_and_inverts_its_sampler() {
        let total = integrate(|l| f64::from(pdf_rgb_spectrum(l)));
        assert!((total - 1.0).abs() < 1e-3, "{total}");
        for k in 0..100 {
            let u = (k as f32 + 0.5) / 100.0;
            let (lambda, weight) = sample_rgb_spectrum(u);
            assert!(
                (LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda),
                "{u} → {lambda}"
            );
            assert!(
                (weight * pdf_rgb_spectrum(lambda) - 1.0).abs() < 1e-3,
                "{lambda}"
            );
            // The CDF at λ is u: integrate the density up to λ.
            let cdf = integrate(|l| {
                if l <= lambda {
                    f64::from(pdf_rgb_spectrum(l))
                } else {
                    0.0
                }
            });
            assert!((cdf - f64::from(u)).abs() < 2e-3, "u {u}: cdf {cdf}");
        }
    }

    /// The estimator of a spectrum's colour converges to the colour of the spectrum: D65 to
    /// white, with stratified hero samples.
    #[test]
    fn wavelength_estimate_of_d65_is_white() {
        let n = 4096;
        let mut sum = Vec3::ZERO;
        for k in 0..n {
            let w = Wavelengths::sample((k as f32 + 0.5) / n as f32);
            sum += w.to_linear_srgb(w.lambda.map(d65));
        }
        let rgb = sum / n as f32;
        assert!((rgb - Vec3::ONE).abs().max_element() < 5e-3, "{rgb}");
        // Terminated secondaries keep the estimate: the hero alone carries 4× its weight.
        let mut sum = Vec3::ZERO;
        for k in 0..n {
            let mut w = Wavelengths::sample((k as f32 + 0.5) / n as f32);
            w.terminate_secondary();
            sum += w.to_linear_srgb(w.lambda.map(d65));
        }
        let rgb = sum / n as f32;
        assert!((rgb - Vec3::ONE).abs().max_element() < 5e-3, "{rgb}");
    }

    /// The KHR formula through its definition: `n(λ_d) = n_d` and `(n_d − 1) / (n_F − n_C)`
    /// is the Abbe number (F 486.13 nm, C 656.27 nm).
    #[test]
    fn dispersive_ior_has_its_abbe_number() {
        for (ior, abbe) in [(1.5, 30.0), (1.5168, 64.17), (1.7, 20.0)] {
            // 523 655 / λ_d² = 1.5168 defines the formula's λ_d.
            assert!((dispersive_ior(ior, abbe, LAMBDA_D) - ior).abs() < 1e-4);
            let n_f = dispersive_ior(ior, abbe, 486.13);
            let n_c = dispersive_ior(ior, abbe, 656.27);
            let measured = (ior - 1.0) / (n_f - n_c);
            assert!(
                (measured - abbe).abs() < 0.01 * abbe,
                "{measured} vs {abbe}"
            );
            assert!(n_f > ior && ior > n_c, "normal dispersion: blue bends more");
        }
        assert_eq!(dispersive_ior(1.5, f32::INFINITY, 400.0), 1.5);
        assert_eq!(abbe_from_dispersion(0.0), f32::INFINITY);
        assert_eq!(abbe_from_dispersion(20.0 / 30.0), 30.0);
    }

    #[test]
    fn sigmoid_spectrum_limits() {
        assert_eq!(sigmoid_spectrum([0.0, 0.0, f32::INFINITY], 500.0), 1.0);
        assert_eq!(sigmoid_spectrum([0.0, 0.0, f32::NEG_INFINITY], 500.0), 0.0);
        assert_eq!(sigmoid_spectrum([0.0, 0.0, 0.0], 500.0), 0.5);
        assert_eq!(sigmoid_spectrum([0.0, 0.0, 8192.0], 500.0), 1.0);
    }
}
