//! Refraction through any number of interfaces on the CPU (method `depth-peel`): the opaque
//! objects from the eye into the screen texture (the engine family's), the surfaces of every
//! refractor, both orientations, depth-peeled into `K` layers (Everitt 2001: layer `k` is the
//! nearest fragment farther from the eye than layer `k − 1`'s by more than the relative
//! [`PEEL_MARGIN`], the distance maps' rule), unpacked into view depth, normal, refractor and
//! the fragment's plane facing away from the eye per layer and texel (the march's one read per
//! layer and sample: a 16-byte load and a dot product; the opaque objects' texels likewise);
//! then per pixel [`refract_core::depth_peel::peel_path`] from the nearest layer and the colour
//! it ends on, times its transmittance.

use std::sync::Arc;

use glam::{UVec2, Vec3, Vec4};
use rayon::prelude::*;
use refract_core::Camera;
use refract_core::depth_peel::{
    PeelEnd, PeelMedium, PeelSettings, PeeledLayers, facing_plane, peel_path,
};
use refract_core::nearby_geometry::{NearbyGeometryTexture, view_depth};
use refract_scene::{Aov, DepthPeelParams, Frame, LayerValue, PixelLayers, RenderError, Scene};

use crate::family::{CpuFamily, FrameCx};
use crate::object_surfaces::{NearbyMeshes, NearbyTexture};
use crate::raster::{
    DepthInterpolation, DepthTest, Faces, PEEL_MARGIN, RasterMesh, SurfaceBuffer, rasterize_into,
    rasterize_peel_into,
};
use crate::scene_meshes::SceneMeshes;

/// Every refractor's mesh as one, and the first triangle of each refractor.
#[derive(Default)]
struct RefractorMeshes {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    first_triangle: Vec<u32>,
}

impl RefractorMeshes {
    fn of(scene: &Scene) -> Self {
        let mut meshes = Self::default();
        for refractor in scene.refractors() {
            let mesh = refractor.mesh();
            let base = meshes.positions.len() as u32;
            meshes.first_triangle.push(meshes.triangles.len() as u32);
            meshes.positions.extend_from_slice(&mesh.positions);
            meshes.normals.extend_from_slice(&mesh.normals);
            meshes
                .triangles
                .extend(mesh.triangles.iter().map(|t| t.map(|v| v + base)));
        }
        meshes
    }

    fn raster(&self) -> RasterMesh<'_> {
        RasterMesh {
            positions: &self.positions,
            normals: &self.normals,
            scalars: &[],
            triangles: &self.triangles,
            depth: DepthInterpolation::Exact,
        }
    }

    /// The refractor of combined triangle `triangle`.
    fn refractor_of(&self, triangle: u32) -> u32 {
        (self.first_triangle.partition_point(|&f| f <= triangle) - 1) as u32
    }
}

/// The peeled layers of one frame, unpacked texel by texel: layer `k` of pixel `i` at
/// `i · count + k`, so that the layers a march sample reads share a cache line.
#[derive(Default)]
struct Layers {
    width: u32,
    count: u32,
    /// View depth, `+∞` where the layer is empty.
    depth: Vec<f32>,
    /// World position (layer 0 starts the paths).
    p_ws: Vec<Vec3>,
    /// Unit shading normal.
    n_ws: Vec<Vec3>,
    /// The fragment's plane facing away from the eye (`facing_plane`), NaN where empty.
    planes: Vec<Vec4>,
    refractor: Vec<u8>,
}

/// The layers and the screen texture as [`peel_path`] reads them.
struct LayerView<'a> {
    layers: &'a Layers,
    screen: Option<&'a NearbyTexture>,
    /// The plane of each screen texel's surface facing away from the eye, NaN where empty.
    screen_planes: &'a [Vec4],
}

impl LayerView<'_> {
    #[inline]
    fn index(&self, texel: UVec2, layer: u32) -> usize {
        (texel.y * self.layers.width + texel.x) as usize * self.layers.count as usize
            + layer as usize
    }
}

impl PeeledLayers for LayerView<'_> {
    #[inline]
    fn layer_plane(&self, texel: UVec2, layer: u32) -> Vec4 {
        if layer >= self.layers.count {
            return Vec4::NAN;
        }
        self.layers.planes[self.index(texel, layer)]
    }

    #[inline]
    fn layer_normal(&self, texel: UVec2, layer: u32) -> Vec3 {
        self.layers.n_ws[self.index(texel, layer)]
    }

    #[inline]
    fn layer_refractor(&self, texel: UVec2, layer: u32) -> u32 {
        u32::from(self.layers.refractor[self.index(texel, layer)])
    }

    #[inline]
    fn opaque_plane(&self, texel: UVec2) -> Vec4 {
        if self.screen.is_none() {
            return Vec4::NAN;
        }
        self.screen_planes[(texel.y * self.layers.width + texel.x) as usize]
    }
}

