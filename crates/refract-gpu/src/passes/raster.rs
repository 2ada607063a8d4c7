//! Rasterising any mesh of the scene from any camera into float targets (`shaders/raster.wgsl`):
//! the back-face and front-face passes of Wyman 2005a §4, and a generic surface pass (position,
//! normal, uv, object id) for opaque objects. Mirrored cameras (cube-map faces) flip the
//! winding, so every pipeline exists for both windings.

use refract_core::{BackSurface, Camera};

use crate::bindings::uniform_entry;
use crate::scene_buffers::{GpuMesh, Vertex};
use crate::shaders::RASTER_MODULE;

/// The format of every colour target: 32-bit float RGBA.
pub(crate) const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// The depth format.
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Depth peeling keeps surfaces farther from the reference point than the previous layer by
/// this relative margin (`fs_surface_peel`; the CPU backend's `refract_cpu::raster::PEEL_MARGIN`).
pub(crate) const PEEL_MARGIN: f32 = 1e-3;

/// `PeelUniforms` of `shaders/raster.wgsl`: the reference point peeling measures distances
/// from (a cube map's centre, the eye) and [`PEEL_MARGIN`].
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct PeelUniforms {
    pub center: [f32; 4],
    pub margin: f32,
    pub _padding: [f32; 3],
}

const _: () = assert!(core::mem::size_of::<PeelUniforms>() == 32);

/// What a raster pass draws and keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum RasterKind {
    /// Back faces, furthest or second surface (Wyman 2005a §3.2): one target, (N, distance).
    BackFaces(BackSurface),
    /// Nearest front faces: (P1, d_N) and (N1, 1).
    FrontFaces,
    /// Nearest front faces of any surface: (P, scalar), (N, 1), (uv, object, 1).
    Surface,
    /// [`RasterKind::Surface`] of the nearest back faces (a distance-map layer).
    SurfaceBack,
    /// [`RasterKind::Surface`] of the nearest face of either orientation.
    SurfaceBoth,
    /// [`RasterKind::SurfaceBoth`] behind the previous layer (depth peeling, `fs_surface_peel`,
    /// with the [`RasterPipelines::peel_layout`] group 1).
    SurfacePeel,
}

impl RasterKind {
    fn targets(self) -> usize {
        match self {
            RasterKind::BackFaces(_) => 1,
            RasterKind::FrontFaces => 2,
            RasterKind::Surface
            | RasterKind::SurfaceBack
            | RasterKind::SurfaceBoth
            | RasterKind::SurfacePeel => 3,
        }
    }

    /// The depth the pass clears to: 0 for depth Greater (furthest), 1 for Less.
    pub(crate) fn clear_depth(self) -> f32 {
        match self {
            RasterKind::BackFaces(BackSurface::Furthest) => 0.0,
            _ => 1.0,
        }
    }

    /// The colour the pass clears to: `w = −1` marks an empty back-face texel, `w = 0` an
    /// empty front-face or surface texel.
    pub(crate) fn clear_color(self) -> wgpu::Color {
        match self {
            RasterKind::BackFaces(_) => wgpu::Color {
                r: 0.0,
                g: 0.0,
                b: 0.0,
                a: -1.0,
            },
            _ => wgpu::Color::TRANSPARENT,
        }
    }
}

const KINDS: [RasterKind; 7] = [
    RasterKind::BackFaces(BackSurface::Furthest),
    RasterKind::BackFaces(BackSurface::Second),
    RasterKind::FrontFaces,
    RasterKind::Surface,
    RasterKind::SurfaceBack,
    RasterKind::SurfaceBoth,
    RasterKind::SurfacePeel,
];

/// The raster pipelines: every [`RasterKind`] for both windings.
pub(crate) struct RasterPipelines {
    /// Binding 0: the frame uniforms.
    pub layout: wgpu::BindGroupLayout,
    /// Group 1 of [`RasterKind::SurfacePeel`]: the previous layer's P and N, the peel uniforms.
    pub peel_layout: wgpu::BindGroupLayout,
    pipelines: Vec<(RasterKind, bool, wgpu::RenderPipeline)>,
}

