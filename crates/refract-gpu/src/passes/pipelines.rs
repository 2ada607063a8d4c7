//! Compute pipelines from one shader module over one bind-group layout: a family's pipelines
//! (one per registry row of the family, each with and without AOV stores) and the compiler
//! they and the shared passes are built with.

use refract_scene::{FrameOutputs, MethodId, MethodParams, REGISTRY};

use crate::shaders::ShaderModule;

/// The compute pipelines of one method family: one per registry method of the family, each
/// compiled with and without AOV stores (the `WRITE_AOVS` override), over one bind-group layout.
pub(crate) struct MethodPipelines {
    pub layout: wgpu::BindGroupLayout,
    pipelines: Vec<(MethodId, FrameOutputs, wgpu::ComputePipeline)>,
}

impl MethodPipelines {
    /// Compiles `module` with `entries` as its layout, one pipeline per
    /// registry row whose parameters are a `P` (the family's parameter type); `entry` gives each
    /// method's entry point and its override constants besides `WRITE_AOVS`.
    pub(crate) fn new<P: TryFrom<MethodParams>>(
        device: &wgpu::Device,
        module: &ShaderModule,
        entries: &[wgpu::BindGroupLayoutEntry],
        entry: impl Fn(&P) -> (&'static str, Vec<(&'static str, f64)>),
    ) -> Self {
        Self::with_passes(device, module, entries, entry, &[]).0
    }

    /// [`Self::new`], and one colour-only pipeline of the same module and layout for each of
    /// `passes` (an entry point with its override constants), in their order: the family's
    /// passes that run before its method's.
    pub(crate) fn with_passes<P: TryFrom<MethodParams>>(
        device: &wgpu::Device,
        module: &ShaderModule,
        entries: &[wgpu::BindGroupLayoutEntry],
        entry: impl Fn(&P) -> (&'static str, Vec<(&'static str, f64)>),
        passes: &[(&'static str, Vec<(&'static str, f64)>)],
    ) -> (Self, Vec<wgpu::ComputePipeline>) {
        let compiler = PipelineCompiler::new(device, module, entries);
        let extra = passes
            .iter()
            .map(|(name, constants)| compiler.compile(name, name, FrameOutputs::Color, constants))
            .collect();
        let mut pipelines = Vec::new();
        let rows = REGISTRY
            .iter()
            .filter_map(|m| P::try_from((m.defaults)()).ok().map(|p| (m.id, p)));
        for (id, params) in rows {
            let (entry_point, method_constants) = entry(&params);
            for outputs in [FrameOutputs::ColorAndAovs, FrameOutputs::Color] {
                let label = format!("{id} ({outputs:?})");
                let pipeline = compiler.compile(&label, entry_point, outputs, &method_constants);
                pipelines.push((id, outputs, pipeline));
            }
        }
        (
            Self {
                layout: compiler.layout,
                pipelines,
            },
            extra,
        )
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

/// One shader module over one bind-group layout, compiling compute pipelines from it with
/// `WRITE_AOVS` set per [`FrameOutputs`].
pub(crate) struct PipelineCompiler<'d> {
    device: &'d wgpu::Device,
    shader: wgpu::ShaderModule,
    pub layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
}

impl<'d> PipelineCompiler<'d> {
    /// Creates `module` and its layout of `entries`.
    pub(crate) fn new(
        device: &'d wgpu::Device,
        module: &ShaderModule,
        entries: &[wgpu::BindGroupLayoutEntry],
    ) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(module.name),
            source: wgpu::ShaderSource::Wgsl(module.source().into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(module.name),
            entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(module.name),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        Self {
            device,
            shader,
            layout,
            pipeline_layout,
        }
    }

    /// The pipeline of `entry_point` for `outputs` (`WRITE_AOVS`) and `constants`.
    pub(crate) fn compile(
        &self,
        label: &str,
        entry_point: &str,
        outputs: FrameOutputs,
        constants: &[(&str, f64)],
    ) -> wgpu::ComputePipeline {
        let write_aovs = f64::from(u8::from(outputs == FrameOutputs::ColorAndAovs));
        let mut all = vec![("WRITE_AOVS", write_aovs)];
        all.extend(constants.iter().copied());
        self.device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&self.pipeline_layout),
                module: &self.shader,
                entry_point: Some(entry_point),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &all,
                    ..Default::default()
                },
                cache: None,
            })
    }
}
