//! Umenhoffer et al. 2007 (GPU Gems 3 ch. 17) on the CPU, method `distance-map`: every frame
//! the layered distance map around the specular object's centre is rebuilt with the shared
//! rasteriser (six mirrored 90° cube-face cameras per layer: the specular object's faces
//! toward the reference point, its faces away from it, then the other geometry, depth-peeled
//! into `layers − 2` layers), the scene is rasterised from the eye, and every pixel that sees a
//! specular surface runs [`refract_core::distance_map::trace_path`].
//!
//! A layer keeps, per texel, the Euclidean distance from the reference point (−1 where empty;
//! what the searches read, 4 bytes) and the rasteriser's visibility (which triangle), from
//! which the normal and material of a hit are interpolated once per hit.

mod eye_pass;

use std::sync::Arc;

use glam::{UVec2, Vec3};
use rayon::prelude::*;
use refract_core::distance_map::{
    DistanceLayers, DistanceMapScene, MAX_LAYERS, PathResult, TexelMaterial, TexelSurface,
    cube_texel, cube_texel_direction, cube_texel_index, cube_texel_indices_x8,
};
use refract_core::lanes::{LANES, Vec3x8};
use refract_core::{Camera, CubeFace};
use refract_scene::{
    Aov, DistanceMapParams, Frame, FrameOutputs, LayerValue, PixelLayers, RenderError, Scene,
    SceneMesh,
};

use crate::family::{CpuFamily, FrameCx};
use crate::prefetch::prefetch;
use crate::raster::{
    DepthTest, Faces, SurfaceBuffer, band_pixels, rasterize_bands, rasterize_into,
};
use crate::scene_meshes::SceneMeshes;
use crate::surfaces::surface_material;
use eye_pass::EyePass;

/// What geometry a layer holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerContent {
    /// The specular object's faces turned toward the reference point.
    SpecularFront,
    /// The specular object's faces turned away from it (all of a convex object).
    SpecularBack,
    /// The other geometry: depth-peeling layer `k`. Layer 0 is the nearest face turned toward
    /// the reference point (the chapter's single diffuse layer); layers `k ≥ 1` are the
    /// nearest face of either orientation behind layer `k − 1`. All are hit only from the
    /// reference point's side (a crossing from behind is a depth discontinuity of the layer far
    /// more often than a real hit: measured, `docs/methods.md`).
    Others(u32),
}

impl LayerContent {
    /// The content of layer `index` of a map with `layers` layers.
    pub fn of(index: usize) -> Self {
        match index {
            0 => Self::SpecularFront,
            1 => Self::SpecularBack,
            k => Self::Others(k as u32 - 2),
        }
    }
}

/// One layer: six faces of `size²` texels.
#[derive(Default)]
struct Layer {
    /// Distance per texel, [`cube_texel_index`] order; −1 where empty.
    distance: Vec<f32>,
    /// The rasteriser's visibility per face.
    faces: Vec<SurfaceBuffer>,
    /// Smallest and largest valid distance.
    range: Option<(f32, f32)>,
}

/// The layered distance map of one frame.
#[derive(Default)]
pub struct DistanceMap {
    size: u32,
    center: Vec3,
    layers: Vec<Layer>,
    specular: SceneMeshes,
    others: SceneMeshes,
    floor_depth: Vec<f32>,
    /// `|(s, t, 1)|` per face texel: the distance of a texel's point over its view depth.
    stretch: Vec<f32>,
}

impl DistanceMap {
    /// Prepares the meshes of `scene` (once per scene).
    pub fn prepare(&mut self, scene: &Scene) {
        self.specular = SceneMeshes::of(scene, [SceneMesh::Refractor]);
        self.others = SceneMeshes::objects(scene);
    }

    /// The reference point: the specular object's bounding-sphere centre (§17.1.1).
    pub fn center(&self) -> Vec3 {
        self.center
    }

