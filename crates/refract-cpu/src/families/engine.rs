//! The refraction today's engines ship, on the CPU (methods `screen-offset`,
//! `volume-thickness`, `proxy-sphere`, `proxy-box`, `proxy-thin`): two passes, as in the
//! engines — the opaque objects from the eye into the screen texture (the nearby-geometry
//! family's [`NearbyTexture`] without a guard band: colour and view depth per texel), the
//! refractor's front faces — then per pixel [`refract_core::engine::engine_path`] and the
//! colour of the texel it reads. No back faces: no engine renders them.
//!
//! Every pixel is one of: a refractor in front of the objects (the engine's refraction), an
//! object seen directly (its texel), or the environment. A scene with several refractors is
//! drawn as the engines draw several transmissive objects: each refractor's front faces, the
//! nearest one per pixel refracting with its own IOR and thickness, every one reading the
//! screen texture of the opaque objects only, so no glass is seen through another
//! (three.js's transmission pass, Filament's and Bevy's single layer).

use std::sync::Arc;

use glam::{Mat3, UVec2, Vec2, Vec3};
use rayon::prelude::*;
use refract_core::Camera;
use refract_core::engine::{EngineModel, OpaqueDepth, engine_path_x8};
use refract_core::engine_dispersion::EngineDispersion;
use refract_core::lanes::{LANES, Vec2x8, Vec3x8};
use refract_core::nearby_geometry::{NearbyGeometryTexture, view_depth};
use refract_core::vector::robust_normalize;
use refract_scene::{
    Aov, EngineParams, Environment, Frame, LayerValue, PixelLayers, RenderError, Scene,
};

use crate::buffers::front_faces_into;
use crate::family::{CpuFamily, FrameCx};
use crate::object_surfaces::{NearbyMeshes, NearbyTexel, NearbyTexture};
use crate::pixel_group::PixelGroup;
use crate::raster::SurfaceBuffer;
use crate::scene_meshes::SceneMeshes;
use crate::screen_pyramid::ScreenPyramid;

/// Per-pixel outputs beside the colour; NaN / false where they do not apply.
#[derive(Clone, Copy, Debug, PartialEq)]
struct EngineAov {
    covered: bool,
    p2: Vec3,
    t2: Vec3,
    p_geom: Vec3,
    ng_texel: Vec3,
    off_screen: bool,
}

impl EngineAov {
    const NONE: Self = Self {
        covered: false,
        p2: Vec3::NAN,
        t2: Vec3::NAN,
        p_geom: Vec3::NAN,
        ng_texel: Vec3::NAN,
        off_screen: false,
    };
}

impl PixelLayers for EngineAov {
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        Some(match aov {
            Aov::Covered => LayerValue::Flag(self.covered),
            Aov::OffScreen => LayerValue::Flag(self.off_screen),
            Aov::P2 => LayerValue::Vec3(self.p2),
            Aov::T2 => LayerValue::Vec3(self.t2),
            Aov::PGeom => LayerValue::Vec3(self.p_geom),
            Aov::NgTexel => LayerValue::Vec3(self.ng_texel),
            _ => return None,
        })
    }
}

/// The screen texture's depths as the engines' lookups read them (`None`: no objects).
struct ScreenDepth<'a>(Option<&'a NearbyTexture>);

impl OpaqueDepth for ScreenDepth<'_> {
    #[inline]
    fn view_depth(&self, texel: UVec2) -> f32 {
        self.0
            .and_then(|t| t.surface(texel))
            .map_or(f32::INFINITY, |s| s.depth)
    }
}

/// The passes of the engine methods, with their memory kept between frames.
#[derive(Default)]
pub struct EnginePasses {
    meshes: NearbyMeshes,
    /// Refractor `k`'s nearest front faces in `fronts[k]`.
    fronts: Vec<SurfaceBuffer>,
    /// Refractor `k`'s model, IOR, dispersion and rough parameter.
    refractors: Vec<RefractorModel>,
    screen: NearbyTexture,
    /// The screen texture's colours, mip-mapped, for rough refractors.
    mips: ScreenPyramid,
    aovs: Vec<EngineAov>,
}

