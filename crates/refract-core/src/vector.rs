//! Small vector helpers that stay finite for every finite input.

use glam::Vec3;

use crate::arctangent::atan2;
use crate::real::{LaneMask, Msk, Real, Vector3};

/// `|‖v‖² − 1|` below which [`robust_normalize`] returns `v` itself: ten `f32` ulps, the
/// rounding of a normalisation or of Snell's formula on unit vectors.
pub const UNIT_TOLERANCE: f32 = 10.0 * f32::EPSILON;

/// Normalises `v`, or returns `None` when `v` is zero or not finite.
///
/// A `v` already unit to within [`UNIT_TOLERANCE`] is returned as is (most vectors of the
/// per-pixel kernels are: interpolated-then-normalised normals, Snell's `T` from unit inputs);
/// otherwise `v̂ = v · (1/‖v‖)` when `‖v‖²` is comfortably inside the normal `f32` range (one square root
/// and one division, the per-pixel case). Unlike `Vec3::try_normalize`, vectors whose squared
/// length overflows or underflows `f32` (components above ~1.8e19 or below ~1e-15) are still
/// normalised: `v` is first scaled by its largest absolute component,
/// `v̂ = (v / max|vᵢ|) / ‖v / max|vᵢ|‖`. The scalar face of [`robust_normalize_masked`].
///
/// ```
/// use glam::Vec3;
/// use refract_core::vector::robust_normalize;
/// assert_eq!(robust_normalize(Vec3::new(0.0, 3.0, 4.0)), Some(Vec3::new(0.0, 0.6, 0.8)));
/// assert_eq!(robust_normalize(Vec3::ZERO), None);
/// // Components near f32::MAX: length² overflows, the direction does not.
/// let huge = robust_normalize(Vec3::splat(f32::MAX)).expect("finite");
/// assert!((huge.length() - 1.0).abs() < 1e-6);
/// ```
#[inline]
pub fn robust_normalize(v: Vec3) -> Option<Vec3> {
    let (n, ok) = robust_normalize_masked(v);
    ok.then_some(n)
}

/// [`robust_normalize`] for one pixel or eight: the normalised vector and the lanes where it
/// exists (the others hold garbage). The two common paths run on lanes; a lane whose squared
/// length is outside `[1e-30, f32::MAX]` takes the scaled path alone.
#[inline]
pub fn robust_normalize_masked<V: Vector3>(v: V) -> (V, Msk<V>) {
    robust_normalize_where(v, LaneMask::splat(true))
}

/// [`robust_normalize_masked`] for the lanes of `active`: the others are not taken through the
/// scaled path (their result is discarded by the caller, e.g. a zero vector under TIR).
#[inline]
pub fn robust_normalize_where<V: Vector3>(v: V, active: Msk<V>) -> (V, Msk<V>) {
    let length_squared = v.dot(v);
    let unit = (length_squared - V::Real::ONE)
        .abs()
        .le(V::Real::splat(UNIT_TOLERANCE));
    // Most vectors are unit already (normals from the rasteriser, Snell's `T`): the square
    // root and division are only spent when some lane needs them.
    if unit.all() {
        return (v, unit);
    }
    // Also false for NaN. Below 1e-30 the squares of small components would lose digits.
    let in_range =
        V::Real::splat(1e-30).le(length_squared) & length_squared.le(V::Real::splat(f32::MAX));
    let scaled = v * (V::Real::ONE / length_squared.sqrt());
    let (mut n, mut ok) = (V::select(unit, v, scaled), unit | in_range);
    let rare = active & !ok;
    if rare.any() {
        rare_lanes(&v, &mut n, &mut ok, rare);
    }
    (n, ok)
}

/// The `rare` lanes, one by one through the scaled path.
#[cold]
#[inline(never)]
fn rare_lanes<V: Vector3>(v: &V, n: &mut V, ok: &mut Msk<V>, rare: Msk<V>) {
    for (i, rare) in rare.lanes().enumerate() {
        if rare && let Some(lane) = robust_normalize_scaled(v.lane(i)) {
            n.set_lane(i, lane);
            ok.set(i, true);
        }
    }
}

fn robust_normalize_scaled(v: Vec3) -> Option<Vec3> {
    let scale = v.abs().max_element();
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    (v / scale).try_normalize()
}

/// The angle between two unit vectors, `θ = atan2(‖a × b‖, a · b)` in `[0, π]` (with
/// [`atan2`]: relative precision kept for small angles).
///
/// Well conditioned everywhere, unlike `acos(a · b)`, which loses most of its digits near 0 and
/// π. Wyman 2005a §3.1 needs `θt/θi` near normal incidence, where `acos` would be useless.
///
/// ```
/// use glam::Vec3;
/// let a = refract_core::vector::angle_between(Vec3::X, Vec3::new(1.0, 1e-4, 0.0));
/// assert!((a - 1e-4).abs() < 1e-9); // small angles keep their digits (acos would not)
/// ```
#[inline]
pub fn angle_between<V: Vector3>(a: V, b: V) -> V::Real {
    atan2(a.cross(b).length(), a.dot(b))
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
