//! Lat-long (equirectangular) environment mapping, as Mitsuba 3 looks maps up (design.md), so
//! a scene can be checked against it.
//!
//! Every lookup is generic over how `atan2` is evaluated ([`Atan2`]): the backends use the
//! inlined polynomial of [`crate::arctangent`] ([`Polynomial`], the twin of WGSL's built-in),
//! the exact reference uses libm's `atan2f` ([`Exact`]), so no approximation of a backend leaks
//! into the ground truth.

use core::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use crate::math;
use crate::real::{Real, Vector3};

/// How an environment lookup evaluates `atan2(y, x)`.
/// Generic over the number type `R` (`f32`, the default, or eight lanes).
pub trait Atan2<R: Real = f32> {
    /// The angle of `(x, y)` from the positive `x` axis, in `[−π, π]`.
    fn atan2(y: R, x: R) -> R;
}

/// The backends' `atan2`: [`crate::arctangent::atan2`] (≤ 8e-8 + 1 ulp from exact).
#[derive(Clone, Copy, Debug, Default)]
pub struct Polynomial;

impl<R: Real> Atan2<R> for Polynomial {
    #[inline]
    fn atan2(y: R, x: R) -> R {
        crate::arctangent::atan2(y, x)
    }
}

/// The reference's `atan2`: libm's `atan2f` through [`f32::atan2`] (within one ulp).
#[derive(Clone, Copy, Debug, Default)]
pub struct Exact;

impl Atan2 for Exact {
    #[inline]
    fn atan2(y: f32, x: f32) -> f32 {
        crate::math::atan2(y, x)
    }
}

/// Texture coordinates of a unit world direction:
/// `u = atan2(d.x, −d.z) / 2π` wrapped to `[0, 1)`, `v = acos(d.y) / π` (`v = 0` straight up),
/// with `acos(d.y)` evaluated as `atan2(√(d.x² + d.z²), d.y)`, which keeps its digits at the
/// poles.
///
/// # Example
///
/// ```
/// use glam::Vec3;
/// use refract_core::environment::{Exact, direction_to_latlong};
/// // −z is the map's left edge (u = 0) on the horizon (v = ½); +x a quarter across; +y the top.
/// assert!((direction_to_latlong::<Exact>(Vec3::NEG_Z) - glam::Vec2::new(0.0, 0.5)).length() < 1e-6);
/// assert!((direction_to_latlong::<Exact>(Vec3::X).x - 0.25).abs() < 1e-6);
/// assert!(direction_to_latlong::<Exact>(Vec3::Y).y.abs() < 1e-6);
/// ```
#[inline]
pub fn direction_to_latlong<A: Atan2>(dir: Vec3) -> Vec2 {
    let (u, v) = latlong_coordinates::<Vec3, A>(dir);
    Vec2::new(u, v)
}

/// [`direction_to_latlong`] for one direction or eight: `(u, v)`.
#[inline]
pub fn latlong_coordinates<V: Vector3, A: Atan2<V::Real>>(dir: V) -> (V::Real, V::Real) {
    let (zero, one) = (V::Real::ZERO, V::Real::ONE);
    let u = A::atan2(dir.x(), -dir.z()) / V::Real::splat(TAU);
    let u = V::Real::select(u.lt(zero), u + one, u);
    // `u + 1` can round to exactly 1 for tiny negative u.
    let u = V::Real::select(u.ge(one), zero, u);
    let theta = A::atan2((dir.x() * dir.x() + dir.z() * dir.z()).sqrt(), dir.y());
    (u, theta / V::Real::splat(PI))
}

/// The unit direction of lat-long coordinates, the inverse of [`direction_to_latlong`]:
/// `θ = π v`, `φ = 2π u`, `d = (sin θ sin φ, cos θ, −sin θ cos φ)`.
///
/// # Example
///
/// ```
/// use glam::{Vec2, Vec3};
/// use refract_core::environment::latlong_to_direction;
/// assert!((latlong_to_direction(Vec2::new(0.25, 0.5)) - Vec3::X).length() < 1e-6);
/// assert!((latlong_to_direction(Vec2::new(0.0, 0.0)) - Vec3::Y).length() < 1e-6);
/// ```
#[inline]
pub fn latlong_to_direction(uv: Vec2) -> Vec3 {
    let (sin_theta, cos_theta) = crate::math::sin_cos(PI * uv.y);
    let (sin_phi, cos_phi) = crate::math::sin_cos(TAU * uv.x);
    Vec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi)
}

