//! Fresnel reflectance: the exact unpolarised dielectric formula, Schlick's approximation, and
//! Schlick for conductors (Umenhoffer et al. 2007, GPU Gems 3 §17.3; Kakimoto et al. 2007 §4).
//!
//! `cos_i` is the cosine of the incidence angle, `cos θi = −I · N ∈ [0, 1]`, and
//! `eta = n_i / n_t`. Every function returns a reflectance in `[0, 1]`; the transmitted
//! fraction is `1 − F` (no absorption at the interface).

/// Exact unpolarised Fresnel reflectance of a dielectric interface:
///
/// `sin²θt = η² (1 − cos²θi)`; `F = 1` if `sin²θt ≥ 1` (total internal reflection); otherwise
/// `r_s = (η cos θi − cos θt)/(η cos θi + cos θt)`, `r_p = (cos θi − η cos θt)/(cos θi + η cos θt)`
/// and `F = (r_s² + r_p²) / 2`. At normal incidence `F = ((1 − η)/(1 + η))²`.
///
/// `cos_i` is clamped to `[0, 1]`.
///
/// ```
/// // Air to glass at normal incidence: ((1 − 1.5)/(1 + 1.5))² = 0.04.
/// let r = refract_core::fresnel::fresnel_dielectric(1.0, 1.0 / 1.5);
/// assert!((r - 0.04).abs() < 1e-6);
/// // Beyond the critical angle inside glass: everything is reflected.
/// assert_eq!(refract_core::fresnel::fresnel_dielectric(0.5, 1.5), 1.0);
/// ```
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = crate::math::sqrt(1.0 - sin2_t);
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (0.5 * (r_s * r_s + r_p * r_p)).clamp(0.0, 1.0)
}

/// Reflectance at normal incidence of a dielectric interface, `F0 = ((1 − η)/(1 + η))²`.
///
/// # Example
///
/// ```
/// assert!((refract_core::fresnel::f0_dielectric(1.0 / 1.5) - 0.04).abs() < 1e-6);
/// ```
#[inline]
pub fn f0_dielectric(eta: f32) -> f32 {
    let r = (1.0 - eta) / (1.0 + eta);
    r * r
}

/// Reflectance at normal incidence of a conductor with complex index `n + ik` seen from a medium
/// of index 1 (Umenhoffer et al. 2007 §17.3): `F_p = ((n − 1)² + k²) / ((n + 1)² + k²)`.
///
/// ```
/// // n = 0.18, k = 3.42 (gold's red channel): ((n − 1)² + k²)/((n + 1)² + k²) ≈ 0.945.
/// let f0 = refract_core::fresnel::f0_conductor(0.18, 3.42);
/// assert!((f0 - 0.944_99).abs() < 1e-4);
/// ```
#[inline]
pub fn f0_conductor(n: f32, k: f32) -> f32 {
    ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k)
}

/// Schlick's approximation, `F = F0 + (1 − F0)(1 − cos θ)⁵`, with `cos θ` clamped to `[0, 1]`.
///
/// ```
/// use refract_core::fresnel::schlick;
/// assert_eq!(schlick(1.0, 0.04), 0.04); // normal incidence: F0
/// assert_eq!(schlick(0.0, 0.04), 1.0); // grazing: everything reflects
/// ```
#[inline]
pub fn schlick(cos_theta: f32, f0: f32) -> f32 {
    let m = 1.0 - cos_theta.clamp(0.0, 1.0);
    let m2 = m * m;
    f0 + (1.0 - f0) * m2 * m2 * m
}

/// Schlick's approximation for a dielectric interface, valid from either side.
///
/// Entering the denser medium (`η ≤ 1`) it uses the incidence cosine; leaving it (`η > 1`) it
/// uses the transmission cosine `cos θt = √(1 − η² sin²θi)` (the reciprocal path), and returns
/// `1` under total internal reflection. `F0 = ((1 − η)/(1 + η))²`.
///
/// Its absolute error against [`fresnel_dielectric`] is at most 0.06 for refractive indices
/// `n ∈ [1.33, 2]` seen from either side (`η = 1/n` or `η = n`), over all angles; the worst
/// case is near grazing incidence (0.036 for glass, `n = 1.5`). It grows quickly toward `n → 1`
/// (0.11 at `n = 1.2`, 0.32 at `n = 1.05`), where the exact reflectance only rises in a sliver
/// near grazing. Measured on a dense sweep in this module's tests.
///
/// # Example
///
/// ```
/// use refract_core::fresnel::{fresnel_dielectric, schlick_dielectric};
/// // Within 0.06 of the exact reflectance for glass, from both sides.
/// for cos_i in [1.0, 0.8, 0.5, 0.2] {
///     for eta in [1.0 / 1.5, 1.5] {
///         assert!((schlick_dielectric(cos_i, eta) - fresnel_dielectric(cos_i, eta)).abs() < 0.06);
///     }
/// }
/// ```
#[inline]
pub fn schlick_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let f0 = f0_dielectric(eta);
    if eta <= 1.0 {
        return schlick(cos_i, f0);
    }
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    schlick(crate::math::sqrt(1.0 - sin2_t), f0)
}

