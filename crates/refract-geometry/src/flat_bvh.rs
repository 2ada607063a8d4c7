//! A mesh's BVH flattened for a GPU shader: an obvhs binary BVH (BVH2) whose nodes are 32-byte
//! records and whose triangles are stored in leaf order, so that a WGSL traversal
//! (`refract-gpu/shaders/bvh.wgsl`) reads two storage arrays and nothing else. The CPU queries stay on
//! [`crate::MeshBvh`] (a wide BVH); both index the same triangles and test them with the same
//! watertight Möller–Trumbore ([`crate::bvh::EDGE_TOLERANCE`]), so their closest hits agree
//! (the GPU conformance test holds them to it).
//!
//! Plain data (`bytemuck::Pod`): this crate links no GPU API.

use std::time::Duration;

use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::bvh2::builder::build_bvh2_from_tris;

use crate::error::GeometryError;
use crate::mesh::Mesh;

/// The deepest traversal stack `refract-gpu/shaders/bvh.wgsl` has (`BVH_STACK`): a flattened BVH is at most
/// this deep.
pub const FLAT_BVH_MAX_DEPTH: u32 = 64;

/// One node, as `struct BvhNode` in `refract-gpu/shaders/bvh.wgsl`: the bounds, then `prim_count` (0 for an
/// inner node, whose children are `first_index` and `first_index + 1`; otherwise a leaf of
/// `prim_count` triangles from `first_index` in [`FlatBvh::triangles`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FlatNode {
    /// Bounds, smallest corner.
    pub min: [f32; 3],
    /// Triangles of a leaf; 0 for an inner node.
    pub prim_count: u32,
    /// Bounds, largest corner.
    pub max: [f32; 3],
    /// First child (inner node) or first triangle (leaf).
    pub first_index: u32,
}

/// One triangle's corners, as `struct BvhTriangle` in `refract-gpu/shaders/bvh.wgsl` (`w` unused).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FlatTriangle {
    /// First corner.
    pub v0: [f32; 4],
    /// Second corner.
    pub v1: [f32; 4],
    /// Third corner.
    pub v2: [f32; 4],
}

/// A mesh's BVH2 as flat arrays; `nodes[0]` is the root.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlatBvh {
    /// The nodes, root first.
    pub nodes: Vec<FlatNode>,
    /// The triangles in leaf order.
    pub triangles: Vec<FlatTriangle>,
    /// The mesh's index of each of [`Self::triangles`].
    pub original: Vec<u32>,
    /// The tree's depth (a lone leaf is 1).
    pub depth: u32,
}

impl FlatBvh {
    /// Builds obvhs's BVH2 of `mesh` (`medium_build`: no pre-splits, every triangle once) and
    /// flattens it. An error when a coordinate's magnitude reaches
    /// [`crate::bvh::MAX_BVH_COORDINATE`] (obvhs panics there) or when the tree is deeper than
    /// [`FLAT_BVH_MAX_DEPTH`].
    pub fn build(mesh: &Mesh) -> Result<Self, GeometryError> {
        crate::bvh::check_coordinates(mesh)?;
        if mesh.triangles.is_empty() {
            return Ok(Self::default());
        }
        let triangles = crate::bvh::obvhs_triangles(mesh);
        let mut build_time = Duration::ZERO;
        let bvh = build_bvh2_from_tris(&triangles, BvhBuildParams::medium_build(), &mut build_time);
        let corner = |v: Vec3A| [v.x, v.y, v.z, 0.0];
        let flat_triangles = bvh
            .primitive_indices
            .iter()
            .map(|&i| {
                let t = &triangles[i as usize];
                FlatTriangle {
                    v0: corner(t.v0),
                    v1: corner(t.v1),
                    v2: corner(t.v2),
                }
            })
            .collect();
        let nodes: Vec<FlatNode> = bvh
            .nodes
            .iter()
            .map(|n| FlatNode {
                min: n.aabb.min.to_array(),
                prim_count: n.prim_count,
                max: n.aabb.max.to_array(),
                first_index: n.first_index,
            })
            .collect();
        let depth = depth_of(&nodes);
        if depth > FLAT_BVH_MAX_DEPTH {
            return Err(GeometryError::BvhTooDeep {
                source_name: mesh.name.clone(),
                depth,
                limit: FLAT_BVH_MAX_DEPTH,
            });
        }
        Ok(Self {
            nodes,
            triangles: flat_triangles,
            original: bvh.primitive_indices.clone(),
            depth,
        })
    }
}

/// The depth of the tree rooted at `nodes[0]` (iterative: no recursion on deep trees).
fn depth_of(nodes: &[FlatNode]) -> u32 {
    let mut deepest = 0;
    let mut stack = vec![(0usize, 1u32)];
    while let Some((i, depth)) = stack.pop() {
        deepest = deepest.max(depth);
        let node = &nodes[i];
        if node.prim_count == 0 {
            let first = node.first_index as usize;
            stack.push((first, depth + 1));
            stack.push((first + 1, depth + 1));
        }
    }
    deepest
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    #[test]
    fn every_triangle_is_in_one_leaf_inside_its_bounds() {
        let mesh = shapes::uv_sphere(24, 12, 1.0).expect("sphere");
        let flat = FlatBvh::build(&mesh).expect("flat");
        assert_eq!(flat.triangles.len(), mesh.triangles.len());
        let mut seen = vec![0u32; mesh.triangles.len()];
        for &o in &flat.original {
            seen[o as usize] += 1;
        }
        assert!(seen.iter().all(|&n| n == 1), "each triangle once");
        // Every leaf's triangles lie inside its bounds, every child inside its parent.
        let inside = |n: &FlatNode, p: [f32; 4]| {
            (0..3).all(|k| p[k] >= n.min[k] - 1e-6 && p[k] <= n.max[k] + 1e-6)
        };
        for n in &flat.nodes {
            if n.prim_count == 0 {
                for c in [n.first_index, n.first_index + 1] {
                    let child = &flat.nodes[c as usize];
                    assert!(inside(n, [child.min[0], child.min[1], child.min[2], 0.0]));
                    assert!(inside(n, [child.max[0], child.max[1], child.max[2], 0.0]));
                }
            } else {
                for t in &flat.triangles[n.first_index as usize..][..n.prim_count as usize] {
                    assert!(inside(n, t.v0) && inside(n, t.v1) && inside(n, t.v2));
                }
            }
        }
        // The triangles are the mesh's, reordered.
        for (t, &o) in flat.triangles.iter().zip(&flat.original) {
            let [a, _, _] = mesh.triangle_positions(o as usize);
            assert_eq!([t.v0[0], t.v0[1], t.v0[2]], a.to_array());
        }
        assert!(
            (2..=FLAT_BVH_MAX_DEPTH).contains(&flat.depth),
            "{}",
            flat.depth
        );
        // 32 and 48 bytes, as the WGSL structs.
        assert_eq!(std::mem::size_of::<FlatNode>(), 32);
        assert_eq!(std::mem::size_of::<FlatTriangle>(), 48);
    }

    #[test]
    fn huge_coordinates_are_an_error_not_a_panic() {
        let mut mesh = shapes::uv_sphere(8, 4, 1.0).expect("sphere");
        mesh.positions[0].x = 1e19;
        assert!(matches!(
            FlatBvh::build(&mesh),
            Err(GeometryError::CoordinatesTooLarge { .. })
        ));
    }
}
