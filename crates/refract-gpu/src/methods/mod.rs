//! One module per method family, the same names as the CPU backend's.

pub(crate) mod distance_map;
pub(crate) mod image_space;
pub(crate) mod nearby_geometry;
pub(crate) mod pvrr;

use refract_scene::{FrameOutputs, MethodId, MethodParams, REGISTRY};

use crate::shaders::module_source;

/// The compute pipelines of one method family: one per registry method of the family, each
/// compiled with and without AOV stores (the `WRITE_AOVS` override), over one bind-group layout.
pub(crate) struct MethodPipelines {
    pub layout: wgpu::BindGroupLayout,
    pipelines: Vec<(MethodId, FrameOutputs, wgpu::ComputePipeline)>,
}

impl MethodPipelines {
    /// Compiles module `module` (`shaders.rs`) with `entries` as its layout, one pipeline per
    /// registry row whose parameters are a `P` (the family's parameter type); `entry` gives each
    /// method's entry point and its override constants besides `WRITE_AOVS`.
    pub(crate) fn new<P: TryFrom<MethodParams>>(
        device: &wgpu::Device,
        module: &str,
        entries: &[wgpu::BindGroupLayoutEntry],
        entry: impl Fn(&P) -> (&'static str, Vec<(&'static str, f64)>),
    ) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(module),
            source: wgpu::ShaderSource::Wgsl(module_source(module).into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(module),
            entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(module),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let mut pipelines = Vec::new();
        let rows = REGISTRY
            .iter()
            .filter_map(|m| P::try_from((m.defaults)()).ok().map(|p| (m.id, p)));
        for (id, params) in rows {
            let (entry_point, method_constants) = entry(&params);
            for outputs in [FrameOutputs::ColorAndAovs, FrameOutputs::Color] {
                let write_aovs = f64::from(u8::from(outputs == FrameOutputs::ColorAndAovs));
                let mut constants = vec![("WRITE_AOVS", write_aovs)];
                constants.extend(method_constants.iter().copied());
                let label = format!("{id} ({outputs:?})");
                let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(&label),
                    layout: Some(&pipeline_layout),
                    module: &shader,
                    entry_point: Some(entry_point),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        ..Default::default()
                    },
                    cache: None,
                });
                pipelines.push((id, outputs, pipeline));
            }
        }
        Self { layout, pipelines }
    }

    /// The pipeline of `method` for `outputs`.
    pub(crate) fn get(&self, method: MethodId, outputs: FrameOutputs) -> &wgpu::ComputePipeline {
        self.pipelines
            .iter()
            .find(|(m, o, _)| *m == method && *o == outputs)
            .map(|(_, _, p)| p)
            .expect("a pipeline for every method of the family")
    }
}