/// Schlick's approximation for a conductor, `F = F_p + (1 − F_p)(1 − cos θ)⁵` with `F_p` from
/// [`f0_conductor`] (Umenhoffer et al. 2007 §17.3).
///
/// # Example
///
/// ```
/// use refract_core::fresnel::{f0_conductor, schlick_conductor};
/// // Silver-like (n = 0.15, k = 3.6): F0 at normal incidence, 1 at grazing.
/// assert_eq!(schlick_conductor(1.0, 0.15, 3.6), f0_conductor(0.15, 3.6));
/// assert!((schlick_conductor(0.0, 0.15, 3.6) - 1.0).abs() < 1e-6);
/// ```
#[inline]
pub fn schlick_conductor(cos_i: f32, n: f32, k: f32) -> f32 {
    schlick(cos_i, f0_conductor(n, k))
}

/// Exact unpolarised Fresnel reflectance of a conductor of complex index `n + ik` seen from a
/// medium of index 1 (the standard form, as in pbrt's `FrConductor` and Mitsuba 3's
/// `fresnel_conductor`): with `c = cos θi`, `s² = 1 − c²`, `t0 = n² − k² − s²`,
/// `a² + b² = √(t0² + 4n²k²)`, `a = √((a² + b² + t0)/2)`,
/// `R_s = (a² + b² + c² − 2ac) / (a² + b² + c² + 2ac)`,
/// `R_p = R_s (c²(a² + b²) + s⁴ − 2acs²) / (c²(a² + b²) + s⁴ + 2acs²)`, `F = (R_s + R_p)/2`.
/// At normal incidence it is [`f0_conductor`]; for `n = 0` (a lossless "perfect mirror") it is 1
/// at every angle. `cos_i` is clamped to `[0, 1]`.
///
/// ```
/// use refract_core::fresnel::{f0_conductor, fresnel_conductor};
/// assert!((fresnel_conductor(1.0, 0.27, 3.61) - f0_conductor(0.27, 3.61)).abs() < 1e-6);
/// assert!((fresnel_conductor(0.3, 0.0, 1.0) - 1.0).abs() < 1e-6);
/// ```
#[inline]
pub fn fresnel_conductor(cos_i: f32, n: f32, k: f32) -> f32 {
    let c = cos_i.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let (n2, k2) = (n * n, k * k);
    let t0 = n2 - k2 - s2;
    let a2b2 = crate::math::sqrt((t0 * t0 + 4.0 * n2 * k2).max(0.0));
    let a = crate::math::sqrt((0.5 * (a2b2 + t0)).max(0.0));
    let t1 = a2b2 + c2;
    let t2 = 2.0 * c * a;
    let r_s = if t1 + t2 > 0.0 {
        (t1 - t2) / (t1 + t2)
    } else {
        1.0
    };
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    let r_p = if t3 + t4 > 0.0 {
        r_s * (t3 - t4) / (t3 + t4)
    } else {
        r_s
    };
    (0.5 * (r_s + r_p)).clamp(0.0, 1.0)
}

/// A conductor (metal or mirror): a complex index of refraction `n + ik` per RGB channel,
/// seen from air. Umenhoffer et al. 2007 §17.3 store its `F_p` ([`Conductor::f0`]) in the
/// distance map and use Schlick's approximation; the reference uses [`fresnel_conductor`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Real part `n` per channel (linear R, G, B).
    pub eta: glam::Vec3,
    /// Extinction coefficient `k` per channel.
    pub k: glam::Vec3,
}

impl Conductor {
    /// An ideal mirror: `n = 0`, `k = 1`, so `F = 1` at every angle, exactly in both the exact
    /// formula and Schlick's (`F_p = 1`).
    pub const MIRROR: Self = Self {
        eta: glam::Vec3::ZERO,
        k: glam::Vec3::ONE,
    };
    /// Gold, at about 650 / 550 / 450 nm (the RGB values commonly tabulated for real-time
    /// rendering from refractiveindex.info data, e.g. Gulbrandsen 2014, JCGT 3(4)).
    pub const GOLD: Self = Self {
        eta: glam::Vec3::new(0.183, 0.421, 1.373),
        k: glam::Vec3::new(3.424, 2.346, 1.770),
    };
    /// Silver (same source as [`Self::GOLD`]).
    pub const SILVER: Self = Self {
        eta: glam::Vec3::new(0.159, 0.145, 0.135),
        k: glam::Vec3::new(3.929, 3.190, 2.381),
    };
    /// Copper (same source as [`Self::GOLD`]).
    pub const COPPER: Self = Self {
        eta: glam::Vec3::new(0.271, 0.677, 1.316),
        k: glam::Vec3::new(3.609, 2.625, 2.292),
    };
    /// Aluminium (same source as [`Self::GOLD`]).
    pub const ALUMINIUM: Self = Self {
        eta: glam::Vec3::new(1.346, 0.965, 0.617),
        k: glam::Vec3::new(7.475, 6.400, 5.303),
    };

