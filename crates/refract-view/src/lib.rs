//! `refract view [SCENE]`: a window (winit 0.30 + a wgpu 30 surface) that renders a scene with
//! any method of the registry on the GPU backend (or the CPU backend), with an orbit camera and
//! live method, IOR, TIR-policy and backend switches; frame time in the title; a screenshot key
//! that writes the PNG and the frame's metrics against the exact reference. `--frames`,
//! `--script` and `--screenshot` run it unattended (the headless test under Xvfb).
//! `docs/viewer.md` lists the keys.
//!
//! Its own crate so that the backends and the experiments never link a window system, and the
//! CLI stays a thin shell; its shader is `shaders/display.wgsl`, validated by naga in its tests.

mod reference;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use glam::Vec3;
use refract_core::exit::TirPolicy;
use refract_core::{Camera, CameraDesc};
use refract_cpu::CpuRenderer;
use refract_eval::atomic_write::{write_png_rgb8, write_text_atomically};
use refract_eval::load_scene;
use refract_eval::metrics::evaluate_method;
use refract_gpu::{GpuContext, GpuRenderer};
use refract_scene::registry::ParamKind;
use refract_scene::tonemap::to_srgb8;
use refract_scene::{
    BackendId, Frame, FrameOutputs, MethodId, MethodParams, Renderer, Scene, TimingSource,
};
use refract_trace::ReferenceRenderer;
use winit::application::ApplicationHandler;

use crate::reference::{Level, ProgressiveReference};
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

/// Arguments of `refract view`.
#[derive(Debug, clap::Args)]
pub struct ViewArgs {
    /// A built-in scene or a .toml scene file.
    #[arg(default_value = "sphere")]
    pub scene: String,
    /// The method shown first (`m`/`n` switch).
    #[arg(long, default_value = "wyman")]
    pub method: MethodId,
    /// `gpu` (default) or `cpu` (`b` switches).
    #[arg(long, default_value = "gpu")]
    pub backend: String,
    /// Window size `WxH` in physical pixels (64 to 4096 a side).
    #[arg(long, default_value = "800x600", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Exit after this many frames (with `--screenshot`, written first).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100000))]
    pub frames: Option<u32>,
    /// Actions applied one per frame (`docs/viewer.md`): `key K`, `orbit DX DY`, `pan DX DY`,
    /// `zoom STEPS`, `wait`.
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// Where `p` (and the end of an unattended run) writes the screenshot PNG; the frame's
    /// metrics go beside it as `.json`.
    #[arg(long, default_value = "refract-view.png")]
    pub screenshot: PathBuf,
    /// Read every GPU frame back to the CPU and upload it to the window again (the viewer's
    /// path before frames stayed on the GPU), to measure what the readback costs.
    #[arg(long)]
    pub readback: bool,
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let err = || format!("`{text}`: expected WxH with sides from 64 to 4096");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(err)?;
    let (w, h) = (
        w.trim().parse::<u32>().map_err(|_| err())?,
        h.trim().parse::<u32>().map_err(|_| err())?,
    );
    if (64..=4096).contains(&w) && (64..=4096).contains(&h) {
        Ok((w, h))
    } else {
        Err(err())
    }
}

/// One scripted action.
#[derive(Clone, Debug, PartialEq)]
enum Action {
    Key(String),
    Orbit(f32, f32),
    Pan(f32, f32),
    Zoom(f32),
    Wait,
}

fn parse_script(text: &str, origin: &str) -> anyhow::Result<Vec<Action>> {
    let mut actions = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        let number = |i: usize| -> anyhow::Result<f32> {
            words
                .get(i)
                .and_then(|w| w.parse::<f32>().ok())
                .filter(|v| v.is_finite() && v.abs() <= 1e4)
                .with_context(|| {
                    format!(
                        "{origin}:{}: `{line}`: expected a number within ±10000",
                        n + 1
                    )
                })
        };
        actions.push(match words[0] {
            "key" if words.len() == 2 => Action::Key(words[1].to_owned()),
            "orbit" => Action::Orbit(number(1)?, number(2)?),
            "pan" => Action::Pan(number(1)?, number(2)?),
            "zoom" => Action::Zoom(number(1)?),
            "wait" => Action::Wait,
            _ => anyhow::bail!(
                "{origin}:{}: `{line}`: expected key K, orbit DX DY, pan DX DY, zoom STEPS or wait",
                n + 1
            ),
        });
    }
    Ok(actions)
}

/// An orbit camera around a target.
#[derive(Clone, Copy, Debug)]
struct Orbit {
    target: Vec3,
    distance: f32,
    yaw: f32,
    pitch: f32,
}

impl Orbit {
    fn of(desc: &CameraDesc) -> Self {
        let offset = desc.eye - desc.target;
        let distance = offset.length().max(1e-3);
        Self {
            target: desc.target,
            distance,
            yaw: offset.x.atan2(offset.z),
            pitch: (offset.y / distance).clamp(-1.0, 1.0).asin(),
        }
    }

    fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(sy * cp, sp, cy * cp)
    }

    /// Pixels dragged to radians.
    fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * 0.01;
        self.pitch = (self.pitch + dy * 0.01).clamp(-1.5, 1.5);
    }

    fn pan(&mut self, dx: f32, dy: f32) {
        let forward = (self.target - self.eye()).normalize();
        let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
        let up = right.cross(forward);
        let scale = 0.002 * self.distance;
        self.target += (-dx * right + dy * up) * scale;
    }

    fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * 0.9f32.powf(steps)).clamp(0.05, 1e4);
    }
}

