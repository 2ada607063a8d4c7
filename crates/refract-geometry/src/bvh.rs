//! The workspace's one BVH: an obvhs compressed wide BVH (CwBvh) over a mesh's triangles, with
//! closest-hit, occlusion and all-hits queries that return what the renderers need.

use std::time::Duration;

use glam::{Vec2, Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray as ObvhsRay, RayHit};
use obvhs::triangle::Triangle;
use refract_core::Ray;

use crate::error::GeometryError;
use crate::mesh::Mesh;

/// What a closest-hit query with a work budget found ([`MeshBvh::closest_hit_within`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BudgetedHit {
    /// The closest hit, found within the budget.
    Hit(Hit),
    /// Nothing is hit.
    Miss,
    /// The budget of triangle tests ran out first.
    OverBudget,
}

/// A ray-triangle hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) ray direction.
    pub t: f32,
    /// Index of the triangle in the mesh's `triangles`.
    pub triangle: u32,
    /// Barycentric weights `(b1, b2)` of the triangle's second and third corners; the hit is
    /// `(1 − b1 − b2) a + b1 b + b2 c`.
    pub barycentrics: Vec2,
    /// Unit geometric normal from the winding, `normalize((b − a) × (c − a))` (outward).
    pub geometric_normal: Vec3,
    /// Unit interpolated vertex normal at the hit (the shading normal every method uses).
    pub shading_normal: Vec3,
}

/// A BVH over one mesh, owning a copy of the triangles in BVH order.
#[derive(Clone, Debug)]
pub struct MeshBvh {
    bvh: CwBvh,
    /// Triangles in `bvh.primitive_indices` order, so leaves index them directly.
    triangles: Vec<Triangle>,
    /// Vertex normals of those triangles.
    normals: Vec<[Vec3A; 3]>,
    /// Original triangle index of each reordered one.
    original: Vec<u32>,
}

/// The largest coordinate magnitude [`MeshBvh::try_build`] accepts: obvhs's builder overflows
/// (and panics) on surface areas of coordinates from about 1e19 on; 1e18 leaves a margin.
pub const MAX_BVH_COORDINATE: f32 = 1e18;

impl MeshBvh {
    /// [`MeshBvh::build`] for meshes of any scale: an error, not a panic inside obvhs, when a
    /// coordinate's magnitude reaches [`MAX_BVH_COORDINATE`].
    pub fn try_build(mesh: &Mesh) -> Result<Self, GeometryError> {
        check_coordinates(mesh)?;
        Ok(Self::build(mesh))
    }

    /// Builds the BVH with obvhs's `medium_build` preset (no pre-splits: every triangle is
    /// referenced once, so all-hits queries need no deduplication).
    ///
    /// # Panics
    /// Inside obvhs when a coordinate's magnitude is [`MAX_BVH_COORDINATE`] or more: use
    /// [`MeshBvh::try_build`] for meshes of unknown scale.
    pub fn build(mesh: &Mesh) -> Self {
        let triangles = obvhs_triangles(mesh);
        let mut build_time = Duration::ZERO;
        let mut bvh =
            build_cwbvh_from_tris(&triangles, BvhBuildParams::medium_build(), &mut build_time);
        let original = std::mem::take(&mut bvh.primitive_indices);
        let reordered: Vec<Triangle> = original.iter().map(|&i| triangles[i as usize]).collect();
        let normals = original
            .iter()
            .map(|&i| mesh.triangles[i as usize].map(|v| Vec3A::from(mesh.normals[v as usize])))
            .collect();
        // Leaves now index the reordered arrays directly.
        bvh.primitive_indices = (0..original.len() as u32).collect();
        Self {
            bvh,
            triangles: reordered,
            normals,
            original,
        }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The closest hit with `t ∈ [t_min, t_max]`.
    pub fn closest_hit(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let query = to_obvhs(ray, t_min, t_max);
        let mut hit = RayHit::none();
        self.bvh
            .ray_traverse(query, &mut hit, |r, id| intersect(&self.triangles[id], r))
            .then(|| self.hit_details(ray, hit.t, hit.primitive_id as usize))
    }

    /// [`MeshBvh::closest_hit`] testing at most `budget` triangles. Where many triangles
    /// overlap (a fan of near-coincident triangles: their boxes cannot be separated) a ray tests
    /// them all, and a query per vertex becomes quadratic in the triangle count; past the budget
    /// the traversal is cut short (a hit before the ray's start culls every node left) and the
    /// query says so.
    pub fn closest_hit_within(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        budget: u32,
    ) -> BudgetedHit {
        let query = to_obvhs(ray, t_min, t_max);
        let mut hit = RayHit::none();
        let mut tests = 0u32;
        let found = self.bvh.ray_traverse(query, &mut hit, |r, id| {
            if tests >= budget {
                tests = budget.saturating_add(1);
                return f32::NEG_INFINITY;
            }
            tests += 1;
            intersect(&self.triangles[id], r)
        });
        if tests > budget {
            BudgetedHit::OverBudget
        } else if found {
            BudgetedHit::Hit(self.hit_details(ray, hit.t, hit.primitive_id as usize))
        } else {
            BudgetedHit::Miss
        }
    }

    /// True when anything is hit with `t ∈ [t_min, t_max]` (stops at the first hit found).
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        let query = to_obvhs(ray, t_min, t_max);
        !self
            .bvh
            .ray_traverse_miss(query, |r, id| intersect(&self.triangles[id], r))
    }

