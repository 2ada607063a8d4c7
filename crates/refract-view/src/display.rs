//! The window's wgpu state and how a frame reaches it: the display pipelines (a CPU frame's
//! tonemapped pixels, or a GPU frame's colour buffer without a readback), the split view, the
//! error maps.

use std::sync::Arc;

use anyhow::Context;
use refract_core::Camera;
use refract_scene::tonemap::to_srgb8;
use refract_scene::{Frame, FrameOutputs, MethodParams};

use winit::window::Window;

use crate::{ErrorView, Viewer};

/// The window's wgpu state: the surface and a pipeline that shows the frame's tonemapped pixels.
pub(crate) struct Display {
    pub(crate) window: Arc<Window>,
    pub(crate) surface: wgpu::Surface<'static>,
    pub(crate) config: wgpu::SurfaceConfiguration,
    pub(crate) pipeline: wgpu::RenderPipeline,
    pub(crate) layout: wgpu::BindGroupLayout,
    /// Draws a GPU frame's colour buffer straight into the window (no readback).
    pub(crate) frame_pipeline: wgpu::RenderPipeline,
    pub(crate) frame_layout: wgpu::BindGroupLayout,
    /// The GPU frame's size and the surface's encoding (`FrameDisplay`), written every frame.
    pub(crate) frame_uniform: wgpu::Buffer,
    pub(crate) texture_format: wgpu::TextureFormat,
    pub(crate) copy_src: bool,
    pub(crate) egui: egui::Context,
    pub(crate) egui_state: egui_winit::State,
    pub(crate) egui_renderer: egui_wgpu::Renderer,
}

/// What the panel draws this frame, tessellated.
pub(crate) struct PanelFrame {
    pub(crate) jobs: Vec<egui::ClippedPrimitive>,
    pub(crate) textures: egui::TexturesDelta,
    pub(crate) screen: egui_wgpu::ScreenDescriptor,
}

impl Drop for PanelFrame {
    /// A frame abandoned on an error path drops its texture changes on purpose (egui panics on
    /// unapplied ones otherwise; `present` applies them before this runs).
    fn drop(&mut self) {
        self.textures.clear();
    }
}

/// The display pass: the frame's texture drawn texel for texel (`shaders/display.wgsl`).
pub(crate) const SHADER: &str = include_str!("../shaders/display.wgsl");
pub(crate) const FRAME_SHADER: &str = include_str!("../shaders/display_frame.wgsl");

/// What a frame shows: pixels tonemapped on the CPU (the CPU backend, the split view, the
/// error maps), or the GPU backend's colour buffer of `method`, drawn without a readback.
pub(crate) enum Source<'a> {
    Pixels(&'a [u8]),
    Gpu(&'a MethodParams),
}

/// A full-screen pass of `source` (entry points `vs` and `fs`) with one bind group of
/// `layout`, drawing into a surface of `format`.
pub(crate) fn display_pipeline(
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
pub(crate) struct FrameDisplay {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) srgb_surface: u32,
    pub(crate) _padding: u32,
}

impl Viewer {
    /// The right half of the window shows the reference (its newest level, scaled), with a
    /// divider.
    pub(crate) fn compose_split(&self, pixels: &mut [u8], width: u32, height: u32) {
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
    pub(crate) fn error_map(
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

    pub(crate) fn present(
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
}
