//! Wyman 2005a §3.1: approximating the distance `d~` from the entry point `P1` to the exit
//! point `P2` along the refracted ray `T1`.

use crate::real::{Real, Vector3};
use crate::vector::angle_between;

/// Below this incidence angle (radians) the ratio `θt/θi` takes its normal-incidence limit `η`.
///
/// With [`angle_between`] both angles keep full relative precision down to ~1e-30, so the
/// threshold only guards the division; at `θi = 1e-6` the ratio already equals `η` to within
/// `η (1 − η²) θi² / 6 < 1e-12`, so the switch is continuous at `f32` precision.
pub const NORMAL_INCIDENCE_ANGLE: f32 = 1e-6;

/// Which distance approximates `‖P2 − P1‖`: the paper's interpolation and its two ablations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum DistanceMode {
    /// `d~ = (θt/θi) d_V + (1 − θt/θi) d_N` (Wyman 2005a §3.1, method `wyman`).
    #[default]
    Interpolated,
    /// `d~ = d_V`, the non-refracted front-to-back distance (ablation `wyman-dv`).
    ViewOnly,
    /// `d~ = d_N`, the precomputed distance along the inverted normal (ablation `wyman-dn`).
    NormalOnly,
}

/// Incidence angle `θi`, between `−V` and `N1` (Wyman 2005a §2), in `[0, π]`.
///
/// # Example
///
/// ```
/// use glam::Vec3;
/// let theta_i = refract_core::interpolated_distance::incidence_angle(Vec3::NEG_Z, Vec3::Z);
/// assert_eq!(theta_i, 0.0); // looking straight at the surface
/// ```
#[inline]
pub fn incidence_angle<V: Vector3>(view: V, n1: V) -> V::Real {
    angle_between(-view, n1)
}

/// Transmission angle `θt`, between `T1` and `−N1` (Wyman 2005a §2), in `[0, π]`.
///
/// # Example
///
/// ```
/// use glam::Vec3;
/// let t1 = Vec3::new(0.6, 0.0, -0.8);
/// let theta_t = refract_core::interpolated_distance::transmission_angle(t1, Vec3::Z);
/// assert!((theta_t - 0.6f32.asin()).abs() < 1e-6);
/// ```
#[inline]
pub fn transmission_angle<V: Vector3>(t1: V, n1: V) -> V::Real {
    angle_between(t1, -n1)
}

/// The interpolation weight `θt/θi` of Wyman 2005a §3.1, with its limit `η` at normal incidence
/// (Snell gives `θt ≈ η θi` for small angles), clamped to `[0, 1]`.
///
/// For a refractor denser than its surroundings (`η < 1`) the ratio lies in `(0, η]` and the
/// clamp never acts; it keeps `d~` between `d_V` and `d_N` when `η > 1` (our departure from the
/// paper, which only considers `n_t > n_i`; see `docs/methods.md`).
///
/// # Example
///
/// ```
/// use refract_core::interpolated_distance::angle_ratio;
/// assert_eq!(angle_ratio(0.4, 0.2, 1.0 / 1.5), 0.5);
/// assert_eq!(angle_ratio(0.0, 0.0, 1.0 / 1.5), 1.0 / 1.5); // the limit at normal incidence
/// ```
#[inline]
pub fn angle_ratio<R: Real>(theta_i: R, theta_t: R, eta: R) -> R {
    let ratio = R::select(
        theta_i.gt(R::splat(NORMAL_INCIDENCE_ANGLE)),
        theta_t / theta_i,
        eta,
    );
    Real::clamp(ratio, R::ZERO, R::ONE)
}

/// Wyman 2005a §3.1: `d~ = (θt/θi)·d_V + (1 − θt/θi)·d_N`, with `θt/θi` from [`angle_ratio`].
///
/// ```
/// use refract_core::interpolated_distance::interpolated_distance;
/// // θt/θi = 0.5: halfway between d_V = 2 and d_N = 1.
/// assert!((interpolated_distance(0.4, 0.2, 1.0 / 1.5, 2.0, 1.0) - 1.5).abs() < 1e-6);
/// // Normal incidence: the ratio's limit η = 1/1.5 weighs d_V.
/// let d = interpolated_distance(0.0, 0.0, 1.0 / 1.5, 2.0, 1.0);
/// assert!((d - (2.0 / 1.5 + 1.0 / 3.0)).abs() < 1e-6);
/// ```
#[inline]
pub fn interpolated_distance<R: Real>(theta_i: R, theta_t: R, eta: R, d_v: R, d_n: R) -> R {
    let w = angle_ratio(theta_i, theta_t, eta);
    w * d_v + (R::ONE - w) * d_n
}

/// `d~` for a [`DistanceMode`]: the interpolation, or one of its ablations.
///
/// # Example
///
/// ```
/// use refract_core::DistanceMode;
/// use refract_core::interpolated_distance::approximate_distance;
/// let (theta_i, theta_t, eta, d_v, d_n) = (0.4, 0.2, 1.0 / 1.5, 2.0, 1.0);
/// assert_eq!(approximate_distance(DistanceMode::ViewOnly, theta_i, theta_t, eta, d_v, d_n), 2.0);
/// assert_eq!(approximate_distance(DistanceMode::NormalOnly, theta_i, theta_t, eta, d_v, d_n), 1.0);
/// assert_eq!(approximate_distance(DistanceMode::Interpolated, theta_i, theta_t, eta, d_v, d_n), 1.5);
/// ```
#[inline]
pub fn approximate_distance<R: Real>(
    mode: DistanceMode,
    theta_i: R,
    theta_t: R,
    eta: R,
    d_v: R,
    d_n: R,
) -> R {
    match mode {
        DistanceMode::Interpolated => interpolated_distance(theta_i, theta_t, eta, d_v, d_n),
        DistanceMode::ViewOnly => d_v,
        DistanceMode::NormalOnly => d_n,
    }
}

/// Wyman 2005a §3.1: the approximate exit point `P~2 = P1 + d~ T1`.
///
/// ```
/// use glam::Vec3;
/// let p2 = refract_core::interpolated_distance::exit_point(Vec3::Z, Vec3::NEG_Z, 2.0);
/// assert_eq!(p2, Vec3::NEG_Z);
/// ```
#[inline]
pub fn exit_point<V: Vector3>(p1: V, t1: V, d_tilde: V::Real) -> V {
    p1 + t1 * d_tilde
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratio_at_normal_incidence_is_eta() {
        assert_eq!(angle_ratio(0.0, 0.0, 1.0 / 1.5), 1.0 / 1.5);
    }

    #[test]
    fn interpolation_weights_d_v_by_the_angle_ratio() {
        // θi = 60°, η = 1/1.5: θt = asin(sin 60° / 1.5) = 35.26°, ratio 0.5877.
        let theta_i = 60f32.to_radians();
        let theta_t = (theta_i.sin() / 1.5).asin();
        let d = interpolated_distance(theta_i, theta_t, 1.0 / 1.5, 2.0, 1.0);
        let w = theta_t / theta_i;
        assert!((w - 0.587_7).abs() < 1e-4);
        assert!((d - (2.0 * w + (1.0 - w))).abs() < 1e-6);
    }

    #[test]
    fn ablations_pick_one_distance() {
        assert_eq!(
            approximate_distance(DistanceMode::ViewOnly, 0.3, 0.2, 0.6, 2.0, 1.0),
            2.0
        );
        assert_eq!(
            approximate_distance(DistanceMode::NormalOnly, 0.3, 0.2, 0.6, 2.0, 1.0),
            1.0
        );
    }
}