/// What [`EnginePasses::mixed_lookups`] reads for eight pixels: the refractor's dispersion,
/// index, model and rough reads, and the pixels' centres and front surfaces.
struct Lookups<'a> {
    dispersion: EngineDispersion,
    ior: f32,
    uv: &'a [Vec2; LANES],
    p1: &'a [Vec3; LANES],
    n1: &'a [Vec3; LANES],
    model: EngineModel,
    rough: Option<Rough>,
}

/// A rough refractor's blurred reads in row `y`: its model and LOD.
#[derive(Clone, Copy, Debug)]
struct Rough {
    model: EngineModel,
    lod: f32,
    y: u32,
}

/// How one refractor is drawn: its engine model, IOR, dispersion
/// ([`EngineModel::dispersion`]) and how its roughness blurs the screen
/// ([`EngineModel::rough_lod`]: a LOD, Bevy's roughness; 0: the nearest texel).
#[derive(Clone, Copy, Debug)]
struct RefractorModel {
    model: EngineModel,
    ior: f32,
    dispersion: EngineDispersion,
    lod: f32,
}

impl CpuFamily for EnginePasses {
    type Params = EngineParams;

    fn prepare(&mut self, scene: &Arc<Scene>) {
        self.meshes = SceneMeshes::objects(scene);
    }

    fn render(
        &mut self,
        cx: &FrameCx<'_>,
        params: &EngineParams,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let FrameCx { scene, camera, .. } = *cx;
        self.refractors.clear();
        self.refractors.extend(scene.refractors().map(|r| {
            let model = params.model(r);
            let dispersion = if r.is_dispersive() {
                model.dispersion(r.ior(), r.abbe())
            } else {
                EngineDispersion::None
            };
            RefractorModel {
                model,
                ior: r.ior(),
                dispersion,
                lod: model.rough_lod(camera, r.roughness(), r.ior()),
            }
        }));
        // Without opaque objects the screen texture is the environment everywhere: not drawn.
        let screen = (!scene.objects.is_empty()).then(|| {
            self.screen.render_into(scene, &self.meshes, camera);
            &self.screen
        });
        // The blurred screen exists where a refractor is rough: the objects, or the environment
        // along each texel's eye ray (the engines draw the sky into the texture).
        let size = glam::UVec2::new(camera.width(), camera.height());
        let levels = self
            .refractors
            .iter()
            .map(|r| r.model.rough_levels(r.lod, size))
            .max()
            .unwrap_or(0);
        let rough = levels > 0;
        if rough {
            self.mips.build(size, levels, |texel| {
                match screen.and_then(|s| s.texel(texel)) {
                    Some(t) => t.color,
                    None => scene
                        .environment
                        .radiance(camera.pixel_ray(Camera::pixel_center(texel.x, texel.y)).dir),
                }
            });
        }
        self.fronts
            .resize_with(scene.refractor_count(), SurfaceBuffer::default);
        for (refractor, front) in scene.refractors().zip(&mut self.fronts) {
            front_faces_into(refractor, camera, front);
        }
        let (width, height) = (camera.width(), camera.height());
        let n = (width * height) as usize;
        frame.resize_for_overwrite(width, height);
        let pixels = PixelContext {
            scene,
            camera,
            refractors: &self.refractors,
            fronts: &self.fronts,
            screen,
            mips: rough.then_some(&self.mips),
        };
        let rows = frame.color.par_chunks_mut(width as usize).enumerate();
        if cx.with_aovs() {
            self.aovs.clear();
            self.aovs.resize(n, EngineAov::NONE);
            rows.zip(self.aovs.par_chunks_mut(width as usize))
                .for_each(|((y, colors), aovs)| pixels.row(y as u32, colors, Some(aovs)));
            frame.write_row_layers(cx.method, &self.aovs[..n])?;
        } else {
            // Colour only, as displayed: no per-pixel AOV memory is touched.
            rows.for_each(|(y, colors)| pixels.row(y as u32, colors, None));
        }
        Ok(())
    }
}

