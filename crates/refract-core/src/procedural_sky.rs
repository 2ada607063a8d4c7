//! The built-in procedural environment (sky with meridian stripes and a sun, checkered
//! ground): structure in every direction, so refraction errors are visible, and no file needed.
//! Generic over [`Atan2`] like every environment lookup; the eight-lane version is the
//! backends' ([`crate::environment::Polynomial`]), bit-identical lane by lane.

use glam::Vec3;

use crate::environment::{Atan2, Polynomial};
use crate::lanes::{F32x8, Vec3x8};
use crate::real::{LaneMask, Real, Vector3};

/// The procedural sky's sun direction, `normalize(0.4, 0.6, −0.7)`.
const SUN: Vec3 = Vec3::new(0.398_014_87, 0.597_022_3, -0.696_526_05);
const SUN_RADIANCE: Vec3 = Vec3::new(8.0, 7.0, 5.0);
const HORIZON: Vec3 = Vec3::new(0.85, 0.88, 0.92);
const ZENITH: Vec3 = Vec3::new(0.12, 0.3, 0.75);
/// The meridian stripes' colours, in turn from azimuth 0 (`−z`).
const STRIPE_HUES: [Vec3; 4] = [
    Vec3::new(0.9, 0.1, 0.1),
    Vec3::new(0.95, 0.6, 0.1),
    Vec3::new(0.2, 0.8, 0.2),
    Vec3::new(0.6, 0.2, 0.8),
];

/// The built-in environment: structure everywhere, so refraction errors are visible.
///
/// - Sky (`d.y > 0`): a gradient from a pale horizon to a deep blue zenith, with twelve
///   coloured meridian stripes (every 30° of azimuth, red at `−z`, up to 58° elevation) and a
///   warm sun disc.
/// - Ground (`d.y < 0`): a black-and-white checkerboard on the plane `y = −1` (squares of 0.5),
///   fading into the horizon colour far away so that it does not alias.
///
/// # Example
///
/// ```
/// use glam::Vec3;
/// use refract_core::environment::Exact;
/// use refract_core::procedural_sky::procedural_radiance;
/// let zenith = procedural_radiance::<Exact>(Vec3::Y);
/// assert!(zenith.z > zenith.x); // a blue sky
/// let ground = procedural_radiance::<Exact>(Vec3::new(0.1, -1.0, 0.2).normalize());
/// assert!(ground.x == ground.y && ground.y == ground.z); // a grey checkerboard
/// ```
pub fn procedural_radiance<A: Atan2>(dir: Vec3) -> Vec3 {
    if dir.y >= 0.0 {
        sky::<Vec3, A>(dir)
    } else {
        ground(dir)
    }
}

/// [`procedural_radiance`] with the polynomial `atan2` for eight directions at once: the halves
/// some lane needs evaluated by the same leaves and selected per lane, so each lane has the
/// scalar function's bits.
///
/// # Example
///
/// ```
/// use glam::Vec3;
/// use refract_core::environment::Polynomial;
/// use refract_core::lanes::Vec3x8;
/// use refract_core::procedural_sky::{procedural_radiance, procedural_radiance_x8};
/// let dirs: [Vec3; 8] = core::array::from_fn(|i| Vec3::new(0.3 * i as f32 - 1.0, 0.4 - 0.1 * i as f32, -1.0).normalize());
/// let lanes = procedural_radiance_x8(Vec3x8::from_lanes(&dirs)).to_lanes();
/// for (lane, d) in lanes.iter().zip(dirs) {
///     assert_eq!(lane.to_array(), procedural_radiance::<Polynomial>(d).to_array());
/// }
/// ```
pub fn procedural_radiance_x8(dir: Vec3x8) -> Vec3x8 {
    // Neighbouring pixels mostly see the same half: only the halves some lane needs are
    // evaluated.
    let up = dir.y.simd_ge(F32x8::ZERO);
    match (up.any(), up.all()) {
        (true, true) => sky::<_, Polynomial>(dir),
        (false, _) => ground(dir),
        (true, false) => Vec3x8::select(up, sky::<_, Polynomial>(dir), ground(dir)),
    }
}

