//! Dispersion for the approximate methods: `N` wavelengths traced through a method's own
//! kernel, one frame each, and their colours combined with per-channel weights.
//!
//! The reference renders a pixel as `c = ∫ L(λ) s(λ) dλ` with the linear-sRGB observer
//! `s(λ) = M_XYZ→sRGB (x̄, ȳ, z̄)(λ) · CIE_Y_NORMALIZATION` ([`super::Wavelengths::to_linear_srgb`]).
//! An approximate method sees, at one wavelength `λᵢ`, the RGB colour `Cᵢ` its path at that
//! wavelength's index finds. Splitting 360–830 nm into `N` bins of equal probability under
//! [`super::sample_rgb_spectrum`]'s density (bin `i` covers `u ∈ [i/N, (i+1)/N)`, traced at its
//! middle `λᵢ = λ(u = (i + ½)/N)`), the frame is
//!
//! `c = Σᵢ Wᵢ ⊙ Cᵢ`,  `Wᵢ = ∫_binᵢ s(λ) D65(λ) dλ / ∫ s(λ) D65(λ) dλ` (per channel),
//!
//! the midpoint rule of the reference's integral with the light taken as white (D65, the
//! illuminant the environment's spectra carry) within each bin. The weights of every channel
//! sum to 1, so glass without dispersion (every `Cᵢ` the same) gives `c = C`, and white light
//! through dispersive glass converges to the reference's spectrum as `N` grows. A weight may be
//! negative where the observer is (the red channel's lobe at 440–540 nm).

use glam::Vec3;

use super::{
    CIE_Y_NORMALIZATION, XYZ_TO_LINEAR_SRGB, cie_1931_xyz, d65, mul3, sample_rgb_spectrum,
};

/// The most wavelengths an approximate method traces.
pub const MAX_WAVELENGTH_BINS: usize = 16;

/// Midpoint-rule steps (in the density's sample space) of all bins together.
const QUADRATURE_STEPS: usize = 1024;

/// One wavelength traced through a method's kernel and the weight of its colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WavelengthBin {
    /// The wavelength traced, nm.
    pub lambda: f32,
    /// The share of each linear-sRGB channel this bin's colour gives the frame.
    pub weight: Vec3,
}

/// The `N` bins of a dispersive frame ([`Self::new`]); their weights sum to 1 per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WavelengthBins {
    bins: [WavelengthBin; MAX_WAVELENGTH_BINS],
    len: usize,
}

impl WavelengthBins {
    /// `n` bins of equal probability under [`sample_rgb_spectrum`]'s density, or `None` for
    /// `n` outside `1..=`[`MAX_WAVELENGTH_BINS`]. One bin is the whole range at 545.9 nm with
    /// weight 1.
    pub fn new(n: usize) -> Option<Self> {
        if !(1..=MAX_WAVELENGTH_BINS).contains(&n) {
            return None;
        }
        let empty = WavelengthBin {
            lambda: 0.0,
            weight: Vec3::ZERO,
        };
        let mut bins = [empty; MAX_WAVELENGTH_BINS];
        let steps = QUADRATURE_STEPS.div_ceil(n);
        let mut total = Vec3::ZERO;
        for (i, bin) in bins[..n].iter_mut().enumerate() {
            let mut weight = Vec3::ZERO;
            for k in 0..steps {
                let u = (i as f32 + (k as f32 + 0.5) / steps as f32) / n as f32;
                let (lambda, inv_pdf) = sample_rgb_spectrum(u);
                weight += observer(lambda) * (d65(lambda) * inv_pdf);
            }
            bin.lambda = sample_rgb_spectrum((i as f32 + 0.5) / n as f32).0;
            bin.weight = weight;
            total += weight;
        }
        for bin in &mut bins[..n] {
            bin.weight /= total;
        }
        Some(Self { bins, len: n })
    }

    /// The bins, shortest wavelength first.
    pub fn as_slice(&self) -> &[WavelengthBin] {
        &self.bins[..self.len]
    }
}

