//! Property tests of refract-core's optics and Wyman 2005a kernels (proptest, 512 cases each).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};
use proptest::prelude::*;
use refract_core::camera::{Camera, CameraDesc};
use refract_core::exit::{TirPolicy, exit_normal_outside_silhouette, refract_exit};
use refract_core::fresnel::{
    f0_conductor, f0_dielectric, fresnel_dielectric, schlick_conductor, schlick_dielectric,
};
use refract_core::interpolated_distance::{
    DistanceMode, approximate_distance, interpolated_distance,
};
use refract_core::kernel::{
    BackFaceSample, BackFaceSampler, FrontSurface, ImageSpaceParams, one_interface, two_interface,
};
use refract_core::optics::{critical_angle, is_total_internal_reflection, reflect, refract};

const CASES: u32 = 512;

/// 512 cases (or `PROPTEST_CASES`), and room for the rejections of `prop_assume!` (TIR cases
/// are rejected by the properties of transmitted rays) when `PROPTEST_CASES` is raised.
fn config() -> ProptestConfig {
    let defaults = ProptestConfig::default();
    let cases = if std::env::var_os("PROPTEST_CASES").is_some() {
        defaults.cases
    } else {
        CASES
    };
    ProptestConfig {
        cases,
        max_global_rejects: cases.saturating_mul(4),
        ..defaults
    }
}

fn unit_vector() -> impl Strategy<Value = Vec3> {
    (-1.0f32..=1.0, 0.0f32..(2.0 * PI)).prop_map(|(z, phi)| {
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z).normalize()
    })
}

/// A unit incident direction and a unit normal facing it (`N · I ≤ 0`).
fn incident_and_normal() -> impl Strategy<Value = (Vec3, Vec3)> {
    (unit_vector(), unit_vector()).prop_map(|(i, n)| if n.dot(i) > 0.0 { (-i, n) } else { (i, n) })
}

/// Refractive index of a material in air: 1 to 2.5 (vacuum to diamond and beyond).
fn ior() -> impl Strategy<Value = f32> {
    1.0f32..=2.5
}

/// `η = n_i/n_t` from either side of an interface between air and [`ior`].
fn eta() -> impl Strategy<Value = f32> {
    (ior(), any::<bool>()).prop_map(|(n, entering)| if entering { 1.0 / n } else { n })
}

/// Below this `cos θi`, `k = cos²θi` is within a few rounding errors (`n² ε`) of zero.
fn grazing_limit(n_index: f32) -> f32 {
    4.0 * n_index * f32::EPSILON.sqrt()
}

fn sin_between(a: Vec3, b: Vec3) -> f32 {
    a.cross(b).length()
}

fn any_finite() -> impl Strategy<Value = f32> {
    prop_oneof![
        any::<f32>().prop_filter("finite", |x| x.is_finite()),
        -10.0f32..10.0,
        Just(0.0f32),
    ]
}

