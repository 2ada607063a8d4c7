//! The CPU backend as a [`Renderer`]: the scene and every family's passes
//! ([`crate::families::Families`], which holds the backend's one exhaustive `match` from
//! [`MethodParams`] to a family), timed by the wall clock.

use std::sync::Arc;
use std::time::Instant;

use refract_core::Camera;
use refract_scene::{
    BackendId, Frame, FrameOutputs, FrameTiming, MethodParams, RenderError, Renderer, Scene,
    TimingSource,
};

use crate::families::Families;
use crate::families::pvrr::PvrrPasses;
use crate::family::FrameCx;

/// The CPU renderer: it keeps its buffers between frames, so that after the first frame at a
/// resolution a colour-only frame allocates nothing.
#[derive(Default)]
pub struct CpuRenderer {
    scene: Option<Arc<Scene>>,
    families: Families,
    /// One wavelength's colour of a dispersive frame ([`refract_scene::render_dispersive`]).
    wavelength_frame: Frame,
}

impl CpuRenderer {
    /// A renderer without a scene.
    pub fn new() -> Self {
        Self::default()
    }

    /// The `pvrr` passes: the last frame's plan and maps (for measurements such as the
    /// per-vertex exactness and the occlusion inconsistency of Kakimoto et al.).
    pub fn pvrr_passes(&self) -> &PvrrPasses {
        &self.families.pvrr
    }
}

impl Renderer for CpuRenderer {
    fn backend(&self) -> BackendId {
        BackendId::Cpu
    }

    fn prepare(&mut self, scene: &Arc<Scene>) -> Result<(), RenderError> {
        // The mesh, its BVH and d_N come built with the scene; buffers are sized per frame.
        self.families.prepare(scene);
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
        let families = &mut self.families;
        refract_scene::render_dispersive(
            scene,
            method,
            outputs,
            frame,
            &mut self.wavelength_frame,
            |lambda_nm, outputs, frame, repeat| {
                let cx = FrameCx {
                    scene,
                    camera,
                    method: id,
                    outputs,
                    lambda_nm,
                    repeat,
                };
                let start = Instant::now();
                families.render(&cx, method, frame)?;
                Ok(FrameTiming {
                    ms: start.elapsed().as_secs_f64() * 1e3,
                    source: TimingSource::Wall,
                })
            },
        )
    }
}