    /// Rebuilds the map: `layers` layers of six `size²` faces around the specular object's
    /// centre. Layers beyond the first of the other geometry are depth-peeled: the nearest
    /// surface farther than the previous layer's (by a relative `10⁻³`).
    pub fn render(&mut self, scene: &Scene, layers: usize, size: u32) -> Result<(), RenderError> {
        let layers = layers.clamp(3, MAX_LAYERS);
        self.size = size;
        self.center = scene.refractor.mesh().bounding_sphere().center;
        let (near, far) = scene.cube_map_clip_planes(self.center);
        self.layers.resize_with(layers, Layer::default);
        let texels = (size * size) as usize;
        if self.stretch.len() != texels {
            self.stretch = (0..texels as u32)
                .map(|i| {
                    cube_texel_direction(CubeFace::PosZ, UVec2::new(i % size, i / size), size)
                        .length()
                })
                .collect();
        }
        let stretch = &self.stretch;
        let cameras: Vec<Camera> = CubeFace::ALL
            .iter()
            .map(|&face| Camera::cube_face(self.center, face, size, near, far))
            .collect::<Result<_, _>>()
            .map_err(|e| RenderError::Parameter(format!("distance map: {e}")))?;
        for index in 0..layers {
            let content = LayerContent::of(index);
            let (previous, rest) = self.layers.split_at_mut(index);
            let layer = &mut rest[0];
            layer.distance.resize(6 * texels, -1.0);
            layer.faces.resize_with(6, SurfaceBuffer::new);
            let floor = match content {
                LayerContent::Others(k) if k > 0 => Some(&previous[index - 1].distance[..]),
                _ => None,
            };
            let (mesh, faces) = match content {
                LayerContent::SpecularFront => (&self.specular, Faces::Front),
                LayerContent::SpecularBack => (&self.specular, Faces::Back),
                LayerContent::Others(0) => (&self.others, Faces::Front),
                LayerContent::Others(_) => (&self.others, Faces::Both),
            };
            let raster = mesh.raster();
            for face in CubeFace::ALL {
                let camera = &cameras[face as usize];
                let out = &mut layer.distance[face as usize * texels..][..texels];
                let buffer = &mut layer.faces[face as usize];
                let center = self.center;
                let floor = floor.map(|f| &f[face as usize * texels..][..texels]);
                match floor {
                    None => rasterize_bands(
                        &raster,
                        camera,
                        faces,
                        DepthTest::Nearest,
                        buffer,
                        out.par_chunks_mut(band_pixels(size)),
                        |band, out| {
                            // |p − o| = −z_view · |(s, t, 1)| at the texel centre: exact for the
                            // interpolated plane of the fragment, no attribute interpolation.
                            for row in 0..band.rows() {
                                let y = band.first_row + row;
                                let stretch = &stretch[(y * size) as usize..][..size as usize];
                                for x in 0..size {
                                    out[(row * size + x) as usize] =
                                        band.depth(x, y).map_or(-1.0, |depth| {
                                            -camera.view_z_from_depth(depth) * stretch[x as usize]
                                        });
                                }
                            }
                        },
                    ),
                    Some(floor) => {
                        let peel = PeeledFace {
                            raster: &raster,
                            camera,
                            face,
                            faces,
                            floor,
                            center,
                        };
                        rasterize_peeled(&peel, buffer, &mut self.floor_depth, out);
                    }
                }
            }
            layer.range = range_of(&layer.distance);
        }
        Ok(())
    }
}

/// One cube-map face of a peeled layer: the meshes, the face's camera and which faces are
/// drawn, the previous layer's distances (`floor`) from the reference point `center`.
#[derive(Clone, Copy)]
struct PeeledFace<'a> {
    raster: &'a crate::raster::RasterMesh<'a>,
    camera: &'a Camera,
    face: CubeFace,
    faces: Faces,
    floor: &'a [f32],
    center: Vec3,
}