fn any_finite_vec3() -> impl Strategy<Value = Vec3> {
    (any_finite(), any_finite(), any_finite()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// A back-face buffer that returns the same (possibly absurd) sample everywhere, or nothing.
struct ConstantBack(Option<BackFaceSample>);

impl BackFaceSampler for ConstantBack {
    fn back_face(&self, _uv_px: Vec2) -> Option<BackFaceSample> {
        self.0
    }
}

fn camera() -> Camera {
    Camera::new(CameraDesc {
        width: 64,
        height: 48,
        ..CameraDesc::default()
    })
    .expect("valid camera")
}

proptest! {
    #![proptest_config(config())]

    /// Snell's law: n_i sin θi = n_t sin θt, i.e. η sin θi = sin θt.
    #[test]
    fn snell_law_holds((i, n) in incident_and_normal(), eta in eta()) {
        let t = refract(i, n, eta);
        prop_assume!(t != Vec3::ZERO);
        let sin_i = sin_between(-i, n);
        let sin_t = sin_between(t, -n);
        prop_assert!((eta * sin_i - sin_t).abs() < 2e-5, "{} vs {}", eta * sin_i, sin_t);
    }

    /// T lies in the plane of incidence spanned by I and N.
    #[test]
    fn refracted_ray_is_coplanar((i, n) in incident_and_normal(), eta in eta()) {
        let t = refract(i, n, eta);
        prop_assume!(t != Vec3::ZERO);
        let plane = i.cross(n);
        prop_assume!(plane.length() > 1e-3);
        prop_assert!(t.dot(plane.normalize()).abs() < 1e-5);
    }

    /// |T| = 1 for unit inputs, and T goes to the other side of the surface.
    #[test]
    fn refracted_ray_is_unit_and_transmitted((i, n) in incident_and_normal(), eta in eta()) {
        let t = refract(i, n, eta);
        prop_assume!(t != Vec3::ZERO);
        prop_assert!((t.length() - 1.0).abs() < 1e-5);
        prop_assert!(t.dot(n) <= 1e-6);
    }

    /// Total internal reflection happens exactly when η sin θi > 1.
    #[test]
    fn tir_exactly_when_eta_sin_exceeds_one((i, n) in incident_and_normal(), eta in eta()) {
        let s = eta * sin_between(-i, n);
        prop_assume!((s - 1.0).abs() > 1e-5);
        prop_assert_eq!(refract(i, n, eta) == Vec3::ZERO, s > 1.0);
        prop_assert_eq!(is_total_internal_reflection(i, n, eta), s > 1.0);
    }

    /// Critical angle: just below it light is transmitted, just above it it is not.
    #[test]
    fn critical_angle_separates_transmission_from_tir(n_index in 1.05f32..=2.5) {
        let theta_c = critical_angle(n_index);
        let normal = Vec3::Y;
        let below = Vec3::new((theta_c - 1e-3).sin(), -(theta_c - 1e-3).cos(), 0.0);
        let above = Vec3::new((theta_c + 1e-3).sin(), -(theta_c + 1e-3).cos(), 0.0);
        prop_assert!(refract(below, normal, n_index) != Vec3::ZERO);
        prop_assert_eq!(refract(above, normal, n_index), Vec3::ZERO);
    }

    /// Reversibility: refracting -T back through the interface with 1/η returns -I.
    #[test]
    fn refraction_is_reversible((i, n) in incident_and_normal(), eta in eta()) {
        let t = refract(i, n, eta);
        prop_assume!(t != Vec3::ZERO);
        // Rays this close to grazing come back at the critical angle, where the rounding of
        // k = cos²θi (≈ n² ε) decides between transmission and TIR; the property is about the rest.
        prop_assume!(-i.dot(n) > grazing_limit(eta.max(1.0 / eta)));
        let back = refract(-t, -n, 1.0 / eta);
        // Conditioning as in `parallel_slab_returns_the_view_direction`: ~n³ ε / cos θi.
        let n_index = eta.max(1.0 / eta);
        let tolerance = 2e-6 + 8.0 * n_index.powi(3) * f32::EPSILON / -i.dot(n);
        prop_assert!((back + i).length() < tolerance, "{} vs {}", back, -i);
    }

    /// Reflection keeps length and mirrors the normal component: R·N = −I·N.
    #[test]
    fn reflection_mirrors_the_normal_component((i, n) in incident_and_normal()) {
        let r = reflect(i, n);
        prop_assert!((r.length() - 1.0).abs() < 1e-5);
        prop_assert!((r.dot(n) + i.dot(n)).abs() < 1e-5);
    }

    /// Exact Fresnel reflectance lies in [0, 1] and is 1 under TIR.
    #[test]
    fn fresnel_is_a_reflectance((i, n) in incident_and_normal(), eta in eta()) {
        let f = fresnel_dielectric(-i.dot(n), eta);
        prop_assert!((0.0..=1.0).contains(&f), "{}", f);
        if is_total_internal_reflection(i, n, eta) {
            prop_assert_eq!(f, 1.0);
        }
    }

    /// At normal incidence F = ((1 − η)/(1 + η))², from either side.
    #[test]
    fn fresnel_at_normal_incidence(eta in eta()) {
        let expected = ((1.0 - eta) / (1.0 + eta)).powi(2);
        prop_assert!((fresnel_dielectric(1.0, eta) - expected).abs() < 1e-6);
        prop_assert!((f0_dielectric(eta) - expected).abs() < 1e-6);
    }

    /// Schlick's approximation stays within 0.06 of the exact Fresnel for n ∈ [1.33, 2].
    #[test]
    fn schlick_is_close_to_exact_fresnel(
        cos_i in 0.0f32..=1.0, n in 1.33f32..=2.0, entering in any::<bool>(),
    ) {
        let eta = if entering { 1.0 / n } else { n };
        let err = (schlick_dielectric(cos_i, eta) - fresnel_dielectric(cos_i, eta)).abs();
        prop_assert!(err <= 0.06, "error {} at cos {} eta {}", err, cos_i, eta);
    }

    /// Conductor Schlick is a reflectance, equal to F_p at normal incidence and 1 at grazing.
    #[test]
    fn conductor_schlick_is_a_reflectance(cos_i in 0.0f32..=1.0, n in 0.05f32..4.0, k in 0.0f32..8.0) {
        let f = schlick_conductor(cos_i, n, k);
        prop_assert!((0.0..=1.0).contains(&f));
        prop_assert!((schlick_conductor(1.0, n, k) - f0_conductor(n, k)).abs() < 1e-7);
        prop_assert_eq!(schlick_conductor(0.0, n, k), 1.0);
    }

    /// d~ lies between d_V and d_N when entering a denser medium.
    #[test]
    fn interpolated_distance_lies_between_d_v_and_d_n(
        (i, n) in incident_and_normal(), n_index in ior(), d_v in 0.0f32..10.0, d_n in 0.0f32..10.0,
    ) {
        let eta = 1.0 / n_index;
        let t = refract(i, n, eta);
        let theta_i = refract_core::vector::angle_between(-i, n);
        let theta_t = refract_core::vector::angle_between(t, -n);
        let d = interpolated_distance(theta_i, theta_t, eta, d_v, d_n);
        prop_assert!(d >= d_v.min(d_n) - 1e-5 && d <= d_v.max(d_n) + 1e-5);
    }

    /// With η = 1 nothing bends, θt = θi, and d~ = d_V.
    #[test]
    fn interpolated_distance_is_d_v_without_refraction(
        (i, n) in incident_and_normal(), d_v in 0.0f32..10.0, d_n in 0.0f32..10.0,
    ) {
        let t = refract(i, n, 1.0);
        let theta_i = refract_core::vector::angle_between(-i, n);
        let theta_t = refract_core::vector::angle_between(t, -n);
        let d = approximate_distance(DistanceMode::Interpolated, theta_i, theta_t, 1.0, d_v, d_n);
        prop_assert!((d - d_v).abs() <= 1e-4 * (1.0 + d_v.max(d_n)), "{} vs {}", d, d_v);
    }

    /// d~ is continuous at normal incidence: approaching θi → 0 along Snell's law gives the limit.
    #[test]
    fn interpolated_distance_is_continuous_at_normal_incidence(
        theta_i in 0.0f32..1e-3, n_index in ior(), d_v in 0.0f32..10.0, d_n in 0.0f32..10.0,
    ) {
        let eta = 1.0 / n_index;
        let theta_t = (eta * theta_i.sin()).asin();
        let near = interpolated_distance(theta_i, theta_t, eta, d_v, d_n);
        let limit = interpolated_distance(0.0, 0.0, eta, d_v, d_n);
        // θt/θi = η (1 + (η² − 1) θi²/6 + …): the gap is O(θi²) plus f32 rounding of the ratio
        // (~1e-6 relative) and of the weighted sum (a few ε of the distances).
        let bound = (theta_i * theta_i + 1e-6) * (d_v - d_n).abs()
            + 4.0 * f32::EPSILON * (d_v + d_n)
            + 1e-7;
        prop_assert!((near - limit).abs() <= bound, "{} vs {}", near, limit);
    }

    /// A parallel slab (exit surface parallel to the entry one) returns T2 = V.
    #[test]
    fn parallel_slab_returns_the_view_direction((v, n1) in incident_and_normal(), n_index in ior()) {
        let t1 = refract(v, n1, 1.0 / n_index);
        prop_assume!(t1 != Vec3::ZERO);
        // The slab's back face has the opposite outward normal.
        let cos_i = -v.dot(n1);
        prop_assume!(cos_i > grazing_limit(n_index)); // see `refraction_is_reversible`
        let exit = refract_exit(t1, -n1, n_index, TirPolicy::ClampToCritical);
        prop_assert!(!exit.tir);
        // Near grazing the exit is ill-conditioned: k = (1 − n²) + n² (N·T1)² = cos²θi carries
        // a rounding error δk ≈ n² ε (from its terms and from T1), which moves T2 by
        // n δk / (2 cos θi); so the bound is ~n³ ε / cos θi (f32 ε ≈ 1.2e-7).
        let tolerance = 2e-6 + 8.0 * n_index.powi(3) * f32::EPSILON / cos_i;
        prop_assert!((exit.t2 - v).length() < tolerance, "{} vs {}", exit.t2, v);
    }

    /// The outside-silhouette exit normal is unit length and perpendicular to the look direction.
    #[test]
    fn silhouette_exit_normal_is_unit_and_perpendicular(t1 in unit_vector(), look in unit_vector()) {
        let sin_tl = t1.cross(look).length();
        prop_assume!(sin_tl > 1e-3);
        let n2 = exit_normal_outside_silhouette(t1, look);
        prop_assert!((n2.length() - 1.0).abs() < 1e-5);
        // T1 − (L·T1) L has length sin∠(T1, L) and absolute rounding ~2ε: relative ~2ε/sin.
        prop_assert!(n2.dot(look).abs() < 1e-6 + 4.0 * f32::EPSILON / sin_tl);
        prop_assert!(n2.dot(t1) >= 0.0);
    }

    /// Under TIR the paper's clamp leaves the exit tangent to the surface, unit length.
    #[test]
    fn clamped_exit_is_tangent((t1, inward) in incident_and_normal(), n_index in 1.05f32..=2.5) {
        let exit = refract_exit(t1, -inward, n_index, TirPolicy::ClampToCritical);
        prop_assume!(exit.tir);
        prop_assert!((exit.t2.length() - 1.0).abs() < 1e-5);
        prop_assert!(exit.t2.dot(inward).abs() < 1e-5);
    }

    /// With IOR 1 both kernels return the view direction: no bending anywhere.
    #[test]
    fn index_one_does_not_bend(
        x in 0u32..64, y in 0u32..48, depth in 0.5f32..4.0, n1 in unit_vector(),
        back_n in unit_vector(), back_d in 0.0f32..3.0, d_n in 0.0f32..3.0,
    ) {
        let camera = camera();
        let uv = Camera::pixel_center(x, y);
        let p1 = camera.pixel_ray(uv).at(depth);
        let front = FrontSurface { p1_ws: p1, n1_ws: n1, d_n };
        let params = ImageSpaceParams::new(1.0, DistanceMode::Interpolated, TirPolicy::Black)
            .expect("valid");
        let back = ConstantBack(Some(BackFaceSample { n_ws: back_n, distance: depth + back_d }));
        let single = one_interface(&camera, &front, &params).expect("well formed");
        let double = two_interface(&camera, uv, &front, &back, &params).expect("well formed");
        let view = (p1 - camera.eye()).normalize();
        prop_assert!((single.t1 - view).length() < 1e-5);
        prop_assert!((double.t2 - view).length() < 1e-5, "{} vs {}", double.t2, view);
    }

    /// Well-formed inputs always give a path with unit T1, T2 and a finite exit point.
    #[test]
    fn kernel_succeeds_on_well_formed_inputs(
        x in 0u32..64, y in 0u32..48, depth in 0.5f32..4.0, n1 in unit_vector(),
        back_n in unit_vector(), back_d in 0.0f32..3.0, d_n in 0.0f32..3.0, n_index in ior(),
        empty in any::<bool>(), mode in 0usize..3, policy in 0usize..2,
    ) {
        let camera = camera();
        let uv = Camera::pixel_center(x, y);
        let p1 = camera.pixel_ray(uv).at(depth);
        let front = FrontSurface { p1_ws: p1, n1_ws: n1, d_n };
        let modes = [DistanceMode::Interpolated, DistanceMode::ViewOnly, DistanceMode::NormalOnly];
        let policies = [TirPolicy::ClampToCritical, TirPolicy::ReflectOnce];
        let params = ImageSpaceParams::new(n_index, modes[mode], policies[policy]).expect("valid");
        let sample = BackFaceSample { n_ws: back_n, distance: depth + back_d };
        let back = ConstantBack((!empty).then_some(sample));
        let path = two_interface(&camera, uv, &front, &back, &params).expect("well formed");
        prop_assert!((path.entry.t1.length() - 1.0).abs() < 1e-4);
        prop_assert!((path.t2.length() - 1.0).abs() < 1e-4, "{}", path.t2);
        prop_assert!((path.n2.length() - 1.0).abs() < 1e-4);
        prop_assert!(path.p2.is_finite() && path.d_tilde >= 0.0);
    }

    /// Any finite input, including unnormalised, zero and huge vectors, gives either a finite
    /// path or a reported degenerate input, never NaN or infinity.
    #[test]
    fn kernel_never_returns_nan_or_inf(
        p1 in any_finite_vec3(), n1 in any_finite_vec3(), d_n in any_finite(),
        back_n in any_finite_vec3(), back_d in any_finite(), empty in any::<bool>(),
        n_index in prop_oneof![ior(), refract_core::optics::IOR_RANGE], x in any_finite(), y in any_finite(),
        policy in 0usize..3,
    ) {
        let camera = camera();
        let policies = [TirPolicy::ClampToCritical, TirPolicy::ReflectOnce, TirPolicy::Black];
        let params = ImageSpaceParams::new(n_index, DistanceMode::Interpolated, policies[policy])
            .expect("valid");
        let front = FrontSurface { p1_ws: p1, n1_ws: n1, d_n };
        let back = ConstantBack((!empty).then_some(BackFaceSample { n_ws: back_n, distance: back_d }));
        if let Ok(single) = one_interface(&camera, &front, &params) {
            prop_assert!(single.t1.is_finite() && single.view.is_finite() && single.n1.is_finite());
        }
        if let Ok(path) = two_interface(&camera, Vec2::new(x, y), &front, &back, &params) {
            prop_assert!(path.t2.is_finite() && path.p2.is_finite() && path.n2.is_finite());
            prop_assert!(path.d_tilde.is_finite() && path.entry.t1.is_finite());
            let len = path.t2.length();
            prop_assert!((len - 1.0).abs() < 1e-4 || (policy == 2 && len == 0.0), "|T2| = {}", len);
        }
    }

    /// Pixel-centre rays and projection are inverse to each other for any valid camera.
    #[test]
    fn pixel_rays_project_back_to_their_pixel(
        eye in (-50.0f32..50.0, -50.0f32..50.0, -50.0f32..50.0).prop_map(Vec3::from),
        dir in unit_vector(), fov_deg in 10.0f32..120.0, w in 1u32..2048, h in 1u32..2048,
        fx in 0.0f32..1.0, fy in 0.0f32..1.0, t in 0.5f32..20.0, mirror_x in proptest::bool::ANY,
    ) {
        prop_assume!(dir.cross(Vec3::Y).length() > 0.05);
        let camera = Camera::new(CameraDesc {
            eye, target: eye + dir, up: Vec3::Y, fov_y: fov_deg.to_radians(),
            near: 0.1, far: 100.0, width: w, height: h, mirror_x,
        }).expect("valid camera");
        let uv = Vec2::new(fx * w as f32, fy * h as f32);
        let back = camera.world_to_pixel(camera.pixel_ray(uv).at(t)).expect("in front");
        let tolerance = 1e-3 * (w.max(h) as f32).max(1.0) * (1.0 + eye.length() / t);
        prop_assert!((back.truncate() - uv).length() < tolerance, "{} vs {}", back, uv);
    }
}
