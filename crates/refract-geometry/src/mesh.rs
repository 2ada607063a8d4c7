//! Indexed triangle meshes: validation, cleanup, vertex normals, facts and normalisation.

use std::collections::HashMap;

use glam::{Affine3A, Vec2, Vec3};

use crate::error::GeometryError;

/// An indexed triangle mesh with per-vertex shading normals.
///
/// Invariants (checked by [`Mesh::new`]): every index is in range, positions and normals are
/// finite, `normals.len() == positions.len()` and `uvs` is empty or as long as `positions`.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Where the mesh came from (`path` or `builtin:name`), used in messages.
    pub name: String,
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit outward vertex normals.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, empty when the mesh has none.
    pub uvs: Vec<Vec2>,
    /// Counter-clockwise (outward-facing) triangles.
    pub triangles: Vec<[u32; 3]>,
}

/// A sphere containing every vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    /// Centre: the centre of the axis-aligned bounding box.
    pub center: Vec3,
    /// Radius: the largest distance from `center` to a vertex.
    pub radius: f32,
}

/// What a user wants to know about a mesh before trusting a measurement on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshFacts {
    /// Number of vertices.
    pub vertices: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Edges (between positions, so split normals do not count) used by one triangle only.
    pub boundary_edges: usize,
    /// Edges used by more than two triangles.
    pub non_manifold_edges: usize,
    /// Closed: every edge is shared by exactly two triangles.
    pub watertight: bool,
    /// Signed volume `Σ (a · (b × c)) / 6`; positive for a closed, outward-wound mesh.
    pub signed_volume: f32,
    /// Bounding sphere.
    pub bounding_sphere: BoundingSphere,
}

