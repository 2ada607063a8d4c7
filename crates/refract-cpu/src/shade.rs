//! The per-pixel work of a frame, eight pixels at a time: each row's covered pixels go through
//! refract-core's lane kernels ([`two_interface_lanes`], [`one_interface_lanes`]) in groups of eight,
//! its background pixels through the eight-lane camera rays and environment lookup. Lanes are
//! bit-identical to the scalar kernels, so grouping changes no pixel.
//!
//! Where the scene has opaque objects, they are drawn as an engine draws them: a pixel whose
//! nearest surface is an object (the refractor absent there, or behind it) shows the object's
//! texel of the eye's object pass; the refraction itself still sees the environment only, as in
//! Wyman 2005a.

use core::ops::Range;

use glam::{UVec2, Vec2, Vec3};
use refract_core::Camera;
use refract_core::exit::ExitNormalSource;
use refract_core::gpu::exit_normal_source_code;
use refract_core::kernel::ImageSpaceParams;
use refract_core::kernel_x8::{FrontLanes, one_interface_lanes, two_interface_lanes};
use refract_core::lanes::{F32x8, LANES, Vec2x8, Vec3x8, mask_from_lanes};
use refract_core::nearby_geometry::view_depth;
use refract_core::real::Vector3;
use refract_scene::{Aov, Environment, LayerValue, PixelLayers};

use crate::buffers::BackFaces;
use crate::object_surfaces::{NearbyTexel, NearbyTexture};
use crate::pixel_group::{PixelGroup, for_each_group};
use crate::raster::{Attribute, Band, SurfaceBuffer, Texel, TexelLanes};

/// Per-pixel outputs of the image-space kernels beside the colour; NaN / `None` where they do
/// not apply (background pixels, degenerate inputs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MethodAov {
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

impl PixelLayers for MethodAov {
    // Called per pixel and layer by `Frame::write_row_layers`; out of line it cost 6.5 M
    // instructions of a 256² frame's 36 M (callgrind), inlined or not by codegen-unit chance.
    #[inline]
    fn value(&self, aov: Aov) -> Option<LayerValue> {
        Some(match aov {
            Aov::Covered => LayerValue::Flag(self.covered),
            Aov::Tir => LayerValue::Flag(self.tir),
            Aov::P2 => LayerValue::Vec3(self.p2),
            Aov::N2 => LayerValue::Vec3(self.n2),
            Aov::T2 => LayerValue::Vec3(self.t2),
            Aov::ExitNormalSource => {
                LayerValue::Count(self.n2_source.map_or(0, exit_normal_source_code))
            }
            _ => return None,
        })
    }
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

/// What the per-pixel work of a frame reads.
pub(crate) struct ShadeContext<'a> {
    /// The back faces (two-interface methods), or `None` (`single`).
    pub back: Option<&'a BackFaces>,
    pub environment: &'a Environment,
    /// The opaque objects seen from the eye, pixel for pixel (`None`: the scene has none).
    pub objects: Option<&'a NearbyTexture>,
    pub camera: &'a Camera,
    pub kernel: &'a ImageSpaceParams,
}

/// The AOVs of a covered pixel without a path (a degenerate input).
const COVERED: MethodAov = MethodAov {
    covered: true,
    ..MethodAov::BACKGROUND
};

/// Where a row's results go.
struct RowOut<'o> {
    colors: &'o mut [Vec3],
    aovs: Option<&'o mut [MethodAov]>,
}

impl RowOut<'_> {
    #[inline]
    fn write(&mut self, x: u32, color: Vec3, aov: impl FnOnce() -> MethodAov) {
        self.colors[x as usize] = color;
        if let Some(aovs) = self.aovs.as_deref_mut() {
            aovs[x as usize] = aov();
        }
    }
}

/// One row of a front-face buffer, read by the per-pixel work: which pixels are covered, and
/// the surfaces of eight covered pixels at once.
pub(crate) trait FrontRow {
    /// Whether pixel `x` of the row sees the refractor.
    fn is_covered(&self, x: u32) -> bool;
    /// The pixels between the row's first and last covered pixel (none outside is covered).
    fn covered_span(&self) -> Range<u32>;
    /// The front surfaces of eight covered pixels, as lanes (position, normal and scalar).
    fn texel_lanes(&self, x: &[u32; LANES]) -> TexelLanes;
    /// The front surface at pixel `x` (`None` where not covered).
    fn texel(&self, x: u32) -> Option<Texel>;
}

