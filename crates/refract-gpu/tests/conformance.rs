//! The WGSL twin against refract-core: every core function evaluated by a compute shader on
//! proptest-generated inputs (TIR cases included) and compared with the Rust function, with a
//! relative tolerance of 1e-5 (2e-5 for the chained exit refraction). Needs an adapter
//! (lavapipe in CI); prints `skipped: no GPU adapter` without one unless REFRACT_REQUIRE_GPU=1.

use glam::Vec2;
use glam::{Vec3, Vec4};
use proptest::prelude::*;
use refract_core::environment::{Polynomial, direction_to_latlong};
use refract_core::exit::{TirPolicy, exit_normal_outside_silhouette, refract_exit};
use refract_core::fresnel::{
    fresnel_conductor, fresnel_dielectric, schlick_conductor, schlick_dielectric,
};
use refract_core::gpu::{distance_mode_code, tir_policy_code};
use refract_core::interpolated_distance::{DistanceMode, angle_ratio, approximate_distance};
use refract_core::microfacet::{ggx_d, sample_rough_interface, smith_g1, visible_normal_pdf};
use refract_core::nearby_geometry::{Plane, screen_fraction_to_segment};
use refract_core::optics::{critical_angle, face_forward_shading_normal, reflect, refract};
use refract_core::procedural_sky::procedural_radiance;
use refract_core::spectral::{Wavelengths, cie_1931_xyz, d65, dispersive_ior, sigmoid_spectrum};
use refract_core::vector::{angle_between, robust_normalize};
use refract_gpu::conformance::evaluate;

#[macro_use]
mod common;
use common::{ROWS, close, close3, config, context, unit};