    /// Every surface crossing with `t ∈ [t_min, t_max]`, sorted by `t` (ties by triangle),
    /// written to `out` (cleared first). Needed for the furthest and second surfaces along a ray.
    ///
    /// A ray through a shared edge or vertex hits every triangle there at the same `t`; such
    /// hits (within `1e-6 · (1 + t)`) count as one crossing and the first triangle is kept.
    pub fn all_hits(&self, ray: &Ray, t_min: f32, t_max: f32, out: &mut Vec<Hit>) {
        out.clear();
        let query = to_obvhs(ray, t_min, t_max);
        self.bvh.ray_traverse_anyhit(query, |r, id| {
            let t = intersect(&self.triangles[id], r);
            if t.is_finite() {
                out.push(self.hit_details(ray, t, id));
            }
        });
        out.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.triangle.cmp(&b.triangle)));
        out.dedup_by(|later, kept| later.t - kept.t <= 1e-6 * (1.0 + kept.t));
    }

    fn hit_details(&self, ray: &Ray, t: f32, id: usize) -> Hit {
        let tri = &self.triangles[id];
        let e1 = tri.v1 - tri.v0;
        let e2 = tri.v2 - tri.v0;
        let face = e1.cross(e2);
        let p = Vec3A::from(ray.at(t));
        // p − a = b1 e1 + b2 e2, so (p − a) × e2 = b1 (e1 × e2) and e1 × (p − a) = b2 (e1 × e2).
        let inv_area2 = 1.0 / face.length_squared();
        let b1 = (p - tri.v0).cross(e2).dot(face) * inv_area2;
        let b2 = e1.cross(p - tri.v0).dot(face) * inv_area2;
        let [n0, n1, n2] = self.normals[id];
        let geometric = face.normalize_or_zero();
        let shading = ((1.0 - b1 - b2) * n0 + b1 * n1 + b2 * n2)
            .try_normalize()
            .unwrap_or(geometric);
        Hit {
            t,
            triangle: self.original[id],
            barycentrics: Vec2::new(b1, b2),
            geometric_normal: geometric.into(),
            shading_normal: shading.into(),
        }
    }
}

/// The triangles of `mesh` as obvhs builds them.
pub(crate) fn obvhs_triangles(mesh: &Mesh) -> Vec<Triangle> {
    (0..mesh.triangles.len())
        .map(|i| {
            let [v0, v1, v2] = mesh.triangle_positions(i).map(Vec3A::from);
            Triangle { v0, v1, v2 }
        })
        .collect()
}

/// An error when a coordinate of `mesh` has a magnitude of [`MAX_BVH_COORDINATE`] or more (or
/// is NaN): obvhs's builders panic there.
pub(crate) fn check_coordinates(mesh: &Mesh) -> Result<(), GeometryError> {
    let magnitude = mesh
        .positions
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0f32, f32::max);
    if magnitude >= MAX_BVH_COORDINATE || magnitude.is_nan() {
        return Err(GeometryError::CoordinatesTooLarge {
            source_name: mesh.name.clone(),
            magnitude,
            limit: MAX_BVH_COORDINATE,
        });
    }
    Ok(())
}

/// The obvhs ray. `−0.0` direction components become `+0.0`: obvhs picks slab bounds by
/// `direction < 0` but inverts `−0.0` to a negative number, which swaps the slab and misses
/// (rays in a coordinate plane, common on symmetric procedural meshes).
fn to_obvhs(ray: &Ray, t_min: f32, t_max: f32) -> ObvhsRay {
    let dir = Vec3A::from(ray.dir) + Vec3A::ZERO;
    ObvhsRay::new(ray.origin.into(), dir, t_min, t_max)
}

/// Barycentric slack of the ray-triangle test: edges are widened by this fraction of the triangle.
pub const EDGE_TOLERANCE: f32 = 1e-5;

/// Double-sided Möller–Trumbore with edges widened by [`EDGE_TOLERANCE`]
/// (`u ≥ −ε`, `v ≥ −ε`, `u + v ≤ 1 + ε`), so that a ray through a shared edge or vertex hits at
/// least one of the triangles there. Plain Möller–Trumbore (and obvhs's `Triangle::intersect`,
/// which also rejects `−0.0` barycentrics) is not watertight: rounding lets such rays slip between
/// the triangles, and the per-vertex `d_N` rays of symmetric meshes aim exactly at vertices all
/// the time (a third of an icosphere's vertices missed). Returns `INFINITY` on a miss.
#[inline(always)]
fn intersect(tri: &Triangle, ray: &ObvhsRay) -> f32 {
    const LO: f32 = -EDGE_TOLERANCE;
    const HI: f32 = 1.0 + EDGE_TOLERANCE;
    let e1 = tri.v1 - tri.v0;
    let e2 = tri.v2 - tri.v0;
    let p = ray.direction.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return f32::INFINITY;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - tri.v0;
    let u = s.dot(p) * inv_det;
    if !(LO..=HI).contains(&u) {
        return f32::INFINITY;
    }
    let q = s.cross(e1);
    let v = ray.direction.dot(q) * inv_det;
    if v < LO || u + v > HI {
        return f32::INFINITY;
    }
    let t = e2.dot(q) * inv_det;
    if t >= ray.tmin && t <= ray.tmax {
        t
    } else {
        f32::INFINITY
    }
}
