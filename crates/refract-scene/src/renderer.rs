//! The interface every renderer implements: the CPU backend, the GPU backend and the exact
//! reference. Prepare a scene once, then render frames for any camera and method.

use std::sync::Arc;

use refract_core::Camera;

use crate::frame::Frame;
use crate::registry::{BackendId, MethodId, MethodParams};
use crate::scene::Scene;

/// What a frame writes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FrameOutputs {
    /// Colour and every AOV layer the method writes (what comparisons need).
    #[default]
    ColorAndAovs,
    /// Colour only, as a real-time renderer displays it (no layers).
    Color,
}

/// Where a frame time came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimingSource {
    /// Wall-clock time around all per-frame passes on this thread.
    Wall,
    /// GPU timestamp queries from the first pass to the last (the queue waited).
    GpuTimestamps,
}

/// The time of one frame: every per-frame pass of the method (not the one-time preparation,
/// not reading results back).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameTiming {
    /// Milliseconds.
    pub ms: f64,
    /// How it was measured.
    pub source: TimingSource,
}

/// Why a renderer could not prepare a scene or render a frame.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The backend does not implement this method (never a silent fallback).
    #[error("method `{method}` is not supported by the {backend} backend (it runs on: {runs_on})", runs_on = runs_on(*method))]
    Unsupported {
        /// The backend.
        backend: BackendId,
        /// The method.
        method: MethodId,
    },
    /// The method cannot render this scene (e.g. an image-space method and a metal object), see
    /// [`crate::scene_support`].
    #[error("{0}")]
    UnsupportedScene(String),
    /// `render` before `prepare`.
    #[error("the {0} backend has no scene: call prepare first")]
    NotPrepared(BackendId),
    /// The family does not compute a layer its registry row lists (a defect of the family).
    #[error(
        "method `{method}` lists the layer {layer} in its registry row, but its family does not compute it"
    )]
    MissingLayer {
        /// The method.
        method: MethodId,
        /// The layer's name.
        layer: &'static str,
    },
    /// A parameter the method cannot use (e.g. an index of refraction ≤ 0).
    #[error("{0}")]
    Parameter(String),
    /// The backend failed (GPU device errors, limits, readback).
    #[error("{backend} backend")]
    Backend {
        /// The backend.
        backend: BackendId,
        /// What went wrong.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}

fn runs_on(method: MethodId) -> String {
    method
        .info()
        .backends
        .iter()
        .map(|b| b.id())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The GPU time of the passes of one label in a frame, from timestamp queries around each pass.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTime {
    /// What the passes do ("back faces", "distance-map kernel", ...).
    pub label: &'static str,
    /// How many passes had the label.
    pub count: u32,
    /// Their summed GPU time in milliseconds.
    pub ms: f64,
}

/// A renderer: one of the CPU backend, the GPU backend, the exact reference.
pub trait Renderer {
    /// Which backend this is.
    fn backend(&self) -> BackendId;

    /// The device it runs on, where it is not this machine's CPU: the GPU adapter's name
    /// (`None` for the CPU backend and the CPU tracer).
    fn device(&self) -> Option<String> {
        None
    }

    /// Whether [`Renderer::render`] runs `method`: the registry row's `backends` (a test renders
    /// every row on every backend and holds `render` to it).
    fn supports(&self, method: MethodId) -> bool {
        method.info().backends.contains(&self.backend())
    }

    /// Prepares `scene` once: uploads, per-scene buffers. Frames of any camera and method then
    /// render without preparing again.
    fn prepare(&mut self, scene: &Arc<Scene>) -> Result<(), RenderError>;

    /// Renders one frame of `method` seen by `camera` into `frame` (resized; its memory is
    /// reused from frame to frame), writing the colour and, with
    /// [`FrameOutputs::ColorAndAovs`], the method's AOV layers. An unsupported method is
    /// [`RenderError::Unsupported`].
    fn render(
        &mut self,
        camera: &Camera,
        method: &MethodParams,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<FrameTiming, RenderError>;

    /// The GPU time of the last frame's passes, summed per label in encoding order; empty for a
    /// backend that does not time its passes (the CPU backend, the CPU tracer) and on an adapter
    /// without timestamp queries.
    fn last_pass_times(&self) -> Vec<PassTime> {
        Vec::new()
    }
}

impl RenderError {
    /// [`RenderError::Backend`] of any error.
    pub fn backend(
        backend: BackendId,
        source: impl Into<Box<dyn std::error::Error + Send + Sync>>,
    ) -> Self {
        Self::Backend {
            backend,
            source: source.into(),
        }
    }
}