/// Rows away from the TIR boundary, where rounding may legitimately pick the other branch.
fn clear_of_tir_boundary(i: Vec3, n: Vec3, eta: f32) -> bool {
    let n_dot_i = n.dot(i);
    let k = (1.0 - eta * eta) + eta * eta * n_dot_i * n_dot_i;
    k.abs() > 1e-4
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn refract_and_reflect_agree(rows in prop::collection::vec((unit(), unit(), 0.3f32..2.5), ROWS)) {
        let context = gpu_or_skip!();
        let rows: Vec<_> = rows.into_iter().map(|(i, n, eta)| if n.dot(i) > 0.0 { (-i, n, eta) } else { (i, n, eta) })
            .filter(|(i, n, eta)| clear_of_tir_boundary(*i, *n, *eta)).collect();
        let a: Vec<Vec4> = rows.iter().map(|(i, _, eta)| i.extend(*eta)).collect();
        let b: Vec<Vec4> = rows.iter().map(|(_, n, _)| n.extend(0.0)).collect();
        let refracted = evaluate(context, "test_refract", &a, &b).expect("gpu");
        let reflected = evaluate(context, "test_reflect", &a, &b).expect("gpu");
        let mut tir = 0;
        for (k, (i, n, eta)) in rows.iter().enumerate() {
            let rust = refract(*i, *n, *eta);
            tir += usize::from(rust == Vec3::ZERO);
            prop_assert_eq!(refracted[k].w > 0.5, rust == Vec3::ZERO, "TIR branch at row {}", k);
            prop_assert!(close3(refracted[k], rust, 1e-5), "refract {} vs {}", refracted[k], rust);
            prop_assert!(close3(reflected[k], reflect(*i, *n), 1e-5));
        }
        prop_assert!(tir > 0, "TIR cases are part of the sample");
    }

    #[test]
    fn face_forward_and_angles_agree(rows in prop::collection::vec((unit(), unit()), ROWS)) {
        let context = gpu_or_skip!();
        let a: Vec<Vec4> = rows.iter().map(|(n, _)| n.extend(0.0)).collect();
        let b: Vec<Vec4> = rows.iter().map(|(_, i)| i.extend(0.0)).collect();
        let out = evaluate(context, "test_face_forward", &a, &b).expect("gpu");
        for (k, (n, i)) in rows.iter().enumerate() {
            prop_assert!(close3(out[k], face_forward_shading_normal(*n, *i), 1e-5), "{} vs {}", out[k], face_forward_shading_normal(*n, *i));
            prop_assert!(close(out[k].w, angle_between(*n, *i), 1e-5));
        }
    }

    #[test]
    fn fresnel_agrees(rows in prop::collection::vec((0.0f32..=1.0, 0.3f32..2.5, 0.05f32..4.0, 0.0f32..8.0), ROWS)) {
        let context = gpu_or_skip!();
        let a: Vec<Vec4> = rows.iter().map(|&(c, e, n, k)| Vec4::new(c, e, n, k)).collect();
        let out = evaluate(context, "test_fresnel", &a, &a).expect("gpu");
        for (k, &(c, e, n, kk)) in rows.iter().enumerate() {
            let sin2_t = e * e * (1.0 - c * c);
            if (sin2_t - 1.0).abs() < 1e-5 { continue; }
            prop_assert!(close(out[k].x, fresnel_dielectric(c, e), 1e-5), "{} vs {}", out[k].x, fresnel_dielectric(c, e));
            prop_assert!(close(out[k].y, schlick_dielectric(c, e), 1e-5));
            prop_assert!(close(out[k].z, schlick_conductor(c, n, kk), 1e-5));
            prop_assert!(close(out[k].w, critical_angle(e), 1e-5));
        }
    }

    #[test]
    // Metals: n ≥ 0.1 and k ≥ 0.5 (silver's n is 0.135, every metal's k > 1 in the visible),
    // and the ideal mirror n = 0, k = 1 at every angle. Toward n, k → 0 the formula itself is
    // ill-conditioned in f32 (a = √(½(a²+b² + t0)) cancels, 4n²k² vanishes beside t0²): both
    // twins are noise there, by up to 1e-3.
    fn exact_conductor_fresnel_agrees(rows in prop::collection::vec((0.0f32..=1.0, 0.1f32..3.0, 0.5f32..8.0), ROWS)) {
        let context = gpu_or_skip!();
        let mut rows = rows;
        rows.extend((0..=10).map(|i| (i as f32 / 10.0, 0.0, 1.0)));
        let a: Vec<Vec4> = rows.iter().map(|&(c, n, k)| Vec4::new(c, n, k, 0.0)).collect();
        let out = evaluate(context, "test_fresnel_conductor", &a, &a).expect("gpu");
        for (row, &(c, n, k)) in rows.iter().enumerate() {
            let rust = fresnel_conductor(c, n, k);
            prop_assert!(close(out[row].x, rust, 1e-5), "F({c}, {n}, {k}): {} vs {rust}", out[row].x);
        }
    }

    #[test]
    fn distances_agree(rows in prop::collection::vec((0.0f32..1.5, 0.0f32..1.5, 0.3f32..1.0, 0.0f32..4.0, 0.0f32..4.0, 0u32..3), ROWS)) {
        let context = gpu_or_skip!();
        let modes = [DistanceMode::Interpolated, DistanceMode::ViewOnly, DistanceMode::NormalOnly];
        let a: Vec<Vec4> = rows.iter().map(|&(ti, tt, eta, dv, _, _)| Vec4::new(ti, tt, eta, dv)).collect();
        let b: Vec<Vec4> = rows.iter().map(|&(_, _, _, _, dn, m)| Vec4::new(dn, distance_mode_code(modes[m as usize]) as f32, 0.0, 0.0)).collect();
        let out = evaluate(context, "test_distance", &a, &b).expect("gpu");
        for (k, &(ti, tt, eta, dv, dn, m)) in rows.iter().enumerate() {
            prop_assert!(close(out[k].x, angle_ratio(ti, tt, eta), 1e-5));
            prop_assert!(close(out[k].y, approximate_distance(modes[m as usize], ti, tt, eta, dv, dn), 1e-5));
        }
    }

    #[test]
    fn exit_refraction_agrees(rows in prop::collection::vec((unit(), unit(), 1.0f32..2.5, 0u32..3), ROWS)) {
        let context = gpu_or_skip!();
        let policies = [TirPolicy::ClampToCritical, TirPolicy::ReflectOnce, TirPolicy::Black];
        let rows: Vec<_> = rows.into_iter()
            .filter(|(t1, n2, ior, _)| clear_of_tir_boundary(*t1, -*n2, *ior) && n2.dot(*t1).abs() > 1e-3)
            .collect();
        let a: Vec<Vec4> = rows.iter().map(|(t1, _, ior, _)| t1.extend(*ior)).collect();
        let b: Vec<Vec4> = rows.iter().map(|(_, n2, _, p)| n2.extend(tir_policy_code(policies[*p as usize]) as f32)).collect();
        let out = evaluate(context, "test_exit", &a, &b).expect("gpu");
        let normals = evaluate(context, "test_exit_normal", &a, &b).expect("gpu");
        for (k, (t1, n2, ior, p)) in rows.iter().enumerate() {
            let rust = refract_exit(*t1, *n2, *ior, policies[*p as usize]);
            prop_assert_eq!(out[k].w > 0.5, rust.tir, "TIR at row {}", k);
            prop_assert!(close3(out[k], rust.t2, 2e-5), "{} vs {}", out[k], rust.t2);
            let fallback = exit_normal_outside_silhouette(*t1, *n2);
            if t1.cross(*n2).length() > 1e-2 {
                prop_assert!(close3(normals[k], fallback, 1e-5));
            }
        }
    }

    #[test]
    fn normalisation_latlong_and_sky_agree(rows in prop::collection::vec((unit(), 1e-3f32..1e3), ROWS)) {
        let context = gpu_or_skip!();
        let a: Vec<Vec4> = rows.iter().map(|(d, s)| (*d * *s).extend(0.0)).collect();
        let normalized = evaluate(context, "test_normalize", &a, &a).expect("gpu");
        let dirs: Vec<Vec4> = rows.iter().map(|(d, _)| d.extend(0.0)).collect();
        let latlong = evaluate(context, "test_latlong", &dirs, &dirs).expect("gpu");
        let sky = evaluate(context, "test_procedural_sky", &dirs, &dirs).expect("gpu");
        let mut sky_mismatch = 0;
        for (k, (d, s)) in rows.iter().enumerate() {
            let rust = robust_normalize(*d * *s).expect("nonzero");
            prop_assert!(close3(normalized[k], rust, 1e-5) && normalized[k].w == 1.0);
            let uv = direction_to_latlong::<Polynomial>(*d);
            // u wraps at the seam: compare on the circle.
            let du = (latlong[k].x - uv.x).abs();
            prop_assert!(du.min(1.0 - du) <= 1e-5 && close(latlong[k].y, uv.y, 1e-5), "{} vs {}", latlong[k], uv);
            sky_mismatch += usize::from(!close3(sky[k], procedural_radiance::<Polynomial>(*d), 1e-5));
        }
        // The sky has hard edges (checker squares, stripes, sun): a direction within rounding of
        // an edge may land on the other side. Allow one such row per batch.
        prop_assert!(sky_mismatch <= 1, "{} sky mismatches", sky_mismatch);
    }

    /// The spectral tables and functions (spectral/mod.rs): CIE 1931 and D65 by wavelength
    /// (inside and outside 360–830 nm), the hero wavelength and its weight before and after
    /// termination, sigmoid spectra (finite and infinite `c₂`) and the dispersive index.
    #[test]
    fn spectral_functions_agree(rows in prop::collection::vec((300f32..900.0, 0f32..1.0, 1.0f32..2.5, 1.0f32..100.0, (-1e-4f32..1e-4, -0.1f32..0.1, -30.0f32..30.0), any::<bool>()), ROWS)) {
        let context = gpu_or_skip!();
        let a: Vec<Vec4> = rows.iter().map(|(l, u, ior, abbe, _, _)| Vec4::new(*u, *l, *ior, *abbe)).collect();
        let b: Vec<Vec4> = rows.iter().enumerate().map(|(k, (_, _, _, _, c, terminate))| {
            // Every eighth row's c₂ is infinite (the constant 0 or 1).
            let c2 = if k % 8 == 0 { f32::INFINITY.copysign(c.2) } else { c.2 };
            Vec4::new(c.0, c.1, c2, if *terminate { 1.0 } else { 0.0 })
        }).collect();
        let tables = evaluate(context, "test_spectral_tables", &a.iter().map(|r| Vec4::splat(r.y)).collect::<Vec<_>>(), &a).expect("gpu");
        let sampled = evaluate(context, "test_spectral_sample", &a, &b).expect("gpu");
        for (k, (lambda, u, ior, abbe, _, terminate)) in rows.iter().enumerate() {
            let xyz = cie_1931_xyz(*lambda);
            prop_assert!(close3(tables[k], xyz, 1e-5) && close(tables[k].w, d65(*lambda), 1e-5), "{} nm: {} vs {} {}", lambda, tables[k], xyz, d65(*lambda));
            let mut w = Wavelengths::sample(*u);
            if *terminate {
                w.terminate_secondary();
            }
            // λ spans 360-830 nm and the weight grows steeply at the ends: relative terms.
            prop_assert!((sampled[k].x - w.lambda[0]).abs() <= 1e-4 * w.lambda[0], "λ {} vs {}", sampled[k].x, w.lambda[0]);
            prop_assert!((sampled[k].y - w.weight[0]).abs() <= 1e-4 * w.weight[0], "weight {} vs {}", sampled[k].y, w.weight[0]);
            let c = [b[k].x, b[k].y, b[k].z];
            prop_assert!(close(sampled[k].z, sigmoid_spectrum(c, *lambda), 1e-5), "S {} vs {}", sampled[k].z, sigmoid_spectrum(c, *lambda));
            prop_assert!(close(sampled[k].w, dispersive_ior(*ior, *abbe, *lambda), 1e-5));
        }
    }

    /// GGX's distribution, Smith's masking and the visible normals' density (microfacet.rs).
    #[test]
    fn ggx_terms_agree(rows in prop::collection::vec((unit(), unit(), 0.01f32..=1.0), ROWS)) {
        let context = gpu_or_skip!();
        let a: Vec<Vec4> = rows.iter().map(|(v, _, alpha)| v.extend(*alpha)).collect();
        let b: Vec<Vec4> = rows.iter().map(|(_, m, _)| m.extend(0.0)).collect();
        let out = evaluate(context, "test_ggx", &a, &b).expect("gpu");
        for (k, (v, m, alpha)) in rows.iter().enumerate() {
            let d = ggx_d(*m, *alpha);
            // D spans decades (1/(πα²) at the pole): relative to its own size.
            prop_assert!((out[k].x - d).abs() <= 1e-5 * d.max(1.0), "D {} vs {}", out[k].x, d);
            prop_assert!(close(out[k].y, smith_g1(*v, *m, *alpha), 1e-5));
            let pdf = visible_normal_pdf(*v, *m, *alpha);
            prop_assert!((out[k].z - pdf).abs() <= 1e-5 * pdf.max(1.0), "pdf {} vs {}", out[k].z, pdf);
        }
    }

    /// One sample of a rough interface (microfacet.rs's sample_rough_interface): the normal,
    /// Fresnel, both directions and their masking, at the sample point both sides derive from
    /// the row index.
    #[test]
    fn rough_interface_samples_agree(rows in prop::collection::vec((unit(), unit(), 0.4f32..2.5, 0.02f32..=1.0), ROWS)) {
        let context = gpu_or_skip!();
        // The ray goes toward the side the facing normal is on.
        let rows: Vec<_> = rows.into_iter().map(|(d, n, eta, alpha)| if d.dot(n) > 0.0 { (-d, n, eta, alpha) } else { (d, n, eta, alpha) }).collect();
        let a: Vec<Vec4> = rows.iter().map(|(d, _, eta, _)| d.extend(*eta)).collect();
        let b: Vec<Vec4> = rows.iter().map(|(_, n, _, alpha)| n.extend(*alpha)).collect();
        let normal = evaluate(context, "test_rough_normal", &a, &b).expect("gpu");
        let reflected = evaluate(context, "test_rough_reflected", &a, &b).expect("gpu");
        let refracted = evaluate(context, "test_rough_refracted", &a, &b).expect("gpu");
        let mut compared = 0;
        for (k, (d, n, eta, alpha)) in rows.iter().enumerate() {
            let u = ((k as f32 + 0.5) * Vec2::new(0.754_877_7, 0.569_840_3)).fract();
            let s = sample_rough_interface(*d, *n, *eta, *alpha, u);
            // Rows near grazing or near TIR about m may take the other branch by rounding.
            let k_tir = 1.0 - eta * eta * (1.0 - d.dot(s.m).powi(2));
            if d.dot(*n).abs() < 1e-3 || k_tir.abs() < 1e-3 {
                continue;
            }
            compared += 1;
            prop_assert!(close3(normal[k], s.m, 2e-4), "m {} vs {}", normal[k], s.m);
            prop_assert!(close(normal[k].w, s.fresnel, 2e-4), "F {} vs {}", normal[k].w, s.fresnel);
            prop_assert!(close3(reflected[k], s.reflected, 5e-4) && close(reflected[k].w, s.reflected_masking, 5e-4),
                "reflected {} vs {} {}", reflected[k], s.reflected, s.reflected_masking);
            prop_assert!(close3(refracted[k], s.refracted, 5e-4) && close(refracted[k].w, s.refracted_masking, 5e-4),
                "refracted {} vs {} {}", refracted[k], s.refracted, s.refracted_masking);
        }
        prop_assert!(compared > ROWS / 2);
    }

    /// Wyman 2005b §4.2–4.3 helpers: ray-plane hits and the screen-spaced seed fraction.
    #[test]
    fn plane_hits_and_seed_fractions_agree(
        rows in prop::collection::vec((unit(), -3.0f32..3.0, unit(), 0.0f32..=1.0, 0.05f32..50.0, 0.05f32..50.0), ROWS)
    ) {
        let context = gpu_or_skip!();
        let a: Vec<Vec4> = rows.iter().map(|(n, d, ..)| n.extend(*d)).collect();
        let b: Vec<Vec4> = rows.iter().map(|(_, _, dir, ..)| dir.extend(0.0)).collect();
        let hits = evaluate(context, "test_plane", &a, &b).expect("gpu");
        let fractions: Vec<Vec4> = rows.iter().map(|(.., s, w0, w1)| Vec4::new(*s, *w0, *w1, 0.0)).collect();
        let lambdas = evaluate(context, "test_seed_fraction", &fractions, &fractions).expect("gpu");
        for (k, (n, d, dir, s, w0, w1)) in rows.iter().enumerate() {
            let rust = Plane { normal: *n, offset: *d }.intersect(Vec3::ZERO, *dir);
            // Grazing rays (|n·dir| tiny) have huge t where rounding decides; skip them.
            if n.dot(*dir).abs() > 1e-3 {
                prop_assert_eq!(hits[k].y > 0.5, rust.is_some(), "row {}", k);
                if let Some(t) = rust {
                    prop_assert!(close(hits[k].x, t, 1e-5), "{} vs {}", hits[k].x, t);
                }
            }
            let lambda = screen_fraction_to_segment(*s, *w0, *w1);
            prop_assert!(close(lambdas[k].x, lambda, 1e-5), "{} vs {}", lambdas[k].x, lambda);
        }
    }

    /// Umenhoffer et al. 2007 on analytic layers (`AnalyticRoom`): cube texels exactly; hits
    /// (distance, layer, step counts) and mirror paths (radiance, bounces). A sample that lands
    /// within rounding of a texel edge or of `|r|/|r'| = 1` may decide differently: at most two
    /// such rows of 256 per batch.
    #[test]
    fn distance_map_search_and_paths_agree(
        rows in prop::collection::vec((unit(), 0.0f32..0.95, unit(), any::<bool>(), 1u32..4), ROWS)
    ) {
        use refract_core::distance_map::{
            AnalyticRoom, PathParams, PathStart, SearchParams, TexelMaterial, cube_texel,
            cube_texel_index, hit, trace_path,
        };
        let context = gpu_or_skip!();
        let room = AnalyticRoom { size: 64 };
        let texels_in: Vec<Vec4> = rows.iter().map(|(d, ..)| d.extend(64.0)).collect();
        let texels = evaluate(context, "test_dm_texel", &texels_in, &texels_in).expect("gpu");
        for (k, (d, ..)) in rows.iter().enumerate() {
            let (face, t) = cube_texel(*d, 64).expect("direction");
            let gpu = texels[k];
            prop_assert_eq!(
                (gpu.x as u32, gpu.y as u32, gpu.z as u32, gpu.w),
                (face as u32, t.x, t.y, 1.0)
            );
        }
        let _ = cube_texel_index;
        // Rays from inside the sphere (start layer none) and from its surface (layer 0).
        let a: Vec<Vec4> = rows
            .iter()
            .map(|(d, s, _, on_surface, _)| {
                if *on_surface { d.extend(0.0) } else { (*d * *s).extend(-1.0) }
            })
            .collect();
        let b: Vec<Vec4> = rows
            .iter()
            .enumerate()
            .map(|(k, (_, _, r, _, _))| r.extend((k % 2) as f32))
            .collect();
        let hits = evaluate(context, "test_dm_hit", &a, &b).expect("gpu");
        let mut mismatches = 0;
        for k in 0..ROWS {
            let search = SearchParams { min_max: k % 2 == 1, ..SearchParams::default() };
            let start = (a[k].w >= 0.0).then_some(0);
            let (h, work) = hit(&room, a[k].truncate(), b[k].truncate(), start, &search);
            let gpu = hits[k];
            let same = match h {
                None => gpu.x < 0.0,
                Some(h) => close(gpu.x, h.d, 1e-4) && gpu.y as u32 == h.layer,
            } && gpu.z as u32 == work.linear_steps && gpu.w as u32 == work.secant_steps;
            mismatches += usize::from(!same);
        }
        prop_assert!(mismatches <= 2, "{} hit mismatches", mismatches);
        // Mirror paths from the sphere toward the inside of the room (V with V·N < 0).
        let a: Vec<Vec4> = rows.iter().map(|(d, .., depth)| d.extend(*depth as f32)).collect();
        let b: Vec<Vec4> = rows
            .iter()
            .map(|(d, _, r, ..)| {
                let v = if r.dot(*d) < 0.0 { *r } else { -*r };
                v.extend(0.0)
            })
            .collect();
        let paths = evaluate(context, "test_dm_path", &a, &b).expect("gpu");
        let mut mismatches = 0;
        for k in 0..ROWS {
            let x = a[k].truncate();
            let start = PathStart {
                x,
                v: b[k].truncate(),
                n: x.normalize(),
                material: TexelMaterial { rgb: Vec3::splat(0.9), ior: -1.0 },
                layer: Some(0),
            };
            let params = PathParams { max_depth: a[k].w as u32, ..PathParams::default() };
            let rust = trace_path(&room, &start, &params);
            let gpu = paths[k];
            let same = close3(gpu, rust.radiance, 1e-4) && gpu.w as u32 == rust.bounces;
            mismatches += usize::from(!same);
        }
        prop_assert!(mismatches <= 2, "{} path mismatches", mismatches);
    }
}