/// Bilinear lookup in a `width × height` lat-long image of linear RGB texels (row 0 at
/// `v = 0`, the zenith), as Mitsuba 3's `envmap` samples it (measured on Mitsuba 3.9.1):
/// columns have their centres at half-integers and wrap, `x = u·W − ½`; rows sit on the poles,
/// `y = v·(H − 1)` (row 0 is the zenith, row `H − 1` the nadir), clamped to `[0, H − 1]`.
/// `L(d) = bilerp(map, x(u), y(v))`.
///
/// # Example
///
/// ```
/// use glam::Vec3;
/// use refract_core::environment::{Polynomial, sample_latlong_bilinear};
/// // A 2 × 3 map: rows 0 (zenith), 1 (horizon), 2 (nadir) in 0, 1, 2.
/// let texels = [0.0, 0.0, 1.0, 1.0, 2.0, 2.0].map(Vec3::splat);
/// let horizon = sample_latlong_bilinear::<Polynomial, _>(&texels, 2, 3, Vec3::X);
/// assert!((horizon - Vec3::ONE).length() < 1e-5); // y = v (H − 1) = 1: row 1 exactly
/// ```
///
/// One direction or eight (the texel fetches lane by lane).
#[inline]
pub fn sample_latlong_bilinear<A: Atan2<V::Real>, V: Vector3>(
    texels: &[Vec3],
    width: u32,
    height: u32,
    dir: V,
) -> V {
    let (u, v) = latlong_coordinates::<V, A>(dir);
    let last_row = V::Real::splat((height - 1) as f32);
    let x = u * V::Real::splat(width as f32) - V::Real::splat(0.5);
    let y = Real::clamp(v * last_row, V::Real::ZERO, last_row);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let w = i64::from(width);
    let wrap = |x: i64| x.rem_euclid(w) as usize;
    let (x0, y0) = (x0.to_lane_array(), y0.to_lane_array());
    // Lane i's texel at column offset dx ∈ {0, 1}, row offset dy ∈ {0, 1}.
    let texel = |i: usize, dx: i64, dy: usize| {
        let (x0, y0) = (x0.as_ref()[i] as i64, y0.as_ref()[i] as usize);
        let y = (y0 + dy).min(height as usize - 1);
        texels[y * width as usize + wrap(x0 + dx)]
    };
    let a = V::gather(|i| texel(i, 0, 0));
    let b = V::gather(|i| texel(i, 1, 0));
    let c = V::gather(|i| texel(i, 0, 1));
    let d = V::gather(|i| texel(i, 1, 1));
    a.lerp(b, fx).lerp(c.lerp(d, fx), fy)
}

