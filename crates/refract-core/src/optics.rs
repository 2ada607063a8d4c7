//! Geometric optics at one interface, in the glam/WGSL conventions: unit vectors, the incident
//! direction `I` points *toward* the surface, the normal `N` faces the incident side
//! (`N · I ≤ 0`), and `eta = n_i / n_t`.

use core::ops::RangeInclusive;

use glam::Vec3;

use crate::real::{LaneMask, Msk, Real, Vector3};

/// The smallest index of refraction accepted (a refractor 100 times less dense than its
/// surroundings; below it `η² = 1/n²` scalings overflow the reference's radiance, issue 54).
pub const MIN_IOR: f32 = 0.01;
/// The largest index of refraction accepted (beyond any material; the kernels stay finite up
/// to it, `docs/methods.md`).
pub const MAX_IOR: f32 = 1000.0;
/// The indices of refraction accepted everywhere: scene files and `--ior`, sweep files,
/// Python, the viewer's slider, the kernels' parameters ([`ior_in_range`]).
pub const IOR_RANGE: RangeInclusive<f32> = MIN_IOR..=MAX_IOR;
/// What an error about an index of refraction says was expected.
pub const IOR_EXPECTED: &str = "an index of refraction from 0.01 to 1000";

/// Whether `ior` is in [`IOR_RANGE`] (NaN is not).
pub fn ior_in_range(ior: f32) -> bool {
    IOR_RANGE.contains(&ior)
}

/// Snell refraction (Wyman 2005a §2: `n_i sin θi = n_t sin θt`), exactly as WGSL's `refract`:
///
/// `k = 1 − η²(1 − (N·I)²)`; if `k < 0` (total internal reflection) the result is the zero
/// vector, otherwise `T = η I − (η (N·I) + √k) N`.
///
/// `k` is evaluated as `(1 − η²) + η² (N·I)²`, which is the same number but keeps its digits
/// near grazing incidence (with `1 − (N·I)²` first, `(N·I)² < 6e-8` is lost to rounding and an
/// index-matched interface, `η = 1`, would bend grazing rays by ~1e-4 rad).
///
/// `incident` and `normal` must be unit length with `normal · incident ≤ 0`; the result is then
/// unit length (up to rounding). A WGSL twin must use the same form, not the builtin `refract`.
///
/// # Example
///
/// Snell's law at a glass surface (`η = 1/1.5`), 30° incidence: `sin θt = sin θi / 1.5`.
///
/// ```
/// use glam::Vec3;
/// use refract_core::optics::refract;
/// let incident = Vec3::new(0.5, -(0.75f32).sqrt(), 0.0); // 30° from the normal +y
/// let t = refract(incident, Vec3::Y, 1.0 / 1.5);
/// assert!((t.x - 0.5 / 1.5).abs() < 1e-6 && t.y < 0.0 && (t.length() - 1.0).abs() < 1e-6);
/// // Leaving the glass at 60° is total internal reflection: the zero vector.
/// let grazing = Vec3::new((0.75f32).sqrt(), -0.5, 0.0);
/// assert_eq!(refract(grazing, Vec3::Y, 1.5), Vec3::ZERO);
/// ```
#[inline]
pub fn refract<V: Vector3>(incident: V, normal: V, eta: V::Real) -> V {
    let n_dot_i = normal.dot(incident);
    let eta2 = eta * eta;
    let k = (V::Real::ONE - eta2) + eta2 * n_dot_i * n_dot_i;
    let t = incident * eta - normal * (eta * n_dot_i + k.sqrt());
    V::select(k.lt(V::Real::ZERO), V::constant(Vec3::ZERO), t)
}

/// True when [`refract`] reports total internal reflection: `η² (1 − (N·I)²) > 1`, i.e.
/// `η sin θi > 1`.
///
/// # Example
///
/// ```
/// use glam::Vec3;
/// use refract_core::optics::is_total_internal_reflection;
/// let at_60_degrees = Vec3::new((0.75f32).sqrt(), -0.5, 0.0);
/// assert!(is_total_internal_reflection(at_60_degrees, Vec3::Y, 1.5)); // glass to air
/// assert!(!is_total_internal_reflection(at_60_degrees, Vec3::Y, 1.0 / 1.5)); // air to glass
/// ```
#[inline]
pub fn is_total_internal_reflection<V: Vector3>(incident: V, normal: V, eta: V::Real) -> Msk<V> {
    let n_dot_i = normal.dot(incident);
    let eta2 = eta * eta;
    ((V::Real::ONE - eta2) + eta2 * n_dot_i * n_dot_i).lt(V::Real::ZERO)
}

