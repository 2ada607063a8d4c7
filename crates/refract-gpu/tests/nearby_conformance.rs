//! The nearby-geometry family's lookups (`src/methods/nearby_lookup.wgsl`: Kay-Greenberg,
//! ray-plane, iterative, seeded) against `refract_core::nearby_geometry::find_nearby`, whole,
//! through the family's own conformance module (`src/methods/nearby_conformance.wgsl`) over an
//! analytic NG texture.

use glam::{UVec2, Vec3, Vec4};
use proptest::prelude::*;
use refract_core::gpu::lookup_code;
use refract_core::nearby_geometry::{
    NearbyGeometryTexture, NearbyLookup, NearbySurface, Plane, SeedSpacing, find_nearby, view_depth,
};
use refract_core::{Camera, CameraDesc};
use refract_gpu::conformance::{FamilyEvaluation, evaluate_family, nearby_uniforms};

#[macro_use]
mod common;
use common::{ROWS, close3, config, context, unit};

/// `nearby_conformance.wgsl`'s analytic NG texture seen by `camera`: empty on every seventh
/// column, else `P = (0.05 (x − 32), −0.05 (y − 24), −1 − 0.125 ((x + y) mod 4))`.
struct AnalyticTexture(Camera);

impl NearbyGeometryTexture for AnalyticTexture {
    fn surface(&self, texel: UVec2) -> Option<NearbySurface> {
        let (x, y) = (texel.x as i32, texel.y as i32);
        if x % 7 == 0 {
            return None;
        }
        let p_ws = Vec3::new(
            0.05 * (x - 32) as f32,
            -0.05 * (y - 24) as f32,
            -1.0 - 0.125 * ((x + y) % 4) as f32,
        );
        Some(NearbySurface {
            p_ws,
            depth: view_depth(&self.0, p_ws),
        })
    }
}

/// Every lookup of the family with the settings its registry rows use, and a few more.
fn lookups() -> Vec<NearbyLookup> {
    vec![
        NearbyLookup::KayGreenberg,
        NearbyLookup::RayPlane,
        NearbyLookup::Iterative { iterations: 1 },
        NearbyLookup::Iterative { iterations: 5 },
        NearbyLookup::Seeded {
            iterations: 5,
            seeds: 4,
            spacing: SeedSpacing::Screen,
        },
        NearbyLookup::Seeded {
            iterations: 2,
            seeds: 7,
            spacing: SeedSpacing::World,
        },
    ]
}

proptest! {
    #![proptest_config(config())]

    /// The whole lookup against the core's for every lookup, from points `P~2` in front of the
    /// texture with directions `T~2` into the half space behind: the texel found, hit,
    /// convergence and iterations the same, `P_geom` within 1e-5. A texel is the floor of a
    /// projected point, so a point within rounding of a texel edge may land in the neighbour
    /// (and an iteration then go another way): at most 3 % of the rows may differ.
    #[test]
    fn find_nearby_agrees(
        rows in prop::collection::vec(((-0.8f32..0.8, -0.6f32..0.6, -0.5f32..0.8), unit()), ROWS),
        plane_z in -1.4f32..-0.9,
    ) {
        let context = gpu_or_skip!();
        let camera = Camera::new(CameraDesc { width: 64, height: 48, ..CameraDesc::default() })
            .expect("camera");
        let texture = AnalyticTexture(camera);
        let planes = [Plane::through(Vec3::new(0.0, 0.0, plane_z), Vec3::Z)];
        let rows: Vec<(Vec3, Vec3)> = rows
            .into_iter()
            .map(|((x, y, z), d)| (Vec3::new(x, y, z), Vec3::new(0.4 * d.x, 0.4 * d.y, -d.z.abs() - 0.2).normalize()))
            .collect();
        let a: Vec<Vec4> = rows.iter().map(|r| r.0.extend(0.0)).collect();
        let b: Vec<Vec4> = rows.iter().map(|r| r.1.extend(0.0)).collect();
        let mut outcomes = [0usize; 3];
        for lookup in lookups() {
            let uniforms = nearby_uniforms(&camera, &planes, lookup);
            let blocks = [(15, bytemuck::bytes_of(&uniforms))];
            let constants = [("LOOKUP", f64::from(lookup_code(lookup)))];
            let eval = |entry| {
                let evaluation = FamilyEvaluation {
                    module: "nearby-conformance",
                    entry,
                    camera: &camera,
                    ior: 1.5,
                    uniforms: &blocks,
                    constants: &constants,
                };
                evaluate_family(context, &evaluation, &a, &b).expect("gpu")
            };
            let (found, p_geom) = (eval("test_find_nearby"), eval("test_find_nearby_p_geom"));
            let mut mismatches = Vec::new();
            for (k, &(p2, t2)) in rows.iter().enumerate() {
                let cpu = find_nearby(&camera, &texture, &planes, lookup, p2, t2);
                let flags = found[k].z as u32;
                let same = (flags & 1 == 1) == cpu.hit.is_some()
                    && (flags & 2 == 2) == cpu.converged
                    && found[k].w as u32 == cpu.iterations
                    && cpu.hit.is_none_or(|hit| {
                        found[k].x == hit.texel.x as f32
                            && found[k].y == hit.texel.y as f32
                            && close3(p_geom[k], hit.p_geom, 1e-5)
                    });
                if !same {
                    mismatches.push(k);
                }
                outcomes[0] += usize::from(cpu.hit.is_some());
                outcomes[1] += usize::from(cpu.hit.is_none());
                outcomes[2] += usize::from(cpu.iterations > 1);
            }
            prop_assert!(
                mismatches.len() * 100 <= 3 * rows.len(),
                "{lookup:?}: {} of {} rows differ (first: {:?}, GPU {:?}, CPU {:?})",
                mismatches.len(),
                rows.len(),
                mismatches.first().map(|&k| rows[k]),
                mismatches.first().map(|&k| (found[k], p_geom[k])),
                mismatches.first().map(|&k| find_nearby(&camera, &texture, &planes, lookup, rows[k].0, rows[k].1)),
            );
        }
        // Hits, misses and refinements are all exercised.
        prop_assert!(outcomes.iter().all(|&n| n > 0), "{outcomes:?}");
    }
}
