//! Rasterising any mesh of a scene (the refractor or an opaque object) from any camera, cube-map
//! faces included: per pixel the nearest front surface with its uv and object id, the pass the
//! nearby-geometry and distance-map methods build on.

use glam::Vec2;
use refract_core::Camera;
use refract_scene::{Scene, SceneMesh, SurfaceTexel};

use crate::raster::{DepthTest, Faces, RasterMesh, rasterize};

/// The nearest front faces of mesh `which` seen by `camera`, row-major from the top (`None`
/// where the mesh is not seen), or `None` for an object index out of range. Texture
/// coordinates are interpolated with the texel's barycentrics ([`crate::raster::Texel::barycentrics`]).
pub fn rasterize_surface(
    scene: &Scene,
    which: SceneMesh,
    camera: &Camera,
) -> Option<Vec<Option<SurfaceTexel>>> {
    let mesh = scene.mesh(which)?;
    let raster = RasterMesh::new(mesh);
    let buffer = rasterize(&raster, camera, Faces::Front, DepthTest::Nearest);
    let object = which.object_id();
    let texels = (0..(camera.width() * camera.height()) as usize)
        .map(|i| {
            buffer.texel(i).map(|t| {
                let uv = if mesh.uvs.is_empty() {
                    Vec2::ZERO
                } else {
                    let w = t.barycentrics;
                    let [a, b, c] =
                        mesh.triangles[t.triangle as usize].map(|v| mesh.uvs[v as usize]);
                    w.x * a + w.y * b + w.z * c
                };
                SurfaceTexel {
                    p_ws: t.p_ws,
                    n_ws: t.n_ws,
                    uv,
                    object,
                }
            })
        })
        .collect();
    Some(texels)
}