/// Row `y` of a band just rasterised.
pub(crate) struct BandRow<'b, 'a> {
    pub band: &'b Band<'a>,
    pub y: u32,
}

impl FrontRow for BandRow<'_, '_> {
    #[inline]
    fn is_covered(&self, x: u32) -> bool {
        self.band.is_covered(x, self.y)
    }
    fn covered_span(&self) -> Range<u32> {
        self.band.covered_span(self.y)
    }
    fn texel_lanes(&self, x: &[u32; LANES]) -> TexelLanes {
        self.band
            .attribute_lanes::<{ Attribute::SCALAR }>(x, self.y)
    }
    fn texel(&self, x: u32) -> Option<Texel> {
        self.band.texel(x, self.y)
    }
}

/// Row `y` of a whole front-face buffer.
pub(crate) struct BufferRow<'b> {
    pub buffer: &'b SurfaceBuffer,
    pub y: u32,
}

impl FrontRow for BufferRow<'_> {
    #[inline]
    fn is_covered(&self, x: u32) -> bool {
        self.buffer
            .is_covered((self.y * self.buffer.width + x) as usize)
    }
    fn covered_span(&self) -> Range<u32> {
        self.buffer.covered_span(self.y)
    }
    fn texel_lanes(&self, x: &[u32; LANES]) -> TexelLanes {
        self.buffer
            .attribute_lanes::<{ Attribute::SCALAR }>(x, self.y)
    }
    fn texel(&self, x: u32) -> Option<Texel> {
        self.buffer.texel((self.y * self.buffer.width + x) as usize)
    }
}