/// A distance-mode code the WGSL twin does not know gives NaN, never another mode's distance
/// (the image-space kernel then paints the pixel magenta: `UNKNOWN_CODE_COLOR`).
#[test]
fn unknown_distance_modes_are_not_another_mode() {
    let Some(context) = context() else {
        return;
    };
    let known: Vec<f32> = [
        DistanceMode::Interpolated,
        DistanceMode::ViewOnly,
        DistanceMode::NormalOnly,
    ]
    .iter()
    .map(|&m| distance_mode_code(m) as f32)
    .collect();
    let unknown = (0..16).map(|c| c as f32).find(|c| !known.contains(c));
    let unknown = unknown.expect("a code outside the three");
    let a = vec![Vec4::new(0.4, 0.3, 0.7, 2.0); 4];
    let b = vec![Vec4::new(1.0, unknown, 0.0, 0.0); 4];
    let out = evaluate(context, "test_distance", &a, &b).expect("gpu");
    assert!(out.iter().all(|v| v.y.is_nan()), "{out:?}");
}

/// The far side of a unit sphere at the origin through each texel's centre, as
/// `src/conformance_kernels.wgsl`'s `back_face` computes it: the analytic back-face buffer
/// of the whole-kernel tests.
struct SphereBackFaces(refract_core::Camera);

