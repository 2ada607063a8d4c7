//! One module per method family, the same names as the CPU backend's, each a
//! [`GpuFamily`](crate::family::GpuFamily); and [`Families`]: one [`FamilySlot`] per family and
//! the backend's one exhaustive `match` from [`MethodParams`] to the family that renders it,
//! both generated from one list (`gpu_families!`). A new family is its module here and its line
//! in that list.

pub(crate) mod distance_map;
pub(crate) mod engine;
pub(crate) mod image_space;
pub(crate) mod nearby_geometry;
pub(crate) mod objects_over_frame;
pub(crate) mod pvrr;

use std::sync::Arc;

use refract_scene::{BackendId, Frame, FrameTiming, RenderError, Scene};

use crate::family::{FamilySlot, GpuFamily, GpuFrameCx};
use crate::passes::raster::RasterPipelines;

/// The backend's one list of families: each line is a [`Families`] slot, the family's module
/// and type (a [`GpuFamily`], built by [`GpuFamily::create`]) and the [`MethodParams`] variant
/// it renders. The list also makes [`SHADERS`] (each family module's `SHADER`, then the shared
/// modules the list names), so a family's shader cannot be left out of naga's validation; the
/// families rendered elsewhere are declined by name. A family of [`MethodParams`] missing from
/// both lists is a non-exhaustive `match`: it does not compile.
macro_rules! gpu_families {
    (
        declined: [$($declined:ident),*],
        shared_shaders: [$($shared:path),*],
        $($(#[doc = $doc:literal])* $field:ident: $module:ident::$family:ident => $variant:ident,)*
    ) => {
        /// Every family with the targets of its last frame.
        pub(crate) struct Families {
            $($(#[doc = $doc])* $field: FamilySlot<$module::$family>,)*
        }

        impl Families {
            /// Compiles every family's pipelines.
            pub(crate) fn new(device: &wgpu::Device, raster: &RasterPipelines) -> Self {
                Self {
                    $($field: FamilySlot::new(<$module::$family as GpuFamily>::create(
                        device, raster,
                    )),)*
                }
            }

            /// Drops every family's targets (bound to the old scene) and prepares it for
            /// `scene`.
            pub(crate) fn prepare(&mut self, scene: &Arc<Scene>) {
                $(self.$field.prepare(scene);)*
            }

            /// One frame of `method` by its family ([`FamilySlot::run_frame`]); the declined
            /// families are [`RenderError::Unsupported`] here.
            pub(crate) fn render(
                &mut self,
                cx: &GpuFrameCx<'_>,
                method: &MethodParams,
                frame: Option<&mut Frame>,
            ) -> Result<FrameTiming, RenderError> {
                match method {
                    $(MethodParams::$variant(p) => self.$field.run_frame(cx, p, frame),)*
                    $(MethodParams::$declined(_))|* => Err(RenderError::Unsupported {
                        backend: BackendId::Gpu,
                        method: cx.method,
                    }),
                }
            }

            /// The colour buffer of the last frame of `method`'s family, `None` before its
            /// first frame (and for the declined families).
            pub(crate) fn color(&self, method: &MethodParams) -> Option<&wgpu::Buffer> {
                match method {
                    $(MethodParams::$variant(_) => self.$field.color(),)*
                    $(MethodParams::$declined(_))|* => None,
                }
            }
        }

        /// Every family's shader module, then the shared ones of the list (validated by naga
        /// in `tests/shaders.rs` with the backend's other modules).
        pub(crate) const SHADERS: &[ShaderModule] = &[$($module::SHADER,)* $($shared,)*];
    };
}

gpu_families! {
    // The GPU reference runs before the families (`GpuRenderer::render`, crate::reference).
    declined: [Reference],
    shared_shaders: [objects_over_frame::SHADER],
    /// Wyman 2005a.
    image_space: image_space::ImageSpacePipelines => ImageSpace,
    /// Wyman 2005b.
    nearby: nearby_geometry::NearbyPipelines => NearbyGeometry,
    /// Umenhoffer et al. 2007.
    distance_map: distance_map::DistanceMapPipelines => DistanceMap,
    /// Kakimoto et al. 2007.
    pvrr: pvrr::PvrrFamily => Pvrr,
    /// Today's engines.
    engine: engine::EnginePipelines => Engine,
}

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
        let compiler = PipelineCompiler::new(device, module, entries);
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
        Self {
            layout: compiler.layout,
            pipelines,
        }
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
