//! The BVH against brute force, and d_N against closed forms.

use glam::Vec3;
use proptest::prelude::*;
use refract_core::Ray;
use refract_geometry::{MeshBvh, normal_distances, shapes};

/// Every hit of `ray` by testing each triangle (Möller–Trumbore, double-sided), sorted.
fn brute_force_hits(mesh: &refract_geometry::Mesh, ray: &Ray) -> Vec<(f32, u32)> {
    let mut hits = Vec::new();
    for i in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle_positions(i);
        let (e1, e2) = (b - a, c - a);
        let p = ray.dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            continue;
        }
        let s = ray.origin - a;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = ray.dir.dot(q) / det;
        let t = e2.dot(q) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 {
            hits.push((t, i as u32));
        }
    }
    hits.sort_by(|x, y| x.0.total_cmp(&y.0));
    hits
}

fn unit_vector() -> impl Strategy<Value = Vec3> {
    (-1.0f32..=1.0, 0.0f32..std::f32::consts::TAU).prop_map(|(z, phi)| {
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Closest hit, hit count and furthest hit agree with brute force on a concave mesh.
    /// Rays that pass within 1e-4 (barycentric) of an edge are skipped: there the double-sided
    /// tests may legitimately disagree about which of two triangles was hit.
    #[test]
    fn bvh_matches_brute_force(origin in unit_vector(), target in unit_vector(), scale in 0.1f32..2.5) {
        let mesh = shapes::torus(0.7, 0.3, 24, 12).expect("torus");
        let bvh = MeshBvh::build(&mesh);
        let origin = origin * scale * 1.5;
        let dir = (target * 0.5 - origin).normalize();
        let ray = Ray { origin, dir };
        let expected = brute_force_hits(&mesh, &ray);
        let mut all = Vec::new();
        bvh.all_hits(&ray, 0.0, f32::INFINITY, &mut all);
        let near_edge = all.iter().any(|h| {
            let b = h.barycentrics;
            b.x.min(b.y).min(1.0 - b.x - b.y) < 1e-4
        });
        prop_assume!(!near_edge);
        prop_assert_eq!(all.len(), expected.len(), "{:?} vs {:?}", all, expected);
        for (hit, (t, tri)) in all.iter().zip(&expected) {
            prop_assert!((hit.t - t).abs() < 1e-4 * (1.0 + t), "{} vs {}", hit.t, t);
            prop_assert_eq!(hit.triangle, *tri);
        }
        let closest = bvh.closest_hit(&ray, 0.0, f32::INFINITY);
        prop_assert_eq!(closest.map(|h| h.triangle), expected.first().map(|e| e.1));
        prop_assert_eq!(bvh.occluded(&ray, 0.0, f32::INFINITY), !expected.is_empty());
        if let (Some(last), Some(furthest)) = (all.last(), expected.last()) {
            prop_assert_eq!(last.triangle, furthest.1);
        }
        for hit in &all {
            // The hit point rebuilt from barycentrics lies on the ray.
            let [a, b, c] = mesh.triangle_positions(hit.triangle as usize);
            let p = (1.0 - hit.barycentrics.x - hit.barycentrics.y) * a
                + hit.barycentrics.x * b + hit.barycentrics.y * c;
            prop_assert!(p.distance(ray.at(hit.t)) < 1e-4);
            prop_assert!((hit.shading_normal.length() - 1.0).abs() < 1e-4);
        }
    }
}

/// A tessellated sphere of radius r: d_N ≈ 2r. Vertices lie on the sphere and triangles are
/// chords, so the antipodal surface is at most r (1 − cos α) inside the sphere, α the largest
/// angle a triangle edge subtends at the centre: 2r − r(1 − cos α) ≤ d_N ≤ 2r.
#[test]
fn sphere_normal_distance_is_its_diameter() {
    let radius = 0.8;
    let mesh = shapes::icosphere(4, radius).expect("icosphere");
    let alpha = (0..mesh.triangles.len())
        .flat_map(|i| {
            let [a, b, c] = mesh.triangle_positions(i);
            [a.angle_between(b), b.angle_between(c), c.angle_between(a)]
        })
        .fold(0.0f32, f32::max);
    let gap = radius * (1.0 - alpha.cos());
    let bvh = MeshBvh::build(&mesh);
    let d_n = normal_distances(&mesh, &bvh);
    assert_eq!(d_n.misses, 0);
    for &d in &d_n.values {
        assert!(
            d <= 2.0 * radius + 1e-5 && d >= 2.0 * radius - gap - 1e-5,
            "{d}, gap {gap}"
        );
    }
}

/// A box: from a vertex inside a face, d_N is the box's width along that face's axis.
#[test]
fn box_normal_distance_is_its_width() {
    let half = Vec3::new(0.3, 0.5, 0.7);
    let mesh = shapes::cuboid(half, 4).expect("box");
    let bvh = MeshBvh::build(&mesh);
    let d_n = normal_distances(&mesh, &bvh);
    let mut checked = 0;
    for (i, p) in mesh.positions.iter().enumerate() {
        let axis = mesh.normals[i].abs().max_position();
        let inside_face = (0..3)
            .filter(|&k| k != axis)
            .all(|k| p[k].abs() < half[k] - 1e-4);
        if inside_face {
            assert!(
                (d_n.values[i] - 2.0 * half[axis]).abs() < 1e-5,
                "vertex {i}: {}",
                d_n.values[i]
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 6 * 9, "3 x 3 interior vertices per face");
}

/// An open shape gets the documented fallback and reports its misses.
#[test]
fn open_plane_misses_use_the_fallback() {
    let mesh = shapes::plane(1.0, 2).expect("plane");
    let bvh = MeshBvh::build(&mesh);
    let d_n = normal_distances(&mesh, &bvh);
    assert_eq!(d_n.misses, mesh.positions.len());
    assert!((d_n.fallback - 2.0 * mesh.bounding_sphere().radius).abs() < 1e-6);
    assert!((d_n.miss_rate() - 1.0).abs() < 1e-6);
}

/// d_N does not depend on how many threads compute it.
#[test]
fn normal_distances_are_deterministic_across_thread_counts() {
    let mesh = shapes::torus(0.7, 0.3, 48, 24).expect("torus");
    let bvh = MeshBvh::build(&mesh);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let single = one.install(|| normal_distances(&mesh, &bvh));
    let parallel = normal_distances(&mesh, &bvh);
    assert_eq!(single, parallel);
    // Torus: from the outer equator, −N crosses the tube: d_N = 2 · minor radius.
    assert!(single.values.iter().any(|d| (d - 0.6).abs() < 1e-3));
}

/// A fan of near-coincident triangles (one corner region within 1e-5, random orientations),
/// which made every `-N` ray test all of them and d_N quadratic (issue 34, item 3: 64k of them
/// took 34 s): each ray stops at the budget and the vertex gets the fallback, counted; a real
/// mesh never reaches the budget. The budgeted query agrees with the plain one within it.
#[test]
fn fans_of_near_coincident_triangles_stay_within_the_ray_budget() {
    use refract_geometry::distance_along_normal::RAY_BUDGET;
    use refract_geometry::{BudgetedHit, Mesh};
    let n = 2 * RAY_BUDGET as usize;
    let mut state = 12345u32;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state as f32 / u32::MAX as f32
    };
    let mut positions = Vec::new();
    for _ in 0..n {
        let o = glam::Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 2e-5;
        let (a, b) = (
            next() * std::f32::consts::TAU,
            next() * std::f32::consts::PI,
        );
        let d = glam::Vec3::new(a.cos() * b.sin(), b.cos(), a.sin() * b.sin());
        positions.extend([o, o + glam::Vec3::X, o + d]);
    }
    let triangles = (0..n as u32)
        .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
        .collect();
    let mesh = Mesh::new("fan", positions, None, Vec::new(), triangles).expect("mesh");
    let bvh = MeshBvh::build(&mesh);
    let d_n = normal_distances(&mesh, &bvh);
    assert!(d_n.over_budget > 0, "{d_n:?}");
    assert_eq!(d_n.values.len(), mesh.positions.len());
    assert!(d_n.values.iter().all(|v| v.is_finite()));

    let sphere = shapes::uv_sphere(32, 16, 1.0).expect("sphere");
    let sphere_bvh = MeshBvh::build(&sphere);
    let sphere_d_n = normal_distances(&sphere, &sphere_bvh);
    assert_eq!(sphere_d_n.over_budget, 0);
    for (p, n) in sphere.positions.iter().zip(&sphere.normals) {
        let ray = refract_core::Ray {
            origin: *p,
            dir: -*n,
        };
        let plain = sphere_bvh.closest_hit(&ray, 1e-4, f32::INFINITY);
        let budgeted = sphere_bvh.closest_hit_within(&ray, 1e-4, f32::INFINITY, RAY_BUDGET);
        assert_eq!(
            plain.map(BudgetedHit::Hit).unwrap_or(BudgetedHit::Miss),
            budgeted
        );
    }
}