/// One raster pass: which faces of which meshes, seen by which camera, into which targets.
#[derive(Clone, Copy)]
pub(crate) struct RasterPass<'a> {
    /// What the pass writes and its depth test.
    pub kind: RasterKind,
    /// The camera (mirrored cube-map face cameras flip the winding).
    pub camera: &'a Camera,
    /// Group 0: the frame uniforms.
    pub uniforms: &'a wgpu::BindGroup,
    /// Group 1, for [`RasterKind::SurfacePeel`]: the previous layer.
    pub peel: Option<&'a wgpu::BindGroup>,
    /// The meshes drawn.
    pub meshes: &'a [&'a GpuMesh],
    /// The colour targets.
    pub targets: &'a [&'a wgpu::TextureView],
    /// The depth target.
    pub depth: &'a wgpu::TextureView,
}

impl RasterPipelines {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("raster.wgsl"),
            source: wgpu::ShaderSource::Wgsl(RASTER_MODULE.source().into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raster"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("raster"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let fragment_texture = |binding| wgpu::BindGroupLayoutEntry {
            visibility: wgpu::ShaderStages::FRAGMENT,
            ..crate::bindings::texture_entry(binding)
        };
        let peel_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raster peel"),
            entries: &[
                fragment_texture(0),
                fragment_texture(1),
                uniform_entry(2, wgpu::ShaderStages::FRAGMENT),
            ],
        });
        let peel_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("raster peel"),
            bind_group_layouts: &[Some(&layout), Some(&peel_layout)],
            immediate_size: 0,
        });
        let vertex_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<Vertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &Vertex::ATTRIBUTES,
        };
        let target = Some(wgpu::ColorTargetState {
            format: TARGET_FORMAT,
            blend: None,
            write_mask: wgpu::ColorWrites::ALL,
        });
        let mut pipelines = Vec::new();
        for kind in KINDS {
            for mirrored in [false, true] {
                let (cull, compare, fragment): (Option<wgpu::Face>, _, _) = match kind {
                    // Wyman 2005a §3.2: the furthest surface (cull front faces, depth Greater
                    // cleared to 0) or the second surface (the nearest back face, Less).
                    RasterKind::BackFaces(BackSurface::Furthest) => (
                        Some(wgpu::Face::Front),
                        wgpu::CompareFunction::Greater,
                        "fs_back",
                    ),
                    RasterKind::BackFaces(BackSurface::Second) => (
                        Some(wgpu::Face::Front),
                        wgpu::CompareFunction::Less,
                        "fs_back",
                    ),
                    RasterKind::FrontFaces => (
                        Some(wgpu::Face::Back),
                        wgpu::CompareFunction::Less,
                        "fs_front",
                    ),
                    RasterKind::Surface => (
                        Some(wgpu::Face::Back),
                        wgpu::CompareFunction::Less,
                        "fs_surface",
                    ),
                    RasterKind::SurfaceBack => (
                        Some(wgpu::Face::Front),
                        wgpu::CompareFunction::Less,
                        "fs_surface",
                    ),
                    RasterKind::SurfaceBoth => (None, wgpu::CompareFunction::Less, "fs_surface"),
                    RasterKind::SurfacePeel => {
                        (None, wgpu::CompareFunction::Less, "fs_surface_peel")
                    }
                };
                let targets = vec![target.clone(); kind.targets()];
                let label = format!(
                    "raster {kind:?}{}",
                    if mirrored { " (mirrored)" } else { "" }
                );
                let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(&label),
                    layout: Some(if kind == RasterKind::SurfacePeel {
                        &peel_pipeline_layout
                    } else {
                        &pipeline_layout
                    }),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_mesh"),
                        compilation_options: Default::default(),
                        buffers: &[Some(vertex_layout.clone())],
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: wgpu::PrimitiveTopology::TriangleList,
                        // A mirrored view turns counter-clockwise triangles clockwise on screen.
                        front_face: if mirrored {
                            wgpu::FrontFace::Cw
                        } else {
                            wgpu::FrontFace::Ccw
                        },
                        cull_mode: cull,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        depth_compare: Some(compare),
                        stencil: wgpu::StencilState::default(),
                        bias: wgpu::DepthBiasState::default(),
                    }),
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(fragment),
                        compilation_options: Default::default(),
                        targets: &targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                });
                pipelines.push((kind, mirrored, pipeline));
            }
        }
        Self {
            layout,
            peel_layout,
            pipelines,
        }
    }

    fn pipeline(&self, kind: RasterKind, camera: &Camera) -> &wgpu::RenderPipeline {
        let mirrored = camera.is_mirrored();
        self.pipelines
            .iter()
            .find(|(k, m, _)| *k == kind && *m == mirrored)
            .map(|(_, _, p)| p)
            .expect("a pipeline for every kind and winding")
    }

    /// Encodes `pass`: its meshes into its targets (as many as its kind writes) with its depth,
    /// cleared first, timed by `timestamp` when given.
    pub(crate) fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pass: &RasterPass<'_>,
        timestamp: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let RasterPass {
            kind,
            camera,
            uniforms,
            peel,
            meshes,
            targets,
            depth,
        } = *pass;
        debug_assert_eq!(targets.len(), kind.targets());
        let color_attachments: Vec<_> = targets
            .iter()
            .map(|view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(kind.clear_color()),
                        store: wgpu::StoreOp::Store,
                    },
                })
            })
            .collect();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("raster"),
            color_attachments: &color_attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(kind.clear_depth()),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timestamp,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(self.pipeline(kind, camera));
        pass.set_bind_group(0, uniforms, &[]);
        if let Some(peel) = peel {
            pass.set_bind_group(1, peel, &[]);
        }
        for mesh in meshes {
            mesh.draw(&mut pass);
        }
    }
}