impl LayerView<'_> {
    /// The view depth of the opaque objects at `texel`, `+∞` where none is drawn.
    #[inline]
    fn opaque_depth(&self, texel: UVec2) -> f32 {
        self.screen
            .and_then(|s| s.surface(texel))
            .map_or(f32::INFINITY, |s| s.depth)
    }
}

/// Per-pixel outputs beside the colour; NaN / false / 0 where they do not apply.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PeelAov {
    covered: bool,
    p2: Vec3,
    t2: Vec3,
    t_out: Vec3,
    p_geom: Vec3,
    interfaces: u32,
    refractors_met: u32,
    tir: bool,
    off_screen: bool,
    miss: bool,
}

impl PeelAov {
    const NONE: Self = Self {
        covered: false,
        p2: Vec3::NAN,
        t2: Vec3::NAN,
        t_out: Vec3::NAN,
        p_geom: Vec3::NAN,
        interfaces: 0,
        refractors_met: 0,
        tir: false,
        off_screen: false,
        miss: false,
    };
}

impl PixelLayers for PeelAov {
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        Some(match aov {
            Aov::Covered => LayerValue::Flag(self.covered),
            Aov::P2 => LayerValue::Vec3(self.p2),
            Aov::T2 => LayerValue::Vec3(self.t2),
            Aov::TOut => LayerValue::Vec3(self.t_out),
            Aov::PGeom => LayerValue::Vec3(self.p_geom),
            Aov::Interfaces => LayerValue::Count(self.interfaces),
            Aov::RefractorsMet => LayerValue::Count(self.refractors_met),
            Aov::Tir => LayerValue::Flag(self.tir),
            Aov::OffScreen => LayerValue::Flag(self.off_screen),
            Aov::Miss => LayerValue::Flag(self.miss),
            _ => return None,
        })
    }
}

/// The passes of `depth-peel`, with their memory kept between frames.
#[derive(Default)]
pub struct DepthPeelPasses {
    refractors: RefractorMeshes,
    objects: NearbyMeshes,
    screen: NearbyTexture,
    screen_normals: Vec<Vec3>,
    screen_planes: Vec<Vec4>,
    peeled: Vec<SurfaceBuffer>,
    floor: Vec<f32>,
    layers: Layers,
    aovs: Vec<PeelAov>,
}

impl DepthPeelPasses {
    /// Peels `count` layers of every refractor seen by `camera` and unpacks them.
    fn peel(&mut self, camera: &Camera, count: u32) {
        let (width, height) = (camera.width(), camera.height());
        let pixels = (width * height) as usize;
        let raster = self.refractors.raster();
        self.peeled
            .resize_with(count as usize, SurfaceBuffer::default);
        let layers = &mut self.layers;
        layers.width = width;
        layers.count = count;
        let total = pixels * count as usize;
        layers.depth.resize(total, f32::INFINITY);
        layers.p_ws.resize(total, Vec3::ZERO);
        layers.n_ws.resize(total, Vec3::Z);
        layers.planes.resize(total, Vec4::NAN);
        layers.refractor.resize(total, 0);
        let eye = camera.eye();
        for k in 0..count as usize {
            let buffer = &mut self.peeled[k];
            if k == 0 {
                rasterize_into(&raster, camera, Faces::Both, DepthTest::Nearest, buffer);
            } else {
                let stride = count as usize;
                let (previous, previous_depth) = (&layers.p_ws, &layers.depth);
                self.floor.resize(pixels, f32::INFINITY);
                self.floor
                    .par_iter_mut()
                    .enumerate()
                    .for_each(|(i, floor)| {
                        let at = i * stride + k - 1;
                        *floor = if previous_depth[at].is_finite() {
                            camera
                                .world_to_pixel(eye + (previous[at] - eye) * (1.0 + PEEL_MARGIN))
                                .map_or(f32::INFINITY, |q| q.z)
                        } else {
                            f32::INFINITY
                        };
                    });
                rasterize_peel_into(&raster, camera, Faces::Both, &self.floor, buffer);
            }
            let buffer = &self.peeled[k];
            let refractors = &self.refractors;
            let stride = count as usize;
            layers
                .depth
                .par_chunks_mut(stride)
                .zip(layers.p_ws.par_chunks_mut(stride))
                .zip(layers.n_ws.par_chunks_mut(stride))
                .zip(layers.planes.par_chunks_mut(stride))
                .zip(layers.refractor.par_chunks_mut(stride))
                .enumerate()
                .for_each(|(i, ((((depth, p), n), plane), r))| match buffer.texel(i) {
                    Some(t) => {
                        depth[k] = view_depth(camera, t.p_ws);
                        p[k] = t.p_ws;
                        n[k] = t.n_ws;
                        plane[k] = facing_plane(t.p_ws, t.n_ws, eye);
                        r[k] = refractors.refractor_of(t.triangle) as u8;
                    }
                    None => {
                        depth[k] = f32::INFINITY;
                        plane[k] = Vec4::NAN;
                    }
                });
        }
    }
}