/// Depth peeling of one face: the window depth of the point a relative `10⁻³` beyond the
/// previous layer's distance on each texel's centre ray (`+∞` where that layer is empty, so
/// nothing is behind it), then the nearest fragment deeper than that.
fn rasterize_peeled(
    peel: &PeeledFace<'_>,
    buffer: &mut SurfaceBuffer,
    floor_depth: &mut Vec<f32>,
    out: &mut [f32],
) {
    let PeeledFace {
        raster,
        camera,
        face,
        faces,
        floor,
        center,
    } = *peel;
    let size = camera.width();
    floor_depth.resize(floor.len(), f32::INFINITY);
    floor_depth
        .par_iter_mut()
        .zip(floor.par_iter())
        .enumerate()
        .for_each(|(i, (depth, d))| {
            *depth = if *d > 0.0 {
                let texel = UVec2::new(i as u32 % size, i as u32 / size);
                let dir = cube_texel_direction(face, texel, size).normalize();
                camera
                    .world_to_pixel(center + dir * (*d * (1.0 + PEEL_MARGIN)))
                    .map_or(f32::INFINITY, |p| p.z)
            } else {
                f32::INFINITY
            };
        });
    crate::raster::rasterize_peel_into(raster, camera, faces, floor_depth, buffer);
    out.par_iter_mut().enumerate().for_each(|(i, o)| {
        *o = buffer.texel(i).map_or(-1.0, |t| (t.p_ws - center).length());
    });
}

pub use crate::raster::PEEL_MARGIN;

fn range_of(distance: &[f32]) -> Option<(f32, f32)> {
    let (lo, hi) = distance
        .par_iter()
        .filter(|d| **d > 0.0)
        .fold(
            || (f32::INFINITY, f32::NEG_INFINITY),
            |(lo, hi), d| (lo.min(*d), hi.max(*d)),
        )
        .reduce(
            || (f32::INFINITY, f32::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    (lo <= hi).then_some((lo, hi))
}

/// The distance map of one frame with the scene whose surfaces it samples.
struct MapScene<'a> {
    map: &'a DistanceMap,
    scene: &'a Scene,
    /// The frame's wavelength ([`FrameCx::lambda_nm`]): the index of its glass.
    lambda_nm: Option<f32>,
}

/// The layers' distances, read at the nearest texel (the search of [`refract_core::distance_map::hit`]
/// runs on the map alone).
impl DistanceLayers for DistanceMap {
    fn layer_count(&self) -> usize {
        self.layers.len()
    }

    fn face_size(&self) -> u32 {
        self.size
    }

    #[inline]
    fn distance(&self, layer: usize, dir: Vec3) -> f32 {
        let Some((face, texel)) = cube_texel(dir, self.size) else {
            return -1.0;
        };
        self.layers[layer].distance[cube_texel_index(face, texel, self.size) as usize]
    }

    /// Prefetches the eight texels' cache lines: a ray's samples are texels apart in layers of
    /// megabytes.
    #[inline]
    fn prefetch_x8(&self, layer: usize, dirs: &Vec3x8) {
        let distance = &self.layers[layer].distance;
        for index in cube_texel_indices_x8(*dirs, self.size)
            .into_iter()
            .flatten()
        {
            if let Some(d) = distance.get(index as usize) {
                prefetch(d);
            }
        }
    }

    /// The eight texels located on lanes ([`cube_texel_indices_x8`]), then read.
    #[inline]
    fn distance_x8(&self, layer: usize, dirs: &Vec3x8) -> [f32; LANES] {
        let distance = &self.layers[layer].distance;
        let mut out = [-1.0; LANES];
        for (o, index) in out.iter_mut().zip(cube_texel_indices_x8(*dirs, self.size)) {
            if let Some(index) = index {
                *o = distance[index as usize];
            }
        }
        out
    }

    fn range(&self, layer: usize) -> Option<(f32, f32)> {
        self.layers[layer].range
    }

    fn two_sided(&self, layer: usize) -> bool {
        layer < 2
    }
}

impl DistanceLayers for MapScene<'_> {
    #[inline]
    fn layer_count(&self) -> usize {
        self.map.layer_count()
    }

    #[inline]
    fn face_size(&self) -> u32 {
        self.map.face_size()
    }

    #[inline]
    fn distance(&self, layer: usize, dir: Vec3) -> f32 {
        self.map.distance(layer, dir)
    }

    #[inline]
    fn prefetch_x8(&self, layer: usize, dirs: &Vec3x8) {
        self.map.prefetch_x8(layer, dirs);
    }

    #[inline]
    fn distance_x8(&self, layer: usize, dirs: &Vec3x8) -> [f32; LANES] {
        self.map.distance_x8(layer, dirs)
    }

    #[inline]
    fn range(&self, layer: usize) -> Option<(f32, f32)> {
        self.map.range(layer)
    }

    #[inline]
    fn two_sided(&self, layer: usize) -> bool {
        self.map.two_sided(layer)
    }
}

