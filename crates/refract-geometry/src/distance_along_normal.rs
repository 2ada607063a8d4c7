//! Wyman 2005a §3.1: the per-vertex distance `d_N` from a vertex along its inverted normal to
//! the far side of the mesh, precomputed with the BVH.

use rayon::prelude::*;
use refract_core::Ray;

use crate::bvh::{BudgetedHit, MeshBvh};
use crate::mesh::Mesh;

/// Start of the `−N` ray, as a fraction of the bounding-sphere radius: skips the triangles
/// around the vertex itself (with `1e-4` of the radius, a 97k-triangle horse still leaves its own
/// fan, whose triangles are ~1e-2 of the radius wide).
pub const RAY_OFFSET: f32 = 1e-4;

/// The most triangles one `−N` ray may test: none of the eight meshes of `../shared/data`
/// (up to the 97k-triangle horse) needs 128; a fan of near-coincident triangles around one
/// point would otherwise make every ray test all of them and `d_N` quadratic (64k such
/// triangles: 34 s before, 1-2 s with the budget).
pub const RAY_BUDGET: u32 = 512;

/// Per-vertex `d_N` and how many vertices needed the fallback.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalDistances {
    /// `d_N` per vertex (mesh units).
    pub values: Vec<f32>,
    /// Vertices whose `−N` ray left the mesh without hitting it (open meshes, outward-facing
    /// holes): they got [`NormalDistances::fallback`].
    pub misses: usize,
    /// The value used for misses: the median `d_N` of the vertices that did hit, or the
    /// bounding-sphere diameter if none did. A hole gives no information about thickness; the
    /// median is the typical thickness of the object and keeps `d~` on the object's scale.
    pub fallback: f32,
    /// Vertices whose ray tested [`RAY_BUDGET`] triangles without settling (near-coincident
    /// triangles): they got the fallback too.
    pub over_budget: usize,
}

impl NormalDistances {
    /// The share of vertices that missed.
    pub fn miss_rate(&self) -> f32 {
        if self.values.is_empty() {
            0.0
        } else {
            self.misses as f32 / self.values.len() as f32
        }
    }
}

/// For every vertex `v` with unit normal `n`: `d_N = t` of the closest hit of the ray
/// `v + t (−n)`, `t ≥ RAY_OFFSET · r` (r the bounding radius). Parallel over vertices with rayon;
/// the result does not depend on the thread count (each vertex is independent). Each ray tests
/// at most [`RAY_BUDGET`] triangles, so the whole is `O(V log T)` on real meshes and at most
/// `O(V · RAY_BUDGET)` on any.
pub fn normal_distances(mesh: &Mesh, bvh: &MeshBvh) -> NormalDistances {
    let radius = mesh.bounding_sphere().radius;
    let t_min = RAY_OFFSET * radius;
    let found: Vec<BudgetedHit> = mesh
        .positions
        .par_iter()
        .zip(mesh.normals.par_iter())
        .map(|(&origin, &normal)| {
            let ray = Ray {
                origin,
                dir: -normal,
            };
            bvh.closest_hit_within(&ray, t_min, f32::INFINITY, RAY_BUDGET)
        })
        .collect();
    let over_budget = found
        .iter()
        .filter(|f| matches!(f, BudgetedHit::OverBudget))
        .count();
    let hits: Vec<Option<f32>> = found
        .iter()
        .map(|f| match f {
            BudgetedHit::Hit(hit) => Some(hit.t),
            BudgetedHit::Miss | BudgetedHit::OverBudget => None,
        })
        .collect();
    let mut hit_values: Vec<f32> = hits.iter().flatten().copied().collect();
    let misses = hits.len() - hit_values.len() - over_budget;
    let fallback = if hit_values.is_empty() {
        2.0 * radius
    } else {
        let mid = hit_values.len() / 2;
        *hit_values.select_nth_unstable_by(mid, f32::total_cmp).1
    };
    let values = hits.into_iter().map(|h| h.unwrap_or(fallback)).collect();
    NormalDistances {
        values,
        misses,
        fallback,
        over_budget,
    }
}