/// The linear-sRGB observer `s(λ)`.
fn observer(lambda: f32) -> Vec3 {
    mul3(
        &XYZ_TO_LINEAR_SRGB,
        cie_1931_xyz(lambda) * CIE_Y_NORMALIZATION,
    )
}

#[cfg(test)]
mod tests {
    use super::super::dispersive_ior;
    use super::*;

    #[test]
    fn weights_sum_to_one_per_channel_and_wavelengths_rise() {
        for n in 1..=MAX_WAVELENGTH_BINS {
            let bins = WavelengthBins::new(n).expect("bins");
            assert_eq!(bins.as_slice().len(), n);
            let sum: Vec3 = bins.as_slice().iter().map(|b| b.weight).sum();
            assert!((sum - Vec3::ONE).abs().max_element() < 1e-5, "{n}: {sum}");
            for pair in bins.as_slice().windows(2) {
                assert!(pair[0].lambda < pair[1].lambda, "{n}: {pair:?}");
            }
        }
        assert!(WavelengthBins::new(0).is_none());
        assert!(WavelengthBins::new(MAX_WAVELENGTH_BINS + 1).is_none());
    }

    /// Three bins: blue, green and red light in that order, each channel mostly from its own
    /// bin; the middles of the bins at 452, 546 and 650 nm.
    #[test]
    fn three_bins_are_blue_green_red() {
        let bins = WavelengthBins::new(3).expect("bins");
        let [b, g, r] = [0, 1, 2].map(|i| bins.as_slice()[i]);
        for (bin, lambda) in [(b, 451.6), (g, 545.9), (r, 649.6)] {
            assert!((bin.lambda - lambda).abs() < 0.5, "{bin:?}");
        }
        assert!(
            b.weight.z > 0.8 && g.weight.y > 0.5 && r.weight.x > 0.5,
            "{bins:?}"
        );
        assert!(
            b.weight.z > b.weight.x && r.weight.x > r.weight.z,
            "{bins:?}"
        );
    }

    /// The frame's estimate of white light through a dispersive path converges to the spectral
    /// integral as `N` grows: a path whose share of a white source rises smoothly with the
    /// wavelength, `t(λ) = ((λ − 360) / 470)²` (a prism's spread over a ramp), gets the colour
    /// `∫ t s D65`; the midpoint rule's error falls about as `1/N²`.
    #[test]
    fn binned_estimate_converges_to_the_spectral_integral() {
        use super::super::{LAMBDA_MAX, LAMBDA_MIN};
        let t = |l: f32| ((l - LAMBDA_MIN) / (LAMBDA_MAX - LAMBDA_MIN)).powi(2);
        let exact = {
            let steps = 47_000;
            let h = (LAMBDA_MAX - LAMBDA_MIN) / steps as f32;
            (0..steps)
                .map(|k| LAMBDA_MIN + (k as f32 + 0.5) * h)
                .map(|l| observer(l) * (d65(l) * t(l) * h))
                .sum::<Vec3>()
        };
        let error = |n: usize| {
            let bins = WavelengthBins::new(n).expect("bins");
            let estimate: Vec3 = bins.as_slice().iter().map(|b| b.weight * t(b.lambda)).sum();
            (estimate - exact).abs().max_element()
        };
        let (e3, e6, e16) = (error(3), error(6), error(16));
        assert!(e6 < 0.5 * e3 && e16 < 0.25 * e6, "{e3} {e6} {e16}");
        assert!(e16 < 2e-3, "{e16} (exact {exact})");
        // And the indices the bins trace spread over the glass's dispersion.
        let bins = WavelengthBins::new(3).expect("bins");
        let n = [0, 1, 2].map(|i| dispersive_ior(1.5, 30.0, bins.as_slice()[i].lambda));
        assert!(n[0] > n[1] && n[1] > n[2], "{n:?}");
    }
}