/// The window's wgpu state: the surface and a pipeline that shows the frame's tonemapped pixels.
struct Display {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    /// Draws a GPU frame's colour buffer straight into the window (no readback).
    frame_pipeline: wgpu::RenderPipeline,
    frame_layout: wgpu::BindGroupLayout,
    /// The GPU frame's size and the surface's encoding (`FrameDisplay`), written every frame.
    frame_uniform: wgpu::Buffer,
    texture_format: wgpu::TextureFormat,
    copy_src: bool,
    egui: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
}

/// What the panel draws this frame, tessellated.
struct PanelFrame {
    jobs: Vec<egui::ClippedPrimitive>,
    textures: egui::TexturesDelta,
    screen: egui_wgpu::ScreenDescriptor,
}

impl Drop for PanelFrame {
    /// A frame abandoned on an error path drops its texture changes on purpose (egui panics on
    /// unapplied ones otherwise; `present` applies them before this runs).
    fn drop(&mut self) {
        self.textures.clear();
    }
}

struct Viewer {
    args: ViewArgs,
    scene: Arc<Scene>,
    actions: Vec<Action>,
    methods: Vec<MethodId>,
    method: usize,
    use_gpu: bool,
    orbit: Orbit,
    home: Orbit,
    frame: Frame,
    frames_done: u32,
    last_ms: f64,
    /// The GPU's own time of the last frame (its passes' timestamps plus the CPU part of the
    /// frame), when the adapter has timestamp queries and the frame ran there.
    gpu_ms: Option<f64>,
    /// The GPU time of the last frame's passes, per pass label (with `gpu_ms`).
    pass_times: Vec<refract_gpu::PassTime>,
    /// The last frame was drawn from the GPU's colour buffer: `frame` is not it.
    shown_from_gpu: bool,
    /// Every frame's time from the start of its redraw to its presentation (the render, the
    /// readback, tonemapping and upload where there are, the window's pass), for the
    /// unattended run's summary.
    frame_ms: Vec<f64>,
    drag: Option<(MouseButton, f64, f64)>,
    cursor: (f64, f64),
    display: Option<Display>,
    gpu: Option<GpuRenderer>,
    cpu: CpuRenderer,
    error: Option<anyhow::Error>,
    /// The window's pixels as presented last (RGB8, unattended runs on surfaces that allow
    /// reading them back).
    captured: Option<(u32, u32, Vec<u8>)>,
    /// The exact reference, refined in the background while the camera rests.
    reference: ProgressiveReference,
    /// The newest reference level of the current view.
    reference_level: Option<Level>,
    reference_generation: u64,
    /// Bumped when the scene changes (IOR), so the reference is asked again.
    scene_version: u64,
    reference_scene_version: u64,
    /// Method on the left, reference on the right.
    split: bool,
    /// What the method's side shows.
    error_view: ErrorView,
    /// Each method's parameters as the panel left them.
    method_params: Vec<MethodParams>,
    /// Show the egui panel (`h` toggles).
    show_panel: bool,
    /// An IOR the panel asked for, applied before the next frame.
    pending_ior: Option<f32>,
}

/// One pass label's GPU time for the title and the panel: `kernel 3.2 ms`, `cube-map faces ×18
/// 9.1 ms`.
fn pass_time(p: &refract_gpu::PassTime) -> String {
    if p.count > 1 {
        format!("{} ×{} {:.2} ms", p.label, p.count, p.ms)
    } else {
        format!("{} {:.2} ms", p.label, p.ms)
    }
}

/// Where a reference level was traced, for the title and the summary.
fn reference_origin(level: &Level) -> String {
    match (&level.backend, &level.gpu_failure) {
        (BackendId::Gpu, _) => "GPU".to_owned(),
        (_, Some(why)) => format!("CPU tracer; the GPU failed: {why}"),
        _ => "CPU tracer".to_owned(),
    }
}

/// The method's image or one of its error maps against the full-resolution reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ErrorView {
    Off,
    Flip,
    T2,
}

/// The display pass: the frame's texture drawn texel for texel (`shaders/display.wgsl`).
const SHADER: &str = include_str!("../shaders/display.wgsl");
const FRAME_SHADER: &str = include_str!("../shaders/display_frame.wgsl");

/// What a frame shows: pixels tonemapped on the CPU (the CPU backend, the split view, the
/// error maps), or the GPU backend's colour buffer of `method`, drawn without a readback.
enum Source<'a> {
    Pixels(&'a [u8]),
    Gpu(&'a MethodParams),
}

/// A full-screen pass of `source` (entry points `vs` and `fs`) with one bind group of
/// `layout`, drawing into a surface of `format`.
fn display_pipeline(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    layout: &wgpu::BindGroupLayout,
    format: wgpu::TextureFormat,
) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            buffers: &[],
            compilation_options: Default::default(),
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            targets: &[Some(format.into())],
            compilation_options: Default::default(),
        }),
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        multiview_mask: None,
        cache: None,
    })
}

/// The uniform of `display_frame.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FrameDisplay {
    width: u32,
    height: u32,
    srgb_surface: u32,
    _padding: u32,
}

impl Viewer {
    fn params(&self) -> MethodParams {
        self.method_params[self.method]
    }