impl DistanceMapScene for MapScene<'_> {
    fn surface(&self, layer: usize, dir: Vec3) -> TexelSurface {
        let size = self.map.size;
        let empty = TexelSurface {
            normal: Vec3::Z,
            material: TexelMaterial {
                rgb: Vec3::ZERO,
                ior: 0.0,
            },
        };
        let Some((face, texel)) = cube_texel(dir, size) else {
            return empty;
        };
        let buffer = &self.map.layers[layer].faces[face as usize];
        let Some(t) = buffer.texel((texel.y * size + texel.x) as usize) else {
            return empty;
        };
        let meshes = match LayerContent::of(layer) {
            LayerContent::SpecularFront | LayerContent::SpecularBack => &self.map.specular,
            LayerContent::Others(_) => &self.map.others,
        };
        let (mesh, triangle) = meshes.source(t.triangle);
        let w = t.barycentrics;
        TexelSurface {
            normal: t.n_ws,
            material: surface_material(
                self.scene,
                self.lambda_nm,
                mesh,
                triangle,
                w,
                t.p_ws,
                t.n_ws,
            ),
        }
    }

    #[inline]
    fn background(&self, dir: Vec3) -> Vec3 {
        self.scene.environment.radiance(dir)
    }
}

/// Per-pixel outputs beside the colour.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct DistanceAov {
    covered: bool,
    hit_layer: u32,
    linear_steps: u32,
    secant_steps: u32,
    bounces: u32,
    miss: bool,
    tir: bool,
}

impl PixelLayers for DistanceAov {
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        Some(match aov {
            Aov::Covered => LayerValue::Flag(self.covered),
            Aov::Tir => LayerValue::Flag(self.tir),
            Aov::Miss => LayerValue::Flag(self.miss),
            Aov::HitLayer => LayerValue::Count(self.hit_layer),
            Aov::LinearSteps => LayerValue::Count(self.linear_steps),
            Aov::SecantSteps => LayerValue::Count(self.secant_steps),
            Aov::Bounces => LayerValue::Count(self.bounces),
            _ => return None,
        })
    }
}

impl DistanceAov {
    fn of(result: &PathResult) -> Self {
        Self {
            covered: true,
            hit_layer: result.last_layer.map_or(0, |l| l + 1),
            linear_steps: result.work.linear_steps,
            secant_steps: result.work.secant_steps,
            bounces: result.bounces,
            miss: result.miss,
            tir: result.tir,
        }
    }
}

/// The layer a surface seen from the eye lies in: the specular object's faces turned away
/// from the reference point are in the back layer, those toward it in the front layer; other
/// geometry in the first of the others.
pub fn start_layer(mesh: SceneMesh, p_ws: Vec3, n_ws: Vec3, center: Vec3) -> usize {
    match mesh {
        SceneMesh::Refractor if n_ws.dot(p_ws - center) >= 0.0 => 1,
        SceneMesh::Refractor => 0,
        SceneMesh::Object(_) => 2,
    }
}

/// The CPU passes of `distance-map`; buffers are kept between frames.
#[derive(Default)]
pub struct DistancePasses {
    map: DistanceMap,
    everything: SceneMeshes,
    camera: SurfaceBuffer,
    aovs: Vec<DistanceAov>,
}