impl Mesh {
    /// Builds a mesh and checks its invariants. Without `normals`, angle-weighted vertex normals
    /// are computed ([`Mesh::compute_vertex_normals`]); given ones are normalised.
    pub fn new(
        name: impl Into<String>,
        positions: Vec<Vec3>,
        normals: Option<Vec<Vec3>>,
        uvs: Vec<Vec2>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Self, GeometryError> {
        let name = name.into();
        let vertex_count = positions.len();
        for (triangle, tri) in triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= vertex_count) {
                return Err(GeometryError::IndexOutOfRange {
                    source_name: name,
                    triangle,
                    index,
                    vertex_count,
                });
            }
        }
        check_finite(&name, &positions, "position")?;
        if !uvs.is_empty() && uvs.len() != vertex_count {
            return Err(GeometryError::AttributeLength {
                source_name: name,
                attribute: "uv",
                found: uvs.len(),
                vertex_count,
            });
        }
        let has_normals = normals.is_some();
        let normals = match normals {
            Some(normals) if normals.len() != vertex_count => {
                return Err(GeometryError::AttributeLength {
                    source_name: name,
                    attribute: "normal",
                    found: normals.len(),
                    vertex_count,
                });
            }
            Some(normals) => {
                check_finite(&name, &normals, "normal")?;
                normals
            }
            None => vec![Vec3::ZERO; vertex_count],
        };
        let mut mesh = Self {
            name,
            positions,
            normals,
            uvs,
            triangles,
        };
        if has_normals {
            mesh.normalize_normals();
        } else {
            mesh.compute_vertex_normals();
        }
        Ok(mesh)
    }

    /// The three corner positions of triangle `index`.
    #[inline]
    pub fn triangle_positions(&self, index: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[index];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Removes triangles with a repeated index or no area at `f32` precision: a height below
    /// `1e-7` of the longest edge, `‖(b − a) × (c − a)‖ ≤ 1e-7 · max‖e‖²` (slivers that thin
    /// have no usable normal, and scanned meshes such as the bunny have a few), evaluated in
    /// `f64` so that the test is scale-free from `1e-30` to `1e38`. Returns how many were
    /// removed; an error when none is left.
    pub fn remove_degenerate_triangles(&mut self) -> Result<usize, GeometryError> {
        let before = self.triangles.len();
        let positions = &self.positions;
        self.triangles.retain(|&[a, b, c]| {
            if a == b || b == c || a == c {
                return false;
            }
            let (pa, pb, pc) = (
                positions[a as usize].as_dvec3(),
                positions[b as usize].as_dvec3(),
                positions[c as usize].as_dvec3(),
            );
            let longest = (pb - pa)
                .length_squared()
                .max((pc - pb).length_squared())
                .max((pa - pc).length_squared());
            (pb - pa).cross(pc - pa).length() > 1e-7 * longest
        });
        let removed = before - self.triangles.len();
        if self.triangles.is_empty() {
            return Err(GeometryError::NoTriangles {
                source_name: self.name.clone(),
                degenerate: removed,
            });
        }
        Ok(removed)
    }

    /// Removes coincident duplicates: triangles whose three corner positions (bit for bit, in
    /// any order or winding) are those of an earlier triangle, keeping the first. Real scans
    /// contain such duplicates, and each stack of coincident triangles makes BVH builds and
    /// `d_N` rays quadratic. Linear time (a hash set); returns how many were removed.
    pub fn remove_duplicate_triangles(&mut self) -> usize {
        let before = self.triangles.len();
        let positions = &self.positions;
        let mut seen = std::collections::HashSet::with_capacity(self.triangles.len());
        self.triangles.retain(|tri| {
            let mut key = tri.map(|i| positions[i as usize].to_array().map(f32::to_bits));
            key.sort_unstable();
            seen.insert(key)
        });
        before - self.triangles.len()
    }

    /// Angle-weighted vertex normals (Thürmer and Wüthrich 1998): each triangle adds its unit
    /// face normal weighted by its interior angle at the vertex, `N_v = normalize(Σ α_f n_f)`.
    /// Insensitive to how a surface is triangulated, unlike area weighting. Vertices at the same
    /// position share one normal (uv seams of OBJ files must not show in the shading);
    /// vertices on no triangle get `+z`.
    pub fn compute_vertex_normals(&mut self) {
        let ids = self.position_ids();
        let mut sums = vec![Vec3::ZERO; self.positions.len()];
        // In f64: edge cross products of meshes at 1e-30 underflow in f32, at 1e38 overflow.
        for &tri in &self.triangles {
            let p = tri.map(|i| self.positions[i as usize].as_dvec3());
            let Some(face) = (p[1] - p[0]).cross(p[2] - p[0]).try_normalize() else {
                continue;
            };
            for corner in 0..3 {
                let e1 = p[(corner + 1) % 3] - p[corner];
                let e2 = p[(corner + 2) % 3] - p[corner];
                let angle = e1.cross(e2).length().atan2(e1.dot(e2));
                sums[ids[tri[corner] as usize] as usize] += (angle * face).as_vec3();
            }
        }
        self.normals = ids
            .iter()
            .map(|&id| sums[id as usize].try_normalize().unwrap_or(Vec3::Z))
            .collect();
    }

    /// For every vertex, the index of the first vertex with bit-identical position.
    fn position_ids(&self) -> Vec<u32> {
        let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(self.positions.len());
        self.positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                *first
                    .entry(p.to_array().map(f32::to_bits))
                    .or_insert(i as u32)
            })
            .collect()
    }

    /// Normalises every normal; zero normals are replaced by angle-weighted ones. Returns how
    /// many normals were not unit length (`| |n| − 1 | > 1e-3`) before.
    pub fn normalize_normals(&mut self) -> usize {
        let not_unit = self
            .normals
            .iter()
            .filter(|n| (n.length() - 1.0).abs() > 1e-3)
            .count();
        if self.normals.iter().any(|n| n.try_normalize().is_none()) {
            let given = std::mem::take(&mut self.normals);
            self.compute_vertex_normals();
            for (computed, n) in self.normals.iter_mut().zip(given) {
                if let Some(n) = n.try_normalize() {
                    *computed = n;
                }
            }
        } else {
            for n in &mut self.normals {
                *n = n.normalize();
            }
        }
        not_unit
    }

    /// Merges vertices whose positions are within `epsilon` (on a grid of cell `epsilon`) and
    /// that have the same normal direction (within 1e-3) and uv, so that creases stay sharp.
    /// Triangles that become degenerate are left for [`Mesh::remove_degenerate_triangles`].
    /// Returns how many vertices were merged away.
    pub fn weld(&mut self, epsilon: f32) -> usize {
        let before = self.positions.len();
        let key = |p: Vec3| (p / epsilon).round().as_ivec3().to_array();
        let mut first_at: HashMap<[i32; 3], Vec<u32>> = HashMap::new();
        let mut remap = Vec::with_capacity(before);
        let mut positions: Vec<Vec3> = Vec::new();
        let mut normals: Vec<Vec3> = Vec::new();
        let mut uvs: Vec<Vec2> = Vec::new();
        for i in 0..before {
            let (p, n) = (self.positions[i], self.normals[i]);
            let uv = self.uvs.get(i).copied();
            let bucket = first_at.entry(key(p)).or_default();
            let same = bucket.iter().copied().find(|&j| {
                let j = j as usize;
                (normals[j] - n).length() < 1e-3 && uvs.get(j).copied() == uv
            });
            let index = same.unwrap_or_else(|| {
                positions.push(p);
                normals.push(n);
                uvs.extend(uv);
                let j = (positions.len() - 1) as u32;
                bucket.push(j);
                j
            });
            remap.push(index);
        }
        for tri in &mut self.triangles {
            *tri = tri.map(|i| remap[i as usize]);
        }
        (self.positions, self.normals, self.uvs) = (positions, normals, uvs);
        before - self.positions.len()
    }

    /// Reverses every triangle's winding and negates the normals.
    pub fn flip_inside_out(&mut self) {
        for tri in &mut self.triangles {
            tri.swap(1, 2);
        }
        for n in &mut self.normals {
            *n = -*n;
        }
    }

    /// Applies an affine transform to positions, and its inverse transpose to normals.
    pub fn transform(&mut self, transform: &Affine3A) {
        let normal_matrix = transform.matrix3.inverse().transpose();
        for p in &mut self.positions {
            *p = transform.transform_point3(*p);
        }
        for n in &mut self.normals {
            *n = (normal_matrix * glam::Vec3A::from(*n))
                .normalize_or_zero()
                .into();
        }
        if transform.matrix3.determinant() < 0.0 {
            for tri in &mut self.triangles {
                tri.swap(1, 2);
            }
        }
    }

    /// Centres the mesh on its bounding sphere and scales it to radius 1 (design.md), returning
    /// the transform applied, `x' = (x − c) / r`.
    pub fn normalize_to_unit_sphere(&mut self) -> Affine3A {
        let sphere = self.bounding_sphere();
        let scale = if sphere.radius > 0.0 {
            1.0 / sphere.radius
        } else {
            1.0
        };
        let transform =
            Affine3A::from_scale(Vec3::splat(scale)) * Affine3A::from_translation(-sphere.center);
        self.transform(&transform);
        transform
    }

    /// Axis-aligned bounds `(min, max)` of the vertices.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
    }

    /// The sphere centred on the bounding box centre through the furthest vertex.
    pub fn bounding_sphere(&self) -> BoundingSphere {
        let (min, max) = self.bounds();
        let center = 0.5 * (min.as_dvec3() + max.as_dvec3());
        // Distances in f64: squared lengths of meshes at 1e38 overflow f32, at 1e-30 underflow.
        let radius = self
            .positions
            .iter()
            .map(|p| p.as_dvec3().distance(center))
            .fold(0.0_f64, f64::max);
        BoundingSphere {
            center: center.as_vec3(),
            radius: radius as f32,
        }
    }

    /// Signed volume by the divergence theorem, `V = Σ a · (b × c) / 6` (positive when closed
    /// and wound counter-clockwise seen from outside).
    pub fn signed_volume(&self) -> f32 {
        let sum: f64 = (0..self.triangles.len())
            .map(|i| {
                let [a, b, c] = self.triangle_positions(i);
                f64::from(a.dot(b.cross(c)))
            })
            .sum();
        (sum / 6.0) as f32
    }

    /// Counts edges by how many triangles use them. Vertices at the same position count as one,
    /// so meshes with split normals or uvs (a box, a lens rim) are still recognised as closed.
    pub fn facts(&self) -> MeshFacts {
        let ids = self.position_ids();
        let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(self.triangles.len() * 3);
        for tri in &self.triangles {
            for k in 0..3 {
                let (a, b) = (ids[tri[k] as usize], ids[tri[(k + 1) % 3] as usize]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let boundary_edges = edges.values().filter(|&&n| n == 1).count();
        let non_manifold_edges = edges.values().filter(|&&n| n > 2).count();
        MeshFacts {
            vertices: self.positions.len(),
            triangles: self.triangles.len(),
            boundary_edges,
            non_manifold_edges,
            watertight: boundary_edges == 0 && non_manifold_edges == 0,
            signed_volume: self.signed_volume(),
            bounding_sphere: self.bounding_sphere(),
        }
    }
}

fn check_finite(name: &str, values: &[Vec3], attribute: &'static str) -> Result<(), GeometryError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(vertex) => Err(GeometryError::NonFinite {
            source_name: name.to_owned(),
            vertex,
            attribute,
            value: values[vertex].to_array(),
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Mesh {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        Mesh::new("quad", positions, None, vec![], vec![[0, 1, 2], [0, 2, 3]]).expect("valid")
    }

    #[test]
    fn computed_normals_face_the_winding() {
        let mesh = quad();
        assert!(mesh.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
        let facts = mesh.facts();
        assert_eq!((facts.boundary_edges, facts.watertight), (4, false));
    }

    #[test]
    fn invalid_meshes_are_rejected_with_the_culprit() {
        let err = Mesh::new("t", vec![Vec3::ZERO; 3], None, vec![], vec![[0, 1, 7]])
            .expect_err("out of range");
        assert!(err.to_string().contains("vertex index 7"), "{err}");
        let err = Mesh::new(
            "t",
            vec![Vec3::ZERO, Vec3::NAN, Vec3::X],
            None,
            vec![],
            vec![[0, 1, 2]],
        )
        .expect_err("NaN");
        assert!(err.to_string().contains("vertex 1"), "{err}");
    }

    #[test]
    fn degenerate_triangles_are_removed_and_counted() {
        let mut mesh = quad();
        mesh.triangles.push([0, 0, 1]);
        mesh.triangles.push([0, 1, 1]);
        assert_eq!(mesh.remove_degenerate_triangles().expect("two left"), 2);
        mesh.triangles = vec![[0, 1, 1]];
        assert!(matches!(
            mesh.remove_degenerate_triangles(),
            Err(GeometryError::NoTriangles { degenerate: 1, .. })
        ));
    }

    #[test]
    fn normalisation_fits_the_unit_sphere() {
        let mut mesh = quad();
        mesh.transform(&Affine3A::from_scale_rotation_translation(
            Vec3::splat(7.0),
            glam::Quat::from_rotation_y(0.3),
            Vec3::new(5.0, -2.0, 1.0),
        ));
        mesh.normalize_to_unit_sphere();
        let sphere = mesh.bounding_sphere();
        assert!(sphere.center.length() < 1e-5 && (sphere.radius - 1.0).abs() < 1e-5);
    }

    #[test]
    fn welding_merges_shared_corners_only() {
        // Two triangles of the quad with their own copies of the shared corners.
        let positions = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::ZERO,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::Y,
        ];
        let mut mesh =
            Mesh::new("q", positions, None, vec![], vec![[0, 1, 2], [3, 4, 5]]).expect("valid");
        assert_eq!(
            mesh.facts().boundary_edges,
            4,
            "facts weld by position already"
        );
        assert_eq!(mesh.weld(1e-6), 2);
        assert_eq!(mesh.positions.len(), 4);
    }
}
