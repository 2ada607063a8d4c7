//! `refract view [SCENE]`: a window (winit 0.30 + a wgpu 30 surface) that renders a scene with
//! any method of the registry on the GPU backend (or the CPU backend), with an orbit camera and
//! live method, IOR, TIR-policy and backend switches; frame time in the title; a screenshot key
//! that writes the PNG and the frame's metrics against the exact reference. `--frames`,
//! `--script` and `--screenshot` run it unattended (the headless test under Xvfb).
//! `docs/viewer.md` lists the keys.
//!
//! Its own crate so that the backends and the experiments never link a window system, and the
//! CLI stays a thin shell; its shader is `shaders/display.wgsl`, validated by naga in its tests.
//!
//! Here: the viewer's state, its event loop, its keys and its frame loop. Beside it: `args` (the
//! command line and unattended scripts), `orbit` (the camera), `display` (the window's wgpu
//! state and how a frame reaches it: pixels, a GPU buffer, the split view, the error maps),
//! `panel` (the egui panel), `screenshot` (the PNG, the frame's metrics, the run's summary),
//! `reference` (the exact reference refined in the background).

mod args;
mod display;
mod orbit;
mod panel;
mod reference;
mod screenshot;

use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use refract_core::exit::TirPolicy;
use refract_core::{Camera, CameraDesc};
use refract_cpu::CpuRenderer;
use refract_eval::load_scene;
use refract_gpu::{GpuContext, GpuRenderer};
use refract_scene::tonemap::to_srgb8;
use refract_scene::{
    BackendId, Frame, FrameOutputs, MethodId, MethodParams, Renderer, Scene, TimingSource,
};
use winit::application::ApplicationHandler;

use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use crate::args::{Action, parse_script};
use crate::display::{Display, FRAME_SHADER, FrameDisplay, SHADER, Source, display_pipeline};
use crate::orbit::Orbit;
use crate::reference::{Level, ProgressiveReference};

pub use crate::args::ViewArgs;

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

impl Viewer {
    fn params(&self) -> MethodParams {
        self.method_params[self.method]
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