/// The sky half (`d.y ≥ 0`): the gradient, the meridian stripes, the sun.
#[inline]
fn sky<V: Vector3, A: Atan2<V::Real>>(dir: V) -> V {
    let splat = V::Real::splat;
    let mut sky = V::constant(HORIZON).lerp(V::constant(ZENITH), dir.y().sqrt());
    // Azimuth in stripe units (30°) in [0, 12): atan2 gives (−6, 6], so one conditional add
    // wraps it (the same number as `rem_euclid(12)`, without a call to fmodf).
    let signed = A::atan2(dir.x(), -dir.z()) * splat(6.0 / core::f32::consts::PI);
    let stripe = V::Real::select(signed.lt(V::Real::ZERO), signed + splat(12.0), signed);
    let nearest = (stripe + splat(0.5)).floor(); // stripe ≥ 0: rounds halves up, as `round` does
    // Meridians converge at the zenith: stop them below it.
    let on_stripe = (stripe - nearest).abs().lt(splat(0.06)) & dir.y().lt(splat(0.85));
    if on_stripe.any() {
        // `nearest as usize % 4` for the integers 0..=12, exactly.
        let hue = nearest - splat(4.0) * (nearest * splat(0.25)).floor();
        for (k, colour) in STRIPE_HUES.iter().enumerate() {
            let this = on_stripe & hue.eq(splat(k as f32));
            sky = V::select(this, V::constant(*colour), sky);
        }
    }
    let sun = dir.dot(V::constant(SUN)).gt(splat(0.995));
    V::select(sun, V::constant(SUN_RADIANCE), sky)
}

/// The ground half (`d.y < 0`): the checkerboard on `y = −1`, faded into the horizon.
#[inline]
fn ground<V: Vector3>(dir: V) -> V {
    let splat = V::Real::splat;
    let p = dir * (V::Real::ONE / -dir.y()); // hit on the plane y = −1
    // Parity of an integer-valued float, a − 2⌊a/2⌋ (exact; equal to `rem_euclid(2)`).
    let cells = (p.x() * splat(2.0)).floor() + (p.z() * splat(2.0)).floor();
    let check = cells - splat(2.0) * (cells * splat(0.5)).floor();
    let tile = V::Real::select(check.lt(V::Real::ONE), splat(0.9), splat(0.05));
    let fade = (-dir.y() * splat(4.0)).min(V::Real::ONE); // grazing rays see the horizon
    V::constant(HORIZON).lerp(V::new(tile, tile, tile), fade)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::environment::Polynomial;

    #[test]
    fn procedural_environment_has_structure_everywhere() {
        let below = procedural_radiance::<Polynomial>(Vec3::new(0.1, -0.5, -0.3).normalize());
        let other = procedural_radiance::<Polynomial>(Vec3::new(0.35, -0.5, -0.3).normalize());
        assert_ne!(below, other, "checker squares differ");
        let sky = procedural_radiance::<Polynomial>(Vec3::Y);
        assert!(sky.z > sky.x, "blue zenith");
        let stripe = procedural_radiance::<Polynomial>(Vec3::new(0.0, 0.2, -1.0).normalize());
        assert!(
            stripe.x > 0.8 && stripe.y < 0.2,
            "red stripe toward −z: {stripe}"
        );
    }

    /// Eight lanes give the scalar function's bits, over directions that cover the sky, the
    /// stripes (and their edges), the sun, the ground and the horizon.
    #[test]
    fn eight_lanes_equal_the_scalar_sky_bit_for_bit() {
        let (n_theta, n_phi) = (181, 720);
        let mut dirs = Vec::new();
        for t in 0..n_theta {
            for p in 0..n_phi {
                let theta = core::f32::consts::PI * t as f32 / (n_theta - 1) as f32;
                let phi = core::f32::consts::TAU * (p as f32 + 0.25) / n_phi as f32;
                let (st, ct) = theta.sin_cos();
                dirs.push(Vec3::new(st * phi.sin(), ct, -st * phi.cos()));
            }
        }
        dirs.push(Vec3::new(0.398_014_87, 0.597_022_3, -0.696_526_05));
        dirs.extend([
            Vec3::X,
            Vec3::NEG_X,
            Vec3::Z,
            Vec3::NEG_Z,
            Vec3::new(0.0, -0.0, -1.0),
        ]);
        while !dirs.len().is_multiple_of(8) {
            dirs.push(Vec3::Y);
        }
        // Also groups mixing sky and ground lanes: the front and back of the list interleaved.
        let n = dirs.len();
        let mixed: Vec<Vec3> = (0..n)
            .map(|i| {
                if i % 2 == 0 {
                    dirs[i / 2]
                } else {
                    dirs[n - 1 - i / 2]
                }
            })
            .collect();
        dirs.extend(mixed);
        for chunk in dirs.chunks_exact(8) {
            let lanes: [Vec3; 8] = chunk.try_into().expect("eight");
            let wide = procedural_radiance_x8(Vec3x8::from_lanes(&lanes)).to_lanes();
            for (d, w) in lanes.iter().zip(wide) {
                assert_eq!(
                    w.to_array(),
                    procedural_radiance::<Polynomial>(*d).to_array(),
                    "{d}"
                );
            }
        }
    }
}
