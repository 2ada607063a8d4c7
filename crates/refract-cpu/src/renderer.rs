//! The CPU backend as a [`Renderer`]: one exhaustive `match` from [`MethodParams`] to the module
//! of the method's family, so a new method does not compile until it is handled or declined.

use std::sync::Arc;
use std::time::Instant;

use refract_core::{Camera, DistanceMode, TirPolicy};
use refract_scene::{
    BackendId, Frame, FrameOutputs, FrameTiming, MethodId, MethodParams, RenderError, Renderer,
    Scene, TimingSource,
};

use crate::image_space::{ImageSpaceMethod, ImageSpacePasses, kernel_params};

/// The CPU renderer: it keeps its buffers between frames, so that after the first frame at a
/// resolution a colour-only frame allocates nothing.
#[derive(Default)]
pub struct CpuRenderer {
    scene: Option<Arc<Scene>>,
    image_space: ImageSpacePasses,
}

impl CpuRenderer {
    /// A renderer without a scene.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Renderer for CpuRenderer {
    fn backend(&self) -> BackendId {
        BackendId::Cpu
    }

    fn supports(&self, method: MethodId) -> bool {
        match MethodParams::defaults(method) {
            MethodParams::Reference(_) => false,
            MethodParams::Single | MethodParams::TwoInterface(_) => true,
        }
    }

    fn prepare(&mut self, scene: &Arc<Scene>) -> Result<(), RenderError> {
        // The mesh, its BVH and d_N come built with the scene; buffers are sized per frame.
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
        let (image_space, kernel) = match method {
            MethodParams::Reference(_) => {
                return Err(RenderError::Unsupported {
                    backend: BackendId::Cpu,
                    method: method.id(),
                });
            }
            MethodParams::Single => (
                ImageSpaceMethod::Single,
                // `single` has no d~ and no exit; the kernel ignores both.
                kernel_params(
                    refractor.ior(),
                    DistanceMode::Interpolated,
                    TirPolicy::default(),
                )?,
            ),
            MethodParams::TwoInterface(p) => (
                ImageSpaceMethod::TwoInterface { back: p.back },
                kernel_params(refractor.ior(), p.distance, p.tir)?,
            ),
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