    /// `F_p` per channel, [`f0_conductor`] (§17.3).
    pub fn f0(&self) -> glam::Vec3 {
        glam::Vec3::new(
            f0_conductor(self.eta.x, self.k.x),
            f0_conductor(self.eta.y, self.k.y),
            f0_conductor(self.eta.z, self.k.z),
        )
    }

    /// The exact reflectance per channel at incidence cosine `cos_i` ([`fresnel_conductor`]).
    pub fn reflectance(&self, cos_i: f32) -> glam::Vec3 {
        glam::Vec3::new(
            fresnel_conductor(cos_i, self.eta.x, self.k.x),
            fresnel_conductor(cos_i, self.eta.y, self.k.y),
            fresnel_conductor(cos_i, self.eta.z, self.k.z),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glass_at_normal_incidence_reflects_four_percent() {
        assert!((fresnel_dielectric(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((f0_dielectric(1.0 / 1.5) - 0.04).abs() < 1e-7);
    }

    #[test]
    fn brewster_angle_kills_p_polarisation() {
        // At Brewster's angle r_p = 0, so F = r_s² / 2.
        let n = 1.5_f32;
        let theta_b = n.atan();
        let cos_i = theta_b.cos();
        let cos_t = (1.0 - (theta_b.sin() / n).powi(2)).sqrt();
        let eta = 1.0 / n;
        let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
        assert!((fresnel_dielectric(cos_i, eta) - 0.5 * r_s * r_s).abs() < 1e-6);
    }

    #[test]
    fn conductor_f0_follows_the_complex_index_formula() {
        // n = 0.25, k = 2.98: F_p = (0.75² + 2.98²) / (1.25² + 2.98²) = 9.4429 / 10.4429.
        let f0 = f0_conductor(0.25, 2.98);
        assert!((f0 - 9.4429 / 10.4429).abs() < 1e-6, "{f0}");
        assert_eq!(schlick_conductor(1.0, 0.25, 2.98), f0);
        assert_eq!(schlick_conductor(0.0, 0.25, 2.98), 1.0);
    }

    /// The bound stated on `schlick_dielectric`, measured on a 4001-angle × 2·31-eta sweep.
    #[test]
    fn schlick_error_bound_holds_on_a_dense_sweep() {
        let mut worst = 0.0_f32;
        for e in 0..=30 {
            let n = 1.33 + 0.67 * e as f32 / 30.0;
            for eta in [1.0 / n, n] {
                for a in 0..=4000 {
                    let cos_i = a as f32 / 4000.0;
                    let err =
                        (schlick_dielectric(cos_i, eta) - fresnel_dielectric(cos_i, eta)).abs();
                    worst = worst.max(err);
                }
            }
        }
        assert!(worst < 0.06, "worst Schlick error {worst}");
    }

    #[test]
    fn exact_conductor_fresnel_matches_f0_and_limits() {
        for metal in [
            Conductor::GOLD,
            Conductor::SILVER,
            Conductor::COPPER,
            Conductor::ALUMINIUM,
        ] {
            let f0 = metal.f0();
            let exact = metal.reflectance(1.0);
            assert!((exact - f0).abs().max_element() < 1e-5, "{exact} vs {f0}");
            // Grazing incidence reflects everything; in between it stays in [0, 1] and dips
            // below F0 only slightly (the metals' shallow minimum near 80°).
            assert!(
                (metal.reflectance(0.0) - glam::Vec3::ONE)
                    .abs()
                    .max_element()
                    < 1e-5
            );
            for a in 0..=100 {
                let r = metal.reflectance(a as f32 / 100.0);
                assert!(r.min_element() >= 0.0 && r.max_element() <= 1.0);
                assert!((r - f0).min_element() > -0.1, "{r} vs {f0}");
            }
        }
        for a in 0..=20 {
            let r = Conductor::MIRROR.reflectance(a as f32 / 20.0);
            assert!((r - glam::Vec3::ONE).abs().max_element() < 1e-6, "{r}");
        }
        assert_eq!(Conductor::MIRROR.f0(), glam::Vec3::ONE);
        // A conductor with k = 0 is a dielectric of index n: the dielectric formula agrees.
        for a in 0..=20 {
            let cos_i = a as f32 / 20.0;
            let d = fresnel_dielectric(cos_i, 1.0 / 1.5);
            assert!((fresnel_conductor(cos_i, 1.5, 0.0) - d).abs() < 1e-5);
        }
    }
}