impl refract_core::kernel::BackFaceSampler for SphereBackFaces {
    fn back_face(&self, uv_px: Vec2) -> Option<refract_core::kernel::BackFaceSample> {
        let (w, h) = (self.0.width() as f32, self.0.height() as f32);
        if !(uv_px.x >= 0.0 && uv_px.y >= 0.0 && uv_px.x < w && uv_px.y < h) {
            return None;
        }
        let ray = self.0.pixel_ray(uv_px.floor() + Vec2::splat(0.5));
        let b = ray.origin.dot(ray.dir);
        let disc = b * b - (ray.origin.length_squared() - 1.0);
        (disc >= 0.0).then(|| {
            let t = -b + disc.sqrt();
            refract_core::kernel::BackFaceSample {
                n_ws: ray.at(t),
                distance: t,
            }
        })
    }
}

/// Front pixels of the unit sphere seen by a 64 × 48 camera: the pixel, `P1` on the sphere
/// through its centre, `N1` the sphere's normal turned, scaled or flipped (back-facing normals,
/// unnormalised ones), `d_N`.
fn kernel_rows() -> impl Strategy<Value = Vec<(u32, u32, Vec3, f32, f32)>> {
    prop::collection::vec(
        (
            0u32..64,
            0u32..48,
            unit(),
            0.0f32..0.6,
            0.5f32..2.0,
            0.0f32..2.5,
        ),
        ROWS,
    )
    .prop_map(|rows| {
        rows.into_iter()
            .map(|(x, y, turn, amount, scale, d_n)| (x, y, turn * amount, scale, d_n))
            .collect()
    })
}

