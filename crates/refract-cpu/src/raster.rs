//! A deterministic tiled triangle rasteriser producing the G-buffers of the image-space methods:
//! pixel-centre sampling, the top-left fill rule on an 8-bit sub-pixel grid (as GPUs do),
//! perspective-correct interpolation, near-plane clipping, and bands of rows rendered in
//! parallel.

use glam::{Vec3, Vec4, Vec4Swizzles};
use rayon::prelude::*;
use refract_core::Camera;

/// Sub-pixel precision of vertex positions (8 bits, as Direct3D and Vulkan guarantee).
const SUBPIXEL_BITS: u32 = 8;
const SUBPIXEL: f64 = (1u32 << SUBPIXEL_BITS) as f64;
/// Height in rows of a band; each band (full width) is rasterised by one task, straight into
/// its rows of the output.
const BAND: u32 = 16;

/// Which faces are drawn (the others are culled), seen from the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Faces {
    /// Counter-clockwise on screen (facing the camera): the front-face pass.
    Front,
    /// Clockwise on screen: the back-face pass.
    Back,
}

/// Which fragment survives the depth test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthTest {
    /// The nearest (depth compare Less; the first triangle in index order wins ties).
    Nearest,
    /// The furthest (depth compare Greater; the first triangle wins ties).
    Furthest,
}

/// One pixel of a [`SurfaceBuffer`]: the fragment that survived the depth test. Whether a
/// texel holds a fragment of the current frame is decided by its generation (see
/// [`SurfaceBuffer::texel`]), so buffers are never cleared between frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Texel {
    /// The buffer generation that wrote this texel; older ones are empty.
    generation: u32,
    /// Window depth in `[0, 1]`.
    pub depth: f32,
    /// Perspective-correct interpolated world position.
    pub p_ws: Vec3,
    /// Perspective-correct interpolated vertex normal (normalised).
    pub n_ws: Vec3,
    /// Perspective-correct interpolated per-vertex scalar (`d_N`).
    pub scalar: f32,
}

impl Texel {
    const NEVER_WRITTEN: Self = Self {
        generation: 0,
        depth: 0.0,
        p_ws: Vec3::ZERO,
        n_ws: Vec3::ZERO,
        scalar: 0.0,
    };
}

/// Per-pixel surface data interpolated from the vertices, row-major from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The current frame's generation (≥ 1 once rendered).
    generation: u32,
    texels: Vec<Texel>,
}

impl SurfaceBuffer {
    /// An empty buffer (no pixels).
    pub fn new() -> Self {
        Self {
            width: 0,
            height: 0,
            generation: 0,
            texels: Vec::new(),
        }
    }

    /// The fragment covering pixel `index` (row-major), or `None` where the pixel is empty:
    /// the explicit empty marker.
    #[inline]
    pub fn texel(&self, index: usize) -> Option<&Texel> {
        self.texels
            .get(index)
            .filter(|t| t.generation == self.generation && self.generation != 0)
    }

    /// Starts a frame of `width × height`: a new generation makes every texel empty without
    /// touching memory (the buffer is only cleared when it is resized or the counter wraps).
    fn begin_frame(&mut self, width: u32, height: u32) {
        let size = (width * height) as usize;
        if self.texels.len() != size || self.generation == u32::MAX {
            self.texels.clear();
            self.texels.resize(size, Texel::NEVER_WRITTEN);
            self.generation = 0;
        }
        self.width = width;
        self.height = height;
        self.generation += 1;
    }
}

impl Default for SurfaceBuffer {
    fn default() -> Self {
        Self::new()
    }
}

/// A triangle mesh ready for rasterisation: world positions, normals and one scalar per vertex.
pub struct RasterMesh<'a> {
    /// World positions.
    pub positions: &'a [Vec3],
    /// Vertex normals.
    pub normals: &'a [Vec3],
    /// One scalar per vertex (`d_N`), interpolated like the normals.
    pub scalars: &'a [f32],
    /// Triangles (counter-clockwise seen from outside).
    pub triangles: &'a [[u32; 3]],
}

/// A vertex after projection, with the attributes to interpolate.
#[derive(Clone, Copy, Debug)]
struct ClipVertex {
    clip: Vec4,
    p_ws: Vec3,
    n_ws: Vec3,
    scalar: f32,
}

impl ClipVertex {
    fn lerp(self, other: Self, t: f32) -> Self {
        Self {
            clip: self.clip.lerp(other.clip, t),
            p_ws: self.p_ws.lerp(other.p_ws, t),
            n_ws: self.n_ws.lerp(other.n_ws, t),
            scalar: self.scalar + (other.scalar - self.scalar) * t,
        }
    }
}

/// A triangle set up for scan conversion: fixed-point screen positions (`y` down), edge data,
/// and what perspective-correct interpolation needs.
#[derive(Clone, Copy, Debug)]
struct ScreenTriangle {
    /// Fixed-point pixel coordinates of the corners, in clockwise-on-screen order.
    xy: [[i64; 2]; 3],
    /// Twice the signed area in fixed point (positive).
    area: i64,
    /// Window depth of each corner.
    depth: [f32; 3],
    /// `1/w` of each corner.
    inv_w: [f32; 3],
    vertices: [ClipVertex; 3],
    /// Pixel bounds, inclusive.
    min: [u32; 2],
    max: [u32; 2],
}