/// Mirror reflection, as WGSL's `reflect`: `R = I − 2 (N·I) N`.
///
/// ```
/// use glam::Vec3;
/// let r = refract_core::optics::reflect(Vec3::new(1.0, -1.0, 0.0), Vec3::Y);
/// assert_eq!(r, Vec3::new(1.0, 1.0, 0.0));
/// ```
#[inline]
pub fn reflect<V: Vector3>(incident: V, normal: V) -> V {
    incident - normal * (V::Real::splat(2.0) * normal.dot(incident))
}

/// The critical angle `θc = asin(1/η)` beyond which light going from the denser medium
/// (`η = n_i/n_t > 1`) is totally internally reflected (Wyman 2005a §3.3), evaluated as
/// `atan2(1, √((η − 1)(η + 1)))`, which is the same angle but well conditioned for `η → 1`
/// (where `asin` of a number near 1 loses its digits).
///
/// For `η ≤ 1` no incidence angle below grazing is reflected totally, and the result is `π/2`.
///
/// ```
/// // Glass to air: θc = asin(1/1.5) ≈ 41.8°.
/// let theta_c = refract_core::optics::critical_angle(1.5);
/// assert!((theta_c.to_degrees() - 41.810_314).abs() < 1e-4);
/// assert_eq!(refract_core::optics::critical_angle(0.8), core::f32::consts::FRAC_PI_2);
/// ```
#[inline]
pub fn critical_angle(eta: f32) -> f32 {
    if eta <= 1.0 {
        core::f32::consts::FRAC_PI_2
    } else {
        crate::math::atan2(1.0, crate::math::sqrt((eta - 1.0) * (eta + 1.0)))
    }
}

/// How far past grazing [`face_forward_shading_normal`] turns a back-facing normal.
pub const FACE_FORWARD_EPSILON: f32 = 1e-4;

/// Turns a shading normal toward the incident side when it faces away from the viewer.
///
/// Interpolated vertex normals can satisfy `N · I > 0` near silhouettes, where refraction is
/// undefined. Every method and the reference tracer then use the same fix: remove the part of
/// `N` along `I` that is too much and keep the normal just past grazing,
/// `N' = normalize(N − (N·I + ε) I)` with `ε = 1e-4`, so that `N' · I = −ε/‖…‖ < 0`.
/// Normals already facing the incident side are returned unchanged.
///
/// ```
/// use glam::Vec3;
/// use refract_core::optics::face_forward_shading_normal;
/// let incident = Vec3::NEG_Y;
/// // Facing the viewer already: unchanged. Facing away: turned just past grazing.
/// assert_eq!(face_forward_shading_normal(Vec3::Y, incident), Vec3::Y);
/// let turned = face_forward_shading_normal(Vec3::new(0.6, -0.8, 0.0), incident);
/// assert!(turned.dot(incident) < 0.0 && (turned.length() - 1.0).abs() < 1e-6);
/// ```
#[inline]
pub fn face_forward_shading_normal<V: Vector3>(normal: V, incident: V) -> V {
    let n_dot_i = normal.dot(incident);
    let facing = n_dot_i.lt(V::Real::ZERO);
    if facing.all() {
        return normal; // the common case: no lane needs turning
    }
    let (turned, ok) =
        (normal - incident * (n_dot_i + V::Real::splat(FACE_FORWARD_EPSILON))).try_normalize();
    let turned = V::select(ok, turned, -incident);
    V::select(facing, normal, turned)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refract_matches_glam() {
        let i = Vec3::new(0.3, -0.8, 0.1).normalize();
        let n = Vec3::Y;
        for eta in [0.5, 1.0 / 1.5, 1.0, 1.33, 1.5] {
            let ours = refract(i, n, eta);
            let glams = i.refract(n, eta);
            assert!(
                (ours - glams).length() < 1e-6,
                "eta {eta}: {ours} vs {glams}"
            );
        }
    }

    #[test]
    fn critical_angle_of_glass() {
        let theta_c = critical_angle(1.5);
        assert!((theta_c.to_degrees() - 41.810_314).abs() < 1e-4);
        assert_eq!(critical_angle(1.0 / 1.5), core::f32::consts::FRAC_PI_2);
    }

    #[test]
    fn face_forward_fixes_backfacing_normals_only() {
        let i = Vec3::new(0.0, 0.0, -1.0);
        let good = Vec3::new(0.0, 0.6, 0.8);
        assert_eq!(face_forward_shading_normal(good, i), good);
        let bad = Vec3::new(0.0, 0.6, -0.8);
        let fixed = face_forward_shading_normal(bad, i);
        assert!(fixed.dot(i) < 0.0 && fixed.dot(i) > -1e-3);
        assert!((fixed.length() - 1.0).abs() < 1e-6);
    }
}