impl ShadeContext<'_> {
    /// Shades row `y` of `front`: colours go to `colors` and, when given, AOVs to `aovs` (both
    /// one row long).
    pub fn row(
        &self,
        y: u32,
        front: &impl FrontRow,
        colors: &mut [Vec3],
        aovs: Option<&mut [MethodAov]>,
    ) {
        let mut out = RowOut { colors, aovs };
        let width = out.colors.len() as u32;
        // Outside the refractor's span (and with no objects to draw) every pixel sees the
        // environment: runs of eight neighbours, no per-pixel test.
        let span = match self.objects {
            None => front.covered_span(),
            Some(_) => 0..width,
        };
        self.background_run(0..span.start, y, &mut out);
        self.background_run(span.end..width, y, &mut out);
        let mut covered = PixelGroup::new();
        let mut background = PixelGroup::new();
        for x in span {
            let object = self.object(front, x, y);
            if let Some(object) = object {
                out.write(x, object.color, || MethodAov::BACKGROUND);
            } else if front.is_covered(x) {
                if covered.push(x) {
                    self.covered(front, &covered, y, &mut out);
                    covered.len = 0;
                }
            } else if background.push(x) {
                self.background(&background, y, &mut out);
                background.len = 0;
            }
        }
        if covered.len > 0 {
            covered.pad();
            self.covered(front, &covered, y, &mut out);
        }
        if background.len > 0 {
            background.pad();
            self.background(&background, y, &mut out);
        }
    }

    /// The object seen at pixel `(x, y)` when it is nearer than the refractor there (or the
    /// refractor does not cover the pixel); `None` where the refractor or the environment is
    /// seen. The refractor's surface is reconstructed only where both cover the pixel.
    #[inline]
    fn object(&self, front: &impl FrontRow, x: u32, y: u32) -> Option<NearbyTexel> {
        let object = self.objects?.texel(UVec2::new(x, y))?;
        let refractor_in_front = front
            .texel(x)
            .is_some_and(|t| view_depth(self.camera, t.p_ws) < object.surface.depth);
        (!refractor_in_front).then_some(object)
    }

    /// Pixels `xs` of row `y`, all of which see the environment directly (see
    /// [`environment_run`]).
    fn background_run(&self, xs: Range<u32>, y: u32, out: &mut RowOut<'_>) {
        if let Some(aovs) = out.aovs.as_deref_mut() {
            aovs[xs.start as usize..xs.end as usize].fill(MethodAov::BACKGROUND);
        }
        environment_run(self.camera, self.environment, xs, y, out.colors);
    }

    /// Eight pixels that see the environment directly.
    fn background(&self, group: &PixelGroup, y: u32, out: &mut RowOut<'_>) {
        let dirs = self.camera.pixel_ray_dir_x8(pixel_centers(&group.x, y));
        let colors = self.environment.radiance_x8(dirs).to_lanes();
        for (&x, &color) in group.x.iter().zip(&colors).take(group.len) {
            out.write(x, color, || MethodAov::BACKGROUND);
        }
    }

    /// Eight pixels that see the refractor: the kernel, then the environment along `T2` (or
    /// `T1` for `single`); black where the kernel reports a degenerate input or the TIR policy
    /// absorbs the ray.
    fn covered(&self, front: &impl FrontRow, group: &PixelGroup, y: u32, out: &mut RowOut<'_>) {
        let texels = front.texel_lanes(&group.x);
        let surfaces = FrontLanes {
            p1_ws: texels.p_ws,
            n1_ws: texels.n_ws,
            d_n: texels.scalar,
        };
        match self.back {
            None => self.one_interface(&surfaces, group, out),
            Some(back) => self.two_interface(&surfaces, back, group, y, out),
        }
    }

    /// `single` on a group: the environment along `T1`.
    fn one_interface(&self, surfaces: &FrontLanes, group: &PixelGroup, out: &mut RowOut<'_>) {
        let paths = one_interface_lanes(self.camera, surfaces, self.kernel);
        // Degenerate lanes look up an arbitrary direction with the others, and are black.
        let mut directions = [Vec3::Y; LANES];
        for (direction, path) in directions.iter_mut().zip(&paths) {
            if let Ok(path) = path {
                *direction = path.t1;
            }
        }
        let radiance = self
            .environment
            .radiance_x8(Vec3x8::from_lanes(&directions))
            .to_lanes();
        for (i, path) in paths.iter().enumerate().take(group.len) {
            match path {
                Ok(path) => out.write(group.x[i], radiance[i], || MethodAov {
                    t2: path.t1,
                    tir: path.tir_entry,
                    ..COVERED
                }),
                Err(_) => out.write(group.x[i], Vec3::ZERO, || COVERED),
            }
        }
    }

    /// `wyman` and its ablations on a group: the environment along `T2`.
    fn two_interface(
        &self,
        surfaces: &FrontLanes,
        back: &BackFaces,
        group: &PixelGroup,
        y: u32,
        out: &mut RowOut<'_>,
    ) {
        let mut uv = [Vec2::ZERO; LANES];
        for (uv, &x) in uv.iter_mut().zip(&group.x) {
            *uv = Camera::pixel_center(x, y);
        }
        let paths = two_interface_lanes(self.camera, &uv, surfaces, back, self.kernel);
        // Absorbed (T2 = 0) and degenerate lanes look up an arbitrary direction, and are black.
        let lit = mask_from_lanes(paths.ok) & !paths.t2.is_zero();
        let lookup = Vec3x8::select(lit, paths.t2, Vec3x8::splat(Vec3::Y));
        let radiance = self.environment.radiance_x8(lookup);
        let colors = Vec3x8::select(lit, radiance, Vec3x8::ZERO).to_lanes();
        if out.aovs.is_none() {
            for (&x, &color) in group.x.iter().zip(&colors).take(group.len) {
                out.colors[x as usize] = color;
            }
            return;
        }
        let (p2, t2, n2) = (
            paths.p2.to_lanes(),
            paths.t2.to_lanes(),
            paths.n2.to_lanes(),
        );
        for i in 0..group.len {
            out.write(group.x[i], colors[i], || {
                if !paths.ok[i] {
                    return COVERED;
                }
                MethodAov {
                    p2: p2[i],
                    t2: t2[i],
                    n2: n2[i],
                    n2_source: Some(if paths.n2_from_back_face[i] {
                        ExitNormalSource::BackFace
                    } else {
                        ExitNormalSource::SilhouetteFallback
                    }),
                    tir: paths.tir[i],
                    ..COVERED
                }
            });
        }
    }
}

