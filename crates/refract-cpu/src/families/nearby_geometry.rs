//! Wyman 2005b refraction of nearby geometry on the CPU (methods `kay-greenberg`, `ray-plane`,
//! `iterative`, `iterative-seeded`): the three passes of §5 — the refractor's back faces, the
//! nearby opaque objects from the eye into the NG texture (surface + colour per texel), and the
//! front faces — then per pixel the two-interface kernel of Wyman 2005a and
//! [`refract_core::nearby_geometry::find_nearby`], both eight refractor pixels at a time
//! ([`two_interface_lanes`], [`find_nearby_x8`]).
//!
//! Every pixel is one of: the refractor in front of the objects (the refraction), an object
//! seen directly (its NG texel), or the environment.

use std::sync::Arc;

use glam::{UVec2, Vec2, Vec3, Vec4};
use rayon::prelude::*;
use refract_core::Camera;
use refract_core::exit::ExitNormalSource;
use refract_core::gpu::exit_normal_source_code;
use refract_core::kernel::ImageSpaceParams;
use refract_core::kernel_x8::{FrontLanes, two_interface_lanes};
use refract_core::lanes::{F32x8, I32x8, LANES, Mask, Vec2x8, Vec3x8, mask_from_lanes};
use refract_core::nearby_geometry::{
    NearbyGeometryTexture, NearbyLookup, NearbySurface, NearbySurfaceLanes, Plane,
    guard_band_camera, view_depth,
};
use refract_core::nearby_geometry_x8::find_nearby_x8;
use refract_core::real::Vector3;
use refract_scene::{
    Aov, Frame, LayerValue, NearbyParams, PixelLayers, RenderError, Scene, SceneMesh,
};

use crate::buffers::{BackFaces, front_faces_into};
use crate::family::{CpuFamily, FrameCx};
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
    /// outside the texture loads [`EMPTY_SURFACE`]) and the depth's sign decides on lanes.
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
    fn shading(&self, texel: UVec2) -> Option<(Vec3, u32)> {
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

/// Per-pixel outputs beside the colour; NaN / 0 / false where they do not apply.
#[derive(Clone, Copy, Debug, PartialEq)]
struct NearbyAov {
    covered: bool,
    p2: Vec3,
    t2: Vec3,
    n2: Vec3,
    n2_source: Option<ExitNormalSource>,
    tir: bool,
    p_geom: Vec3,
    ng_texel: Vec3,
    iterations: u32,
    converged: bool,
}

impl PixelLayers for NearbyAov {
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        Some(match aov {
            Aov::Covered => LayerValue::Flag(self.covered),
            Aov::Tir => LayerValue::Flag(self.tir),
            Aov::Converged => LayerValue::Flag(self.converged),
            Aov::P2 => LayerValue::Vec3(self.p2),
            Aov::N2 => LayerValue::Vec3(self.n2),
            Aov::T2 => LayerValue::Vec3(self.t2),
            Aov::PGeom => LayerValue::Vec3(self.p_geom),
            Aov::NgTexel => LayerValue::Vec3(self.ng_texel),
            Aov::Iterations => LayerValue::Count(self.iterations),
            Aov::ExitNormalSource => {
                LayerValue::Count(self.n2_source.map_or(0, exit_normal_source_code))
            }
            _ => return None,
        })
    }
}

impl NearbyAov {
    const NONE: Self = Self {
        covered: false,
        p2: Vec3::NAN,
        t2: Vec3::NAN,
        n2: Vec3::NAN,
        n2_source: None,
        tir: false,
        p_geom: Vec3::NAN,
        ng_texel: Vec3::NAN,
        iterations: 0,
        converged: false,
    };
}

/// The passes of the nearby-geometry methods, with their memory kept between frames.
#[derive(Default)]
pub struct NearbyPasses {
    meshes: NearbyMeshes,
    front: SurfaceBuffer,
    back: BackFaces,
    nearby: NearbyTexture,
    aovs: Vec<NearbyAov>,
}

impl NearbyPasses {
    /// The NG texture of the last frame.
    pub fn nearby_texture(&self) -> &NearbyTexture {
        &self.nearby
    }
}

impl CpuFamily for NearbyPasses {
    type Params = NearbyParams;

    /// Prepares the passes for `scene` (its objects as one mesh).
    fn prepare(&mut self, scene: &Arc<Scene>) {
        self.meshes = SceneMeshes::objects(scene);
    }

