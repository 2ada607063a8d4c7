//! Several meshes of a scene as one mesh, so that one rasterisation, one depth test and one
//! interpolation per texel serve them all (the NG pass of Wyman 2005b, the camera and the
//! distance-map passes of Umenhoffer et al. 2007).

use glam::Vec3;
use refract_scene::{Scene, SceneMesh};

use crate::raster::{DepthInterpolation, RasterMesh};

/// Meshes of a scene concatenated in order: vertices and triangles, and for each triangle the
/// mesh it came from and its index in that mesh.
#[derive(Clone, Debug, Default)]
pub struct SceneMeshes {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    sources: Vec<(SceneMesh, u32)>,
}

impl SceneMeshes {
    /// The opaque objects of `scene`, in object order.
    pub fn objects(scene: &Scene) -> Self {
        Self::of(scene, (0..scene.objects.len()).map(SceneMesh::Object))
    }

    /// The refractor, then the opaque objects.
    pub fn everything(scene: &Scene) -> Self {
        Self::of(
            scene,
            core::iter::once(SceneMesh::Refractor)
                .chain((0..scene.objects.len()).map(SceneMesh::Object)),
        )
    }

    /// The meshes `which` of `scene` (indices out of range are skipped).
    pub fn of(scene: &Scene, which: impl IntoIterator<Item = SceneMesh>) -> Self {
        let mut meshes = Self::default();
        for id in which {
            let Some(mesh) = scene.mesh(id) else {
                continue;
            };
            let base = meshes.positions.len() as u32;
            meshes.positions.extend_from_slice(&mesh.positions);
            meshes.normals.extend_from_slice(&mesh.normals);
            meshes
                .triangles
                .extend(mesh.triangles.iter().map(|t| t.map(|v| v + base)));
            meshes
                .sources
                .extend((0..mesh.triangles.len() as u32).map(|t| (id, t)));
        }
        meshes
    }

    /// The combined mesh for the rasteriser.
    pub fn raster(&self) -> RasterMesh<'_> {
        RasterMesh {
            positions: &self.positions,
            normals: &self.normals,
            scalars: &[],
            triangles: &self.triangles,
            depth: DepthInterpolation::Exact,
        }
    }

    /// The mesh and the triangle (in that mesh) of combined triangle `triangle`.
    #[inline]
    pub fn source(&self, triangle: u32) -> (SceneMesh, u32) {
        self.sources[triangle as usize]
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
}