    /// The panel (egui): method and its parameters, IOR, TIR policy, backend, views, frame time
    /// and the keys. Changes are applied after the frame's UI ran.
    fn panel(&mut self, width: u32, height: u32) -> Option<PanelFrame> {
        if !self.show_panel {
            return None;
        }
        let display = self.display.as_mut()?;
        let raw = display.egui_state.take_egui_input(&display.window);
        let mut method = self.method;
        let mut params = self.method_params[self.method];
        let mut ior = self.scene.refractor.ior();
        let mut use_gpu = self.use_gpu;
        let mut split = self.split;
        let mut error_view = self.error_view;
        let (ms, methods, has_gpu) = (self.last_ms, &self.methods, self.gpu.is_some());
        let gpu_passes = self
            .gpu_ms
            .map_or_else(String::new, |ms| format!("GPU passes {ms:.1} ms; "));
        let pass_lines: Vec<String> = self.pass_times.iter().map(pass_time).collect();
        let readback = if self.use_gpu && !self.shown_from_gpu {
            "read back to the CPU"
        } else if self.use_gpu {
            "drawn on the GPU, no readback"
        } else {
            "CPU frame"
        };
        let output = display.egui.run_ui(raw, |ui| {
            egui::Window::new("refract")
                .default_pos([8.0, 8.0])
                .resizable(false)
                .show(ui.ctx(), |ui| {
                    ui.label(format!(
                        "{ms:.1} ms / frame ({:.0} fps)",
                        1e3 / ms.max(1e-3)
                    ));
                    ui.label(format!("{gpu_passes}{readback}"));
                    for line in &pass_lines {
                        ui.label(format!("  {line}"));
                    }
                    egui::ComboBox::from_label("method (m/n)")
                        .selected_text(methods[method].name())
                        .show_ui(ui, |ui| {
                            for (i, id) in methods.iter().enumerate() {
                                ui.selectable_value(&mut method, i, id.name());
                            }
                        });
                    for spec in methods[method].info().params {
                        let Some(value) = params.get(spec.name) else {
                            continue;
                        };
                        match spec.kind {
                            ParamKind::Choice(choices) => {
                                let mut chosen = value.clone();
                                egui::ComboBox::from_label(spec.name)
                                    .selected_text(&chosen)
                                    .show_ui(ui, |ui| {
                                        for c in choices {
                                            ui.selectable_value(&mut chosen, (*c).to_owned(), *c);
                                        }
                                    });
                                if chosen != value {
                                    let _ = params.set(spec.name, &chosen, "panel");
                                }
                            }
                            ParamKind::Integer { min, max } => {
                                let mut v: u32 = value.parse().unwrap_or(min);
                                ui.add(egui::Slider::new(&mut v, min..=max).text(spec.name));
                                if v.to_string() != value {
                                    let _ = params.set(spec.name, &v.to_string(), "panel");
                                }
                            }
                        }
                    }
                    ui.add(
                        egui::Slider::new(&mut ior, refract_scene::scene::IOR_RANGE)
                            .logarithmic(true)
                            .text("IOR (i/k)"),
                    );
                    ui.horizontal(|ui| {
                        ui.label("backend (b)");
                        if has_gpu {
                            ui.radio_value(&mut use_gpu, true, "GPU");
                        }
                        ui.radio_value(&mut use_gpu, false, "CPU");
                    });
                    ui.checkbox(&mut split, "split view with the exact reference (v)");
                    ui.horizontal(|ui| {
                        ui.label("show (e)");
                        ui.radio_value(&mut error_view, ErrorView::Off, "image");
                        ui.radio_value(&mut error_view, ErrorView::Flip, "FLIP");
                        ui.radio_value(&mut error_view, ErrorView::T2, "T2 error");
                    });
                    ui.collapsing("keys", |ui| {
                        ui.label(
                            "left drag orbit · right drag pan · wheel zoom · r reset\n\
                             m/n method · b backend · i/k IOR · t TIR · v split · e error map\n\
                             p screenshot + metrics · h hide this panel · q quit",
                        );
                    });
                });
        });
        display
            .egui_state
            .handle_platform_output(&display.window, output.platform_output);
        let pixels_per_point = output.pixels_per_point;
        let jobs = display.egui.tessellate(output.shapes, pixels_per_point);
        // Apply what the panel changed.
        self.method = method;
        self.method_params[method] = params;
        self.use_gpu = use_gpu;
        self.split = split;
        self.error_view = error_view;
        if (ior - self.scene.refractor.ior()).abs() > 1e-6 {
            self.pending_ior = Some(ior);
        }
        Some(PanelFrame {
            jobs,
            textures: output.textures_delta,
            screen: egui_wgpu::ScreenDescriptor {
                size_in_pixels: [width, height],
                pixels_per_point,
            },
        })
    }

    /// Changes the refractor's IOR (re-uploading the scene to both renderers).
    fn set_ior(&mut self, ior: f32) -> anyhow::Result<()> {
        Arc::make_mut(&mut self.scene).refractor.set_ior(ior.clamp(
            *refract_scene::scene::IOR_RANGE.start(),
            *refract_scene::scene::IOR_RANGE.end(),
        ))?;
        self.scene_version += 1;
        if let Some(gpu) = &mut self.gpu {
            gpu.prepare(&self.scene)?;
        }
        self.cpu.prepare(&self.scene)?;
        Ok(())
    }

    fn camera(&self, width: u32, height: u32) -> anyhow::Result<Camera> {
        Ok(Camera::new(CameraDesc {
            eye: self.orbit.eye(),
            target: self.orbit.target,
            width,
            height,
            ..self.scene.camera
        })?)
    }

