//! The refraction today's engines ship, on the CPU (methods `screen-offset`,
//! `volume-thickness`, `proxy-sphere`, `proxy-box`, `proxy-thin`): two passes, as in the
//! engines — the opaque objects from the eye into the screen texture (the nearby-geometry
//! family's [`NearbyTexture`] without a guard band: colour and view depth per texel), the
//! refractor's front faces — then per pixel [`refract_core::engine::engine_path`] and the
//! colour of the texel it reads. No back faces: no engine renders them.
//!
//! Every pixel is one of: the refractor in front of the objects (the engine's refraction), an
//! object seen directly (its texel), or the environment.

use std::sync::Arc;

use glam::{UVec2, Vec3};
use rayon::prelude::*;
use refract_core::Camera;
use refract_core::engine::{EngineModel, OpaqueDepth, engine_path};
use refract_core::nearby_geometry::{NearbyGeometryTexture, view_depth};
use refract_core::vector::robust_normalize;
use refract_scene::{Aov, EngineParams, Frame, LayerValue, PixelLayers, RenderError, Scene};

use super::nearby_geometry::{NearbyMeshes, NearbyTexture};
use crate::buffers::front_faces_into;
use crate::family::{CpuFamily, FrameCx};
use crate::raster::SurfaceBuffer;
use crate::scene_meshes::SceneMeshes;

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

/// The screen texture's depths as the engines' lookups read them.
struct ScreenDepth<'a>(&'a NearbyTexture);

impl OpaqueDepth for ScreenDepth<'_> {
    #[inline]
    fn view_depth(&self, texel: UVec2) -> f32 {
        self.0.surface(texel).map_or(f32::INFINITY, |s| s.depth)
    }
}

/// The passes of the engine methods, with their memory kept between frames.
#[derive(Default)]
pub struct EnginePasses {
    meshes: NearbyMeshes,
    front: SurfaceBuffer,
    screen: NearbyTexture,
    aovs: Vec<EngineAov>,
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
        let model = params.model(&scene.refractor);
        self.screen.render_into(scene, &self.meshes, camera);
        front_faces_into(&scene.refractor, camera, &mut self.front);
        let (width, height) = (camera.width(), camera.height());
        let n = (width * height) as usize;
        frame.resize_for_overwrite(width, height);
        let pixels = PixelContext {
            scene,
            camera,
            model,
            front: &self.front,
            screen: &self.screen,
        };
        let rows = frame.color.par_chunks_mut(width as usize).enumerate();
        if cx.with_aovs() {
            self.aovs.clear();
            self.aovs.resize(n, EngineAov::NONE);
            rows.zip(self.aovs.par_chunks_mut(width as usize))
                .for_each(|((y, colors), aovs)| {
                    for (x, (c, a)) in colors.iter_mut().zip(aovs).enumerate() {
                        (*c, *a) = pixels.pixel(x as u32, y as u32);
                    }
                });
            frame.write_row_layers(cx.method, &self.aovs[..n])?;
        } else {
            rows.for_each(|(y, colors)| {
                for (x, c) in colors.iter_mut().enumerate() {
                    *c = pixels.pixel(x as u32, y as u32).0;
                }
            });
        }
        Ok(())
    }
}

/// What the per-pixel work reads.
struct PixelContext<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    model: EngineModel,
    front: &'a SurfaceBuffer,
    screen: &'a NearbyTexture,
}

impl PixelContext<'_> {
    /// The screen texture at `texel`: the object drawn there, or the environment along that
    /// texel's eye ray (the engines draw the sky before the glass).
    #[inline]
    fn screen_color(&self, texel: UVec2) -> Vec3 {
        match self.screen.texel(texel) {
            Some(t) => t.color,
            None => {
                let dir = self
                    .camera
                    .pixel_ray(Camera::pixel_center(texel.x, texel.y))
                    .dir;
                self.scene.environment.radiance(dir)
            }
        }
    }

    /// Pixel `(x, y)`: its colour and layers.
    fn pixel(&self, x: u32, y: u32) -> (Vec3, EngineAov) {
        let index = (y * self.camera.width() + x) as usize;
        let texel = UVec2::new(x, y);
        let object = self.screen.texel(texel);
        let front = self
            .front
            .texel(index)
            .filter(|f| object.is_none_or(|o| view_depth(self.camera, f.p_ws) < o.surface.depth));
        let Some(front) = front else {
            return (self.screen_color(texel), EngineAov::NONE);
        };
        let n1 = robust_normalize(front.n_ws).unwrap_or(front.n_ws);
        let path = engine_path(
            self.camera,
            &ScreenDepth(self.screen),
            Camera::pixel_center(x, y),
            front.p_ws,
            n1,
            self.scene.refractor.ior(),
            self.model,
        );
        let mut aov = EngineAov {
            covered: true,
            p2: path.p2,
            t2: path.t2,
            off_screen: path.off_screen,
            ..EngineAov::NONE
        };
        let mut color = Vec3::ZERO;
        if path.screen_weight > 0.0 {
            color += path.screen_weight * self.screen_color(path.texel);
            if let Some(t) = self.screen.texel(path.texel) {
                aov.p_geom = t.surface.p_ws;
                aov.ng_texel = Vec3::new(path.texel.x as f32, path.texel.y as f32, t.object as f32);
            }
        }
        if path.screen_weight < 1.0 {
            color +=
                (1.0 - path.screen_weight) * self.scene.environment.radiance(path.environment_dir);
        }
        (color, aov)
    }
}