/// The four texels and weights of [`sample_latlong_bilinear`]'s lookup of unit `dir` (one
/// direction): `index` of the texels at `(x₀, y₀)`, `(x₀+1, y₀)`, `(x₀, y₀+1)`, `(x₀+1, y₀+1)`
/// and the fractions `(fx, fy)`, for lookups that interpolate something other than the texels'
/// RGB (the reference's spectra, as Mitsuba 3's spectral `envmap` does).
#[inline]
pub fn latlong_bilinear_taps<A: Atan2>(width: u32, height: u32, dir: Vec3) -> ([usize; 4], Vec2) {
    let (u, v) = latlong_coordinates::<Vec3, A>(dir);
    let last_row = (height - 1) as f32;
    let x = u * width as f32 - 0.5;
    let y = (v * last_row).clamp(0.0, last_row);
    let (x0, y0) = (math::floor(x), math::floor(y));
    let w = i64::from(width);
    let column = |dx: i64| (x0 as i64 + dx).rem_euclid(w) as usize;
    let row = |dy: usize| (y0 as usize + dy).min(height as usize - 1) * width as usize;
    (
        [
            row(0) + column(0),
            row(0) + column(1),
            row(1) + column(0),
            row(1) + column(1),
        ],
        Vec2::new(x - x0, y - y0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The taps and weights interpolate to the RGB lookup (both axes, the wrap and the poles).
    #[test]
    fn bilinear_taps_match_the_lookup() {
        let (w, h) = (7u32, 5u32);
        let texels: Vec<Vec3> = (0..w * h)
            .map(|i| Vec3::new(i as f32, (i * i % 11) as f32, (i % 3) as f32))
            .collect();
        for k in 0..200 {
            let t = k as f32 * 0.37;
            let dir = Vec3::new(t.sin(), (t * 0.7).cos(), (t * 1.3).sin() - 0.2).normalize();
            let ([a, b, c, d], f) = latlong_bilinear_taps::<Exact>(w, h, dir);
            let taps = texels[a]
                .lerp(texels[b], f.x)
                .lerp(texels[c].lerp(texels[d], f.x), f.y);
            let lookup = sample_latlong_bilinear::<Exact, _>(&texels, w, h, dir);
            assert!(
                (taps - lookup).abs().max_element() < 1e-5,
                "{dir}: {taps} vs {lookup}"
            );
        }
    }

    #[test]
    fn mitsuba_axes() {
        // −z is u = 0, +x is u = 1/4, +z is u = 1/2; +y is v = 0.
        assert!(
            (direction_to_latlong::<Polynomial>(Vec3::NEG_Z) - Vec2::new(0.0, 0.5)).length() < 1e-6
        );
        assert!(
            (direction_to_latlong::<Polynomial>(Vec3::X) - Vec2::new(0.25, 0.5)).length() < 1e-6
        );
        assert!(
            (direction_to_latlong::<Polynomial>(Vec3::Z) - Vec2::new(0.5, 0.5)).length() < 1e-6
        );
        assert!(direction_to_latlong::<Polynomial>(Vec3::Y).y.abs() < 1e-6);
    }

    #[test]
    fn round_trip() {
        for &d in &[
            Vec3::new(0.3, 0.5, -0.2),
            Vec3::new(-0.7, -0.1, 0.4),
            Vec3::new(0.0, -1.0, 1e-3),
        ] {
            let d = d.normalize();
            let back = latlong_to_direction(direction_to_latlong::<Exact>(d));
            assert!((back - d).length() < 1e-5, "{d} -> {back}");
        }
    }

    /// Mitsuba's convention pinned on a synthetic 4 × 3 map of distinct texels: the poles are
    /// rows 0 and H − 1 exactly, the equator row 1; columns are centred at half-integers and
    /// wrap across the seam at u = 0; the corners of the map are reached at the poles.
    #[test]
    fn bilinear_follows_mitsuba_rows_on_poles_and_wrapping_columns() {
        let (w, h) = (4u32, 3u32);
        let texels: Vec<Vec3> = (0..w * h).map(|i| Vec3::splat(i as f32)).collect();
        let at = |u: f32, v: f32| {
            sample_latlong_bilinear::<Exact, _>(
                &texels,
                w,
                h,
                latlong_to_direction(Vec2::new(u, v)),
            )
        };
        let close = |a: Vec3, b: f32| (a - Vec3::splat(b)).abs().max_element() < 2e-3;
        // Column centres: u = (x + ½)/W. Zenith (v = 0) is row 0, the nadir row 2, the equator
        // (v = ½) row 1 exactly: y = v (H − 1).
        assert!(
            close(at(1.5 / 4.0, 0.5), 5.0),
            "equator, column 1: {}",
            at(1.5 / 4.0, 0.5)
        );
        assert!(close(at(2.5 / 4.0, 0.5), 6.0));
        // A quarter of the way down: halfway between rows 0 and 1.
        assert!(close(at(1.5 / 4.0, 0.25), 3.0), "{}", at(1.5 / 4.0, 0.25));
        // Seam: u = 0 is halfway between column 3 and column 0 (wrapping), on row 1.
        assert!(close(at(0.0, 0.5), 0.5 * (7.0 + 4.0)), "{}", at(0.0, 0.5));
        // Corners: near the zenith and nadir, on the first and last columns' centres.
        assert!(close(at(0.5 / 4.0, 1e-4), 0.0), "{}", at(0.5 / 4.0, 1e-4));
        assert!(close(at(3.5 / 4.0, 1e-4), 3.0));
        assert!(
            close(at(0.5 / 4.0, 1.0 - 1e-4), 8.0),
            "{}",
            at(0.5 / 4.0, 1.0 - 1e-4)
        );
        assert!(close(at(3.5 / 4.0, 1.0 - 1e-4), 11.0));
        // The old convention (rows at half-integers, y = v·H − ½) would give row 1.0 at v = ½
        // too, but 0.25 at v = 1/4 (a quarter of the way to row 1): this pins the difference.
        assert!(!close(at(1.5 / 4.0, 0.25), 1.0 + 0.25 * 4.0));
    }

    #[test]
    fn one_row_maps_sample_that_row_everywhere() {
        let texels = vec![Vec3::X, Vec3::Y];
        for v in [0.1, 0.5, 0.9] {
            let c = sample_latlong_bilinear::<Exact, _>(
                &texels,
                2,
                1,
                latlong_to_direction(Vec2::new(0.25, v)),
            );
            assert!((c - Vec3::X).length() < 1e-5, "{c}");
        }
    }
}