    fn renderer(&mut self) -> &mut dyn Renderer {
        match (&mut self.gpu, self.use_gpu) {
            (Some(gpu), true) => gpu,
            _ => &mut self.cpu,
        }
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let (w, h) = self.args.size;
        let window = Arc::new(
            event_loop.create_window(
                Window::default_attributes()
                    .with_title("refract view")
                    .with_inner_size(PhysicalSize::new(w, h)),
            )?,
        );
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        let surface = instance.create_surface(Arc::clone(&window))?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|err| {
            anyhow::anyhow!(
                "no GPU adapter can show a window here ({err}); install a Vulkan driver (Debian: mesa-vulkan-drivers)"
            )
        })?;
        let context = GpuContext::from_adapter(&adapter)?;
        eprintln!("GPU: {} ({:?})", context.info.name, context.info.backend);
        let gpu = GpuRenderer::with_context(context)?;
        let device = &gpu.context().device;
        let caps = surface.get_capabilities(&adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .context("the surface supports no format")?;
        let copy_src = caps.usages.contains(wgpu::TextureUsages::COPY_SRC);
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: if copy_src {
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC
            } else {
                wgpu::TextureUsages::RENDER_ATTACHMENT
            },
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::Fifo,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: Vec::new(),
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(device, &config);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("view"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let pipeline = display_pipeline(device, "view", SHADER, &layout, format);
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("view frame"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: true },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let frame_pipeline =
            display_pipeline(device, "view frame", FRAME_SHADER, &frame_layout, format);
        let frame_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("view frame size"),
            size: std::mem::size_of::<FrameDisplay>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // The frame's bytes are sRGB-encoded: an sRGB surface gets them through an sRGB
        // texture (decoded, then encoded again), a linear one as they are.
        let texture_format = if format.is_srgb() {
            wgpu::TextureFormat::Rgba8UnormSrgb
        } else {
            wgpu::TextureFormat::Rgba8Unorm
        };
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer =
            egui_wgpu::Renderer::new(device, format, egui_wgpu::RendererOptions::default());
        let mut gpu = gpu;
        gpu.prepare(&self.scene)?;
        self.cpu.prepare(&self.scene)?;
        self.gpu = Some(gpu);
        self.display = Some(Display {
            window,
            surface,
            config,
            pipeline,
            layout,
            frame_pipeline,
            frame_layout,
            frame_uniform,
            texture_format,
            copy_src,
            egui: egui_ctx,
            egui_state,
            egui_renderer,
        });
        Ok(())
    }

    fn title(&self) -> String {
        let reference = if self.split || self.error_view != ErrorView::Off {
            match &self.reference_level {
                None => " — reference: tracing".to_owned(),
                Some(l) => {
                    let traced = reference_origin(l);
                    if l.full {
                        format!(" — reference ({traced}): done")
                    } else {
                        format!(
                            " — reference ({traced}): {}×{} (refining)",
                            l.frame.width, l.frame.height
                        )
                    }
                }
            }
        } else {
            String::new()
        };
        let view = match self.error_view {
            ErrorView::Off => "",
            ErrorView::Flip => " — FLIP map",
            ErrorView::T2 => " — T2 error map (0–20°)",
        };
        let passes = self.gpu_ms.map_or_else(String::new, |ms| {
            let passes: Vec<String> = self.pass_times.iter().map(pass_time).collect();
            if passes.is_empty() {
                format!(", GPU passes {ms:.1} ms")
            } else {
                format!(", GPU passes {ms:.1} ms: {}", passes.join(", "))
            }
        });
        let readback = if self.use_gpu && !self.shown_from_gpu {
            ", read back"
        } else {
            ""
        };
        format!(
            "refract view — {} — {} ({}) on {} — IOR {} — {:.1} ms ({:.0} fps{passes}{readback}){view}{reference} — h panel, m/n method, b backend, v split, e error map, i/k IOR, t TIR, r reset, p screenshot, q quit",
            self.scene.name,
            self.methods[self.method],
            self.params().describe(),
            if self.use_gpu { "GPU" } else { "CPU" },
            self.scene.refractor.ior(),
            self.last_ms,
            1e3 / self.last_ms.max(1e-3)
        )
    }

    fn key(&mut self, key: &str) -> anyhow::Result<bool> {
        let n = self.methods.len();
        match key {
            "m" => self.method = (self.method + 1) % n,
            "n" => self.method = (self.method + n - 1) % n,
            "b" => self.use_gpu = !self.use_gpu && self.gpu.is_some(),
            "t" => {
                // The current method's exit TIR policy (methods without one ignore it).
                let next = match self.params().get("tir").as_deref() {
                    Some("clamp") => TirPolicy::ReflectOnce,
                    Some("reflect") => TirPolicy::Black,
                    _ => TirPolicy::ClampToCritical,
                };
                let p = &mut self.method_params[self.method];
                *p = p.with_tir_policy(next);
            }
            "v" => self.split = !self.split,
            "e" => {
                self.error_view = match self.error_view {
                    ErrorView::Off => ErrorView::Flip,
                    ErrorView::Flip => ErrorView::T2,
                    ErrorView::T2 => ErrorView::Off,
                }
            }
            "i" | "k" => {
                let step = if key == "i" { 0.05 } else { -0.05 };
                self.set_ior(self.scene.refractor.ior() + step)?;
            }
            "h" => self.show_panel = !self.show_panel,
            "r" => self.orbit = self.home,
            "p" => self.screenshot()?,
            "q" | "escape" => return Ok(false),
            _ => {}
        }
        Ok(true)
    }

    fn apply(&mut self, action: &Action) -> anyhow::Result<bool> {
        match action {
            Action::Key(k) => return self.key(&k.to_lowercase()),
            Action::Orbit(dx, dy) => self.orbit.orbit(*dx, *dy),
            Action::Pan(dx, dy) => self.orbit.pan(*dx, *dy),
            Action::Zoom(s) => self.orbit.zoom(*s),
            Action::Wait => {}
        }
        Ok(true)
    }

    /// Renders the current view and shows it; returns whether to go on.
    fn redraw(&mut self) -> anyhow::Result<bool> {
        if let Some(action) = self.actions.get(self.frames_done as usize).cloned()
            && !self.apply(&action)?
        {
            return Ok(false);
        }
        let Some(display) = &self.display else {
            return Ok(true);
        };
        let (width, height) = (display.config.width, display.config.height);
        let panel = self.panel(width, height);
        if let Some(ior) = self.pending_ior.take() {
            self.set_ior(ior)?;
        }
        let begun = Instant::now();
        let camera = self.camera(width, height)?;
        let params = self.params();
        let composed = self.split || self.error_view != ErrorView::Off;
        let on_gpu = self.use_gpu && !composed && !self.args.readback;
        if let (Some(gpu), true) = (&mut self.gpu, on_gpu) {
            // The GPU's frame goes to the window on the GPU: no readback, no upload.
            let start = Instant::now();
            let shown = gpu.render_on_gpu(&camera, &params)?;
            self.last_ms = start.elapsed().as_secs_f64() * 1e3;
            self.gpu_ms =
                (shown.timing.source == TimingSource::GpuTimestamps).then_some(shown.timing.ms);
            self.pass_times = gpu.last_pass_times();
            self.shown_from_gpu = true;
            self.present(Source::Gpu(&params), width, height, panel)?;
            return self.after_present(begun);
        }
        let mut frame = std::mem::take(&mut self.frame);
        let start = Instant::now();
        let timing = self
            .renderer()
            .render(&camera, &params, FrameOutputs::Color, &mut frame)?;
        self.last_ms = start.elapsed().as_secs_f64() * 1e3;
        self.gpu_ms = (timing.source == TimingSource::GpuTimestamps).then_some(timing.ms);
        self.pass_times = match (&self.gpu, self.gpu_ms) {
            (Some(gpu), Some(_)) if self.use_gpu => gpu.last_pass_times(),
            _ => Vec::new(),
        };
        self.shown_from_gpu = false;
        self.frame = frame;
        let mut pixels: Vec<u8> = self
            .frame
            .color
            .iter()
            .flat_map(|&c| {
                let [r, g, b] = to_srgb8(c);
                [r, g, b, 255]
            })
            .collect();
        if self.split || self.error_view != ErrorView::Off {
            self.refine_reference(*camera.desc());
        }
        if self.error_view != ErrorView::Off {
            self.error_map(&camera, &params, &mut pixels)?;
        }
        if self.split {
            self.compose_split(&mut pixels, width, height);
        }
        self.present(Source::Pixels(&pixels), width, height, panel)?;
        self.after_present(begun)
    }

    /// Counts the frame, titles the window and, for unattended runs, ends with the screenshot;
    /// returns whether to go on.
    fn after_present(&mut self, begun: Instant) -> anyhow::Result<bool> {
        self.frames_done += 1;
        self.frame_ms.push(begun.elapsed().as_secs_f64() * 1e3);
        if let Some(display) = &self.display {
            display.window.set_title(&self.title());
        }
        // Unattended runs that show the reference end once it is complete (the run goes on
        // past `--frames` until then).
        let waiting = (self.split || self.error_view != ErrorView::Off)
            && !self.reference_level.as_ref().is_some_and(|l| l.full);
        if self.args.frames.is_some_and(|n| self.frames_done >= n) && !waiting {
            eprintln!("{}", self.frame_summary());
            self.screenshot()?;
            return Ok(false);
        }
        Ok(true)
    }

    /// Asks the background tracer for the current view (a no-op while it is unchanged) and
    /// keeps its newest level.
    fn refine_reference(&mut self, camera: CameraDesc) {
        let force = self.scene_version != self.reference_scene_version;
        self.reference_scene_version = self.scene_version;
        // On the GPU when the method runs there (the viewer's device, another thread).
        let gpu = self
            .gpu
            .as_ref()
            .filter(|_| self.use_gpu)
            .map(GpuRenderer::context);
        let generation = self.reference.request(&self.scene, camera, gpu, force);
        if generation != self.reference_generation {
            self.reference_generation = generation;
            self.reference_level = None;
        }
        if let Some(level) = self.reference.poll(generation) {
            self.reference_level = Some(level);
        }
    }

    /// The right half of the window shows the reference (its newest level, scaled), with a
    /// divider.
    fn compose_split(&self, pixels: &mut [u8], width: u32, height: u32) {
        let Some(level) = &self.reference_level else {
            return;
        };
        let (lw, lh) = (level.frame.width, level.frame.height);
        for y in 0..height {
            for x in width / 2..width {
                let i = 4 * (y * width + x) as usize;
                let color = if x < width / 2 + 2 {
                    [255, 255, 255]
                } else {
                    let (sx, sy) = ((x * lw / width).min(lw - 1), (y * lh / height).min(lh - 1));
                    to_srgb8(level.frame.color[(sy * lw + sx) as usize])
                };
                pixels[i..i + 3].copy_from_slice(&color);
            }
        }
    }

    /// Replaces the method's pixels by its FLIP or T2-error map against the full-resolution
    /// reference (magma, FLIP 0–1, T2 0–20°), once that reference has arrived.
    fn error_map(
        &mut self,
        camera: &Camera,
        params: &MethodParams,
        pixels: &mut [u8],
    ) -> anyhow::Result<()> {
        let Some(level) = self.reference_level.as_ref().filter(|l| l.full) else {
            return Ok(());
        };
        if (level.frame.width, level.frame.height) != (camera.width(), camera.height()) {
            return Ok(());
        }
        let truth = level.frame.clone();
        let mut frame = Frame::default();
        self.renderer()
            .render(camera, params, FrameOutputs::ColorAndAovs, &mut frame)?;
        let (_, maps) = refract_eval::metrics::evaluate(
            &truth,
            &frame,
            camera,
            self.scene.refractor.diameter(),
        );
        let (values, max) = match self.error_view {
            ErrorView::Flip => (maps.flip, 1.0),
            _ => (maps.t2_deg, refract_eval::images::T2_SCALE_DEG),
        };
        let lut = nv_flip::magma_lut().to_vec();
        for (px, v) in pixels.chunks_exact_mut(4).zip(values) {
            let rgb = if v.is_nan() {
                [40, 40, 40]
            } else {
                refract_eval::images::magma(&lut, v / max)
            };
            px[..3].copy_from_slice(&rgb);
        }
        Ok(())
    }

    fn present(
        &mut self,
        source: Source<'_>,
        width: u32,
        height: u32,
        mut panel: Option<PanelFrame>,
    ) -> anyhow::Result<()> {
        let (Some(display), Some(gpu)) = (&mut self.display, &self.gpu) else {
            if let Some(panel) = &mut panel {
                panel.textures.clear();
            }
            return Ok(());
        };
        let (device, queue) = (&gpu.context().device, &gpu.context().queue);
        // The panel's new textures first (egui requires every delta applied, even when this
        // frame is then skipped); its freed ones after the frame is drawn, below.
        let freed: Vec<egui::TextureId> = match &mut panel {
            Some(panel) => {
                for (id, deltas) in &panel.textures.set {
                    for delta in deltas {
                        display
                            .egui_renderer
                            .update_texture(device, queue, *id, delta);
                    }
                }
                let freed = std::mem::take(&mut panel.textures.free)
                    .into_iter()
                    .collect();
                panel.textures.clear();
                freed
            }
            None => Vec::new(),
        };
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let (pipeline, group) = match source {
            Source::Pixels(pixels) => {
                let texture = device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("view frame"),
                    size,
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: display.texture_format,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                });
                queue.write_texture(
                    texture.as_image_copy(),
                    pixels,
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(4 * width),
                        rows_per_image: Some(height),
                    },
                    size,
                );
                let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
                let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("view frame"),
                    layout: &display.layout,
                    entries: &[wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&view),
                    }],
                });
                (&display.pipeline, group)
            }
            Source::Gpu(params) => {
                let color = gpu
                    .last_color(params)
                    .context("the GPU frame's colour buffer is gone")?;
                let uniform = &display.frame_uniform;
                let srgb_surface = u32::from(display.config.format.is_srgb());
                queue.write_buffer(
                    uniform,
                    0,
                    bytemuck::bytes_of(&FrameDisplay {
                        width,
                        height,
                        srgb_surface,
                        _padding: 0,
                    }),
                );
                let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("view frame"),
                    layout: &display.frame_layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: color.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: uniform.as_entire_binding(),
                        },
                    ],
                });
                (&display.frame_pipeline, group)
            }
        };
        let output = match display.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                display.surface.configure(device, &display.config);
                for id in &freed {
                    display.egui_renderer.free_texture(id);
                }
                return Ok(());
            }
            // Minimised or hidden: skip the frame.
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                for id in &freed {
                    display.egui_renderer.free_texture(id);
                }
                return Ok(());
            }
            other => anyhow::bail!("the window surface is not available: {other:?}"),
        };
        let target = output
            .texture
            .create_view(&wgpu::TextureViewDescriptor::default());
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("view"),
        });
        if let Some(panel) = &panel {
            let extra = display.egui_renderer.update_buffers(
                device,
                queue,
                &mut encoder,
                &panel.jobs,
                &panel.screen,
            );
            queue.submit(extra);
        }
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("view"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.draw(0..3, 0..1);
            if let Some(panel) = &panel {
                display.egui_renderer.render(
                    &mut pass.forget_lifetime(),
                    &panel.jobs,
                    &panel.screen,
                );
            }
        }
        for id in &freed {
            display.egui_renderer.free_texture(id);
        }
        // Unattended runs read the presented image back: the screenshot is the window's.
        let capture = (self.args.frames.is_some() && display.copy_src).then(|| {
            let bytes_per_row = (4 * width).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
                * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("window readback"),
                size: u64::from(bytes_per_row) * u64::from(height),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            encoder.copy_texture_to_buffer(
                output.texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(bytes_per_row),
                        rows_per_image: Some(height),
                    },
                },
                size,
            );
            (buffer, bytes_per_row)
        });
        queue.submit([encoder.finish()]);
        let bgra = matches!(
            display.config.format,
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        display.window.pre_present_notify();
        queue.present(output);
        if let Some((buffer, bytes_per_row)) = capture {
            let data = gpu.context().read_buffer(&buffer)?;
            let rgb: Vec<u8> = data
                .chunks_exact(bytes_per_row as usize)
                .flat_map(|row| {
                    row[..4 * width as usize].chunks_exact(4).flat_map(|p| {
                        if bgra {
                            [p[2], p[1], p[0]]
                        } else {
                            [p[0], p[1], p[2]]
                        }
                    })
                })
                .collect();
            self.captured = Some((width, height, rgb));
        }
        Ok(())
    }

    /// The unattended run's frame times: the median after the first frame (which compiles and
    /// allocates), how the last frame reached the window.
    fn frame_summary(&self) -> String {
        let mut ms: Vec<f64> = self.frame_ms.iter().skip(1).copied().collect();
        ms.sort_by(f64::total_cmp);
        let median = ms.get(ms.len() / 2).copied().unwrap_or(f64::NAN);
        let path = match (self.use_gpu, self.shown_from_gpu) {
            (true, true) => "GPU frames drawn into the window on the GPU, no readback",
            (true, false) => "GPU frames read back and uploaded to the window",
            (false, _) => "CPU frames uploaded to the window",
        };
        let reference = self
            .reference_level
            .as_ref()
            .map(|l| {
                format!(
                    "; split-view reference traced on the {}",
                    reference_origin(l)
                )
            })
            .unwrap_or_default();
        let passes = if self.pass_times.is_empty() {
            String::new()
        } else {
            let passes: Vec<String> = self.pass_times.iter().map(pass_time).collect();
            format!("; last frame's GPU passes: {}", passes.join(", "))
        };
        format!(
            "frames: {}, median {median:.2} ms a frame from redraw to present after the first ({path}){reference}{passes}",
            self.frames_done
        )
    }

    /// Writes the last frame as PNG and its metrics against the exact reference as JSON.
    fn screenshot(&mut self) -> anyhow::Result<()> {
        if self.shown_from_gpu {
            // The frame never left the GPU: read it back once, for the file and the metrics.
            if let Some(display) = &self.display {
                let (width, height) = (display.config.width, display.config.height);
                let camera = self.camera(width, height)?;
                let params = self.params();
                let mut frame = std::mem::take(&mut self.frame);
                self.renderer()
                    .render(&camera, &params, FrameOutputs::Color, &mut frame)?;
                self.frame = frame;
            }
        }
        let (width, height) = (self.frame.width, self.frame.height);
        if width == 0 {
            return Ok(());
        }
        // The window's pixels when they were read back, else the frame's (the same bytes).
        let (pixels, source): (Vec<u8>, &str) = match &self.captured {
            Some((w, h, rgb)) if (*w, *h) == (width, height) => (rgb.clone(), "the window"),
            _ => (
                self.frame.color.iter().flat_map(|&c| to_srgb8(c)).collect(),
                "the frame",
            ),
        };
        let path = self.args.screenshot.clone();
        write_png_rgb8(&path, width, height, &pixels)?;
        let camera = self.camera(width, height)?;
        // The split view's full level when it is of this view, else traced here on the CPU.
        let level = self.reference_level.take().filter(|l| {
            l.full
                && l.generation == self.reference_generation
                && (l.frame.width, l.frame.height) == (width, height)
        });
        let truth = match level {
            Some(level) => level.frame,
            None => {
                let mut reference = ReferenceRenderer::new();
                reference.prepare(&self.scene)?;
                let mut truth = Frame::default();
                reference.render(
                    &camera,
                    &MethodParams::defaults(MethodId::Reference),
                    FrameOutputs::ColorAndAovs,
                    &mut truth,
                )?;
                truth
            }
        };
        let params = self.params();
        let mut frame = Frame::default();
        self.renderer()
            .render(&camera, &params, FrameOutputs::ColorAndAovs, &mut frame)?;
        let (mut record, _) = evaluate_method(&truth, &frame, &camera, &self.scene, &params);
        record.scene.clone_from(&self.scene.name);
        record.method = params.id().name().to_owned();
        record.backend = if self.use_gpu { "gpu" } else { "cpu" }.to_owned();
        record.params = params.describe();
        record.ms_per_frame = Some(self.last_ms);
        write_text_atomically(
            &path.with_extension("json"),
            &serde_json::to_string_pretty(&record)?,
        )?;
        eprintln!(
            "screenshot of {source}: {} ({width}x{height}), metrics: {}",
            path.display(),
            path.with_extension("json").display()
        );
        Ok(())
    }
}