/// What the per-pixel work reads.
struct PixelContext<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    /// How refractor `k` is drawn.
    refractors: &'a [RefractorModel],
    /// Refractor `k`'s front faces.
    fronts: &'a [SurfaceBuffer],
    /// The opaque objects' screen texture; `None` for a scene without objects.
    screen: Option<&'a NearbyTexture>,
    /// The screen's colours mip-mapped, where a refractor is rough.
    mips: Option<&'a ScreenPyramid>,
}

impl PixelContext<'_> {
    /// Row `y`: pixels that see an object or the environment directly at once, each
    /// refractor's pixels eight at a time through [`engine_path_x8`] (bit-identical to the
    /// scalar path), the environment lookups eight at a time ([`EnvironmentLanes`]).
    fn row(&self, y: u32, colors: &mut [Vec3], aovs: Option<&mut [EngineAov]>) {
        // The number of refractors decided once a row, not at every pixel: each case is its own
        // copy of the loop (asked per pixel, the row loop took 8.3 % of the engine bench's CPU
        // time on one-refractor scenes; once a row, 5.8 %).
        match self.fronts {
            [front] => self.row_with(y, colors, aovs, |index, texel| {
                // Its depth only where an object is there to test against.
                let drawn = front.is_covered(index)
                    && self.before_objects(texel, || self.front_depth(front, index));
                drawn.then_some(0)
            }),
            _ => self.row_with(y, colors, aovs, |index, texel| {
                self.refractor_at(index, texel)
            }),
        }
    }

    /// [`Self::row`] with `refractor_at` telling the refractor drawn at a pixel.
    #[inline(always)]
    fn row_with(
        &self,
        y: u32,
        colors: &mut [Vec3],
        mut aovs: Option<&mut [EngineAov]>,
        refractor_at: impl Fn(usize, UVec2) -> Option<usize>,
    ) {
        let mut lanes = EnvironmentLanes::new(&self.scene.environment, self.camera);
        let mut group = PixelGroup::new();
        // The refractor of the pixels in `group`.
        let mut group_refractor = 0;
        for x in 0..colors.len() as u32 {
            colors[x as usize] = Vec3::ZERO;
            let index = (y * self.camera.width() + x) as usize;
            let texel = UVec2::new(x, y);
            match refractor_at(index, texel) {
                Some(k) => {
                    if group.len > 0 && k != group_refractor {
                        group.pad();
                        self.refractor(
                            &group,
                            group_refractor,
                            y,
                            colors,
                            &mut lanes,
                            aovs.as_deref_mut(),
                        );
                        group.len = 0;
                    }
                    group_refractor = k;
                    if group.push(x) {
                        self.refractor(&group, k, y, colors, &mut lanes, aovs.as_deref_mut());
                        group.len = 0;
                    }
                }
                None => {
                    self.screen(x, texel, Vec3::ONE, colors, &mut lanes);
                    if let Some(aovs) = aovs.as_deref_mut() {
                        aovs[x as usize] = EngineAov::NONE;
                    }
                }
            }
        }
        if group.len > 0 {
            group.pad();
            self.refractor(&group, group_refractor, y, colors, &mut lanes, aovs);
        }
        lanes.flush(colors);
    }

    /// The refractor drawn at pixel `index` (texel `texel`): the nearest of those covering it,
    /// where it is in front of any object there. Surfaces are reconstructed here only for these
    /// depth tests (else eight at a time in [`Self::refractor`]).
    #[inline]
    fn refractor_at(&self, index: usize, texel: UVec2) -> Option<usize> {
        let (nearest, nearest_depth) = self
            .fronts
            .iter()
            .enumerate()
            .filter(|(_, f)| f.is_covered(index))
            .map(|(k, f)| (k, self.front_depth(f, index)))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        self.before_objects(texel, || nearest_depth)
            .then_some(nearest)
    }

    /// The view depth of `front`'s surface at pixel `index` (infinite where it has none).
    #[inline]
    fn front_depth(&self, front: &SurfaceBuffer, index: usize) -> f32 {
        front
            .texel(index)
            .map_or(f32::INFINITY, |f| view_depth(self.camera, f.p_ws))
    }

    /// Whether a surface at view depth `depth()` is nearer than any object drawn at `texel`
    /// (`depth` is asked only where one is).
    #[inline]
    fn before_objects(&self, texel: UVec2, depth: impl FnOnce() -> f32) -> bool {
        self.object(texel).is_none_or(|o| depth() < o.surface.depth)
    }

    /// Eight pixels of row `y` where refractor `k` is drawn (padding repeats lane 0): their
    /// front surfaces eight at a time (bit-identical to one at a time), the engine's path with
    /// refractor `k`'s model and IOR, then its reads; a dispersive model
    /// ([`EngineModel::dispersion`]) takes one path per lookup at the lookup's index, the AOVs
    /// from [`EngineDispersion::aov_lookup`]'s: three.js's reads each channel from its own,
    /// Filament's mixes its four full reads by their matrices ([`Self::mixed_lookups`]).
    fn refractor(
        &self,
        group: &PixelGroup,
        k: usize,
        y: u32,
        colors: &mut [Vec3],
        lanes: &mut EnvironmentLanes<'_>,
        mut aovs: Option<&mut [EngineAov]>,
    ) {
        let fronts = self.fronts[k].texels_x8(&group.x, y);
        let RefractorModel {
            model,
            ior,
            dispersion,
            lod,
        } = self.refractors[k];
        let (mut p1, mut n1) = ([Vec3::ZERO; LANES], [Vec3::Z; LANES]);
        for (i, f) in fronts.iter().enumerate() {
            p1[i] = f.p_ws;
            n1[i] = robust_normalize(f.n_ws).unwrap_or(f.n_ws);
        }
        let (p1, n1) = (&p1, &n1);
        let uv: [Vec2; LANES] = core::array::from_fn(|i| Camera::pixel_center(group.x[i], y));
        let rough = (lod > 0.0).then_some(Rough { model, lod, y });
        if !dispersion.is_diagonal() {
            let lookups = Lookups {
                dispersion,
                ior,
                uv: &uv,
                p1,
                n1,
                model,
                rough,
            };
            self.mixed_lookups(group, &lookups, colors, lanes, aovs);
            return;
        }
        for j in 0..dispersion.lookups() {
            // Diagonal schemes: the index is the pixel's own only through the jitter, which
            // they have not.
            let (lookup_ior, matrix) = dispersion.lookup(ior, j, uv[0]);
            let channels = Vec3::new(matrix.x_axis.x, matrix.y_axis.y, matrix.z_axis.z);
            let paths = engine_path_x8(
                self.camera,
                &ScreenDepth(self.screen),
                &uv,
                p1,
                n1,
                &[lookup_ior; LANES],
                model,
            );
            let aovs = if j == dispersion.aov_lookup() {
                aovs.as_deref_mut()
            } else {
                None
            };
            self.read_paths(group, &paths, p1, channels, rough, colors, lanes, aovs);
        }
    }

    /// Filament's dispersion ([`EngineDispersion::Filament`]) for the pixels of `group`: each
    /// of its lookups read in full (the pixel's own jittered index), flushed, multiplied by the
    /// lookup's matrix and summed in the lookups' order; the sum clamped at 0 and added to
    /// what the pixels held.
    fn mixed_lookups(
        &self,
        group: &PixelGroup,
        l: &Lookups<'_>,
        colors: &mut [Vec3],
        lanes: &mut EnvironmentLanes<'_>,
        mut aovs: Option<&mut [EngineAov]>,
    ) {
        lanes.flush(colors);
        let pixels = &group.x[..group.len];
        let held: [Vec3; LANES] =
            core::array::from_fn(|i| pixels.get(i).map_or(Vec3::ZERO, |&x| colors[x as usize]));
        let mut mixed = [Vec3::ZERO; LANES];
        for j in 0..l.dispersion.lookups() {
            let mut iors = [l.ior; LANES];
            let mut matrix = Mat3::IDENTITY;
            for (i, uv) in l.uv.iter().enumerate() {
                (iors[i], matrix) = l.dispersion.lookup(l.ior, j, *uv);
            }
            let screen = ScreenDepth(self.screen);
            let paths = engine_path_x8(self.camera, &screen, l.uv, l.p1, l.n1, &iors, l.model);
            for &x in pixels {
                colors[x as usize] = Vec3::ZERO;
            }
            let aovs = if j == l.dispersion.aov_lookup() {
                aovs.as_deref_mut()
            } else {
                None
            };
            self.read_paths(group, &paths, l.p1, Vec3::ONE, l.rough, colors, lanes, aovs);
            lanes.flush(colors);
            for (sum, &x) in mixed.iter_mut().zip(pixels) {
                *sum += matrix * colors[x as usize];
            }
        }
        for ((&x, held), sum) in pixels.iter().zip(held).zip(mixed) {
            colors[x as usize] = held + sum.max(Vec3::ZERO);
        }
    }

    /// Adds the reads of `paths` (lane `i` for pixel `group.x[i]`) times `channels` to the
    /// pixels' colours, and their AOVs when asked. On a `rough` refractor the screen is read
    /// blurred, as its model reads the mip-mapped screen ([`EngineModel::read_rough`]; the AOVs
    /// still name the nearest texel).
    #[allow(clippy::too_many_arguments)]
    fn read_paths(
        &self,
        group: &PixelGroup,
        paths: &[refract_core::engine::EnginePath; LANES],
        p1: &[Vec3; LANES],
        channels: Vec3,
        rough: Option<Rough>,
        colors: &mut [Vec3],
        lanes: &mut EnvironmentLanes<'_>,
        mut aovs: Option<&mut [EngineAov]>,
    ) {
        for ((&x, path), p1) in group.x.iter().zip(paths).zip(p1).take(group.len) {
            let mut aov = EngineAov {
                covered: true,
                p2: path.p2,
                t2: path.t2,
                off_screen: path.off_screen,
                ..EngineAov::NONE
            };
            if path.screen_weight > 0.0
                && let Some(t) = self.object(path.texel)
            {
                aov.p_geom = t.surface.p_ws;
                aov.ng_texel = Vec3::new(path.texel.x as f32, path.texel.y as f32, t.object as f32);
            }
            let (screen_weight, environment_dir) = match (self.mips, rough) {
                (Some(mips), Some(r)) => {
                    let uv_px = Camera::pixel_center(x, r.y);
                    let screen = ScreenDepth(self.screen);
                    let read =
                        r.model
                            .read_rough(self.camera, mips, &screen, uv_px, *p1, path, r.lod);
                    if read.screen_weight > 0.0 {
                        colors[x as usize] += read.screen_weight * channels * read.color;
                    }
                    (read.screen_weight, read.environment_dir)
                }
                _ => {
                    if path.screen_weight > 0.0 {
                        let weight = path.screen_weight * channels;
                        self.screen(x, path.texel, weight, colors, lanes);
                    }
                    (path.screen_weight, path.environment_dir)
                }
            };
            if screen_weight < 1.0 {
                let weight = (1.0 - screen_weight) * channels;
                lanes.push(x, environment_dir, weight, colors);
            }
            if let Some(aovs) = aovs.as_deref_mut() {
                aovs[x as usize] = aov;
            }
        }
    }

    /// The object drawn at screen texel `texel`, if any.
    #[inline]
    fn object(&self, texel: UVec2) -> Option<NearbyTexel> {
        self.screen.and_then(|s| s.texel(texel))
    }

    /// Adds the screen texture at `texel` times `weight` to pixel `x`: the object drawn there,
    /// or the environment along the texel's eye ray (the engines draw the sky before the
    /// glass), queued in `lanes`.
    #[inline]
    fn screen(
        &self,
        x: u32,
        texel: UVec2,
        weight: Vec3,
        colors: &mut [Vec3],
        lanes: &mut EnvironmentLanes<'_>,
    ) {
        match self.object(texel) {
            Some(t) => colors[x as usize] += weight * t.color,
            None => lanes.push_texel(x, texel, weight, colors),
        }
    }
}