impl CpuFamily for DepthPeelPasses {
    type Params = DepthPeelParams;

    fn prepare(&mut self, scene: &Arc<Scene>) {
        self.refractors = RefractorMeshes::of(scene);
        self.objects = SceneMeshes::objects(scene);
    }

    fn render(
        &mut self,
        cx: &FrameCx<'_>,
        params: &DepthPeelParams,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let FrameCx { scene, camera, .. } = *cx;
        // The peeled layers and the objects' surfaces (with their planes) do not depend on the
        // index: kept for the other wavelengths of a dispersive frame.
        let repeat = cx.repeat;
        let screen = (!scene.objects.is_empty()).then(|| {
            if repeat {
                return;
            }
            self.screen.render_into(scene, &self.objects, camera);
            self.screen.normals_into(&mut self.screen_normals);
            let (screen, eye, width) = (&self.screen, camera.eye(), camera.width());
            self.screen_planes
                .resize(self.screen_normals.len(), Vec4::NAN);
            self.screen_planes
                .par_iter_mut()
                .zip(&self.screen_normals)
                .enumerate()
                .for_each(|(i, (plane, n))| {
                    let texel = UVec2::new(i as u32 % width, i as u32 / width);
                    *plane = screen
                        .surface(texel)
                        .map_or(Vec4::NAN, |s| facing_plane(s.p_ws, *n, eye));
                });
        });
        if !repeat {
            self.peel(camera, params.layers);
        }
        let media = params.media(scene, cx.lambda_nm);
        let pixels = PixelContext {
            scene,
            camera,
            view: LayerView {
                layers: &self.layers,
                screen: screen.map(|()| &self.screen),
                screen_planes: &self.screen_planes,
            },
            media: &media,
            settings: params.settings(scene),
        };
        let (width, height) = (camera.width(), camera.height());
        let n = (width * height) as usize;
        frame.resize_for_overwrite(width, height);
        self.aovs.clear();
        self.aovs.resize(n, PeelAov::NONE);
        frame
            .color
            .par_chunks_mut(width as usize)
            .zip(self.aovs.par_chunks_mut(width as usize))
            .enumerate()
            .for_each(|(y, (colors, aovs))| {
                for (x, (color, aov)) in colors.iter_mut().zip(aovs).enumerate() {
                    (*color, *aov) = pixels.pixel(UVec2::new(x as u32, y as u32));
                }
            });
        if cx.with_aovs() {
            frame.write_row_layers(cx.method, &self.aovs[..n])?;
        }
        Ok(())
    }
}

/// What the per-pixel work reads.
struct PixelContext<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    view: LayerView<'a>,
    media: &'a [PeelMedium],
    settings: PeelSettings,
}

impl PixelContext<'_> {
    /// Pixel `texel`: the path from its nearest refractor surface where that is in front of
    /// any object, else what the screen texture shows there.
    fn pixel(&self, texel: UVec2) -> (Vec3, PeelAov) {
        let layers = self.view.layers;
        // Layer 0 of the pixel.
        let i = self.view.index(texel, 0);
        let depth = layers.depth[i];
        // +∞ for an empty layer and where no object is drawn: never NaN.
        if depth >= self.view.opaque_depth(texel) {
            return (self.screen(texel), PeelAov::NONE);
        }
        let path = peel_path(
            self.camera,
            &self.view,
            self.media,
            &self.settings,
            layers.p_ws[i],
            layers.n_ws[i],
            u32::from(layers.refractor[i]),
        );
        let (color, p_geom) = match path.opaque {
            Some((texel, p)) => (self.screen(texel), p),
            None => (self.scene.environment.radiance(path.dir), Vec3::NAN),
        };
        let aov = PeelAov {
            covered: true,
            p2: path.first_exit.map_or(Vec3::NAN, |(p, _)| p),
            t2: path.first_exit.map_or(Vec3::NAN, |(_, t)| t),
            t_out: path.dir,
            p_geom,
            interfaces: path.interfaces,
            refractors_met: path.refractors_met,
            tir: path.reflections > 0,
            off_screen: path.end == PeelEnd::OffScreen,
            miss: path.end == PeelEnd::Lost,
        };
        (path.transmittance * color, aov)
    }

    /// What the screen texture shows at `texel`: the object drawn there, or the environment
    /// along the texel's eye ray.
    fn screen(&self, texel: UVec2) -> Vec3 {
        match self.view.screen.and_then(|s| s.texel(texel)) {
            Some(t) => t.color,
            None => {
                let ray = self
                    .camera
                    .pixel_ray(Camera::pixel_center(texel.x, texel.y));
                self.scene.environment.radiance(ray.dir)
            }
        }
    }
}