proptest! {
    #![proptest_config(config())]

    /// The whole two-interface kernel (`two_interface.wgsl`: entry refraction, `d_V` at the
    /// pixel, `d~`, `P~2`, the back-face lookup at `P~2` or the silhouette fallback, the exit
    /// refraction with the TIR policy) against `refract_core::kernel::two_interface` over the
    /// same analytic back faces, for every distance mode and TIR policy and indices on both
    /// sides of 1. A few rows may legitimately differ: `P~2` projected within rounding of a
    /// texel edge reads the neighbouring texel (a normal one pixel away), and TIR decided within
    /// rounding of the critical angle; at most 3 % of the rows may.
    #[test]
    fn two_interface_kernel_agrees(
        rows in kernel_rows(),
        ior in prop::sample::select(vec![1.5f32, 1.33, 2.4, 0.8]),
        mode in prop::sample::select(vec![DistanceMode::Interpolated, DistanceMode::ViewOnly, DistanceMode::NormalOnly]),
        policy in prop::sample::select(vec![TirPolicy::ClampToCritical, TirPolicy::ReflectOnce, TirPolicy::Black]),
    ) {
        use refract_core::kernel::{FrontSurface, ImageSpaceParams, one_interface, two_interface};
        use refract_core::{Camera, CameraDesc, ExitNormalSource};
        let context = gpu_or_skip!();
        let camera = Camera::new(CameraDesc { width: 64, height: 48, ..CameraDesc::default() })
            .expect("camera");
        let back = SphereBackFaces(camera);
        let params = ImageSpaceParams::new(ior, mode, policy).expect("params");
        // Pixels whose centre ray hits the sphere, with P1 on it.
        let mut pixels = Vec::new();
        for (x, y, turn, scale, d_n) in rows {
            let uv = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let ray = camera.pixel_ray(uv);
            let b = ray.origin.dot(ray.dir);
            let disc = b * b - (ray.origin.length_squared() - 1.0);
            if disc < 0.0 {
                continue;
            }
            let p1 = ray.at(-b - disc.sqrt());
            let n1 = (p1 + turn) * scale;
            pixels.push((x, y, uv, FrontSurface { p1_ws: p1, n1_ws: n1, d_n }));
        }
        prop_assume!(pixels.len() > 40);
        let a: Vec<Vec4> = pixels.iter().map(|(.., f)| f.p1_ws.extend(f.d_n)).collect();
        let b: Vec<Vec4> = pixels
            .iter()
            .map(|(x, y, _, f)| f.n1_ws.extend((x + 4096 * y) as f32))
            .collect();
        let frame = refract_gpu::conformance::KernelFrame { camera: &camera, ior, tir: policy, distance_mode: mode };
        let eval = |entry| {
            refract_gpu::conformance::evaluate_kernel(context, entry, &frame, &a, &b).expect("gpu")
        };
        let (entry, t2, p2, n2) = (
            eval("test_one_interface"),
            eval("test_two_interface_t2"),
            eval("test_two_interface_p2"),
            eval("test_two_interface_n2"),
        );
        let mut mismatches = Vec::new();
        let mut kinds = [0usize; 3];
        for (k, (_, _, uv, front)) in pixels.iter().enumerate() {
            let single = one_interface(&camera, front, &params);
            let entry_ok = match single {
                Ok(path) => {
                    entry[k].w as u32 & 1 == 1
                        && close3(entry[k], path.t1, 2e-5)
                        && (entry[k].w as u32 & 2 == 2) == path.tir_entry
                }
                Err(_) => entry[k].w as u32 & 1 == 0,
            };
            let flags = t2[k].w as u32;
            let two_ok = match two_interface(&camera, *uv, front, &back, &params) {
                Ok(path) => {
                    kinds[usize::from(path.tir_exit || path.entry.tir_entry)] += 1;
                    kinds[2] += usize::from(path.n2_source == ExitNormalSource::BackFace);
                    flags & 1 == 1
                        && (flags & 2 == 2) == (path.tir_exit || path.entry.tir_entry)
                        && (flags & 4 == 4) == (path.n2_source == ExitNormalSource::BackFace)
                        && close3(t2[k], path.t2, 1e-4)
                        && close3(p2[k], path.p2, 1e-4)
                        && close3(n2[k], path.n2, 1e-4)
                }
                Err(_) => flags & 1 == 0,
            };
            if !(entry_ok && two_ok) {
                mismatches.push(k);
            }
        }
        prop_assert!(
            mismatches.len() * 100 <= 3 * pixels.len(),
            "{} of {} rows differ (first: {:?}, GPU t2 {:?} p2 {:?})",
            mismatches.len(),
            pixels.len(),
            mismatches.first().map(|k| pixels[*k].3),
            mismatches.first().map(|k| t2[*k]),
            mismatches.first().map(|k| p2[*k]),
        );
        // The rows exercise exits through the back faces and (at indices above 1) past the
        // silhouette: both exit-normal sources.
        prop_assert!(kinds[0] > 0 && kinds[2] > 0, "{kinds:?}");
    }
}