    fn render(
        &mut self,
        cx: &FrameCx<'_>,
        method: &NearbyParams,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let FrameCx { scene, camera, .. } = *cx;
        let refractor = &scene.refractor;
        let kernel = &method.two.kernel(refractor.ior())?;
        let planes = &scene.nearby_planes(camera.look_dir());
        let (ng_desc, pad) = guard_band_camera(camera.desc(), method.guard_band_percent);
        let ng_camera =
            Camera::new(ng_desc).map_err(|err| RenderError::Parameter(err.to_string()))?;
        self.back.render_into(refractor, camera, method.two.back);
        self.nearby.render_into(scene, &self.meshes, &ng_camera);
        front_faces_into(refractor, camera, &mut self.front);

        let (width, height) = (camera.width(), camera.height());
        let n = (width * height) as usize;
        frame.resize_for_overwrite(width, height);
        let pixels = PixelContext {
            scene,
            planes,
            camera,
            ng_camera: &ng_camera,
            pad,
            kernel,
            lookup: method.lookup,
            front: &self.front,
            back: &self.back,
            nearby: &self.nearby,
        };
        let rows = frame.color.par_chunks_mut(width as usize).enumerate();
        if cx.with_aovs() {
            self.aovs.clear();
            self.aovs.resize(n, NearbyAov::NONE);
            rows.zip(self.aovs.par_chunks_mut(width as usize))
                .for_each(|((y, colors), aovs)| pixels.row(y as u32, colors, Some(aovs)));
        } else {
            // Colour only, as displayed: no per-pixel AOV memory is touched.
            rows.for_each(|(y, colors)| pixels.row(y as u32, colors, None));
        }
        if cx.with_aovs() {
            frame.write_row_layers(cx.method, &self.aovs[..n])?;
        }
        Ok(())
    }
}

/// What the per-pixel work reads.
struct PixelContext<'a> {
    scene: &'a Scene,
    planes: &'a [Plane],
    camera: &'a Camera,
    ng_camera: &'a Camera,
    pad: UVec2,
    kernel: &'a ImageSpaceParams,
    lookup: NearbyLookup,
    front: &'a SurfaceBuffer,
    back: &'a BackFaces,
    nearby: &'a NearbyTexture,
}

