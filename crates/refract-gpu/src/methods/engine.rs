//! The refraction today's engines ship, on the GPU (methods `screen-offset`,
//! `volume-thickness`, `proxy-sphere`, `proxy-box`, `proxy-thin`): the opaque objects' surface
//! pass from the eye (the nearby-geometry family's NG targets without a guard band), the
//! refractor's front faces (no back faces), then `shade_engine` of `engine.wgsl` (beside this module) as a
//! compute pass, one pipeline per method (`ENGINE_MODEL` fixed per pipeline). Every refractor's
//! front faces are drawn, each pixel refracting with its nearest refractor's IOR and amount
//! (binding 17, [`refractor_table`]), as on the CPU.

use glam::Vec3;
use refract_core::engine::EngineUniforms;
use refract_scene::{
    Aov, EngineParams, Frame, FrameOutputs, LayerValue, MAX_REFRACTORS, MethodId, PixelLayers,
    RenderError,
};

use crate::bindings::{bind_group, storage_entry, uniform_entry};
use crate::context::{GpuContext, GpuError};
use crate::family::{GpuFamily, GpuFrameCx};
use crate::frame_uniforms::frame_uniforms;
use crate::passes::object_surfaces::{
    NearbyFrame, nearby_layout, nearby_resources, nearby_uniforms,
};
use crate::passes::outputs::{OutputBuffers, check_limits};
use crate::passes::pipelines::MethodPipelines;
use crate::passes::raster::RasterPipelines;
use crate::passes::raster::SurfaceTargets;
use crate::passes::refractor::RefractorTargets;
use crate::shaders::{
    CORE, ENVIRONMENT, FRAME, IMAGE_SPACE, MATERIALS, OBJECT_SURFACES, OBJECT_TEXTURE,
    PROCEDURAL_SKY, ShaderModule, TWO_INTERFACE, WgslFile,
};
use refract_core::screen_mips::{level_count, level_size};

/// Where each engine reads the screen (`engine_path`), over a `screen_depth` its includer
/// provides.
const ENGINE_PATH: WgslFile = ("engine_path.wgsl", include_str!("engine_path.wgsl"));

/// The mip-mapped screen's levels and three.js's rough lookup, over a `mip_texel` its includer
/// provides.
const SCREEN_MIPS: WgslFile = ("screen_mips.wgsl", include_str!("screen_mips.wgsl"));

/// The family's modules: its pass, and its conformance module.
pub(crate) const SHADERS: &[ShaderModule] = &[SHADER, CONFORMANCE];

/// The module of the engine methods: the front faces and environment of the image-space
/// shader, the readers of the objects' surfaces from the eye, the path, then `shade_engine`.
pub(crate) const SHADER: ShaderModule = ShaderModule {
    name: "engine",
    files: &[
        CORE,
        PROCEDURAL_SKY,
        FRAME,
        ENVIRONMENT,
        TWO_INTERFACE,
        IMAGE_SPACE,
        MATERIALS,
        OBJECT_SURFACES,
        OBJECT_TEXTURE,
        ENGINE_PATH,
        SCREEN_MIPS,
        ("engine.wgsl", include_str!("engine.wgsl")),
    ],
};

/// The conformance module (`engine_conformance.wgsl`): the path over an analytic screen and
/// the models' leaves, run by `crate::conformance::evaluate_family` (entry points:
/// [`CONFORMANCE_ENTRY_POINTS`]).
pub(crate) const CONFORMANCE: ShaderModule = ShaderModule {
    name: "engine-conformance",
    files: &[
        CORE,
        FRAME,
        ENGINE_PATH,
        SCREEN_MIPS,
        (
            "engine_conformance.wgsl",
            include_str!("engine_conformance.wgsl"),
        ),
    ],
};

/// The `shade_engine` pipelines: one per engine method (`ENGINE_MODEL` fixed per method), and
/// the two passes that mip-map the screen texture for rough refractors (`screen_mip_base`,
/// `screen_mip_levels`).
pub(crate) struct EnginePipelines {
    shade: MethodPipelines,
    mip_base: wgpu::ComputePipeline,
    mip_levels: wgpu::ComputePipeline,
}