/// Environment lookups of one row queued eight at a time: `colors[x] += weight · L(dir)`,
/// added in the order they were queued (so a pixel's screen term precedes its fallback, as
/// on the GPU). A request is a direction, or a screen texel whose eye ray is the direction
/// (computed eight at a time, [`Camera::pixel_ray_dir_x8`], bit-identical to the scalar ray).
struct EnvironmentLanes<'a> {
    environment: &'a Environment,
    camera: &'a Camera,
    x: [u32; LANES],
    dirs: [Vec3; LANES],
    texels: [Option<Vec2>; LANES],
    weights: [Vec3; LANES],
    len: usize,
}

impl<'a> EnvironmentLanes<'a> {
    fn new(environment: &'a Environment, camera: &'a Camera) -> Self {
        Self {
            environment,
            camera,
            x: [0; LANES],
            dirs: [Vec3::Z; LANES],
            texels: [None; LANES],
            weights: [Vec3::ZERO; LANES],
            len: 0,
        }
    }

    /// Queues `weight · L(dir)` for pixel `x`.
    #[inline]
    fn push(&mut self, x: u32, dir: Vec3, weight: Vec3, colors: &mut [Vec3]) {
        self.queue(x, dir, None, weight, colors);
    }

    /// Queues `weight · L(eye ray through the centre of texel)` for pixel `x`.
    #[inline]
    fn push_texel(&mut self, x: u32, texel: UVec2, weight: Vec3, colors: &mut [Vec3]) {
        let uv = Camera::pixel_center(texel.x, texel.y);
        self.queue(x, Vec3::Z, Some(uv), weight, colors);
    }