fn edge(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// Top-left rule for clockwise-on-screen (y down) triangles: a pixel centre exactly on an edge
/// belongs to the triangle if the edge is a top edge (horizontal, going right) or a left edge
/// (going up), so that pixels on a shared edge are drawn exactly once.
fn is_top_left(a: [i64; 2], b: [i64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    (dy == 0 && dx > 0) || dy < 0
}

/// Clips a triangle against the near plane `z_clip ≥ 0` (Sutherland–Hodgman): 0, 3 or 4
/// vertices, attributes interpolated linearly in clip space.
fn clip_near(v: [ClipVertex; 3], out: &mut Vec<ClipVertex>) {
    out.clear();
    for i in 0..3 {
        let (a, b) = (v[i], v[(i + 1) % 3]);
        let (da, db) = (a.clip.z, b.clip.z);
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            out.push(a.lerp(b, da / (da - db)));
        }
    }
}

fn setup(v: [ClipVertex; 3], camera: &Camera, faces: Faces) -> Option<ScreenTriangle> {
    let (w, h) = (camera.width() as f32, camera.height() as f32);
    let mut xy = [[0i64; 2]; 3];
    let mut depth = [0.0f32; 3];
    let mut inv_w = [0.0f32; 3];
    for k in 0..3 {
        let c = v[k].clip;
        let ndc = c.xyz() / c.w;
        let px = 0.5 * (ndc.x + 1.0) * w;
        let py = 0.5 * (1.0 - ndc.y) * h;
        if !(px.is_finite() && py.is_finite()) {
            return None;
        }
        xy[k] = [
            (f64::from(px) * SUBPIXEL).round() as i64,
            (f64::from(py) * SUBPIXEL).round() as i64,
        ];
        depth[k] = ndc.z;
        inv_w[k] = 1.0 / c.w;
    }
    // In pixel coordinates (y down) a positive edge function means clockwise on screen; a
    // triangle wound counter-clockwise seen from outside appears counter-clockwise on screen
    // (negative) when it faces the camera.
    let area = edge(xy[0], xy[1], xy[2]);
    let front = area < 0;
    if area == 0 || front != (faces == Faces::Front) {
        return None;
    }
    let (mut vertices, mut area) = (v, area);
    if area < 0 {
        xy.swap(1, 2);
        depth.swap(1, 2);
        inv_w.swap(1, 2);
        vertices.swap(1, 2);
        area = -area;
    }
    let lo = |k: usize| xy.iter().map(|p| p[k]).min().unwrap_or(0);
    let hi = |k: usize| xy.iter().map(|p| p[k]).max().unwrap_or(0);
    let size = [camera.width() as i64, camera.height() as i64];
    // Pixels whose centre (x + ½) can lie inside [lo, hi].
    let first = |k: usize| {
        ((lo(k) - (SUBPIXEL as i64) / 2) as f64 / SUBPIXEL)
            .ceil()
            .max(0.0) as i64
    };
    let last = |k: usize| {
        (((hi(k) - (SUBPIXEL as i64) / 2) as f64 / SUBPIXEL).floor() as i64).min(size[k] - 1)
    };
    let (x0, x1, y0, y1) = (first(0), last(0), first(1), last(1));
    if x0 > x1 || y0 > y1 {
        return None;
    }
    Some(ScreenTriangle {
        xy,
        area,
        depth,
        inv_w,
        vertices,
        min: [x0 as u32, y0 as u32],
        max: [x1 as u32, y1 as u32],
    })
}

/// Rasterises `mesh` seen by `camera`, keeping `faces` and the fragment chosen by `test`.
///
/// Deterministic: triangles are binned into bands of rows in index order and each band is owned
/// by one task, so the result does not depend on the thread count.
pub fn rasterize(
    mesh: &RasterMesh<'_>,
    camera: &Camera,
    faces: Faces,
    test: DepthTest,
) -> SurfaceBuffer {
    let mut buffer = SurfaceBuffer::new();
    rasterize_into(mesh, camera, faces, test, &mut buffer);
    buffer
}

/// [`rasterize`] into an existing buffer, reusing its memory (a renderer's per-frame path: no
/// allocation, no page faults once the buffer has reached its size).
pub fn rasterize_into(
    mesh: &RasterMesh<'_>,
    camera: &Camera,
    faces: Faces,
    test: DepthTest,
    buffer: &mut SurfaceBuffer,
) {
    let world_to_clip = camera.world_to_clip();
    let clip: Vec<Vec4> = mesh
        .positions
        .par_iter()
        .map(|p| world_to_clip * p.extend(1.0))
        .collect();

    // Set up every (clipped) triangle, in index order.
    let triangles: Vec<ScreenTriangle> = mesh
        .triangles
        .par_chunks(4096)
        .flat_map_iter(|chunk| {
            let mut polygon = Vec::with_capacity(4);
            let mut out = Vec::new();
            for tri in chunk {
                let v = tri.map(|i| ClipVertex {
                    clip: clip[i as usize],
                    p_ws: mesh.positions[i as usize],
                    n_ws: mesh.normals[i as usize],
                    scalar: mesh.scalars[i as usize],
                });
                if v.iter().all(|v| v.clip.z >= 0.0) {
                    out.extend(setup(v, camera, faces));
                } else {
                    clip_near(v, &mut polygon);
                    for k in 1..polygon.len().saturating_sub(1) {
                        out.extend(setup(
                            [polygon[0], polygon[k], polygon[k + 1]],
                            camera,
                            faces,
                        ));
                    }
                }
            }
            out
        })
        .collect();

    // Bin into bands of rows, preserving triangle order within each band.
    let (width, height) = (camera.width(), camera.height());
    let bands = height.div_ceil(BAND);
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); bands as usize];
    for (index, t) in triangles.iter().enumerate() {
        for band in t.min[1] / BAND..=t.max[1] / BAND {
            bins[band as usize].push(index as u32);
        }
    }
    buffer.begin_frame(width, height);
    let generation = buffer.generation;
    buffer
        .texels
        .par_chunks_mut((BAND * width) as usize)
        .zip(bins.par_iter())
        .enumerate()
        .for_each(|(band, (rows, bin))| {
            rasterize_band(
                &triangles,
                bin,
                band as u32 * BAND,
                width,
                rows,
                test,
                generation,
            )
        });
}