impl ApplicationHandler for Viewer {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.display.is_none()
            && let Err(err) = self.open(event_loop)
        {
            self.error = Some(err);
            event_loop.exit();
            return;
        }
        if let Some(display) = &self.display {
            display.window.request_redraw();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        // The panel sees every event first; what it consumes (clicks, drags on it) stops here.
        if self.show_panel
            && let Some(display) = &mut self.display
        {
            let response = display.egui_state.on_window_event(&display.window, &event);
            if response.consumed
                && matches!(
                    event,
                    WindowEvent::MouseInput { .. }
                        | WindowEvent::CursorMoved { .. }
                        | WindowEvent::MouseWheel { .. }
                        | WindowEvent::KeyboardInput { .. }
                )
            {
                display.window.request_redraw();
                return;
            }
        }
        let result = match event {
            WindowEvent::CloseRequested => Ok(false),
            WindowEvent::Resized(size) => {
                // A minimised window (size 0) keeps its configuration and skips frames.
                if let (Some(display), Some(gpu)) = (&mut self.display, &self.gpu)
                    && size.width > 0
                    && size.height > 0
                {
                    display.config.width = size.width;
                    display.config.height = size.height;
                    display
                        .surface
                        .configure(&gpu.context().device, &display.config);
                }
                Ok(true)
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                match &event.logical_key {
                    Key::Character(c) => self.key(&c.to_lowercase()),
                    Key::Named(NamedKey::Escape) => self.key("escape"),
                    _ => Ok(true),
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.drag = (state == ElementState::Pressed).then_some((
                    button,
                    self.cursor.0,
                    self.cursor.1,
                ));
                Ok(true)
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.cursor = (position.x, position.y);
                if let Some((button, x, y)) = self.drag {
                    let (dx, dy) = ((position.x - x) as f32, (position.y - y) as f32);
                    match button {
                        MouseButton::Left => self.orbit.orbit(dx, dy),
                        _ => self.orbit.pan(dx, dy),
                    }
                    self.drag = Some((button, position.x, position.y));
                }
                Ok(true)
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                self.orbit.zoom(steps);
                Ok(true)
            }
            WindowEvent::RedrawRequested => self.redraw(),
            _ => Ok(true),
        };
        match result {
            Ok(true) => {
                if let Some(display) = &self.display {
                    display.window.request_redraw();
                }
            }
            Ok(false) => event_loop.exit(),
            Err(err) => {
                self.error = Some(err);
                event_loop.exit();
            }
        }
    }
}

/// Runs `refract view`.
pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    let loaded = load_scene(&args.scene)?;
    for warning in &loaded.warnings {
        eprintln!("warning: {warning}");
    }
    let scene = Arc::new(loaded.scene);
    let actions = match &args.script {
        Some(path) => parse_script(
            &std::fs::read_to_string(path)
                .with_context(|| format!("{}: cannot read the script", path.display()))?,
            &path.display().to_string(),
        )?,
        None => Vec::new(),
    };
    // The methods that can render this scene (glass-only families skip mirrors and metals).
    let methods: Vec<MethodId> = MethodId::approximations()
        .filter(|m| refract_scene::scene_support(*m, &scene).is_ok())
        .collect();
    anyhow::ensure!(
        args.method != MethodId::Reference,
        "--method: the viewer shows approximations; the reference is what `p` compares with"
    );
    let method = match methods.iter().position(|m| *m == args.method) {
        Some(k) => k,
        None => {
            if let Err(reason) = refract_scene::scene_support(args.method, &scene) {
                eprintln!("note: {reason}; showing distance-map");
            }
            methods
                .iter()
                .position(|m| *m == MethodId::DistanceMap)
                .context("no method renders this scene")?
        }
    };
    let use_gpu = match args.backend.as_str() {
        "gpu" => true,
        "cpu" => false,
        other => anyhow::bail!("--backend: unknown backend `{other}`; expected gpu or cpu"),
    };
    let home = Orbit::of(&scene.camera);
    let methods_params: Vec<MethodParams> =
        methods.iter().map(|&m| MethodParams::defaults(m)).collect();
    let event_loop = EventLoop::new().map_err(|err| {
        anyhow::anyhow!(
            "cannot open a window ({err}); is a display (DISPLAY or WAYLAND_DISPLAY) available?"
        )
    })?;
    let mut viewer = Viewer {
        args,
        scene,
        actions,
        methods,
        method,
        use_gpu,
        orbit: home,
        home,
        frame: Frame::default(),
        frames_done: 0,
        last_ms: 0.0,
        gpu_ms: None,
        pass_times: Vec::new(),
        shown_from_gpu: false,
        frame_ms: Vec::new(),
        drag: None,
        cursor: (0.0, 0.0),
        display: None,
        gpu: None,
        cpu: CpuRenderer::new(),
        error: None,
        captured: None,
        reference: ProgressiveReference::start(),
        reference_level: None,
        reference_generation: 0,
        scene_version: 0,
        reference_scene_version: 0,
        split: false,
        error_view: ErrorView::Off,
        method_params: methods_params,
        show_panel: true,
        pending_ior: None,
    };
    event_loop.run_app(&mut viewer)?;
    match viewer.error {
        Some(err) => Err(err),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scripts_parse_and_errors_name_the_line() {
        let actions =
            parse_script("# comment\nkey m\norbit 10 -5\nzoom 2\nwait\n", "s").expect("ok");
        assert_eq!(
            actions,
            [
                Action::Key("m".into()),
                Action::Orbit(10.0, -5.0),
                Action::Zoom(2.0),
                Action::Wait
            ]
        );
        let err = parse_script("key m\nspin 3\n", "s.txt")
            .expect_err("bad")
            .to_string();
        assert!(err.contains("s.txt:2"), "{err}");
        assert!(parse_script("orbit nan 1\n", "s").is_err());
        assert_eq!(parse_size("320x240"), Ok((320, 240)));
        assert!(parse_size("10x10").is_err());
    }

    #[test]
    fn the_orbit_camera_starts_at_the_scene_camera() {
        let desc = CameraDesc::default();
        let orbit = Orbit::of(&desc);
        assert!((orbit.eye() - desc.eye).length() < 1e-5, "{}", orbit.eye());
        let mut moved = orbit;
        moved.orbit(100.0, 0.0);
        assert!((moved.eye() - moved.target).length() - orbit.distance < 1e-4);
        moved.zoom(1.0);
        assert!(moved.distance < orbit.distance);
    }
}
