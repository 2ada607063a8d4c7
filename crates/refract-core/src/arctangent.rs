//! A branch-light `atan2` for the per-pixel paths, inlined instead of a libm call.
//!
//! Per pixel the methods need two angles (Wyman 2005a §3.1, `θi` and `θt`) and the environment
//! lookups need an azimuth; as libm calls (`atan2f` → `atanf`) these were a fifth of a CPU
//! frame. This version reduces the argument to `a = min(|x|, |y|) / max(|x|, |y|) ∈ [0, 1]` and
//! evaluates `atan(a) = a + a·s·P(s)`, `s = a²`, with `P` a degree-8 polynomial (the Chebyshev
//! interpolant of `(atan(√s) − √s)/s^{3/2}` on `[0, 1]`, coefficients rounded to `f32`).
//!
//! Measured against `f64` (tests below): error ≤ 8e-8 + 2⁻²³·|θ| rad, i.e. the polynomial's
//! 7e-8 plus one `f32` ulp of the result (from rounding `π/2 − r`, `π − r`); libm's `atan2f`
//! is within one ulp. Relative error ≤ 2e-7 below π/4 down to the smallest normal numbers:
//! small angles keep their digits, which the ratio `θt/θi` needs near normal incidence.
//!
//! The WGSL twin uses the built-in `atan2` (a GPU's own polynomial); the conformance tests hold
//! the two within their 1e-5 relative tolerance.

use core::f32::consts::{FRAC_PI_2, PI};

use crate::real::Real;

/// Coefficients of `P(s)`, constant term first.
const ATAN_POLYNOMIAL: [f32; 9] = [
    -0.333_333_3,
    0.199_997_66,
    -0.142_791_1,
    0.110_379_94,
    -0.086_731_71,
    0.062_843_606,
    -0.036_270_175,
    0.013_750_284,
    -0.002_447_031_2,
];

/// `atan(a)` for `a ∈ [0, 1]`: `a + a·s·P(s)`, `P` ([`ATAN_POLYNOMIAL`]) evaluated with
/// Estrin's scheme (four dependent multiply-adds instead of Horner's eight: the latency, not the
/// arithmetic, bounds a pixel).
#[inline]
fn atan_unit<R: Real>(a: R) -> R {
    let p = |k: usize| R::splat(ATAN_POLYNOMIAL[k]);
    let s = a * a;
    let s2 = s * s;
    let s4 = s2 * s2;
    let p01 = p(0) + p(1) * s;
    let p23 = p(2) + p(3) * s;
    let p45 = p(4) + p(5) * s;
    let p67 = p(6) + p(7) * s;
    let p03 = p01 + p23 * s2;
    let p47 = p45 + p67 * s2;
    let poly = p03 + (p47 + p(8) * s4) * s4;
    a + a * s * poly
}

/// The angle of the point `(x, y)` from the positive `x` axis, in `[−π, π]`, like
/// [`f32::atan2`]: `atan2(±0, x ≥ +0) = ±0`, `atan2(±0, x ≤ −0) = ±π`, NaN in, NaN out.
/// Meant for finite arguments (two infinities give NaN, where libm gives a multiple of π/4).
/// One body for one pixel (`f32`) and eight ([`crate::lanes::F32x8`]), see [`crate::real`].
///
/// # Example
///
/// ```
/// let a = refract_core::arctangent::atan2(1.0f32, -1.0);
/// assert!((a - 3.0 * core::f32::consts::FRAC_PI_4).abs() < 1e-6);
/// ```
#[inline]
pub fn atan2<R: Real>(y: R, x: R) -> R {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    // hi = 0 only at the origin, where the angle is that of the signed zeros.
    let a = R::select(hi.gt(R::ZERO), lo / hi, R::ZERO);
    let mut r = atan_unit(a);
    r = R::select(ay.gt(ax), R::splat(FRAC_PI_2) - r, r);
    r = R::select(x.is_sign_negative(), R::splat(PI) - r, r);
    R::select(x.is_nan() | y.is_nan(), R::splat(f32::NAN), r.copysign(y))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error(y: f32, x: f32) -> (f64, f64) {
        let exact = f64::from(y).atan2(f64::from(x));
        let ours = f64::from(atan2(y, x));
        (
            (ours - exact).abs(),
            (ours - exact).abs() / exact.abs().max(f64::MIN_POSITIVE),
        )
    }

    #[test]
    fn within_one_ulp_of_the_result_plus_the_polynomial_error() {
        let (mut worst, mut worst_rel) = (0.0f64, 0.0f64);
        let n = 20_000;
        for i in 0..n {
            // All directions, at several magnitudes.
            let phi = (i as f64 + 0.37) / n as f64 * std::f64::consts::TAU;
            for scale in [1e-30, 1e-3, 1.0, 7.5e3, 1e30] {
                let (y, x) = ((phi.sin() * scale) as f32, (phi.cos() * scale) as f32);
                let (abs, rel) = error(y, x);
                let exact = f64::from(y).atan2(f64::from(x)).abs();
                worst = worst.max(abs / (8e-8 + exact * f64::from(f32::EPSILON)));
                if f64::from(y.abs()) < f64::from(x.abs()) && x > 0.0 {
                    worst_rel = worst_rel.max(rel);
                }
            }
        }
        assert!(worst <= 1.0, "error / (8e-8 + ulp(θ)) = {worst}");
        assert!(worst_rel <= 2e-7, "relative error below π/4 {worst_rel:e}");
    }

    #[test]
    fn small_angles_keep_their_relative_precision() {
        for k in 1..=35 {
            let y = 10f32.powi(-k);
            let (_, rel) = error(y, 1.0);
            assert!(rel <= 2e-7, "atan2({y:e}, 1): relative error {rel:e}");
        }
    }

    #[test]
    fn signed_zeros_axes_and_nan_match_libm() {
        for (y, x) in [
            (0.0, 1.0),
            (-0.0, 1.0),
            (0.0, -1.0),
            (-0.0, -1.0),
            (0.0, 0.0),
            (-0.0, 0.0),
            (0.0, -0.0),
            (-0.0, -0.0),
            (1.0, 0.0),
            (-1.0, 0.0),
            (1.0, 1.0),
            (-3.0, -3.0),
        ] {
            let (ours, libm) = (atan2(y, x), f32::atan2(y, x));
            assert!(
                (ours - libm).abs() <= 2.4e-7 && ours.is_sign_negative() == libm.is_sign_negative(),
                "atan2({y}, {x}) = {ours}, libm {libm}"
            );
        }
        assert!(atan2(f32::NAN, 1.0).is_nan());
        assert!(atan2(1.0, f32::NAN).is_nan());
    }
}
