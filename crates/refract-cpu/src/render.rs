//! Running a method on the CPU: buffers (rasterised), then the refract-core kernel per pixel
//! (rows in parallel), then the environment lookup.

use glam::Vec3;
use rayon::iter::Either;
use rayon::prelude::*;
use refract_core::exit::{ExitNormalSource, TirPolicy};
use refract_core::kernel::{ImageSpaceParams, InvalidIor};
use refract_core::{Camera, Method};
use refract_trace::Environment;

use crate::buffers::{BackFaces, PreparedRefractor, front_faces_into};
use crate::raster::{Band, DepthTest, Faces, SurfaceBuffer, band_pixels, rasterize_bands};
use crate::shade::{BandRow, BufferRow, ShadeContext};

/// Parameters of one method run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MethodParams {
    /// Which method (and back surface).
    pub method: Method,
    /// The refractor's index of refraction.
    pub ior: f32,
    /// Second-interface TIR policy (two-interface methods).
    pub tir_policy: TirPolicy,
}

/// Why a method could not run.
#[derive(Debug, thiserror::Error)]
pub enum CpuError {
    /// IOR ≤ 0 or not finite.
    #[error(transparent)]
    Ior(#[from] InvalidIor),
    /// `d_N` does not match the mesh.
    #[error("d_N has {found} values for a mesh of {expected} vertices")]
    NormalDistances {
        /// Values given.
        found: usize,
        /// Vertices in the mesh.
        expected: usize,
    },
}

/// Per-pixel outputs beside the colour; NaN / `None` where they do not apply.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MethodAov {
    /// The pixel sees the refractor.
    pub covered: bool,
    /// `P~2` (two-interface methods).
    pub p2: Vec3,
    /// The direction looked up in the environment (`T1` for `single`).
    pub t2: Vec3,
    /// The exit normal used (two-interface methods).
    pub n2: Vec3,
    /// Where `N2` came from.
    pub n2_source: Option<ExitNormalSource>,
    /// Total internal reflection at the entry or exit.
    pub tir: bool,
}

impl MethodAov {
    /// A pixel that does not see the refractor.
    pub const BACKGROUND: Self = Self {
        covered: false,
        p2: Vec3::NAN,
        t2: Vec3::NAN,
        n2: Vec3::NAN,
        n2_source: None,
        tir: false,
    };
}

/// A rendered method frame: linear RGB colour and AOVs, row-major from the top.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MethodFrame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB.
    pub color: Vec<Vec3>,
    /// Per-pixel outputs.
    pub aov: Vec<MethodAov>,
}

/// The buffers of one frame: front faces always, back faces for two-interface methods.
#[derive(Default)]
pub struct FrameBuffers {
    /// Front faces (P1, N1, d_N).
    pub front: SurfaceBuffer,
    /// Back faces of the chosen surface.
    pub back: Option<BackFaces>,
}

/// Pass 1 and 2 of Wyman 2005a §4: rasterise what `method` needs.
pub fn render_buffers(
    refractor: &PreparedRefractor<'_>,
    camera: &Camera,
    method: Method,
) -> Result<FrameBuffers, CpuError> {
    let mut buffers = FrameBuffers::default();
    render_buffers_into(refractor, camera, method, &mut buffers)?;
    Ok(buffers)
}

/// [`render_buffers`] into existing buffers, reusing their memory.
pub fn render_buffers_into(
    refractor: &PreparedRefractor<'_>,
    camera: &Camera,
    method: Method,
    buffers: &mut FrameBuffers,
) -> Result<(), CpuError> {
    check_normal_distances(refractor)?;
    match method {
        Method::Single => buffers.back = None,
        Method::TwoInterface { back, .. } => buffers
            .back
            .get_or_insert_with(BackFaces::default)
            .render_into(refractor, camera, back),
    }
    front_faces_into(refractor, camera, &mut buffers.front);
    Ok(())
}

/// The per-pixel kernel over the buffers, and the environment lookup.
pub fn shade(
    buffers: &FrameBuffers,
    environment: &Environment,
    camera: &Camera,
    params: &MethodParams,
) -> Result<MethodFrame, CpuError> {
    let mut frame = MethodFrame::default();
    shade_into(buffers, environment, camera, params, &mut frame)?;
    Ok(frame)
}

/// [`shade`] into an existing frame (colours and AOVs), reusing its memory.
pub fn shade_into(
    buffers: &FrameBuffers,
    environment: &Environment,
    camera: &Camera,
    params: &MethodParams,
    frame: &mut MethodFrame,
) -> Result<(), CpuError> {
    let kernel = kernel_params(params)?;
    let (width, height) = (camera.width(), camera.height());
    let n = (width * height) as usize;
    frame.width = width;
    frame.height = height;
    frame.color.resize(n, Vec3::ZERO);
    frame.aov.resize(n, MethodAov::BACKGROUND);
    let context = ShadeContext {
        back: buffers.back.as_ref(),
        environment,
        camera,
        kernel: &kernel,
    };
    // Rows in parallel, written in place.
    frame
        .color
        .par_chunks_mut(width as usize)
        .zip(frame.aov.par_chunks_mut(width as usize))
        .enumerate()
        .for_each(|(y, (colors, aovs))| {
            let y = y as u32;
            let front = BufferRow {
                buffer: &buffers.front,
                y,
            };
            context.row(y, &front, colors, Some(aovs));
        });
    Ok(())
}