    #[inline]
    fn queue(&mut self, x: u32, dir: Vec3, texel: Option<Vec2>, weight: Vec3, colors: &mut [Vec3]) {
        self.x[self.len] = x;
        self.dirs[self.len] = dir;
        self.texels[self.len] = texel;
        self.weights[self.len] = weight;
        self.len += 1;
        if self.len == LANES {
            self.flush(colors);
        }
    }

    fn flush(&mut self, colors: &mut [Vec3]) {
        if self.len == 0 {
            return;
        }
        if self.texels[..self.len].iter().any(Option::is_some) {
            let uv: [Vec2; LANES] =
                core::array::from_fn(|i| self.texels[i].unwrap_or(Vec2::splat(0.5)));
            let rays = self
                .camera
                .pixel_ray_dir_x8(Vec2x8::from_lanes(&uv))
                .to_lanes();
            let queued = self.texels.iter().zip(&mut self.dirs).zip(rays);
            for ((texel, dir), ray) in queued.take(self.len) {
                if texel.is_some() {
                    *dir = ray;
                }
            }
        }
        let first = self.dirs[0];
        self.dirs[self.len..].fill(first);
        let radiance = self
            .environment
            .radiance_x8(Vec3x8::from_lanes(&self.dirs))
            .to_lanes();
        for i in 0..self.len {
            colors[self.x[i] as usize] += self.weights[i] * radiance[i];
        }
        self.len = 0;
    }
}
