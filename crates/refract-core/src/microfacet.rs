//! Rough interfaces: the GGX (Trowbridge–Reitz) microfacet distribution with Smith's
//! separable masking, sampled by its visible normals, and one sample of a rough dielectric or
//! conductor interface (Walter et al. 2007, *Microfacet Models for Refraction through Rough
//! Surfaces*; Heitz 2018, *Sampling the GGX Distribution of Visible Normals*).
//!
//! Parametrised as Mitsuba 3's `roughdielectric` and `roughconductor` with
//! `distribution = "ggx"` and `sample_visible = true`: isotropic `α`, which is glTF's
//! `roughness²` ([`alpha_from_roughness`]). Vectors named `*_local` are in the interface's
//! frame, the macro-surface normal along `+z` ([`orthonormal_basis`]); the others are in world
//! space with this crate's conventions (incident directions toward the surface,
//! `eta = n_i / n_t`).

use glam::{Vec2, Vec3};

use crate::fresnel::fresnel_dielectric;
use crate::math;
use crate::optics::{reflect, refract};

/// The roughness of an interface, glTF's `roughnessFactor` range: 0 is a smooth (specular)
/// interface, 1 the roughest.
pub const ROUGHNESS_RANGE: core::ops::RangeInclusive<f32> = 0.0..=1.0;
/// What an error about a roughness says was expected.
pub const ROUGHNESS_EXPECTED: &str = "a roughness from 0 (smooth) to 1";

/// Whether `roughness` is in [`ROUGHNESS_RANGE`] (NaN is not).
pub fn roughness_in_range(roughness: f32) -> bool {
    ROUGHNESS_RANGE.contains(&roughness)
}

/// GGX's `α` of a glTF roughness `r`: `α = r²` (glTF 2.0 Appendix B; Mitsuba's `alpha` is this
/// `α` directly).
///
/// ```
/// assert_eq!(refract_core::microfacet::alpha_from_roughness(0.5), 0.25);
/// ```
#[inline]
pub fn alpha_from_roughness(roughness: f32) -> f32 {
    roughness * roughness
}

/// Two unit tangents `(t, b)` such that `(t, b, n)` is a right-handed orthonormal frame, for a
/// unit `n` (Duff et al. 2017, *Building an Orthonormal Basis, Revisited*: branchless but for
/// the sign, continuous except across `n.z = 0`).
#[inline]
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The GGX normal distribution of a microfacet normal `m_local`:
/// `D(m) = 1 / (π α² ((m_x² + m_y²)/α² + m_z²)²)` (Walter et al. 2007 eq. 33), 0 for normals
/// below the macro surface or where `D cos θm` underflows (Mitsuba's guard). Normalised so
/// that `∫ D(m) cos θm dm = 1` over the hemisphere.
#[inline]
pub fn ggx_d(m_local: Vec3, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let s = (m_local.x * m_local.x + m_local.y * m_local.y) / a2 + m_local.z * m_local.z;
    let d = 1.0 / (core::f32::consts::PI * a2 * s * s);
    if d * m_local.z > 1e-20 { d } else { 0.0 }
}

/// Smith's masking of GGX for a direction `v_local` (either side) and microfacet `m_local`:
/// `G1(v, m) = 2 / (1 + √(1 + α² tan²θv))` (Walter et al. 2007 eq. 34), 1 at normal incidence,
/// 0 where `v` would see the back of the microfacet (`(v·m) cos θv ≤ 0`).
#[inline]
pub fn smith_g1(v_local: Vec3, m_local: Vec3, alpha: f32) -> f32 {
    if v_local.dot(m_local) * v_local.z <= 0.0 {
        return 0.0;
    }
    let xy = alpha * alpha * (v_local.x * v_local.x + v_local.y * v_local.y);
    if xy == 0.0 {
        return 1.0;
    }
    let tan2_alpha2 = xy / (v_local.z * v_local.z);
    2.0 / (1.0 + math::sqrt(1.0 + tan2_alpha2))
}

