//! The opaque objects' surfaces seen from a camera, shaded: the nearby-geometry (NG) texture of
//! Wyman 2005b §4 (Fig. 10) from the NG camera, which the nearby-geometry lookups search, and
//! the same pass from the eye, the engine family's screen texture and the objects drawn over an
//! image-space frame (`shade`). The twin of the GPU's `passes::object_surfaces`.

use glam::{UVec2, Vec2, Vec3, Vec4};
use rayon::prelude::*;
use refract_core::Camera;
use refract_core::lanes::{F32x8, I32x8, LANES, Mask, Vec2x8, Vec3x8};
use refract_core::nearby_geometry::{NearbyGeometryTexture, NearbySurface, NearbySurfaceLanes};
use refract_core::real::Vector3;
use refract_scene::{Scene, SceneMesh};

use crate::pixel_group::PixelGroup;
use crate::raster::{
    Attribute, Band, DepthTest, Faces, SurfaceBuffer, Texel, at_most_three, band_pixels,
    rasterize_bands,
};
use crate::scene_meshes::SceneMeshes;

/// One texel of the NG texture: the nearest opaque surface seen through it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearbyTexel {
    /// The surface the lookups read: world position and view depth in the NG camera.
    pub surface: NearbySurface,
    /// Outgoing radiance of the surface (the object's material under the scene light).
    pub color: Vec3,
    /// [`refract_scene::SceneMesh::object_id`] of the object (`1 + k`).
    pub object: u32,
}

/// The texel store the lookups search: `(P, depth)`, depth `< 0` where empty (16 bytes, so a
/// search touches only these; colours are read once per pixel).
const EMPTY_SURFACE: Vec4 = Vec4::new(0.0, 0.0, 0.0, -1.0);

/// The colour and object of a texel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Shading {
    color: Vec3,
    object: u32,
}

/// Every opaque object of a scene as one mesh for the NG pass ([`SceneMeshes::objects`]).
pub type NearbyMeshes = SceneMeshes;

/// The NG texture (Wyman 2005b §4, Fig. 10): every opaque object rasterised from the NG
/// camera (the eye's, widened by a guard band), nearest surface per texel, each band of rows
/// shaded right after it is rasterised. Its memory is kept between frames.
#[derive(Default)]
pub struct NearbyTexture {
    width: u32,
    surfaces: Vec<Vec4>,
    shading: Vec<Shading>,
    scratch: SurfaceBuffer,
}

impl NearbyGeometryTexture for NearbyTexture {
    #[inline]
    fn surface(&self, texel: UVec2) -> Option<NearbySurface> {
        let s = *self.surfaces.get(self.index(texel)?)?;
        (s.w >= 0.0).then(|| NearbySurface {
            p_ws: s.truncate(),
            depth: s.w,
        })
    }

    /// The scalar reads without a branch per lane: every lane loads (a lane not read or
    /// outside the texture loads `EMPTY_SURFACE`) and the depth's sign decides on lanes.
    #[inline]
    fn surfaces_x8(&self, x: I32x8, y: I32x8, read: Mask) -> NearbySurfaceLanes {
        let (x, y, read) = (x.to_array(), y.to_array(), read.to_bitmask());
        let mut columns = [[0.0; LANES]; 4];
        for i in 0..LANES {
            let texel = UVec2::new(x[i] as u32, y[i] as u32);
            let s = match self.index(texel).and_then(|at| self.surfaces.get(at)) {
                Some(s) if read & (1 << i) != 0 => *s,
                _ => EMPTY_SURFACE,
            };
            (columns[0][i], columns[1][i], columns[2][i], columns[3][i]) = (s.x, s.y, s.z, s.w);
        }
        let depth = F32x8::new(columns[3]);
        NearbySurfaceLanes {
            p_ws: Vec3x8 {
                x: F32x8::new(columns[0]),
                y: F32x8::new(columns[1]),
                z: F32x8::new(columns[2]),
            },
            depth,
            found: depth.simd_ge(F32x8::ZERO),
        }
    }
}

impl NearbyTexture {
    #[inline]
    fn index(&self, texel: UVec2) -> Option<usize> {
        (texel.x < self.width).then(|| texel.y as usize * self.width as usize + texel.x as usize)
    }

    /// The colour and object id of texel `(x, y)` (meaningful where it is not empty).
    #[inline]
    pub(crate) fn shading(&self, texel: UVec2) -> Option<(Vec3, u32)> {
        let s = self.shading.get(self.index(texel)?)?;
        Some((s.color, s.object))
    }

    /// The texel at `(x, y)` (`None` where empty or outside).
    #[inline]
    pub fn texel(&self, texel: UVec2) -> Option<NearbyTexel> {
        let surface = self.surface(texel)?;
        let (color, object) = self.shading(texel)?;
        Some(NearbyTexel {
            surface,
            color,
            object,
        })
    }