impl EnginePipelines {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let mut entries = nearby_layout();
        entries.push(uniform_entry(16, wgpu::ShaderStages::COMPUTE));
        entries.push(uniform_entry(17, wgpu::ShaderStages::COMPUTE));
        entries.push(storage_entry(18, false));
        let volume = f64::from(refract_core::engine::ENGINE_VOLUME_THICKNESS);
        let (shade, mut passes) = MethodPipelines::with_passes(
            device,
            &SHADER,
            &entries,
            |p: &EngineParams| {
                let code = f64::from(p.method.model_code());
                ("shade_engine", vec![("ENGINE_MODEL", code)])
            },
            &[
                ("screen_mip_base", vec![("ENGINE_MODEL", volume)]),
                ("screen_mip_levels", vec![("ENGINE_MODEL", volume)]),
            ],
        );
        let mip_levels = passes.pop().expect("two passes");
        let mip_base = passes.pop().expect("two passes");
        Self {
            shade,
            mip_base,
            mip_levels,
        }
    }
}

/// Whether a frame of `params` on `scene` reads the blurred screen: a refractor whose model
/// blurs at its roughness ([`refract_core::engine::EngineModel::rough_lod`]).
fn needs_mips(cx: &GpuFrameCx<'_>, params: &EngineParams) -> bool {
    let table = refractor_table(cx.scene, params, cx.camera);
    mip_levels(cx, params, &table) > 0
}

/// How many levels of the screen pyramid a frame of `params` reads: the most any refractor's
/// model reads at its LOD (`table`'s, [`refractor_table`];
/// [`refract_core::engine::EngineModel::rough_levels`]; 0: none).
fn mip_levels(
    cx: &GpuFrameCx<'_>,
    params: &EngineParams,
    table: &[[f32; 4]; MAX_REFRACTORS],
) -> u32 {
    let size = glam::UVec2::new(cx.camera.width(), cx.camera.height());
    table
        .iter()
        .zip(cx.scene.refractors())
        .map(|(entry, refractor)| params.model(refractor).rough_levels(entry[3], size))
        .max()
        .unwrap_or(0)
}

/// The screen pyramid's texels in levels 1 to `levels − 1` at `size` (all levels above 0 when
/// `levels` is the pyramid's count).
fn texels_above_base((width, height): (u32, u32), levels: u32) -> u64 {
    let size = glam::UVec2::new(width, height);
    (1..levels.min(level_count(size)))
        .map(|level| {
            let s = level_size(size, level);
            u64::from(s.x) * u64::from(s.y)
        })
        .sum()
}

impl GpuFamily for EnginePipelines {
    type Params = EngineParams;
    type Targets = EngineTargets;
    const LABEL: &'static str = "engine frame";

    fn create(device: &wgpu::Device, _raster: &RasterPipelines) -> Self {
        Self::new(device)
    }

    fn fits(&self, targets: &EngineTargets, cx: &GpuFrameCx<'_>, params: &EngineParams) -> bool {
        targets.size == cx.size() && targets.mips == needs_mips(cx, params)
    }

    fn allocate(
        &self,
        cx: &GpuFrameCx<'_>,
        params: &EngineParams,
    ) -> Result<EngineTargets, GpuError> {
        EngineTargets::new(cx, self, needs_mips(cx, params))
    }

    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        params: &EngineParams,
        targets: &mut EngineTargets,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), RenderError> {
        let model = params.model(&cx.scene.refractor);
        let has_objects = !cx.scene.objects.is_empty();
        let uniforms = EngineUniforms::new(cx.camera, &model, has_objects);
        let table = refractor_table(cx.scene, params, cx.camera);
        cx.context
            .queue
            .write_buffer(&targets.refractor_table, 0, bytemuck::cast_slice(&table));
        targets.encode(cx, self, &uniforms, mip_levels(cx, params, &table), encoder);
        Ok(())
    }

    fn color<'t>(&self, targets: &'t Self::Targets) -> &'t wgpu::Buffer {
        &targets.outputs.outputs[0]
    }

    fn read(
        &self,
        cx: &GpuFrameCx<'_>,
        targets: &EngineTargets,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        targets.read(cx.context, cx.method, cx.outputs, frame)
    }
}

/// Refractor `k`'s `(IOR, amount, dispersion, LOD)` in entry `k` (`engine.wgsl`'s
/// `engine_refractors`): the IOR, the model's `amount` ([`EngineUniforms::amount`]) of `params`
/// on that refractor, its dispersion's one number
/// ([`refract_core::engine_dispersion::EngineDispersion::amount`]: three.js's half spread,
/// Filament's factor; 0 for one index; the model says which) and how its
/// roughness blurs the screen ([`refract_core::engine::EngineModel::rough_lod`]: a LOD, Bevy's
/// roughness; 0: the nearest texel).
fn refractor_table(
    scene: &refract_scene::Scene,
    params: &EngineParams,
    camera: &refract_core::Camera,
) -> [[f32; 4]; MAX_REFRACTORS] {
    let mut table = [[0.0; 4]; MAX_REFRACTORS];
    for (entry, refractor) in table.iter_mut().zip(scene.refractors()) {
        let model = params.model(refractor);
        let amount = EngineUniforms::new(camera, &model, false).amount;
        let spread = if refractor.is_dispersive() {
            model.dispersion(refractor.ior(), refractor.abbe()).amount()
        } else {
            0.0
        };
        let lod = model.rough_lod(camera, refractor.roughness(), refractor.ior());
        *entry = [refractor.ior(), amount, spread, lod];
    }
    table
}