impl PixelContext<'_> {
    /// Shades row `y`: the pixels the refractor covers eight at a time (their front texels
    /// resolved on lanes, then the lane kernel `two_interface_lanes`, bit-identical to the
    /// scalar kernel, and each lane's lookup, or the object where one is nearer), pixels that
    /// see an object directly at once, and the environment eight pixels at a time.
    fn row(&self, y: u32, colors: &mut [Vec3], mut aovs: Option<&mut [NearbyAov]>) {
        let mut group = PixelGroup::new();
        let mut background = PixelGroup::new();
        let row = (y * self.camera.width()) as usize;
        for x in 0..colors.len() as u32 {
            if self.front.is_covered(row + x as usize) {
                if group.push(x) {
                    self.refractor(&group, y, colors, aovs.as_deref_mut());
                    group.len = 0;
                }
            } else if let Some(object) = self.nearby.texel(UVec2::new(x, y) + self.pad) {
                colors[x as usize] = object.color;
                if let Some(aovs) = aovs.as_deref_mut() {
                    aovs[x as usize] = NearbyAov::NONE;
                }
            } else if background.push(x) {
                self.background(&background, y, colors, aovs.as_deref_mut());
                background.len = 0;
            }
        }
        if background.len > 0 {
            background.pad();
            self.background(&background, y, colors, aovs.as_deref_mut());
        }
        if group.len > 0 {
            group.pad();
            self.refractor(&group, y, colors, aovs);
        }
    }

    /// Eight pixels of row `y` that see the environment: eight-lane rays and lookups
    /// (bit-identical to the scalar ones).
    fn background(
        &self,
        group: &PixelGroup,
        y: u32,
        colors: &mut [Vec3],
        mut aovs: Option<&mut [NearbyAov]>,
    ) {
        let uv: [Vec2; LANES] = core::array::from_fn(|i| Camera::pixel_center(group.x[i], y));
        let dirs = self.camera.pixel_ray_dir_x8(Vec2x8::from_lanes(&uv));
        let radiance = self.scene.environment.radiance_x8(dirs).to_lanes();
        for (&x, &color) in group.x.iter().zip(&radiance).take(group.len) {
            colors[x as usize] = color;
            if let Some(aovs) = aovs.as_deref_mut() {
                aovs[x as usize] = NearbyAov::NONE;
            }
        }
    }

    /// Eight pixels of row `y` the refractor covers: the lane kernel, then per lane the object
    /// when one is nearer than the refractor there, else the lookup, the eight lookups on
    /// lanes ([`find_nearby_x8`], bit-identical to the scalar
    /// [`refract_core::nearby_geometry::find_nearby`]).
    fn refractor(
        &self,
        group: &PixelGroup,
        y: u32,
        colors: &mut [Vec3],
        mut aovs: Option<&mut [NearbyAov]>,
    ) {
        let uv: [Vec2; LANES] = core::array::from_fn(|i| Camera::pixel_center(group.x[i], y));
        let texels = self
            .front
            .attribute_lanes::<{ Attribute::SCALAR }>(&group.x, y);
        let front = FrontLanes {
            p1_ws: texels.p_ws,
            n1_ws: texels.n_ws,
            d_n: texels.scalar,
        };
        let paths = two_interface_lanes(self.camera, &uv, &front, self.back, self.kernel);
        let (p1, p2, t2, n2) = (
            texels.p_ws.to_lanes(),
            paths.p2.to_lanes(),
            paths.t2.to_lanes(),
            paths.n2.to_lanes(),
        );
        // Per lane: the object where it is nearer, black for a degenerate input, else the
        // path (a lookup, or black where the TIR policy `black` absorbed it: `T~2 = 0`).
        let mut shown = [Shown::Degenerate; LANES];
        let mut looked_up = [false; LANES];
        for i in 0..group.len {
            // The refractor wins only where it is strictly nearer (NaN: the object).
            let refractor_nearer = |depth: f32| view_depth(self.camera, p1[i]) < depth;
            let object = self
                .nearby
                .texel(UVec2::new(group.x[i], y) + self.pad)
                .filter(|o| !refractor_nearer(o.surface.depth));
            shown[i] = if let Some(object) = object {
                Shown::Object(object.color)
            } else if !paths.ok[i] {
                Shown::Degenerate
            } else {
                looked_up[i] = t2[i] != Vec3::ZERO;
                Shown::Path
            };
        }
        let results = looked_up.contains(&true).then(|| {
            find_nearby_x8(
                self.ng_camera,
                self.nearby,
                self.planes,
                self.lookup,
                &paths.p2,
                &paths.t2,
                mask_from_lanes(looked_up),
            )
        });
        for i in 0..group.len {
            let x = group.x[i] as usize;
            let result = results.as_ref().filter(|_| looked_up[i]).map(|r| r[i]);
            // A hit's surface was read by the lookup: only its colour and object remain.
            let shaded = result
                .and_then(|r| r.hit)
                .and_then(|hit| Some((hit, self.nearby.shading(hit.texel)?)));
            colors[x] = match (shown[i], shaded) {
                (Shown::Object(color), _) => color,
                (Shown::Degenerate, _) => Vec3::ZERO,
                (Shown::Path, Some((_, (color, _)))) => color,
                (Shown::Path, None) if looked_up[i] => self.scene.environment.radiance(t2[i]),
                (Shown::Path, None) => Vec3::ZERO,
            };
            let Some(aovs) = aovs.as_deref_mut() else {
                continue;
            };
            let covered = NearbyAov {
                covered: true,
                ..NearbyAov::NONE
            };
            aovs[x] = match shown[i] {
                Shown::Object(_) => NearbyAov::NONE,
                Shown::Degenerate => covered,
                Shown::Path => {
                    let (p_geom, ng_texel) = shaded.map_or(
                        (NearbyAov::NONE.p_geom, NearbyAov::NONE.ng_texel),
                        |(hit, (_, object))| {
                            let texel = hit.texel.as_vec2();
                            (hit.p_geom, Vec3::new(texel.x, texel.y, object as f32))
                        },
                    );
                    NearbyAov {
                        p2: p2[i],
                        t2: t2[i],
                        n2: n2[i],
                        n2_source: Some(if paths.n2_from_back_face[i] {
                            ExitNormalSource::BackFace
                        } else {
                            ExitNormalSource::SilhouetteFallback
                        }),
                        tir: paths.tir[i],
                        p_geom,
                        ng_texel,
                        iterations: result.map_or(0, |r| r.iterations),
                        converged: result.is_some_and(|r| r.converged),
                        ..covered
                    }
                }
            };
        }
    }
}

/// What a refractor pixel shows before its lookup.
#[derive(Clone, Copy, Debug)]
enum Shown {
    /// An object nearer than the refractor: its NG texel's colour.
    Object(Vec3),
    /// A degenerate input to the kernel: black, no path.
    Degenerate,
    /// The refracted path: the lookup's colour (black where the TIR policy absorbed it).
    Path,
}

#[cfg(test)]
mod tests {
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