/// A microfacet normal drawn from the normals visible from `wi_local` (`wi_local.z > 0`),
/// with density [`visible_normal_pdf`], from `u ∈ [0, 1)²` (Heitz 2018, listing 1: stretch the
/// view to the hemisphere configuration, sample the projected disk, unstretch).
#[inline]
pub fn sample_visible_normal(wi_local: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    let vh = Vec3::new(alpha * wi_local.x, alpha * wi_local.y, wi_local.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) * (1.0 / math::sqrt(lensq))
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    let r = math::sqrt(u.x);
    let (sin_phi, cos_phi) = math::sin_cos(2.0 * core::f32::consts::PI * u.y);
    let p1 = r * cos_phi;
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * math::sqrt(1.0 - p1 * p1) + s * (r * sin_phi);
    let nh = t1 * p1 + t2 * p2 + vh * math::sqrt((1.0 - p1 * p1 - p2 * p2).max(0.0));
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// The density of [`sample_visible_normal`] over microfacet normals (solid angle):
/// `D_wi(m) = G1(wi, m) max(0, wi·m) D(m) / cos θi` (Heitz 2018 eq. 2).
#[inline]
pub fn visible_normal_pdf(wi_local: Vec3, m_local: Vec3, alpha: f32) -> f32 {
    if wi_local.z <= 0.0 {
        return 0.0;
    }
    smith_g1(wi_local, m_local, alpha) * wi_local.dot(m_local).max(0.0) * ggx_d(m_local, alpha)
        / wi_local.z
}

/// One visible microfacet normal of a rough interface and what both lobes do about it: the
/// terms of the sampled estimator `f cos θo / pdf` of Walter et al.'s BSDF with visible-normal
/// sampling, which reduce to `F G1(wo_r, m)` for the reflection and `(1 − F) G1(wo_t, m)` for
/// the transmission (times the caller's radiance factor `η²`), as Mitsuba 3's
/// `roughdielectric::sample` computes them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MicrofacetSample {
    /// The microfacet normal (world space), facing the incident ray.
    pub m: Vec3,
    /// Exact Fresnel reflectance at the microfacet, `F(wi·m, η)`; 1 under TIR about `m`.
    pub fresnel: f32,
    /// The direction reflected about `m` (unit).
    pub reflected: Vec3,
    /// `G1(wo_r, m)`, 0 where `wo_r` goes below the macro surface.
    pub reflected_masking: f32,
    /// The direction refracted through `m` (unit; the zero vector under TIR about `m`).
    pub refracted: Vec3,
    /// `G1(wo_t, m)`, 0 under TIR or where `wo_t` does not cross the macro surface.
    pub refracted_masking: f32,
}

/// Samples the microfacet normal of a rough interface seen along `dir` (unit, toward the
/// surface) with macro-surface normal `facing` (unit, toward the ray: `dir·facing ≤ 0`),
/// relative index `eta = n_i / n_t` and GGX `alpha > 0`, from `u ∈ [0, 1)²`; reflects and
/// refracts about it. A ray at or past grazing (`dir·facing ≥ 0`) yields zero masking on both
/// lobes.
#[inline]
pub fn sample_rough_interface(
    dir: Vec3,
    facing: Vec3,
    eta: f32,
    alpha: f32,
    u: Vec2,
) -> MicrofacetSample {
    let (t, b) = orthonormal_basis(facing);
    let to_local = |v: Vec3| Vec3::new(v.dot(t), v.dot(b), v.dot(facing));
    let wi_local = to_local(-dir);
    if wi_local.z <= 0.0 {
        return MicrofacetSample {
            m: facing,
            fresnel: 1.0,
            reflected: reflect(dir, facing),
            reflected_masking: 0.0,
            refracted: Vec3::ZERO,
            refracted_masking: 0.0,
        };
    }
    let m_local = sample_visible_normal(wi_local, alpha, u);
    let m = (t * m_local.x + b * m_local.y + facing * m_local.z).normalize();
    let reflected = reflect(dir, m).normalize();
    let refracted = refract(dir, m, eta);
    let tir = refracted == Vec3::ZERO;
    let refracted = if tir {
        refracted
    } else {
        refracted.normalize()
    };
    let fresnel = if tir {
        1.0
    } else {
        fresnel_dielectric(-dir.dot(m), eta)
    };
    let m_local = to_local(m);
    let reflected_local = to_local(reflected);
    let reflected_masking = if reflected_local.z > 0.0 {
        smith_g1(reflected_local, m_local, alpha)
    } else {
        0.0
    };
    let refracted_local = to_local(refracted);
    let refracted_masking = if !tir && refracted_local.z < 0.0 {
        smith_g1(refracted_local, m_local, alpha)
    } else {
        0.0
    };
    MicrofacetSample {
        m,
        fresnel,
        reflected,
        reflected_masking,
        refracted,
        refracted_masking,
    }
}

