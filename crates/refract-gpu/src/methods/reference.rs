//! The exact reference as a family of the backend (method `reference`): the scene uploaded for
//! [`GpuReference`] on the first frame after [`GpuFamily::prepare`] (with the pipeline, compiled
//! once per renderer), the frame's buffers kept while its size and outputs stay, and the
//! samples traced by [`GpuReference::encode`]'s batches. Timed by the wall clock: its batches
//! are separate submissions, which the frame's timestamp queries do not span.

use std::sync::Arc;

use refract_scene::{Frame, RenderError, Scene, TraceSettings};

use crate::context::GpuError;
use crate::family::{GpuFamily, GpuFrameCx};
use crate::passes::raster::RasterPipelines;
use crate::reference::{GpuReference, OutputBuffers, ReferencePipeline};
use crate::shaders::ShaderModule;

/// The reference's modules: over the WGSL traversal and over the adapter's ray queries.
pub(crate) const SHADERS: &[ShaderModule] = &[
    crate::reference::REFERENCE_MODULE,
    crate::reference::REFERENCE_RAY_QUERY_MODULE,
];

/// The reference's pipeline (compiled on its first frame) and the scene uploaded for it.
#[derive(Default)]
pub(crate) struct ReferenceFamily {
    pipeline: Option<Arc<ReferencePipeline>>,
    uploaded: Option<GpuReference>,
}

impl ReferenceFamily {
    /// The uploaded scene; [`GpuFamily::plan`] uploads it before every frame's targets.
    fn uploaded(&self) -> &GpuReference {
        self.uploaded
            .as_ref()
            .expect("the reference's plan uploads the scene before its targets are allocated")
    }
}

impl GpuFamily for ReferenceFamily {
    type Params = TraceSettings;
    type Targets = OutputBuffers;
    const LABEL: &'static str = "reference frame";
    const TIMESTAMPS: bool = false;

    fn create(_device: &wgpu::Device, _raster: &RasterPipelines) -> Self {
        Self::default()
    }

    fn prepare(&mut self, _scene: &Arc<Scene>) {
        self.uploaded = None;
    }

    fn plan(&mut self, cx: &GpuFrameCx<'_>, _: &TraceSettings) -> Result<(), RenderError> {
        if self.uploaded.is_none() {
            let pipeline = match &self.pipeline {
                Some(pipeline) => Arc::clone(pipeline),
                None => Arc::clone(
                    self.pipeline
                        .insert(Arc::new(ReferencePipeline::new(cx.context)?)),
                ),
            };
            self.uploaded = Some(GpuReference::upload(
                cx.context,
                pipeline,
                cx.scene,
                cx.gpu_scene,
            )?);
        }
        Ok(())
    }

    fn fits(&self, targets: &OutputBuffers, cx: &GpuFrameCx<'_>, _: &TraceSettings) -> bool {
        let (width, height) = cx.size();
        targets.fits(width, height, cx.outputs)
    }

    fn allocate(&self, cx: &GpuFrameCx<'_>, _: &TraceSettings) -> Result<OutputBuffers, GpuError> {
        let (width, height) = cx.size();
        self.uploaded()
            .output_buffers(cx.context, width, height, cx.outputs)
    }

    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        settings: &TraceSettings,
        targets: &mut OutputBuffers,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), RenderError> {
        self.uploaded()
            .encode(cx.context, cx.camera, settings, targets, encoder)
    }

    fn color<'t>(&self, targets: &'t OutputBuffers) -> &'t wgpu::Buffer {
        GpuReference::color(targets)
    }

    fn read(
        &self,
        cx: &GpuFrameCx<'_>,
        targets: &OutputBuffers,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        self.uploaded().read(cx.context, targets, frame)
    }
}