/// The targets of engine frames at one resolution.
pub(crate) struct EngineTargets {
    size: (u32, u32),
    refractor: RefractorTargets,
    screen: SurfaceTargets,
    nearby_uniforms: wgpu::Buffer,
    engine_uniforms: wgpu::Buffer,
    /// [`refractor_table`] (binding 17).
    refractor_table: wgpu::Buffer,
    /// Whether the bind group's mip-mapped screen colours (binding 18, kept alive by the group)
    /// hold the whole pyramid (a rough refractor), else one texel.
    mips: bool,
    group: wgpu::BindGroup,
    /// Colour, T2, P2, flags (off screen, screen weight), P_geom (w: hit), texel (x, y, object).
    outputs: OutputBuffers,
}

impl EngineTargets {
    fn new(cx: &GpuFrameCx<'_>, pipelines: &EnginePipelines, mips: bool) -> Result<Self, GpuError> {
        let (width, height) = cx.size();
        let context = cx.context;
        check_limits(context, width, height)?;
        let mip_texels = if mips {
            u64::from(width) * u64::from(height) + texels_above_base((width, height), u32::MAX)
        } else {
            1
        };
        let mip_bytes = mip_texels * 16;
        let limit = context.device.limits().max_storage_buffer_binding_size;
        if mip_bytes > limit {
            return Err(GpuError::Wgpu(format!(
                "the mip-mapped screen of a rough refractor at {width} × {height} takes {mip_bytes} bytes, more than the adapter's largest storage buffer ({limit})"
            )));
        }
        let device = &context.device;
        let scene = cx.gpu_scene;
        context.checked(|| {
            let refractor = RefractorTargets::allocate(device, cx.raster, width, height);
            let screen = SurfaceTargets::new(device, cx.raster, "screen", width, height);
            let uniform_buffer = |label, size: usize| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: size as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            };
            let nearby_uniforms = uniform_buffer(
                "screen uniforms",
                std::mem::size_of::<refract_core::gpu::NearbyUniforms>(),
            );
            let engine_uniforms =
                uniform_buffer("engine uniforms", std::mem::size_of::<EngineUniforms>());
            let refractor_table = uniform_buffer(
                "engine refractors",
                std::mem::size_of::<[[f32; 4]; MAX_REFRACTORS]>(),
            );
            let outputs = OutputBuffers::new(
                device,
                &["colour", "T2", "P2", "flags", "P_geom", "texel"],
                u64::from(width) * u64::from(height),
            );
            let screen_mips = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("screen mips"),
                size: mip_bytes,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
            let mut resources =
                nearby_resources(&refractor, scene, &outputs, &screen, &nearby_uniforms);
            resources.push(engine_uniforms.as_entire_binding());
            resources.push(refractor_table.as_entire_binding());
            resources.push(screen_mips.as_entire_binding());
            let group = bind_group(device, "engine", &pipelines.shade.layout, &resources);
            Self {
                size: (width, height),
                refractor,
                screen,
                nearby_uniforms,
                engine_uniforms,
                refractor_table,
                mips,
                group,
                outputs,
            }
        })
    }

    /// Encodes the passes of one frame and the copies of its outputs.
    /// Encodes a frame: the refractor's and the screen's passes, the `mip_levels` levels of
    /// the screen pyramid a rough frame reads (level 0 and the ones above it; the buffer holds
    /// them all), then the kernel.
    fn encode(
        &self,
        cx: &GpuFrameCx<'_>,
        pipelines: &EnginePipelines,
        engine: &EngineUniforms,
        mip_levels: u32,
        encoder: &mut wgpu::CommandEncoder,
    ) {
        let GpuFrameCx {
            context,
            raster,
            gpu_scene: scene,
            camera,
            method,
            outputs,
            timestamps,
            ..
        } = *cx;
        let ior = cx.scene.refractor.ior();
        let uniforms = frame_uniforms(
            camera,
            &scene.environment,
            ior,
            refract_core::TirPolicy::default(),
        );
        let screen = NearbyFrame::eye(camera, cx.scene.light);
        context.queue.write_buffer(
            &self.nearby_uniforms,
            0,
            bytemuck::bytes_of(&nearby_uniforms(&screen)),
        );
        context
            .queue
            .write_buffer(&self.engine_uniforms, 0, bytemuck::bytes_of(engine));
        self.refractor.encode(cx, &uniforms, None, true, encoder);
        // Without opaque objects the shader never reads the screen texture.
        if engine.has_objects != 0 {
            let objects: Vec<_> = scene.objects.iter().collect();
            self.screen.encode(
                &context.queue,
                raster,
                encoder,
                camera,
                &uniforms,
                &objects,
                timestamps.and_then(|t| t.render_pass("object surfaces")),
            );
        }
        if self.mips {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("screen mips"),
                timestamp_writes: timestamps.and_then(|t| t.compute_pass("screen mips")),
            });
            pass.set_bind_group(0, &self.group, &[]);
            let (width, height) = self.size;
            pass.set_pipeline(&pipelines.mip_base);
            pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
            // `screen_mip_levels` numbers its invocations x + 65535 · 64 · y.
            // The levels are laid out in order: the first invocations make the lower ones.
            let groups = texels_above_base(self.size, mip_levels).div_ceil(64);
            if groups > 0 {
                pass.set_pipeline(&pipelines.mip_levels);
                let x = groups.min(65_535) as u32;
                let y = groups.div_ceil(65_535) as u32;
                pass.dispatch_workgroups(x, y, 1);
            }
        }
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("engine kernel"),
                timestamp_writes: timestamps.and_then(|t| t.compute_pass("engine kernel")),
            });
            pass.set_pipeline(pipelines.shade.get(method, outputs));
            pass.set_bind_group(0, &self.group, &[]);
            let (width, height) = self.size;
            pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
        }
        if let Some(timestamps) = timestamps {
            timestamps.resolve(encoder);
        }
        let copies = match outputs {
            FrameOutputs::ColorAndAovs => 6,
            FrameOutputs::Color => 1,
        };
        if cx.readback {
            self.outputs.copy(encoder, copies);
        }
    }

    /// Reads the last submitted frame into `frame` (the colour and the registry row's AOVs).
    fn read(
        &self,
        context: &GpuContext,
        method: MethodId,
        outputs: FrameOutputs,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let (width, height) = self.size;
        let color = self.outputs.read(context, 0)?;
        frame.resize_for_overwrite(width, height);
        for (out, c) in frame.color.iter_mut().zip(&color) {
            *out = Vec3::new(c[0], c[1], c[2]);
        }
        if outputs == FrameOutputs::Color {
            return Ok(());
        }
        let planes: Vec<Vec<[f32; 4]>> = (1..6)
            .map(|i| self.outputs.read(context, i))
            .collect::<Result<_, _>>()?;
        let pixels: Vec<EnginePixel> = (0..frame.pixel_count())
            .map(|i| EnginePixel {
                covered: color[i][3].round() as u32 == refract_core::gpu::COVERAGE_PATH,
                t2: planes[0][i],
                p2: planes[1][i],
                flags: planes[2][i],
                p_geom: planes[3][i],
                texel: planes[4][i],
            })
            .collect();
        frame.write_row_layers(method, &pixels)?;
        Ok(())
    }
}

/// One pixel of the engine outputs as the shader stores them.
struct EnginePixel {
    covered: bool,
    t2: [f32; 4],
    p2: [f32; 4],
    flags: [f32; 4],
    p_geom: [f32; 4],
    texel: [f32; 4],
}

impl PixelLayers for EnginePixel {
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        let xyz = |v: [f32; 4], valid: bool| {
            LayerValue::Vec3(if valid {
                Vec3::new(v[0], v[1], v[2])
            } else {
                Vec3::NAN
            })
        };
        let hit = self.covered && self.p_geom[3] > 0.5;
        Some(match aov {
            Aov::Covered => LayerValue::Flag(self.covered),
            Aov::OffScreen => LayerValue::Flag(self.covered && self.flags[0] > 0.5),
            Aov::T2 => xyz(self.t2, self.covered && self.t2[3] > 0.5),
            Aov::P2 => xyz(self.p2, self.covered && self.p2[3] > 0.5),
            Aov::PGeom => xyz(self.p_geom, hit),
            Aov::NgTexel => xyz(
                [self.texel[0], self.texel[1], self.texel[2].round(), 0.0],
                hit,
            ),
            _ => return None,
        })
    }
}