impl DistancePasses {
    /// The distance map of the last frame.
    pub fn map(&self) -> &DistanceMap {
        &self.map
    }
}

impl CpuFamily for DistancePasses {
    type Params = DistanceMapParams;

    /// Prepares the meshes of `scene`.
    fn prepare(&mut self, scene: &Arc<Scene>) {
        self.map.prepare(scene);
        self.everything = SceneMeshes::everything(scene);
    }

    /// One frame: the distance map, the eye pass, the paths.
    fn render(
        &mut self,
        cx: &FrameCx<'_>,
        params: &DistanceMapParams,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let FrameCx {
            scene,
            camera,
            outputs,
            ..
        } = *cx;
        let (width, height) = (camera.width(), camera.height());
        let n = (width * height) as usize;
        frame.resize_for_overwrite(width, height);
        // The layers and the eye's surfaces do not depend on the index: kept for the other
        // wavelengths of a dispersive frame.
        if !cx.repeat {
            self.map
                .render(scene, params.layers as usize, params.resolution)?;
            let raster = self.everything.raster();
            rasterize_into(
                &raster,
                camera,
                Faces::Front,
                DepthTest::Nearest,
                &mut self.camera,
            );
        }
        let with_aovs = outputs == FrameOutputs::ColorAndAovs;
        self.aovs
            .resize(if with_aovs { n } else { 0 }, DistanceAov::default());
        let map_scene = MapScene {
            map: &self.map,
            scene,
            lambda_nm: cx.lambda_nm,
        };
        let eye = EyePass {
            scene,
            camera,
            buffer: &self.camera,
            everything: &self.everything,
            map: &map_scene,
            path: &params.path,
        };
        let rows = frame.color.par_chunks_mut(width as usize).enumerate();
        if with_aovs {
            rows.zip(self.aovs.par_chunks_mut(width as usize))
                .for_each(|((y, colors), aovs)| eye.row(y as u32, colors, Some(aovs)));
            frame.write_row_layers(cx.method, &self.aovs)?;
        } else {
            rows.for_each(|(y, colors)| eye.row(y as u32, colors, None));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane lookups of a rendered map are the scalar ones lane by lane, in every layer,
    /// over directions of every face (and a zero and a non-finite one).
    #[test]
    fn eight_lane_distances_equal_the_scalar_distances() {
        let scene = refract_eval::load_scene("glass-room")
            .expect("glass-room")
            .scene;
        let mut map = DistanceMap::default();
        map.prepare(&scene);
        map.render(&scene, 4, 24).expect("map");
        let lookup = MapScene {
            map: &map,
            scene: &scene,
            lambda_nm: None,
        };
        // Directions spread evenly over the sphere (a golden-angle spiral, shuffled in height
        // so that a group's lanes land on different faces).
        let spiral = |k: usize| {
            let z = (k as f32 * 0.618_034).fract() * 2.0 - 1.0;
            let (s, phi) = ((1.0 - z * z).sqrt(), k as f32 * 2.399_963);
            Vec3::new(s * phi.cos(), z, s * phi.sin())
        };
        let (mut filled, mut empty) = (0, 0);
        for group in 0..400 {
            let mut dirs: [Vec3; LANES] = core::array::from_fn(|i| spiral(group * LANES + i));
            if group == 0 {
                (dirs[0], dirs[1]) = (Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 1.0));
            }
            for layer in 0..lookup.layer_count() {
                let lanes = lookup.distance_x8(layer, &Vec3x8::from_lanes(&dirs));
                for (dir, lane) in dirs.iter().zip(lanes) {
                    let scalar = lookup.distance(layer, *dir);
                    assert_eq!(lane.to_bits(), scalar.to_bits(), "{dir} in layer {layer}");
                    if scalar > 0.0 {
                        filled += 1;
                    } else {
                        empty += 1;
                    }
                }
            }
        }
        assert!(
            filled > 1000 && empty > 100,
            "{filled} filled, {empty} empty"
        );
    }
}
