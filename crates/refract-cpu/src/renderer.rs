//! The CPU backend as a [`Renderer`]: one exhaustive `match` from [`MethodParams`] to the module
//! of the method's family, so a new method does not compile until it is handled or declined.

use std::sync::Arc;
use std::time::Instant;

use refract_core::Camera;
use refract_scene::{
    BackendId, Frame, FrameOutputs, FrameTiming, MethodId, MethodParams, RenderError, Renderer,
    Scene, TimingSource,
};

use crate::distance_map::DistancePasses;
use crate::image_space::{ImageSpaceMethod, ImageSpacePasses};
use crate::nearby_geometry::{NearbyMethod, NearbyPasses};
use crate::pvrr::PvrrPasses;

/// The CPU renderer: it keeps its buffers between frames, so that after the first frame at a
/// resolution a colour-only frame allocates nothing.
#[derive(Default)]
pub struct CpuRenderer {
    scene: Option<Arc<Scene>>,
    image_space: ImageSpacePasses,
    nearby: NearbyPasses,
    distance_map: DistancePasses,
    pvrr: PvrrPasses,
}

impl CpuRenderer {
    /// A renderer without a scene.
    pub fn new() -> Self {
        Self::default()
    }

    /// The `pvrr` passes: the last frame's plan and maps (for measurements such as the
    /// per-vertex exactness and the occlusion inconsistency of Kakimoto et al.).
    pub fn pvrr_passes(&self) -> &PvrrPasses {
        &self.pvrr
    }
}

impl Renderer for CpuRenderer {
    fn backend(&self) -> BackendId {
        BackendId::Cpu
    }

    fn supports(&self, method: MethodId) -> bool {
        match MethodParams::defaults(method) {
            MethodParams::Reference(_) => false,
            MethodParams::Single
            | MethodParams::TwoInterface(_)
            | MethodParams::NearbyGeometry(_)
            | MethodParams::DistanceMap(_)
            | MethodParams::Pvrr(_) => true,
        }
    }

    fn prepare(&mut self, scene: &Arc<Scene>) -> Result<(), RenderError> {
        // The mesh, its BVH and d_N come built with the scene; buffers are sized per frame.
        self.nearby.prepare(scene);
        self.distance_map.prepare(scene);
        self.pvrr.prepare(scene);
        self.scene = Some(Arc::clone(scene));
        Ok(())
    }

    fn render(
        &mut self,
        camera: &Camera,
        method: &MethodParams,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<FrameTiming, RenderError> {
        let scene = self
            .scene
            .as_ref()
            .ok_or(RenderError::NotPrepared(BackendId::Cpu))?;
        let refractor = &scene.refractor;
        let start = Instant::now();
        let unsupported = || RenderError::Unsupported {
            backend: BackendId::Cpu,
            method: method.id(),
        };
        refract_scene::scene_support(method.id(), scene).map_err(RenderError::UnsupportedScene)?;
        if let MethodParams::DistanceMap(p) = method {
            self.distance_map.render(scene, camera, p, outputs, frame)?;
            return Ok(FrameTiming {
                ms: start.elapsed().as_secs_f64() * 1e3,
                source: TimingSource::Wall,
            });
        }
        if let MethodParams::Pvrr(p) = method {
            self.pvrr.render(scene, camera, p, outputs, frame)?;
            return Ok(FrameTiming {
                ms: start.elapsed().as_secs_f64() * 1e3,
                source: TimingSource::Wall,
            });
        }
        let kernel = method
            .image_space_kernel(refractor.ior())
            .ok_or_else(unsupported)??;
        let image_space = match method {
            MethodParams::Reference(_) | MethodParams::DistanceMap(_) | MethodParams::Pvrr(_) => {
                return Err(unsupported());
            }
            MethodParams::Single => ImageSpaceMethod::Single,
            MethodParams::TwoInterface(p) => ImageSpaceMethod::TwoInterface { back: p.back },
            MethodParams::NearbyGeometry(p) => {
                let planes = scene.nearby_planes(camera.look_dir());
                self.nearby.render(
                    scene,
                    &planes,
                    camera,
                    &kernel,
                    NearbyMethod {
                        back: p.two.back,
                        lookup: p.lookup,
                        guard_band_percent: p.guard_band_percent,
                    },
                    method.id(),
                    outputs,
                    frame,
                )?;
                return Ok(FrameTiming {
                    ms: start.elapsed().as_secs_f64() * 1e3,
                    source: TimingSource::Wall,
                });
            }
        };
        self.image_space.render(
            refractor,
            &scene.environment,
            camera,
            &kernel,
            image_space,
            method.id(),
            outputs,
            frame,
        );
        Ok(FrameTiming {
            ms: start.elapsed().as_secs_f64() * 1e3,
            source: TimingSource::Wall,
        })
    }
}
