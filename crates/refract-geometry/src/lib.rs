//! # refract-geometry
//!
//! The geometry precompute every refraction method needs:
//!
//! * [`mesh`]: indexed triangle meshes, validation, angle-weighted normals, welding,
//!   normalisation into the unit bounding sphere, mesh facts (watertight, signed volume).
//!   The cleanup real files need (inside-out meshes, non-unit normals, degenerates) is here;
//!   reading OBJ and glTF files is in refract-eval (`refract_eval::mesh_files`), so that the
//!   renderers link no file format.
//! * [`bvh`]: the workspace's BVH (obvhs CwBvh) with closest-hit, occlusion and all-hits queries;
//!   [`flat_bvh`]: a BVH2 flattened into plain arrays for a GPU traversal.
//! * [`distance_along_normal`]: Wyman 2005a §3.1 per-vertex `d_N`.
//! * [`shapes`], [`lens`], [`builtin`]: procedural shapes and spectacle lenses (spade).
//!
//! Every failure is a [`GeometryError`] naming the file or shape; nothing panics on user input.

pub mod builtin;
pub mod bvh;
pub mod distance_along_normal;
pub mod error;
pub mod flat_bvh;
pub mod lens;
pub mod mesh;
pub mod shapes;

pub use bvh::{BudgetedHit, Hit, MeshBvh};
pub use distance_along_normal::{NormalDistances, normal_distances};
pub use error::GeometryError;
pub use flat_bvh::{FLAT_BVH_MAX_DEPTH, FlatBvh, FlatNode, FlatTriangle};
pub use lens::LensDesc;
pub use mesh::{BoundingSphere, Mesh, MeshFacts};
