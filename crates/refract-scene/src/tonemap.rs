//! Display encoding: the one tonemap every PNG of refract goes through.

use glam::Vec3;

/// Narkowicz's fit of the ACES filmic curve, `f(x) = x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)`,
/// per channel, clamped to `[0, 1]`: linear near black, a soft shoulder for HDR highlights.
#[inline]
pub fn aces_filmic(x: f32) -> f32 {
    let x = x.max(0.0);
    (x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value in `[0, 1]`.
#[inline]
pub fn srgb_encode(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear radiance to an 8-bit sRGB pixel: `round(255 · srgb(aces(c)))`. NaN becomes black.
#[inline]
pub fn to_srgb8(c: Vec3) -> [u8; 3] {
    c.to_array().map(|v| {
        let v = if v.is_nan() { 0.0 } else { v };
        (255.0 * srgb_encode(aces_filmic(v)) + 0.5) as u8
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn black_white_and_monotone() {
        assert_eq!(to_srgb8(Vec3::ZERO), [0, 0, 0]);
        assert_eq!(to_srgb8(Vec3::splat(100.0)), [255, 255, 255]);
        assert_eq!(to_srgb8(Vec3::NAN), [0, 0, 0]);
        let mut last = 0;
        for i in 0..100 {
            let v = to_srgb8(Vec3::splat(i as f32 / 20.0))[0];
            assert!(v >= last);
            last = v;
        }
    }
}
