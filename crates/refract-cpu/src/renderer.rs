//! The CPU backend as a [`Renderer`]: one value of every method family ([`crate::family`]) and
//! one exhaustive `match` from [`MethodParams`] to the family that renders it, so a new
//! parameter set does not compile until it is handled or declined.

use std::sync::Arc;
use std::time::Instant;

use refract_core::Camera;
use refract_scene::{
    BackendId, Frame, FrameOutputs, FrameTiming, MethodId, MethodParams, RenderError, Renderer,
    Scene, TimingSource,
};

use crate::distance_map::DistancePasses;
use crate::family::{CpuFamily, FrameCx};
use crate::image_space::ImageSpacePasses;
use crate::nearby_geometry::NearbyPasses;
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

    /// The registry row's word; `render` declines every other method (tested for every row).
    fn supports(&self, method: MethodId) -> bool {
        method.info().backends.contains(&BackendId::Cpu)
    }

    fn prepare(&mut self, scene: &Arc<Scene>) -> Result<(), RenderError> {
        // The mesh, its BVH and d_N come built with the scene; buffers are sized per frame.
        self.image_space.prepare(scene);
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
        let id = method.id();
        refract_scene::scene_support(id, scene).map_err(RenderError::UnsupportedScene)?;
        let cx = FrameCx {
            scene,
            camera,
            method: id,
            outputs,
        };
        let start = Instant::now();
        match method {
            MethodParams::Reference(_) => Err(RenderError::Unsupported {
                backend: BackendId::Cpu,
                method: id,
            }),
            MethodParams::ImageSpace(p) => self.image_space.render(&cx, p, frame),
            MethodParams::NearbyGeometry(p) => self.nearby.render(&cx, p, frame),
            MethodParams::DistanceMap(p) => self.distance_map.render(&cx, p, frame),
            MethodParams::Pvrr(p) => self.pvrr.render(&cx, p, frame),
        }?;
        Ok(FrameTiming {
            ms: start.elapsed().as_secs_f64() * 1e3,
            source: TimingSource::Wall,
        })
    }
}