/// The environment seen directly by pixels `xs` of row `y` of `camera`, written to
/// `colors[xs]`: eight neighbours at a time, their centres computed on lanes (no per-pixel
/// gather), each lane the bits of [`Camera::pixel_ray`] and [`Environment::radiance`]'s lane
/// twin for its pixel.
pub(crate) fn environment_run(
    camera: &Camera,
    environment: &Environment,
    xs: Range<u32>,
    y: u32,
    colors: &mut [Vec3],
) {
    let row_y = F32x8::splat(y as f32 + 0.5);
    let mut x0 = xs.start;
    while x0 < xs.end {
        let len = (xs.end - x0).min(LANES as u32) as usize;
        let uv = Vec2x8 {
            x: F32x8::splat(x0 as f32) + LANE_INDEX + F32x8::splat(0.5),
            y: row_y,
        };
        let radiance = environment
            .radiance_x8(camera.pixel_ray_dir_x8(uv))
            .to_lanes();
        let start = x0 as usize;
        if len == LANES {
            // A constant length: inline stores instead of a call to `memcpy` per eight pixels.
            colors[start..start + LANES].copy_from_slice(&radiance);
        } else {
            colors[start..start + len].copy_from_slice(&radiance[..len]);
        }
        x0 += len as u32;
    }
}

/// The environment seen directly by the pixels of `group` (of row `y` of `camera`), written to
/// `colors`: their rays and radiances on lanes, each the bits of [`Camera::pixel_ray`] and
/// [`Environment::radiance`] for its pixel.
pub(crate) fn environment_group(
    camera: &Camera,
    environment: &Environment,
    group: &PixelGroup,
    y: u32,
    colors: &mut [Vec3],
) {
    let mut uv = [Vec2::ZERO; LANES];
    for (uv, &x) in uv.iter_mut().zip(&group.x) {
        *uv = Camera::pixel_center(x, y);
    }
    let dirs = camera.pixel_ray_dir_x8(Vec2x8::from_lanes(&uv));
    let radiance = environment.radiance_x8(dirs).to_lanes();
    for (&x, &color) in group.x.iter().zip(&radiance).take(group.len) {
        colors[x as usize] = color;
    }
}

/// A rasterised view seen row by row: what [`ViewRow::shade`] reads.
pub(crate) struct ViewRow<'a> {
    pub camera: &'a Camera,
    pub environment: &'a Environment,
    pub buffer: &'a SurfaceBuffer,
}

impl ViewRow<'_> {
    /// Shades pixels `wanted` of row `y` into `colors` (the row) and, when given, `aovs`: the
    /// pixels outside the row's covered span see the environment (runs of eight neighbours,
    /// no per-pixel test); those inside are gathered eight at a time ([`for_each_group`]),
    /// the groups that see the environment shaded here ([`environment_group`]) and those that
    /// see a surface handed to `surfaces`. Pixels that see the environment get `A::default()`
    /// as their AOVs. Every pixel gets the bits of shading it alone, however it is grouped.
    pub fn shade<A: Copy + Default>(
        &self,
        y: u32,
        wanted: Range<u32>,
        colors: &mut [Vec3],
        mut aovs: Option<&mut [A]>,
        mut surfaces: impl FnMut(&PixelGroup, &mut [Vec3], Option<&mut [A]>),
    ) {
        let covered = self.buffer.covered_span(y);
        let span = covered.start.max(wanted.start)..covered.end.min(wanted.end);
        let (runs, span) = if span.is_empty() {
            ([wanted, 0..0], 0..0)
        } else {
            ([wanted.start..span.start, span.end..wanted.end], span)
        };
        for run in runs {
            if let Some(aovs) = aovs.as_deref_mut() {
                aovs[run.start as usize..run.end as usize].fill(A::default());
            }
            environment_run(self.camera, self.environment, run, y, colors);
        }
        let row = (y as usize) * colors.len();
        let covered = |x: u32| self.buffer.is_covered(row + x as usize);
        for_each_group(span, covered, |group, covered| {
            if covered {
                surfaces(group, colors, aovs.as_deref_mut());
                return;
            }
            environment_group(self.camera, self.environment, group, y, colors);
            if let Some(aovs) = aovs.as_deref_mut() {
                for &x in group.x.iter().take(group.len) {
                    aovs[x as usize] = A::default();
                }
            }
        });
    }
}

/// `0, 1, …, 7`: lane `i`'s offset in a run of neighbouring pixels.
const LANE_INDEX: F32x8 = F32x8::new([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);

/// The centres of pixels `x` of row `y`, as lanes.
#[inline]
fn pixel_centers(x: &[u32; LANES], y: u32) -> Vec2x8 {
    let mut uv = [Vec2::ZERO; LANES];
    for (uv, &x) in uv.iter_mut().zip(x) {
        *uv = Camera::pixel_center(x, y);
    }
    Vec2x8::from_lanes(&uv)
}