/// A 2D render target usable as a texture binding and copy source.
pub(crate) fn target(
    device: &wgpu::Device,
    label: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// The targets of one [`RasterKind::Surface`] pass at one size, with its own camera uniforms:
/// the nearest front faces of some meshes as (P, scalar), (N, 1), (uv, object, 1). The NG
/// texture of Wyman 2005b and the eye pass of the distance maps.
pub(crate) struct SurfaceTargets {
    uniforms: wgpu::Buffer,
    group: wgpu::BindGroup,
    /// P, N, uv + object.
    pub views: [wgpu::TextureView; 3],
    depth: wgpu::TextureView,
}

impl SurfaceTargets {
    /// Allocates `width × height` targets; `label` names them.
    pub(crate) fn new(
        device: &wgpu::Device,
        raster: &RasterPipelines,
        label: &str,
        width: u32,
        height: u32,
    ) -> Self {
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&format!("{label} frame uniforms")),
            size: std::mem::size_of::<refract_core::gpu::FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let group = crate::bindings::bind_group(
            device,
            label,
            &raster.layout,
            &[uniforms.as_entire_binding()],
        );
        let views = ["P", "N", "uv, object"].map(|what| {
            target(
                device,
                &format!("{label} {what}"),
                width,
                height,
                TARGET_FORMAT,
            )
            .create_view(&wgpu::TextureViewDescriptor::default())
        });
        let depth = target(
            device,
            &format!("{label} depth"),
            width,
            height,
            DEPTH_FORMAT,
        )
        .create_view(&wgpu::TextureViewDescriptor::default());
        Self {
            uniforms,
            group,
            views,
            depth,
        }
    }

    /// The camera uniforms buffer (a compute pass reading the targets may bind it too).
    pub(crate) fn uniforms(&self) -> &wgpu::Buffer {
        &self.uniforms
    }

    /// Writes `uniforms` (those of `camera`) and encodes the surface pass of `meshes`, timed by
    /// `timestamp` when given.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn encode(
        &self,
        queue: &wgpu::Queue,
        raster: &RasterPipelines,
        encoder: &mut wgpu::CommandEncoder,
        camera: &Camera,
        uniforms: &refract_core::gpu::FrameUniforms,
        meshes: &[&GpuMesh],
        timestamp: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(uniforms));
        raster.encode(
            encoder,
            &RasterPass {
                kind: RasterKind::Surface,
                camera,
                uniforms: &self.group,
                peel: None,
                meshes,
                targets: &[&self.views[0], &self.views[1], &self.views[2]],
                depth: &self.depth,
            },
            timestamp,
        );
    }
}
