//! Small vector helpers that stay finite for every finite input.

use glam::Vec3;

/// Normalises `v`, or returns `None` when `v` is zero or not finite.
///
/// Unlike `Vec3::try_normalize`, vectors whose squared length overflows `f32` (components
/// above ~1.8e19) are still normalised: `v` is first divided by its largest absolute component,
/// `v̂ = (v / max|vᵢ|) / ‖v / max|vᵢ|‖`.
#[inline]
pub fn robust_normalize(v: Vec3) -> Option<Vec3> {
    let scale = v.abs().max_element();
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    (v / scale).try_normalize()
}

/// The angle between two unit vectors, `θ = atan2(‖a × b‖, a · b)` in `[0, π]`.
///
/// Well conditioned everywhere, unlike `acos(a · b)`, which loses most of its digits near 0 and
/// π. Wyman 2005a §3.1 needs `θt/θi` near normal incidence, where `acos` would be useless.
#[inline]
pub fn angle_between(a: Vec3, b: Vec3) -> f32 {
    a.cross(b).length().atan2(a.dot(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn robust_normalize_handles_huge_tiny_and_zero() {
        let huge = robust_normalize(Vec3::new(3e38, -3e38, 0.0)).expect("finite");
        assert!((huge.length() - 1.0).abs() < 1e-6);
        let tiny = robust_normalize(Vec3::new(1e-40, 0.0, 0.0)).expect("denormal is fine");
        assert_eq!(tiny, Vec3::X);
        assert_eq!(robust_normalize(Vec3::ZERO), None);
        assert_eq!(robust_normalize(Vec3::new(f32::NAN, 0.0, 1.0)), None);
        assert_eq!(robust_normalize(Vec3::new(f32::INFINITY, 0.0, 1.0)), None);
    }

    #[test]
    fn angle_between_is_accurate_near_zero() {
        let theta = 1e-4_f32;
        let a = Vec3::Z;
        let b = Vec3::new(theta.sin(), 0.0, theta.cos());
        assert!((angle_between(a, b) - theta).abs() < 1e-9);
        assert!((angle_between(a, -a) - std::f32::consts::PI).abs() < 1e-6);
    }
}