    /// The unit normal of every texel's surface of the last [`Self::render_into`] (row-major;
    /// `+z` where empty) into `normals`.
    pub(crate) fn normals_into(&self, normals: &mut Vec<Vec3>) {
        normals.resize(self.surfaces.len(), Vec3::Z);
        normals.par_iter_mut().enumerate().for_each(|(i, n)| {
            *n = self.scratch.texel(i).map_or(Vec3::Z, |t| t.n_ws);
        });
    }

    /// Renders the objects of `scene` (as `meshes`, [`SceneMeshes::objects`] of the same scene)
    /// seen by `camera` into this texture: front faces, nearest by depth (the first object wins
    /// ties). Colours use the object's material under the scene's light
    /// ([`refract_scene::Object::shade`]), as the reference does.
    pub fn render_into(&mut self, scene: &Scene, meshes: &NearbyMeshes, camera: &Camera) {
        let (width, height) = (camera.width(), camera.height());
        let n = (width * height) as usize;
        self.width = width;
        self.surfaces.resize(n, EMPTY_SURFACE);
        self.shading.resize(n, Shading::default());
        let (eye, look) = (camera.eye(), camera.look_dir());
        let raster = meshes.raster();
        let band = band_pixels(width);
        rasterize_bands(
            &raster,
            camera,
            Faces::Front,
            DepthTest::Nearest,
            &mut self.scratch,
            self.surfaces
                .par_chunks_mut(band)
                .zip(self.shading.par_chunks_mut(band)),
            |rows, (surfaces, shading)| {
                for row in 0..rows.rows() {
                    let at = (row * width) as usize..((row + 1) * width) as usize;
                    let texels = TexelRow {
                        scene,
                        meshes,
                        eye,
                        look,
                    };
                    texels.shade(
                        rows,
                        rows.first_row + row,
                        &mut surfaces[at.clone()],
                        &mut shading[at],
                    );
                }
            },
        );
    }
}

/// What the NG pass's rows are shaded with.
struct TexelRow<'a> {
    scene: &'a Scene,
    meshes: &'a NearbyMeshes,
    eye: Vec3,
    look: Vec3,
}

impl TexelRow<'_> {
    /// Row `y` of a band of the NG pass: empty texels outside the row's covered span and
    /// between, the covered ones eight at a time ([`Self::group`]).
    fn shade(&self, rows: &Band<'_>, y: u32, surfaces: &mut [Vec4], shading: &mut [Shading]) {
        let span = rows.covered_span(y);
        surfaces[..span.start as usize].fill(EMPTY_SURFACE);
        surfaces[span.end as usize..].fill(EMPTY_SURFACE);
        let mut group = PixelGroup::new();
        for x in span {
            if !rows.is_covered(x, y) {
                surfaces[x as usize] = EMPTY_SURFACE;
            } else if group.push(x) {
                self.group(rows, &group, y, surfaces, shading);
                group.len = 0;
            }
        }
        if group.len > 0 {
            group.pad();
            self.group(rows, &group, y, surfaces, shading);
        }
    }

    /// Eight covered texels: each of their triangles (at most three; more, texel by texel)
    /// shaded on all eight lanes (uv, albedo and light: `Object::shade_x8`), each lane keeping
    /// its own triangle's; bit for bit [`Self::texel`] per lane.
    fn group(
        &self,
        rows: &Band<'_>,
        group: &PixelGroup,
        y: u32,
        surfaces: &mut [Vec4],
        shading: &mut [Shading],
    ) {
        let t = rows.attribute_lanes::<{ Attribute::BARYCENTRICS }>(&group.x, y);
        let Some((distinct, count)) = at_most_three(&t.triangle) else {
            for (i, texel) in t.to_texels().iter().enumerate().take(group.len) {
                let x = group.x[i] as usize;
                if let Some((surface, shade)) = self.texel(texel) {
                    (surfaces[x], shading[x]) = (surface, shade);
                }
            }
            return;
        };
        let depth = (t.p_ws - Vec3x8::splat(self.eye)).dot(Vec3x8::splat(self.look));
        let (p, depth) = (t.p_ws.to_lanes(), depth.to_array());
        for &triangle in &distinct[..count] {
            let (mesh, source) = self.meshes.source(triangle);
            let SceneMesh::Object(k) = mesh else {
                continue;
            };
            let object = &self.scene.objects[k];
            let w = t.barycentrics;
            let uv = object.uv_at_x8(source, Vec2x8 { x: w.y, y: w.z }, t.p_ws);
            let color = object.shade_x8(&self.scene.light, uv, t.n_ws).to_lanes();
            for i in (0..group.len).filter(|&i| t.triangle[i] == triangle) {
                let x = group.x[i] as usize;
                surfaces[x] = p[i].extend(depth[i]);
                shading[x] = Shading {
                    color: color[i],
                    object: mesh.object_id(),
                };
            }
        }
    }

    /// One covered texel: its surface and its shading (`None` for a mesh that is not an
    /// object).
    fn texel(&self, t: &Texel) -> Option<(Vec4, Shading)> {
        let (mesh, triangle) = self.meshes.source(t.triangle);
        let SceneMesh::Object(k) = mesh else {
            return None;
        };
        let object = &self.scene.objects[k];
        let w = t.barycentrics;
        let uv = object.uv_at(triangle, Vec2::new(w.y, w.z), t.p_ws);
        Some((
            t.p_ws.extend((t.p_ws - self.eye).dot(self.look)),
            Shading {
                color: object.shade(&self.scene.light, uv, t.n_ws),
                object: mesh.object_id(),
            },
        ))
    }
}