/// Walter et al.'s rough dielectric BSDF times its cosine, `f(wi, wo) |cos θo|`, in the
/// interface frame (`wi_local.z > 0`; `eta = n_i / n_t` for the side `wi` is on), without the
/// radiance factor `η²` of a transmission (Mitsuba's `eval` in radiance mode is this times
/// `η²` for transmitted `wo`). Reflection (`wo_local.z > 0`): `F D G / (4 cos θi)` with
/// `m = ĥ(wi + wo)`; transmission: `(1 − F) D G |wi·m| |wo·m| / (cos θi (η (wi·m) + wo·m)²)`
/// with `m = ĥ(−(η wi + wo))` turned up (Walter et al. 2007 eqs. 20 and 21 divided through by
/// `n_t²`). `G = G1(wi, m) G1(wo, m)`. The tests hold [`sample_rough_interface`] to it.
pub fn rough_dielectric_eval(wi_local: Vec3, wo_local: Vec3, eta: f32, alpha: f32) -> f32 {
    if wi_local.z <= 0.0 || wo_local.z == 0.0 {
        return 0.0;
    }
    if wo_local.z > 0.0 {
        let h = wi_local + wo_local;
        if h.length_squared() == 0.0 {
            return 0.0;
        }
        let m = h.normalize();
        let f = fresnel_dielectric(wi_local.dot(m), eta);
        let g = smith_g1(wi_local, m, alpha) * smith_g1(wo_local, m, alpha);
        return f * ggx_d(m, alpha) * g / (4.0 * wi_local.z);
    }
    let h = wi_local * eta + wo_local;
    if h.length_squared() == 0.0 {
        return 0.0;
    }
    let mut m = -h.normalize();
    if m.z < 0.0 {
        m = -m;
    }
    let i_m = wi_local.dot(m);
    let o_m = wo_local.dot(m);
    // Both on the sides the refraction about m puts them.
    if i_m <= 0.0 || o_m >= 0.0 {
        return 0.0;
    }
    let f = fresnel_dielectric(i_m, eta);
    let g = smith_g1(wi_local, m, alpha) * smith_g1(wo_local, m, alpha);
    let denominator = eta * i_m + o_m;
    (1.0 - f) * ggx_d(m, alpha) * g * i_m * (-o_m) / (wi_local.z * denominator * denominator)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;

    fn from_angles(theta: f32, phi: f32) -> Vec3 {
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    }

    /// Midpoint quadrature over the sphere in (θ, φ), `∫ f(ω) dω = ∫∫ f sin θ dθ dφ`, with
    /// `n` steps in θ (the peaks of small α are narrow in θ, not in cos θ).
    fn integrate_sphere(f: impl Fn(Vec3) -> f64, n: usize) -> f64 {
        let (d_theta, d_phi) = (
            std::f64::consts::PI / n as f64,
            std::f64::consts::PI / n as f64,
        );
        let mut sum = 0.0;
        for i in 0..n {
            let theta = (i as f64 + 0.5) * d_theta;
            let (s, z) = theta.sin_cos();
            let mut ring = 0.0;
            for j in 0..2 * n {
                let phi = (j as f64 + 0.5) * d_phi;
                ring += f(Vec3::new(
                    (s * phi.cos()) as f32,
                    (s * phi.sin()) as f32,
                    z as f32,
                ));
            }
            sum += ring * s;
        }
        sum * d_theta * d_phi
    }

    #[test]
    fn basis_is_orthonormal_and_right_handed() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
            Vec3::new(-0.2, 0.1, -0.97).normalize(),
        ] {
            let (t, b) = orthonormal_basis(n);
            assert!((t.length() - 1.0).abs() < 1e-6 && (b.length() - 1.0).abs() < 1e-6);
            assert!(t.dot(b).abs() < 1e-6 && t.dot(n).abs() < 1e-6 && b.dot(n).abs() < 1e-6);
            assert!((t.cross(b) - n).length() < 1e-5, "{n}");
        }
    }

    /// `∫ D(m) cos θm dm = 1` (the projected microfacet area is the macro area).
    #[test]
    fn distribution_is_normalised() {
        for alpha in [0.05f32, 0.2, 0.5, 1.0] {
            let n = if alpha < 0.1 { 1600 } else { 400 };
            let integral = integrate_sphere(|m| (ggx_d(m, alpha) * m.z.max(0.0)) as f64, n);
            assert!((integral - 1.0).abs() < 2e-3, "α {alpha}: {integral}");
        }
    }

    /// The weak white furnace (Heitz 2014 §5): the visible normals' density integrates to 1 for
    /// every view, which holds only when D and G1 belong together.
    #[test]
    fn visible_normal_density_is_normalised() {
        for alpha in [0.1f32, 0.4, 1.0] {
            for theta in [0.0f32, 0.6, 1.2, 1.5] {
                let wi = from_angles(theta, 0.7);
                let integral = integrate_sphere(|m| visible_normal_pdf(wi, m, alpha) as f64, 800);
                assert!(
                    (integral - 1.0).abs() < 5e-3,
                    "α {alpha} θ {theta}: {integral}"
                );
            }
        }
    }

    /// Pearson's χ² of sampled visible normals against their density on a (cos θ, φ) grid, as
    /// Mitsuba's and pbrt's microfacet tests do: a wrong stretch, a missing `s` blend or a
    /// density off by a cosine fails it by orders of magnitude.
    #[test]
    fn visible_normals_follow_their_density() {
        const CELLS_Z: usize = 16;
        const CELLS_PHI: usize = 32;
        const SAMPLES: usize = 400_000;
        for (alpha, theta) in [(0.3f32, 0.4f32), (0.6, 1.2), (0.1, 1.0)] {
            let wi = from_angles(theta, 2.0);
            let cell = |m: Vec3| {
                let z = ((m.z.clamp(0.0, 1.0 - 1e-7)) * CELLS_Z as f32) as usize;
                let phi = m.y.atan2(m.x).rem_euclid(2.0 * PI);
                let p = ((phi / (2.0 * PI) * CELLS_PHI as f32) as usize).min(CELLS_PHI - 1);
                z * CELLS_PHI + p
            };
            let mut observed = vec![0.0f64; CELLS_Z * CELLS_PHI];
            let mut state = 0x1234_5678u64;
            let mut uniform = || {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                (state >> 40) as f32 / (1u64 << 24) as f32
            };
            for _ in 0..SAMPLES {
                let m = sample_visible_normal(wi, alpha, Vec2::new(uniform(), uniform()));
                assert!((m.length() - 1.0).abs() < 1e-5 && m.z >= 0.0);
                observed[cell(m)] += 1.0;
            }
            // Expected counts: the density integrated over each cell, in (θ, φ) sub-steps
            // fine enough for the narrowest lobe.
            let mut expected = vec![0.0f64; CELLS_Z * CELLS_PHI];
            const STEPS_THETA: usize = 3000;
            const STEPS_PHI: usize = CELLS_PHI * 12;
            let d_theta = std::f64::consts::FRAC_PI_2 / STEPS_THETA as f64;
            let d_phi = 2.0 * std::f64::consts::PI / STEPS_PHI as f64;
            for it in 0..STEPS_THETA {
                let (s, z) = ((it as f64 + 0.5) * d_theta).sin_cos();
                for ip in 0..STEPS_PHI {
                    let phi = (ip as f64 + 0.5) * d_phi;
                    let m = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32);
                    expected[cell(m)] += visible_normal_pdf(wi, m, alpha) as f64
                        * s
                        * d_theta
                        * d_phi
                        * SAMPLES as f64;
                }
            }
            // Pool cells with fewer than 5 expected samples (the usual χ² rule).
            let (mut chi2, mut dof, mut pooled_o, mut pooled_e) = (0.0, 0usize, 0.0, 0.0);
            for (o, e) in observed.iter().zip(&expected) {
                if *e < 5.0 {
                    pooled_o += o;
                    pooled_e += e;
                } else {
                    chi2 += (o - e) * (o - e) / e;
                    dof += 1;
                }
            }
            if pooled_e >= 5.0 {
                chi2 += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
                dof += 1;
            }
            // dof − 1 degrees of freedom; mean dof, standard deviation √(2 dof): 6σ above.
            let bound = dof as f64 + 6.0 * (2.0 * dof as f64).sqrt();
            assert!(
                chi2 < bound,
                "α {alpha} θ {theta}: χ² {chi2:.1} over {dof} cells (bound {bound:.1})"
            );
        }
    }

    /// The sampled lobes are the BSDF over the sampling density: the estimator's expected
    /// value over `u` equals `∫ f |cos θo| dωo` computed by quadrature of [`rough_dielectric_eval`]
    /// (the directional albedo), for reflection and transmission separately, both sides.
    #[test]
    fn sampled_weights_match_the_evaluated_bsdf() {
        for (eta, alpha, theta) in [
            (1.0 / 1.5f32, 0.3f32, 0.5f32),
            (1.0 / 1.5, 0.6, 1.2),
            (1.5, 0.3, 0.3),
            (1.5, 0.5, 0.9),
        ] {
            let wi = from_angles(theta, 0.3);
            let dir = -wi;
            let (mut reflected, mut transmitted) = (0.0f64, 0.0f64);
            const N: usize = 256;
            for i in 0..N {
                for j in 0..N {
                    let u = Vec2::new((i as f32 + 0.5) / N as f32, (j as f32 + 0.5) / N as f32);
                    let s = sample_rough_interface(dir, Vec3::Z, eta, alpha, u);
                    reflected += (s.fresnel * s.reflected_masking) as f64;
                    transmitted += ((1.0 - s.fresnel) * s.refracted_masking) as f64;
                }
            }
            reflected /= (N * N) as f64;
            transmitted /= (N * N) as f64;
            let quad_r = integrate_sphere(
                |wo| {
                    if wo.z > 0.0 {
                        rough_dielectric_eval(wi, wo, eta, alpha) as f64
                    } else {
                        0.0
                    }
                },
                800,
            );
            let quad_t = integrate_sphere(
                |wo| {
                    if wo.z < 0.0 {
                        rough_dielectric_eval(wi, wo, eta, alpha) as f64
                    } else {
                        0.0
                    }
                },
                800,
            );
            assert!(
                (reflected - quad_r).abs() < 3e-3,
                "η {eta} α {alpha} θ {theta}: reflection sampled {reflected:.4} vs {quad_r:.4}"
            );
            assert!(
                (transmitted - quad_t).abs() < 3e-3,
                "η {eta} α {alpha} θ {theta}: transmission sampled {transmitted:.4} vs {quad_t:.4}"
            );
            // And energy is not created: reflection + transmission ≤ 1.
            assert!(reflected + transmitted <= 1.0 + 1e-3);
        }
    }

    /// Reciprocity: `f(wi, wo) = f(wo, wi)` for reflection, and `f(wi, wo) / η_o² = f(wo, wi)
    /// / η_i²` for transmission (Walter et al. 2007 eq. 22), with the `|cos θo|` taken back out.
    #[test]
    fn bsdf_is_reciprocal() {
        let alpha = 0.35;
        let n_outside = 1.0f32;
        let n_inside = 1.5f32;
        for (a, b) in [(0.3f32, 0.8f32), (1.1, 0.2), (0.6, 1.3), (0.05, 0.9)] {
            // Reflection, outside.
            let wi = from_angles(a, 0.4);
            let wo = from_angles(b, 2.9);
            let f_io = rough_dielectric_eval(wi, wo, n_outside / n_inside, alpha) / wo.z;
            let f_oi = rough_dielectric_eval(wo, wi, n_outside / n_inside, alpha) / wi.z;
            assert!(
                f_io > 0.0 && (f_io - f_oi).abs() <= 1e-4 * f_io,
                "{f_io} vs {f_oi}"
            );
            // Transmission: wi outside refracted into the glass about a microfacet `m` tilted
            // by `b` (a pair that exists); back: both in the frame seen from inside (z flipped).
            let m = from_angles(b * 0.5, 2.9);
            let wo_in = refract(-wi, m, n_outside / n_inside).normalize();
            let f_t = rough_dielectric_eval(wi, wo_in, n_outside / n_inside, alpha) / -wo_in.z;
            let flip = |v: Vec3| Vec3::new(v.x, v.y, -v.z);
            let f_back =
                rough_dielectric_eval(flip(wo_in), flip(wi), n_inside / n_outside, alpha) / wi.z;
            let lhs = f_t / (n_inside * n_inside);
            let rhs = f_back / (n_outside * n_outside);
            assert!(f_t > 0.0, "the transmission exists ({a}, {b})");
            assert!((lhs - rhs).abs() <= 1e-4 * lhs, "{lhs} vs {rhs}");
        }
    }

    /// Smooth limit: as α → 0 the sampled normal is the macro normal and the lobes are the
    /// specular ones.
    #[test]
    fn tiny_roughness_is_specular() {
        let dir = Vec3::new(0.4, 0.0, -0.9165).normalize();
        let s = sample_rough_interface(dir, Vec3::Z, 1.0 / 1.5, 1e-4, Vec2::new(0.37, 0.81));
        assert!((s.m - Vec3::Z).length() < 1e-3);
        assert!((s.refracted - refract(dir, Vec3::Z, 1.0 / 1.5)).length() < 1e-3);
        assert!((s.fresnel - fresnel_dielectric(-dir.z, 1.0 / 1.5)).abs() < 1e-4);
        assert!(s.refracted_masking > 0.999 && s.reflected_masking > 0.999);
    }
}
