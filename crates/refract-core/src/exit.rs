//! Wyman 2005a §3.2–3.3: the normal at the exit point and refraction out of the refractor.

use glam::Vec3;

use crate::optics::{face_forward_shading_normal, reflect, refract};
use crate::real::{LaneMask, Msk, Vector3};
use crate::vector::robust_normalize_where;

/// What to do when the ray inside the refractor meets the exit surface beyond the critical
/// angle (total internal reflection at the second interface, Wyman 2005a §3.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TirPolicy {
    /// The paper's choice: clamp `θi` to the critical angle, so the ray leaves tangent to the
    /// exit surface, `T2 = normalize(T1 − (T1·N2) N2)`.
    #[default]
    ClampToCritical,
    /// Reflect once off the exit surface, `T2 = reflect(T1, −N2)`, and look that direction up
    /// as if it had left the object (the further interfaces are ignored).
    ReflectOnce,
    /// The ray is absorbed: the pixel is black.
    Black,
}

/// Where the exit normal `N2` came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ExitNormalSource {
    /// The back-face normal buffer at the screen position of `P~2` (Wyman 2005a §3.2).
    BackFace,
    /// `P~2` projected outside the refractor's silhouette (or behind the camera): the
    /// fallback normal of [`exit_normal_outside_silhouette`] (Wyman 2005a §3.3).
    SilhouetteFallback,
}

/// Wyman 2005a §3.3: when `P~2` falls outside the silhouette, the exit normal is `T1` projected
/// onto the plane perpendicular to the camera's look-at direction `L`,
/// `N2 = normalize(T1 − (L·T1) L)`, a unit vector (the division is by the length, not the
/// squared length).
///
/// When `T1 ∥ L` the projection vanishes; the result is then `T1` itself (normal exit).
///
/// ```
/// use glam::Vec3;
/// use refract_core::exit::exit_normal_outside_silhouette;
/// let look = Vec3::NEG_Z;
/// let t1 = Vec3::new(0.6, 0.0, -0.8);
/// // T1 with its component along L removed: +x, unit length.
/// assert!((exit_normal_outside_silhouette(t1, look) - Vec3::X).length() < 1e-6);
/// ```
#[inline]
pub fn exit_normal_outside_silhouette<V: Vector3>(t1: V, look_dir: V) -> V {
    let (n, ok) = (t1 - look_dir * look_dir.dot(t1)).try_normalize();
    V::select(ok, n, t1)
}

/// The refracted direction leaving the refractor, and whether the exit was totally reflected.
/// For one pixel (the default, `Vec3`) or eight lanes ([`crate::lanes::Vec3x8`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExitRefraction<V: Vector3 = Vec3> {
    /// `T2`, unit length; the zero vector when the ray was absorbed ([`TirPolicy::Black`]).
    pub t2: V,
    /// Total internal reflection at this interface (before the policy was applied).
    pub tir: Msk<V>,
}

/// Refraction at the exit surface with outward normal `n2`, inner index `ior` and outside
/// index 1: `T2 = refract(T1, −N2, ior)` (Wyman 2005a §3, `T2 ≈ Refract(T1, N2)`), with the
/// [`TirPolicy`] applied when `ior · sin θi > 1`.
///
/// An `n2` facing away from `T1` (possible with interpolated normals on concave meshes) is
/// turned with [`face_forward_shading_normal`], the same fix as at the entry point. The
/// refracted direction is renormalised: with indices far beyond physical ones (`n ≳ 10³`)
/// `f32` rounding in Snell's formula no longer keeps `|T2| = 1` by itself.
///
/// ```
/// use glam::Vec3;
/// use refract_core::exit::{TirPolicy, refract_exit};
/// // Leaving a slab head-on: straight through.
/// let straight = refract_exit(Vec3::NEG_Z, Vec3::NEG_Z, 1.5, TirPolicy::ClampToCritical);
/// assert!(!straight.tir && (straight.t2 - Vec3::NEG_Z).length() < 1e-6);
/// // 60° inside glass is beyond the critical angle: clamped to leave tangent to the surface.
/// let t1 = Vec3::new((0.75f32).sqrt(), 0.0, -0.5);
/// let clamped = refract_exit(t1, Vec3::NEG_Z, 1.5, TirPolicy::ClampToCritical);
/// assert!(clamped.tir && clamped.t2.z.abs() < 1e-3);
/// assert_eq!(refract_exit(t1, Vec3::NEG_Z, 1.5, TirPolicy::Black).t2, Vec3::ZERO);
/// ```
#[inline]
pub fn refract_exit<V: Vector3>(
    t1: V,
    n2: V,
    ior: V::Real,
    policy: TirPolicy,
) -> ExitRefraction<V> {
    let inward = face_forward_shading_normal(-n2, t1);
    let refracted = refract(t1, inward, ior);
    let tir = refracted.is_zero();
    // `robust_normalize(T2).unwrap_or(T1)`; TIR lanes are replaced below.
    let (t2, ok) = robust_normalize_where(refracted, !tir);
    let t2 = if ok.all() { t2 } else { V::select(ok, t2, t1) };
    if !tir.any() {
        return ExitRefraction { t2, tir };
    }
    let tir_t2 = match policy {
        TirPolicy::ClampToCritical => {
            let (tangent, ok) = (t1 - inward * t1.dot(inward)).try_normalize();
            V::select(ok, tangent, t1)
        }
        TirPolicy::ReflectOnce => reflect(t1, inward),
        TirPolicy::Black => V::constant(Vec3::ZERO),
    };
    ExitRefraction {
        t2: V::select(tir, tir_t2, t2),
        tir,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fallback_normal_is_unit_and_perpendicular_to_look() {
        let l = Vec3::NEG_Z;
        let t1 = Vec3::new(0.3, 0.1, -0.9).normalize();
        let n2 = exit_normal_outside_silhouette(t1, l);
        assert!((n2.length() - 1.0).abs() < 1e-6);
        assert!(n2.dot(l).abs() < 1e-6);
        assert_eq!(exit_normal_outside_silhouette(l, l), l);
    }

    #[test]
    fn clamp_policy_leaves_tangent_to_the_surface() {
        // 60° inside glass is past the 41.8° critical angle.
        let n2 = Vec3::Y;
        let t1 = Vec3::new(60f32.to_radians().sin(), 60f32.to_radians().cos(), 0.0);
        let exit = refract_exit(t1, n2, 1.5, TirPolicy::ClampToCritical);
        assert!(exit.tir);
        assert!((exit.t2 - Vec3::X).length() < 1e-6);
        let mirrored = refract_exit(t1, n2, 1.5, TirPolicy::ReflectOnce);
        assert!((mirrored.t2 - Vec3::new(t1.x, -t1.y, 0.0)).length() < 1e-6);
        assert_eq!(refract_exit(t1, n2, 1.5, TirPolicy::Black).t2, Vec3::ZERO);
    }

    #[test]
    fn below_the_critical_angle_snell_holds() {
        let n2 = Vec3::Y;
        let theta = 30f32.to_radians();
        let t1 = Vec3::new(theta.sin(), theta.cos(), 0.0);
        let exit = refract_exit(t1, n2, 1.5, TirPolicy::ClampToCritical);
        assert!(!exit.tir);
        assert!((exit.t2.x - 1.5 * theta.sin()).abs() < 1e-6);
    }
}
