//! Running a method on the CPU: buffers (rasterised), then the refract-core kernel per pixel
//! (rows in parallel), then the environment lookup.

use glam::Vec3;
use rayon::prelude::*;
use refract_core::exit::{ExitNormalSource, TirPolicy};
use refract_core::kernel::{
    FrontSurface, ImageSpaceParams, InvalidIor, one_interface, two_interface,
};
use refract_core::{Camera, Method};
use refract_trace::Environment;

use crate::buffers::{BackFaces, PreparedRefractor, front_faces, front_faces_into};
use crate::raster::SurfaceBuffer;

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
#[derive(Clone, Debug, PartialEq)]
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
    if refractor.d_n.len() != refractor.mesh.positions.len() {
        return Err(CpuError::NormalDistances {
            found: refractor.d_n.len(),
            expected: refractor.mesh.positions.len(),
        });
    }
    let back = match method {
        Method::Single => None,
        Method::TwoInterface { back, .. } => Some(BackFaces::render(refractor, camera, back)),
    };
    Ok(FrameBuffers {
        front: front_faces(refractor, camera),
        back,
    })
}

/// The per-pixel kernel over the buffers, and the environment lookup.
pub fn shade(
    buffers: &FrameBuffers,
    environment: &Environment,
    camera: &Camera,
    params: &MethodParams,
) -> Result<MethodFrame, CpuError> {
    let distance = params.method.distance_mode();
    let kernel = ImageSpaceParams::new(params.ior, distance, params.tir_policy)?;
    let mut frame = MethodFrame {
        width: 0,
        height: 0,
        color: Vec::new(),
        aov: Vec::new(),
    };
    shade_into(buffers, environment, camera, &kernel, &mut frame);
    Ok(frame)
}

/// [`shade`] into an existing frame, reusing its memory.
fn shade_into(
    buffers: &FrameBuffers,
    environment: &Environment,
    camera: &Camera,
    kernel: &ImageSpaceParams,
    frame: &mut MethodFrame,
) {
    let (width, height) = (camera.width(), camera.height());
    let front = &buffers.front;
    let n = (width * height) as usize;
    frame.width = width;
    frame.height = height;
    frame.color.resize(n, Vec3::ZERO);
    frame.aov.resize(n, MethodAov::BACKGROUND);
    // Rows in parallel, written in place.
    frame
        .color
        .par_chunks_mut(width as usize)
        .zip(frame.aov.par_chunks_mut(width as usize))
        .enumerate()
        .for_each(|(y, (colors, aovs))| {
            let y = y as u32;
            for x in 0..width {
                let uv = Camera::pixel_center(x, y);
                let (color, aov) = match front.texel((y * width + x) as usize) {
                    Some(texel) => {
                        let surface = FrontSurface {
                            p1_ws: texel.p_ws,
                            n1_ws: texel.n_ws,
                            d_n: texel.scalar,
                        };
                        shade_pixel(
                            &surface,
                            uv,
                            buffers.back.as_ref(),
                            environment,
                            camera,
                            kernel,
                        )
                    }
                    None => (
                        environment.radiance(camera.pixel_ray(uv).dir),
                        MethodAov::BACKGROUND,
                    ),
                };
                colors[x as usize] = color;
                aovs[x as usize] = aov;
            }
        });
}

fn shade_pixel(
    surface: &FrontSurface,
    uv: glam::Vec2,
    back: Option<&BackFaces>,
    environment: &Environment,
    camera: &Camera,
    kernel: &ImageSpaceParams,
) -> (Vec3, MethodAov) {
    let covered = MethodAov {
        covered: true,
        ..MethodAov::BACKGROUND
    };
    match back {
        None => match one_interface(camera, surface, kernel) {
            Ok(path) => (
                environment.radiance(path.t1),
                MethodAov {
                    t2: path.t1,
                    tir: path.tir_entry,
                    ..covered
                },
            ),
            Err(_) => (Vec3::ZERO, covered),
        },
        Some(back) => match two_interface(camera, uv, surface, back, kernel) {
            Ok(path) => {
                let color = if path.t2 == Vec3::ZERO {
                    Vec3::ZERO
                } else {
                    environment.radiance(path.t2)
                };
                let aov = MethodAov {
                    p2: path.p2,
                    t2: path.t2,
                    n2: path.n2,
                    n2_source: Some(path.n2_source),
                    tir: path.tir_exit || path.entry.tir_entry,
                    ..covered
                };
                (color, aov)
            }
            Err(_) => (Vec3::ZERO, covered),
        },
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

/// A CPU renderer that keeps its buffers and output between frames, as a real-time renderer
/// does: after the first frame at a resolution, a frame allocates nothing.
pub struct CpuRenderer {
    buffers: FrameBuffers,
    frame: MethodFrame,
}

impl Default for CpuRenderer {
    fn default() -> Self {
        let empty = SurfaceBuffer::new;
        Self {
            buffers: FrameBuffers {
                front: empty(),
                back: None,
            },
            frame: MethodFrame {
                width: 0,
                height: 0,
                color: Vec::new(),
                aov: Vec::new(),
            },
        }
    }
}

impl CpuRenderer {
    /// One frame of `params.method`: buffers and kernel, into the renderer's memory.
    pub fn render(
        &mut self,
        refractor: &PreparedRefractor<'_>,
        environment: &Environment,
        camera: &Camera,
        params: &MethodParams,
    ) -> Result<&MethodFrame, CpuError> {
        let distance = params.method.distance_mode();
        let kernel = ImageSpaceParams::new(params.ior, distance, params.tir_policy)?;
        if refractor.d_n.len() != refractor.mesh.positions.len() {
            return Err(CpuError::NormalDistances {
                found: refractor.d_n.len(),
                expected: refractor.mesh.positions.len(),
            });
        }
        front_faces_into(refractor, camera, &mut self.buffers.front);
        match (params.method, &mut self.buffers.back) {
            (Method::Single, back) => *back = None,
            (Method::TwoInterface { back: surface, .. }, Some(back)) => {
                back.render_into(refractor, camera, surface)
            }
            (Method::TwoInterface { back: surface, .. }, back @ None) => {
                *back = Some(BackFaces::render(refractor, camera, surface));
            }
        }
        shade_into(&self.buffers, environment, camera, &kernel, &mut self.frame);
        Ok(&self.frame)
    }
}
