//! The exact reference as a [`Renderer`]: it runs `reference` and declines every approximate
//! method.

use std::sync::Arc;
use std::time::Instant;

use refract_core::Camera;
use refract_scene::{
    BackendId, Frame, FrameOutputs, FrameTiming, MethodParams, RenderError, Renderer, Scene,
    TimingSource,
};

use refract_scene::spectral::SpectralLighting;

use crate::tracer::{Tracer, render_with, spectral_lighting};

/// The reference tracer behind the [`Renderer`] interface.
#[derive(Debug, Default)]
pub struct ReferenceRenderer {
    scene: Option<Arc<Scene>>,
    /// The scene's emitter spectra when it is dispersive, computed once in `prepare`.
    lighting: Option<Arc<SpectralLighting>>,
}

impl ReferenceRenderer {
    /// A renderer without a scene.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Renderer for ReferenceRenderer {
    fn backend(&self) -> BackendId {
        BackendId::Trace
    }

    fn prepare(&mut self, scene: &Arc<Scene>) -> Result<(), RenderError> {
        // The BVHs were built with the scene: nothing to upload but, for a dispersive scene, its
        // emitters' spectra (a lat-long map's per texel), once for every frame.
        self.scene = Some(Arc::clone(scene));
        self.lighting = spectral_lighting(scene);
        Ok(())
    }

    /// The reference always writes its AOV layers (the ground truth costs nothing extra).
    fn render(
        &mut self,
        camera: &Camera,
        method: &MethodParams,
        _outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<FrameTiming, RenderError> {
        let scene = self
            .scene
            .as_ref()
            .ok_or(RenderError::NotPrepared(BackendId::Trace))?;
        // The tracer renders the reference only: every other family is declined here, so a new
        // family needs no arm in this renderer.
        let MethodParams::Reference(settings) = method else {
            return Err(RenderError::Unsupported {
                backend: BackendId::Trace,
                method: method.id(),
            });
        };
        let start = Instant::now();
        let tracer = Tracer::with_lighting(scene, *settings, self.lighting.clone());
        render_with(&tracer, camera, frame);
        Ok(FrameTiming {
            ms: start.elapsed().as_secs_f64() * 1e3,
            source: TimingSource::Wall,
        })
    }
}