#[cfg(test)]
mod tests {
    use refract_core::lanes::mask_from_lanes;

    use super::*;

    /// The NG pass shaded eight texels at a time is texel for texel the scalar shading, bit for
    /// bit: positions, depths, colours (the chart's patches, the wood floor, the checker
    /// and constant albedos of `engine-failures`) and object ids; empty texels empty.
    #[test]
    fn lane_shaded_ng_texture_equals_the_scalar_shading_bit_for_bit() {
        let mut object_texels = 0;
        for name in ["chart", "engine-failures"] {
            let scene = refract_eval::load_scene(name).expect(name).scene;
            let camera = scene.camera(150, 110).expect("camera");
            let meshes = SceneMeshes::objects(&scene);
            let mut texture = NearbyTexture::default();
            texture.render_into(&scene, &meshes, &camera);
            let row = TexelRow {
                scene: &scene,
                meshes: &meshes,
                eye: camera.eye(),
                look: camera.look_dir(),
            };
            let bits = |v: Vec4| v.to_array().map(f32::to_bits);
            for (i, surface) in texture.surfaces.iter().enumerate() {
                match texture.scratch.texel(i).and_then(|t| row.texel(&t)) {
                    None => assert_eq!(*surface, EMPTY_SURFACE, "{name}, texel {i}"),
                    Some((expected, shading)) => {
                        assert_eq!(bits(*surface), bits(expected), "{name}, texel {i}");
                        let (color, object) = (texture.shading[i].color, texture.shading[i].object);
                        assert_eq!(
                            color.to_array().map(f32::to_bits),
                            shading.color.to_array().map(f32::to_bits)
                        );
                        assert_eq!(object, shading.object);
                        object_texels += 1;
                    }
                }
            }
        }
        assert!(object_texels > 1000, "{object_texels} object texels");
    }

    /// The texture's eight-lane reads are its scalar reads: found where the scalar read finds
    /// a surface (inside the texture, not empty, lane read), with the same position and depth;
    /// lanes not read, texels past the right edge or the last row, and empty texels are not
    /// found.
    #[test]
    fn eight_lane_surface_reads_equal_the_scalar_reads() {
        let scene = refract_eval::load_scene("chart").expect("chart").scene;
        let camera = scene.camera(70, 50).expect("camera");
        let meshes = SceneMeshes::objects(&scene);
        let mut texture = NearbyTexture::default();
        texture.render_into(&scene, &meshes, &camera);
        let mut found = [0usize; 2];
        // Every texel once, and texels past each edge.
        let texels: Vec<(i32, i32)> = (-1..52)
            .flat_map(|y| (-1..73).map(move |x| (x, y)))
            .collect();
        for (group, chunk) in texels.chunks_exact(LANES).enumerate() {
            let x: [i32; LANES] = core::array::from_fn(|i| chunk[i].0);
            let y: [i32; LANES] = core::array::from_fn(|i| chunk[i].1);
            let read: [bool; LANES] = core::array::from_fn(|i| (group + i) % 5 != 0);
            let lanes = texture.surfaces_x8(I32x8::new(x), I32x8::new(y), mask_from_lanes(read));
            let (p, depth) = (lanes.p_ws.to_lanes(), lanes.depth.to_array());
            let lane_found = refract_core::lanes::mask_lanes(lanes.found);
            for i in 0..LANES {
                let expected = read[i]
                    .then(|| texture.surface(UVec2::new(x[i] as u32, y[i] as u32)))
                    .flatten();
                let got = lane_found[i].then_some((p[i], depth[i]));
                assert_eq!(
                    got.map(|(p, d)| (p.to_array().map(f32::to_bits), d.to_bits())),
                    expected.map(|s| (s.p_ws.to_array().map(f32::to_bits), s.depth.to_bits())),
                    "texel ({}, {}), read {}",
                    x[i],
                    y[i],
                    read[i]
                );
                found[usize::from(got.is_some())] += 1;
            }
        }
        assert!(found.iter().all(|&n| n > 300), "{found:?}");
    }
}