fn kernel_params(params: &MethodParams) -> Result<ImageSpaceParams, CpuError> {
    let distance = params.method.distance_mode();
    Ok(ImageSpaceParams::new(
        params.ior,
        distance,
        params.tir_policy,
    )?)
}

/// The pixels of a band of rows just rasterised: colours, and AOVs when asked for.
fn shade_band(
    context: &ShadeContext<'_>,
    band: &Band<'_>,
    colors: &mut [Vec3],
    mut aovs: Option<&mut [MethodAov]>,
) {
    let width = band.width() as usize;
    for (row, colors) in colors.chunks_exact_mut(width).enumerate() {
        let y = band.first_row + row as u32;
        let aovs = aovs
            .as_deref_mut()
            .map(|aovs| &mut aovs[row * width..][..width]);
        context.row(y, &BandRow { band, y }, colors, aovs);
    }
}

/// Buffers and kernel together: one frame of `params.method`.
pub fn render_method(
    refractor: &PreparedRefractor<'_>,
    environment: &Environment,
    camera: &Camera,
    params: &MethodParams,
) -> Result<MethodFrame, CpuError> {
    let mut renderer = CpuRenderer::default();
    renderer.render(refractor, environment, camera, params)?;
    Ok(renderer.frame)
}

/// What a frame writes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FrameOutputs {
    /// Colour and every [`MethodAov`] (what comparisons against the reference need).
    #[default]
    ColorAndAovs,
    /// Colour only, as a real-time renderer displays it ([`MethodFrame::aov`] stays empty).
    Color,
}

/// A CPU renderer that keeps its buffers and output between frames, as a real-time renderer
/// does: after the first frame at a resolution, a frame allocates nothing.
///
/// A frame is two passes (Wyman 2005a §4): the back faces are rasterised and resolved into
/// normals and distances; then the front faces are rasterised band by band, and each band of
/// rows is shaded by the kernel right after it is rasterised, while it is in cache (the front
/// surface is never stored as a whole G-buffer). The result is bit-identical to
/// [`render_buffers`] followed by [`shade`].
#[derive(Default)]
pub struct CpuRenderer {
    outputs: FrameOutputs,
    front: SurfaceBuffer,
    back: BackFaces,
    frame: MethodFrame,
}

impl CpuRenderer {
    /// A renderer writing `outputs`.
    pub fn new(outputs: FrameOutputs) -> Self {
        Self {
            outputs,
            ..Self::default()
        }
    }

    /// One frame of `params.method`: buffers and kernel, into the renderer's memory.
    pub fn render(
        &mut self,
        refractor: &PreparedRefractor<'_>,
        environment: &Environment,
        camera: &Camera,
        params: &MethodParams,
    ) -> Result<&MethodFrame, CpuError> {
        let kernel = kernel_params(params)?;
        check_normal_distances(refractor)?;
        let back = match params.method {
            Method::Single => None,
            Method::TwoInterface { back: surface, .. } => {
                self.back.render_into(refractor, camera, surface);
                Some(&self.back)
            }
        };
        let context = ShadeContext {
            back,
            environment,
            camera,
            kernel: &kernel,
        };
        let (width, height) = (camera.width(), camera.height());
        let n = (width * height) as usize;
        let frame = &mut self.frame;
        frame.width = width;
        frame.height = height;
        frame.color.resize(n, Vec3::ZERO);
        let band = band_pixels(width);
        let colors = frame.color.par_chunks_mut(band);
        let outputs = match self.outputs {
            FrameOutputs::ColorAndAovs => {
                frame.aov.resize(n, MethodAov::BACKGROUND);
                Either::Left(colors.zip(frame.aov.par_chunks_mut(band).map(Some)))
            }
            FrameOutputs::Color => {
                frame.aov.clear();
                Either::Right(colors.map(|colors| (colors, None)))
            }
        };
        rasterize_bands(
            &refractor.raster_mesh(),
            camera,
            Faces::Front,
            DepthTest::Nearest,
            &mut self.front,
            outputs,
            |rows, (colors, aovs)| shade_band(&context, rows, colors, aovs),
        );
        Ok(&self.frame)
    }
}

fn check_normal_distances(refractor: &PreparedRefractor<'_>) -> Result<(), CpuError> {
    if refractor.d_n.len() == refractor.mesh.positions.len() {
        Ok(())
    } else {
        Err(CpuError::NormalDistances {
            found: refractor.d_n.len(),
            expected: refractor.mesh.positions.len(),
        })
    }
}