/// Scan-converts the triangles of `bin` into `rows`, the texels of the rows starting at
/// `first_row` (full width).
fn rasterize_band(
    triangles: &[ScreenTriangle],
    bin: &[u32],
    first_row: u32,
    width: u32,
    rows: &mut [Texel],
    test: DepthTest,
    generation: u32,
) {
    let last_row = first_row + (rows.len() as u32 / width) - 1;
    let half = (SUBPIXEL as i64) / 2;
    for &index in bin {
        let t = &triangles[index as usize];
        let [a, b, c] = t.xy;
        let (tl0, tl1, tl2) = (is_top_left(b, c), is_top_left(c, a), is_top_left(a, b));
        let inv_area = 1.0 / t.area as f64;
        // Edge functions step by −Δy·SUBPIXEL per pixel to the right (exact integer arithmetic).
        let step = [-(c[1] - b[1]), -(a[1] - c[1]), -(b[1] - a[1])].map(|d| d * SUBPIXEL as i64);
        for y in t.min[1].max(first_row)..=t.max[1].min(last_row) {
            let p = [
                i64::from(t.min[0]) * SUBPIXEL as i64 + half,
                i64::from(y) * SUBPIXEL as i64 + half,
            ];
            let (mut e0, mut e1, mut e2) = (edge(b, c, p), edge(c, a, p), edge(a, b, p));
            let row = &mut rows[((y - first_row) * width) as usize..][..width as usize];
            for x in t.min[0]..=t.max[0] {
                let (f0, f1, f2) = (e0, e1, e2);
                e0 += step[0];
                e1 += step[1];
                e2 += step[2];
                let inside = (f0 > 0 || (f0 == 0 && tl0))
                    && (f1 > 0 || (f1 == 0 && tl1))
                    && (f2 > 0 || (f2 == 0 && tl2));
                if !inside {
                    continue;
                }
                // Screen-space barycentrics (exact integers, scaled by 1/area in f64).
                let l = [
                    f0 as f64 * inv_area,
                    f1 as f64 * inv_area,
                    f2 as f64 * inv_area,
                ]
                .map(|v| v as f32);
                let depth = l[0] * t.depth[0] + l[1] * t.depth[1] + l[2] * t.depth[2];
                if depth > 1.0 {
                    continue; // beyond the far plane (the near plane is clipped geometrically)
                }
                let texel = &mut row[x as usize];
                let better = texel.generation != generation
                    || match test {
                        DepthTest::Nearest => depth < texel.depth,
                        DepthTest::Furthest => depth > texel.depth,
                    };
                if !better {
                    continue;
                }
                // Perspective-correct weights: λᵢ/wᵢ normalised.
                let pw = [l[0] * t.inv_w[0], l[1] * t.inv_w[1], l[2] * t.inv_w[2]];
                let sum = pw[0] + pw[1] + pw[2];
                let pw = pw.map(|v| v / sum);
                let [v0, v1, v2] = t.vertices;
                *texel = Texel {
                    generation,
                    depth,
                    p_ws: pw[0] * v0.p_ws + pw[1] * v1.p_ws + pw[2] * v2.p_ws,
                    n_ws: (pw[0] * v0.n_ws + pw[1] * v1.n_ws + pw[2] * v2.n_ws).normalize_or_zero(),
                    scalar: pw[0] * v0.scalar + pw[1] * v1.scalar + pw[2] * v2.scalar,
                };
            }
        }
    }
}
