//! Rasterising any mesh of a scene (the refractor or an opaque object) from any camera, cube-map
//! faces included: per pixel the nearest front surface with its uv and object id, the pass the
//! nearby-geometry and distance-map methods build on; and the material a surface texel shows
//! (the distance maps' and `pvrr`'s texels).

use glam::{Vec2, Vec3};
use refract_core::Camera;
use refract_core::distance_map::TexelMaterial;
use refract_core::lanes::{Vec2x8, Vec3x8};
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

/// The material and normal of the surface of mesh `mesh` at triangle `triangle` with
/// barycentrics `w` (diffuse: its radiance under the scene light; the refractor's glass at
/// wavelength `lambda_nm`, [`refract_scene::Refractor::ior_at`]).
pub fn surface_material(
    scene: &Scene,
    lambda_nm: Option<f32>,
    mesh: SceneMesh,
    triangle: u32,
    w: Vec3,
    p_ws: Vec3,
    n_ws: Vec3,
) -> TexelMaterial {
    match mesh {
        SceneMesh::Refractor => scene.refractor.texel_material_at(lambda_nm),
        SceneMesh::Object(k) => {
            let object = &scene.objects[k];
            match object.conductor() {
                Some(c) => TexelMaterial {
                    rgb: c.f0(),
                    ior: -1.0,
                },
                None => TexelMaterial {
                    rgb: object.shade(
                        &scene.light,
                        object.uv_at(triangle, Vec2::new(w.y, w.z), p_ws),
                        n_ws,
                    ),
                    ior: 0.0,
                },
            }
        }
    }
}

/// [`surface_material`]'s `rgb` at eight points of one triangle (barycentrics `w`, positions
/// `p_ws`, normals `n_ws` as lanes): lane `i` bit for bit the scalar function's.
pub fn surface_rgb_x8(
    scene: &Scene,
    mesh: SceneMesh,
    triangle: u32,
    w: Vec3x8,
    p_ws: Vec3x8,
    n_ws: Vec3x8,
) -> Vec3x8 {
    match mesh {
        SceneMesh::Refractor => Vec3x8::splat(scene.refractor.texel_material().rgb),
        SceneMesh::Object(k) => {
            let object = &scene.objects[k];
            match object.conductor() {
                Some(c) => Vec3x8::splat(c.f0()),
                None => {
                    let uv = object.uv_at_x8(triangle, Vec2x8 { x: w.y, y: w.z }, p_ws);
                    object.shade_x8(&scene.light, uv, n_ws)
                }
            }
        }
    }
}
