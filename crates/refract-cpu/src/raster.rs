//! A deterministic visibility-buffer rasteriser producing the G-buffers of the image-space
//! methods: pixel-centre sampling, the top-left fill rule on an 8-bit sub-pixel grid (as GPUs
//! do), perspective-correct interpolation, near-plane clipping, and bands of rows rendered in
//! parallel.
//!
//! The scan conversion keeps only what the depth test needs per pixel (window depth and a
//! triangle id, 8 bytes); the attributes of the surviving fragment are interpolated when a
//! pixel is read ([`SurfaceBuffer::texel`], eight at a time with [`Band::attribute_lanes`],
//! only the attributes asked for), so overdraw costs an edge test and a depth compare, never an
//! interpolation. As on a GPU, each triangle's attributes are set up once as planes in screen
//! space (`1/w` and each attribute over `w`), so a pixel evaluates one multiply-add pair per
//! attribute and divides once. The window depth is a plane too where the mesh asks for it
//! ([`DepthInterpolation::Plane`]); by default it is interpolated from the exact integer edge
//! functions. A texel carries its perspective-correct barycentric weights in its mesh
//! triangle, through near-plane clipping. A renderer can run its per-pixel work band by band
//! right after the band is rasterised ([`rasterize_bands`]), while the band is in cache.
//!
//! Per frame the work follows the geometry: each row records the extent of its covered pixels
//! ([`Band::covered_span`]), so per-pixel passes skip the rest and the next frame of the same
//! size clears only those extents; a wide triangle's inside pixels on a row are solved as one
//! run from its three edge functions, exactly (the same pixels as testing each).

use core::ops::Range;

use glam::{Vec3, Vec4, Vec4Swizzles};
use rayon::prelude::*;
use refract_core::Camera;
use refract_core::lanes::{F32x8, LANES, Mask, Vec3x8, mask_from_lanes};
use refract_core::real::Vector3;
use refract_geometry::Mesh;

/// Sub-pixel precision of vertex positions (8 bits, as Direct3D and Vulkan guarantee).
const SUBPIXEL_BITS: u32 = 8;
const SUBPIXEL: i64 = 1 << SUBPIXEL_BITS;
/// Height in rows of a band; each band (full width) is rasterised by one task, straight into
/// its rows of the output.
pub const BAND_ROWS: u32 = 16;
/// Input triangles set up per task; the set-up triangles of a chunk are stored together and a
/// triangle id is `chunk · CHUNK_SLOTS + index in chunk`.
const CHUNK_TRIANGLES: usize = 4096;
/// Near-plane clipping turns a triangle into at most two.
const CHUNK_SLOTS: u32 = 2 * CHUNK_TRIANGLES as u32;
/// The triangle id of an empty pixel.
const EMPTY: u32 = u32::MAX;

/// Which faces are drawn (the others are culled), seen from the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Faces {
    /// Counter-clockwise on screen (facing the camera): the front-face pass.
    Front,
    /// Clockwise on screen: the back-face pass.
    Back,
    /// Both (no culling): the depth-peeled distance-map layers.
    Both,
}

/// Which fragment survives the depth test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthTest {
    /// The nearest (depth compare Less; the first triangle in index order wins ties).
    Nearest,
    /// The furthest (depth compare Greater; the first triangle wins ties).
    Furthest,
}

impl DepthTest {
    /// The depth of an empty pixel: every fragment passes against it.
    fn cleared(self) -> Visibility {
        let depth = match self {
            Self::Nearest => f32::INFINITY,
            Self::Furthest => f32::NEG_INFINITY,
        };
        Visibility {
            depth,
            triangle: EMPTY,
        }
    }
}

/// One pixel of the visibility buffer: the depth and id of the fragment that survived.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Visibility {
    depth: f32,
    triangle: u32,
}

/// The surface seen at one pixel: the attributes of the fragment that survived the depth test,
/// interpolated at the pixel centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Texel {
    /// Window depth in `[0, 1]`.
    pub depth: f32,
    /// Perspective-correct interpolated world position.
    pub p_ws: Vec3,
    /// Perspective-correct interpolated vertex normal (normalised).
    pub n_ws: Vec3,
    /// Perspective-correct interpolated per-vertex scalar (`d_N`; 0 for meshes without one).
    pub scalar: f32,
    /// The fragment's barycentric weights `(w0, w1, w2)` in its mesh triangle (vertex order
    /// of `triangles[triangle]`), perspective-correct: any other per-vertex attribute (uv,
    /// albedo) is `w0·a0 + w1·a1 + w2·a2`. The rasteriser carries them as an attribute (the
    /// corners' own weights, interpolated like the position), so pieces of a clipped
    /// triangle give weights in the whole triangle.
    pub barycentrics: Vec3,
    /// The mesh triangle the fragment belongs to (the mesh says which object it is).
    pub triangle: u32,
}

/// A triangle mesh ready for rasterisation: world positions, normals and, optionally, one
/// scalar per vertex. Any mesh of a scene (refractor or opaque object) rasterises.
#[derive(Clone, Copy, Debug)]
pub struct RasterMesh<'a> {
    /// World positions.
    pub positions: &'a [Vec3],
    /// Vertex normals.
    pub normals: &'a [Vec3],
    /// One scalar per vertex (`d_N`), interpolated like the normals; empty: 0 everywhere.
    pub scalars: &'a [f32],
    /// Triangles (counter-clockwise seen from outside).
    pub triangles: &'a [[u32; 3]],
    /// How the window depth is interpolated.
    pub depth: DepthInterpolation,
}

/// How the rasteriser interpolates the window depth (the depth test's value and
/// [`Texel::depth`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DepthInterpolation {
    /// `Σ λₖ·depthₖ` with the barycentrics `λₖ` from the exact integer edge functions (the
    /// default): what a pass that turns window depths into distances needs (the distance
    /// maps; converting magnifies the depth's last bits).
    #[default]
    Exact,
    /// A plane like the attributes, `(value + dy·Δy) + dx·Δx` in `f32`: fewer operations per
    /// pixel, last bits different; for passes whose depth only decides visibility (the
    /// image-space front and back faces).
    Plane,
}

impl<'a> RasterMesh<'a> {
    /// A mesh without a per-vertex scalar (an opaque object).
    pub fn new(mesh: &'a Mesh) -> Self {
        Self::with_scalars(mesh, &[])
    }

    /// A mesh with one scalar per vertex (the refractor's `d_N`); `scalars` must be empty or
    /// have one value per vertex.
    pub fn with_scalars(mesh: &'a Mesh, scalars: &'a [f32]) -> Self {
        debug_assert!(scalars.is_empty() || scalars.len() == mesh.positions.len());
        Self {
            positions: &mesh.positions,
            normals: &mesh.normals,
            scalars,
            triangles: &mesh.triangles,
            depth: DepthInterpolation::Exact,
        }
    }

    /// This mesh with its window depth interpolated as `depth` says.
    pub fn with_depth(self, depth: DepthInterpolation) -> Self {
        Self { depth, ..self }
    }

    #[inline]
    fn scalar(&self, vertex: u32) -> f32 {
        self.scalars.get(vertex as usize).copied().unwrap_or(0.0)
    }
}

/// The barycentric weights of a triangle's three vertices.
const CORNER_BARYCENTRICS: [Vec3; 3] = [Vec3::X, Vec3::Y, Vec3::Z];

/// A vertex after projection, with the attributes to interpolate.
#[derive(Clone, Copy, Debug)]
struct ClipVertex {
    clip: Vec4,
    p_ws: Vec3,
    n_ws: Vec3,
    scalar: f32,
    /// Barycentric weights in the mesh triangle (a unit vector at its vertices).
    bary: Vec3,
}

impl ClipVertex {
    fn lerp(self, other: Self, t: f32) -> Self {
        Self {
            clip: self.clip.lerp(other.clip, t),
            p_ws: self.p_ws.lerp(other.p_ws, t),
            n_ws: self.n_ws.lerp(other.n_ws, t),
            scalar: self.scalar + (other.scalar - self.scalar) * t,
            bary: self.bary.lerp(other.bary, t),
        }
    }
}

/// The attributes of a corner, interpolated when a pixel is read.
#[derive(Clone, Copy, Debug)]
struct Attributes {
    p_ws: Vec3,
    n_ws: Vec3,
    scalar: f32,
    /// Barycentric weights of the corner in the mesh triangle.
    bary: Vec3,
}

/// A per-pixel quantity of a triangle as an affine function of the pixel centre: its value at
/// the centre of the triangle's anchor pixel and what it gains per pixel to the right (`dx`)
/// and per row down (`dy`). Set up in `f64` and rounded once; evaluated in `f32` as
/// `(at_anchor + dy·Δy) + dx·Δx`, one row value shared by the row's pixels, the same
/// operations in the scalar and the eight-lane paths.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Plane {
    at_anchor: f32,
    dx: f32,
    dy: f32,
}

impl Plane {
    /// `Σₖ vₖ·λₖ` over the corners' values `v` and the barycentric planes `l` (`f64`).
    fn of(v: [f64; 3], l: &[[f64; 3]; 3]) -> Self {
        let sum = |i: usize| v[0] * l[0][i] + v[1] * l[1][i] + v[2] * l[2][i];
        Self {
            at_anchor: sum(0) as f32,
            dx: sum(1) as f32,
            dy: sum(2) as f32,
        }
    }

    /// The value at the anchor's column of the row `dy` rows below the anchor.
    #[inline(always)]
    fn row(self, dy: f32) -> f32 {
        self.at_anchor + self.dy * dy
    }

    /// The value `dx` pixels right of the anchor's column, from the row's value.
    #[inline(always)]
    fn at(self, row: f32, dx: f32) -> f32 {
        row + self.dx * dx
    }

    /// [`Self::at`] on eight lanes: each lane `row + dx·Δxᵢ`, the same bits.
    #[inline(always)]
    fn at_x8(self, row: f32, dx: F32x8) -> F32x8 {
        F32x8::splat(row) + F32x8::splat(self.dx) * dx
    }
}

/// A triangle's attributes as [`Plane`]s for perspective-correct interpolation: `1/w` and each
/// attribute over `w` (`a/w` is affine in screen space), so that a pixel's attribute is
/// `(a/w)(x, y) / (1/w)(x, y)`: one division per pixel, whatever the number of attributes.
/// (The window depth is a separate, optional plane: see [`ScreenTriangle::depth_at`].)
#[derive(Clone, Copy, Debug, Default)]
struct AttributePlanes {
    inv_w: Plane,
    p_ws: [Plane; 3],
    /// The normal over `w`; normalised without the division, which only scales it.
    n_ws: [Plane; 3],
    scalar: Plane,
    bary: [Plane; 3],
}

/// A triangle set up for scan conversion: fixed-point screen positions (`y` down) for the
/// coverage test and the depth, and its attributes as planes about an anchor pixel.
#[derive(Clone, Copy, Debug)]
struct ScreenTriangle {
    /// Fixed-point pixel coordinates of the corners, in clockwise-on-screen order.
    xy: [[i64; 2]; 3],
    /// `1 / (twice the area in fixed point)`.
    inv_area: f64,
    /// Window depth of each corner.
    depth: [f32; 3],
    /// The window depth as a plane, for a mesh with [`DepthInterpolation::Plane`].
    depth_plane: Option<Plane>,
    /// The pixel the planes are set up about: the one holding the corners' centroid,
    /// clamped to the bounds (near every pixel the triangle covers, so that the planes are
    /// evaluated without large cancellations).
    anchor: [i32; 2],
    planes: AttributePlanes,
    /// Pixel bounds, inclusive.
    min: [u32; 2],
    max: [u32; 2],
    /// The mesh triangle it was set up from (clipped pieces share it).
    source: u32,
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

/// The fixed-point position of the centre of pixel `(x, y)`.
#[inline]
fn pixel_center_fixed(x: u32, y: u32) -> [i64; 2] {
    [
        i64::from(x) * SUBPIXEL + SUBPIXEL / 2,
        i64::from(y) * SUBPIXEL + SUBPIXEL / 2,
    ]
}

/// A triangle's quantities at pixel centres, before the perspective division (position,
/// normal, scalar and barycentrics over `w`).
#[derive(Clone, Copy, Debug)]
struct PlaneValues {
    depth: f32,
    inv_w: f32,
    p_ws: Vec3,
    n_ws: Vec3,
    scalar: f32,
    bary: Vec3,
}

/// [`PlaneValues`] of eight pixels, as lanes; the attributes not asked for are zero.
#[derive(Clone, Copy, Debug)]
struct PlaneValuesX8 {
    depth: F32x8,
    inv_w: F32x8,
    p_ws: Vec3x8,
    n_ws: Vec3x8,
    scalar: F32x8,
    bary: Vec3x8,
}

impl PlaneValuesX8 {
    /// `a`'s lanes where `take_a` is set, `b`'s elsewhere.
    #[inline(always)]
    fn select(take_a: Mask, a: &Self, b: &Self) -> Self {
        Self {
            depth: take_a.select(a.depth, b.depth),
            inv_w: take_a.select(a.inv_w, b.inv_w),
            p_ws: Vec3x8::select(take_a, a.p_ws, b.p_ws),
            n_ws: Vec3x8::select(take_a, a.n_ws, b.n_ws),
            scalar: take_a.select(a.scalar, b.scalar),
            bary: Vec3x8::select(take_a, a.bary, b.bary),
        }
    }
}

impl ScreenTriangle {
    /// The rows from the anchor to row `y`, and the columns from it to `x`, as `f32` (exact).
    #[inline(always)]
    fn offsets(&self, x: u32, y: u32) -> (f32, f32) {
        (
            (x as i32 - self.anchor[0]) as f32,
            (y as i32 - self.anchor[1]) as f32,
        )
    }

    /// The three edge functions at the centre of pixel `(x, y)` (exact integers).
    #[inline]
    fn edges_at(&self, x: u32, y: u32) -> [i64; 3] {
        let [a, b, c] = self.xy;
        let q = pixel_center_fixed(x, y);
        [edge(b, c, q), edge(c, a, q), edge(a, b, q)]
    }

    /// What each edge function gains from one pixel to the next on its right: `−Δy·SUBPIXEL`.
    #[inline]
    fn edge_steps(&self) -> [i64; 3] {
        let [a, b, c] = self.xy;
        [
            -(c[1] - b[1]) * SUBPIXEL,
            -(a[1] - c[1]) * SUBPIXEL,
            -(b[1] - a[1]) * SUBPIXEL,
        ]
    }

    /// The window depth at the centre of pixel `(x, y)`, as the scan conversion computed it:
    /// from the depth plane where the triangle has one, else `Σₖ λₖ·depthₖ` in `f32` with the
    /// screen-space barycentrics `λₖ = eₖ / area` from the exact integer edge functions,
    /// scaled in `f64` and rounded (what the distance maps need: they turn window depths into
    /// distances, which magnifies their last bits; performance.md, "Tried and not kept").
    #[inline]
    fn depth_at(&self, x: u32, y: u32) -> f32 {
        if let Some(plane) = self.depth_plane {
            let (dx, dy) = self.offsets(x, y);
            return plane.at(plane.row(dy), dx);
        }
        self.depth_from_edges(self.edges_at(x, y))
    }

    /// [`Self::depth_at`] from the edge functions `e` at the pixel.
    #[inline]
    fn depth_from_edges(&self, e: [i64; 3]) -> f32 {
        let l = |e: i64| (e as f64 * self.inv_area) as f32;
        l(e[0]) * self.depth[0] + l(e[1]) * self.depth[1] + l(e[2]) * self.depth[2]
    }

    /// Every quantity at the centre of pixel `(x, y)`, before the perspective division.
    #[inline]
    fn values(&self, x: u32, y: u32) -> PlaneValues {
        let (dx, dy) = self.offsets(x, y);
        let at = |plane: Plane| plane.at(plane.row(dy), dx);
        let at3 = |p: [Plane; 3]| Vec3::new(at(p[0]), at(p[1]), at(p[2]));
        let planes = &self.planes;
        PlaneValues {
            depth: self.depth_at(x, y),
            inv_w: at(planes.inv_w),
            p_ws: at3(planes.p_ws),
            n_ws: at3(planes.n_ws),
            scalar: at(planes.scalar),
            bary: at3(planes.bary),
        }
    }

    /// [`Self::values`] at pixels `x` of row `y`, eight at once (lane `i`: pixel `x[i]`, the
    /// same bits); only the position, the normal, `1/w` and the [`Attribute`]s in
    /// `ATTRIBUTES`, the others zero.
    #[inline(always)]
    fn values_x8<const ATTRIBUTES: u8>(&self, x: &[u32; LANES], y: u32) -> PlaneValuesX8 {
        let dy = (y as i32 - self.anchor[1]) as f32;
        let mut dx = [0.0f32; LANES];
        for (dx, &x) in dx.iter_mut().zip(x) {
            *dx = (x as i32 - self.anchor[0]) as f32;
        }
        let dx = F32x8::new(dx);
        let at = |plane: Plane| plane.at_x8(plane.row(dy), dx);
        let at3 = |p: [Plane; 3]| Vec3x8 {
            x: at(p[0]),
            y: at(p[1]),
            z: at(p[2]),
        };
        let wanted = |attribute: u8| ATTRIBUTES & attribute != 0;
        let planes = &self.planes;
        PlaneValuesX8 {
            depth: match wanted(Attribute::DEPTH) {
                true => {
                    let mut depth = [0.0f32; LANES];
                    for (depth, &x) in depth.iter_mut().zip(x) {
                        *depth = self.depth_at(x, y);
                    }
                    F32x8::new(depth)
                }
                false => F32x8::ZERO,
            },
            inv_w: at(planes.inv_w),
            p_ws: at3(planes.p_ws),
            n_ws: at3(planes.n_ws),
            scalar: match wanted(Attribute::SCALAR) {
                true => at(planes.scalar),
                false => F32x8::ZERO,
            },
            bary: match wanted(Attribute::BARYCENTRICS) {
                true => at3(planes.bary),
                false => Vec3x8::ZERO,
            },
        }
    }

    /// The attributes at pixel `(x, y)`'s centre (inside or not): the planes over `w` divided
    /// by the plane of `1/w` (perspective-correct), the normal renormalised, the depth as the
    /// scan conversion computed it.
    fn texel(&self, x: u32, y: u32) -> Texel {
        let v = self.values(x, y);
        let inv = 1.0 / v.inv_w;
        Texel {
            depth: v.depth,
            p_ws: v.p_ws * inv,
            n_ws: v.n_ws.normalize_or_zero(),
            scalar: v.scalar * inv,
            barycentrics: v.bary * inv,
            triangle: self.source,
        }
    }
}

/// The interpolated attributes of a texel beyond its position and normal, as bits: a caller of
/// [`SurfaceBuffer::attribute_lanes`] or [`Band::attribute_lanes`] names the ones it reads, and
/// the others are neither gathered nor interpolated (they read zero).
pub struct Attribute;

impl Attribute {
    /// [`Texel::depth`].
    pub const DEPTH: u8 = 1;
    /// [`Texel::scalar`].
    pub const SCALAR: u8 = 2;
    /// [`Texel::barycentrics`].
    pub const BARYCENTRICS: u8 = 4;
    /// Every attribute.
    pub const ALL: u8 = Self::DEPTH | Self::SCALAR | Self::BARYCENTRICS;
}

/// Eight texels as lanes (structure of arrays): lane `i` holds [`Texel`] `i`'s fields, so a
/// lane kernel reads them without a transpose.
#[derive(Clone, Copy, Debug)]
pub struct TexelLanes {
    /// Window depth.
    pub depth: F32x8,
    /// Perspective-correct interpolated world position.
    pub p_ws: Vec3x8,
    /// Perspective-correct interpolated vertex normal (normalised; zero where it cannot be).
    pub n_ws: Vec3x8,
    /// The interpolated per-vertex scalar.
    pub scalar: F32x8,
    /// The barycentric weights in the mesh triangle ([`Texel::barycentrics`]).
    pub barycentrics: Vec3x8,
    /// The mesh triangle of each lane.
    pub triangle: [u32; LANES],
}

impl TexelLanes {
    /// The texel of each lane.
    pub fn to_texels(&self) -> [Texel; LANES] {
        let (depth, scalar) = (self.depth.to_array(), self.scalar.to_array());
        let (p_ws, n_ws) = (self.p_ws.to_lanes(), self.n_ws.to_lanes());
        let barycentrics = self.barycentrics.to_lanes();
        let mut texels = [Texel {
            depth: 0.0,
            p_ws: Vec3::ZERO,
            n_ws: Vec3::ZERO,
            scalar: 0.0,
            barycentrics: Vec3::ZERO,
            triangle: 0,
        }; LANES];
        for (i, texel) in texels.iter_mut().enumerate() {
            *texel = Texel {
                depth: depth[i],
                p_ws: p_ws[i],
                n_ws: n_ws[i],
                scalar: scalar[i],
                barycentrics: barycentrics[i],
                triangle: self.triangle[i],
            };
        }
        texels
    }
}

/// [`ScreenTriangle::texel`] for eight pixels (lane `i`: triangle `triangles[i]`, pixel
/// `(x[i], y)`): the planes evaluated with the same operations lane by lane, the division
/// and the normalisation on eight SIMD lanes, so each texel has the scalar function's bits.
///
/// Only the attributes in `ATTRIBUTES` ([`Attribute`] bits) beside the position and the normal
/// are evaluated; the others are zero.
#[inline]
fn texel_lanes<const ATTRIBUTES: u8>(
    triangles: [&ScreenTriangle; LANES],
    x: &[u32; LANES],
    y: u32,
) -> TexelLanes {
    let mut source = [0; LANES];
    for (source, t) in source.iter_mut().zip(&triangles) {
        *source = t.source;
    }
    // At most three triangles (one: inside a triangle; two or three: straddling one or two
    // edges, the common mixed cases): each triangle's planes on every lane, each lane keeping
    // its own triangle's values.
    if let Some((distinct, count)) = at_most_three(&triangles) {
        let mut values = distinct[0].values_x8::<ATTRIBUTES>(x, y);
        for &other in &distinct[1..count] {
            let mut on_other = [false; LANES];
            for (on, t) in on_other.iter_mut().zip(&triangles) {
                *on = core::ptr::eq(*t, other);
            }
            let on_other = mask_from_lanes(on_other);
            let theirs = other.values_x8::<ATTRIBUTES>(x, y);
            values = PlaneValuesX8::select(on_other, &theirs, &values);
        }
        return divide_x8::<ATTRIBUTES>(&values, source);
    }
    // Each lane on its own triangle: every plane's coefficients gathered lane by lane, then
    // evaluated on lanes with the scalar path's operations, `(value + dy·Δy) + dx·Δx`.
    let (mut dx, mut dy) = ([0.0f32; LANES], [0.0f32; LANES]);
    for (i, t) in triangles.iter().enumerate() {
        (dx[i], dy[i]) = t.offsets(x[i], y);
    }
    let (dx, dy) = (F32x8::new(dx), F32x8::new(dy));
    let at = |plane: fn(&AttributePlanes) -> Plane| gathered(&triangles, dx, dy, plane);
    let at3 = |plane: fn(&AttributePlanes) -> &[Plane; 3]| Vec3x8 {
        x: gathered(&triangles, dx, dy, |p| plane(p)[0]),
        y: gathered(&triangles, dx, dy, |p| plane(p)[1]),
        z: gathered(&triangles, dx, dy, |p| plane(p)[2]),
    };
    let wanted = |attribute: u8| ATTRIBUTES & attribute != 0;
    let mut depth = [0.0f32; LANES];
    if wanted(Attribute::DEPTH) {
        for (i, t) in triangles.iter().enumerate() {
            depth[i] = t.depth_at(x[i], y);
        }
    }
    let values = PlaneValuesX8 {
        depth: F32x8::new(depth),
        inv_w: at(|p| p.inv_w),
        p_ws: at3(|p| &p.p_ws),
        n_ws: at3(|p| &p.n_ws),
        scalar: match wanted(Attribute::SCALAR) {
            true => at(|p| p.scalar),
            false => F32x8::ZERO,
        },
        bary: match wanted(Attribute::BARYCENTRICS) {
            true => at3(|p| &p.bary),
            false => Vec3x8::ZERO,
        },
    };
    divide_x8::<ATTRIBUTES>(&values, source)
}

/// One plane (chosen by `plane`) of each lane's triangle at the lanes' offsets `dx`, `dy` from
/// their triangles' anchors: the coefficients gathered lane by lane, then
/// `(value + dy·Δy) + dx·Δx` on lanes, [`Plane::row`] and [`Plane::at`]'s operations.
#[inline(always)]
fn gathered(
    triangles: &[&ScreenTriangle; LANES],
    dx: F32x8,
    dy: F32x8,
    plane: impl Fn(&AttributePlanes) -> Plane,
) -> F32x8 {
    let (mut value, mut per_x, mut per_y) = ([0.0f32; LANES], [0.0f32; LANES], [0.0; LANES]);
    for (i, t) in triangles.iter().enumerate() {
        let p = plane(&t.planes);
        (value[i], per_x[i], per_y[i]) = (p.at_anchor, p.dx, p.dy);
    }
    (F32x8::new(value) + F32x8::new(per_y) * dy) + F32x8::new(per_x) * dx
}

/// The distinct values of eight lanes (triangles, triangle ids), in lane order, and how many
/// there are; `None` when there are more than three.
#[inline]
pub(crate) fn at_most_three<T: Copy + Distinct>(lanes: &[T; LANES]) -> Option<([T; 3], usize)> {
    let mut distinct = [lanes[0]; 3];
    let mut count = 1;
    for &t in lanes {
        if distinct[..count].iter().any(|d| d.same(t)) {
            continue;
        }
        if count == distinct.len() {
            return None;
        }
        distinct[count] = t;
        count += 1;
    }
    Some((distinct, count))
}

/// What [`at_most_three`] compares: a triangle by identity, an id by value.
pub(crate) trait Distinct {
    /// Whether `self` and `other` are the same.
    fn same(self, other: Self) -> bool;
}

impl Distinct for &ScreenTriangle {
    #[inline]
    fn same(self, other: Self) -> bool {
        core::ptr::eq(self, other)
    }
}

impl Distinct for u32 {
    #[inline]
    fn same(self, other: Self) -> bool {
        self == other
    }
}

/// Eight texels from their plane values: [`ScreenTriangle::texel`]'s perspective division
/// and normalisation on lanes, the same operations, so the same bits.
#[inline(always)]
fn divide_x8<const ATTRIBUTES: u8>(v: &PlaneValuesX8, source: [u32; LANES]) -> TexelLanes {
    let inv = F32x8::ONE / v.inv_w;
    let (n_ws, n_ok) = v.n_ws.try_normalize();
    TexelLanes {
        depth: v.depth,
        p_ws: v.p_ws * inv,
        n_ws: Vec3x8::select(n_ok, n_ws, Vec3x8::ZERO),
        scalar: match ATTRIBUTES & Attribute::SCALAR != 0 {
            true => v.scalar * inv,
            false => F32x8::ZERO,
        },
        barycentrics: match ATTRIBUTES & Attribute::BARYCENTRICS != 0 {
            true => v.bary * inv,
            false => Vec3x8::ZERO,
        },
        triangle: source,
    }
}

/// The texels of pixels `x` of row `y` (`row` starts at the row's first pixel): eight
/// neighbours inside one triangle (most groups) take one triangle lookup, compared as ids
/// straight from the visibility buffer; other groups go through [`gather_triangles`] and
/// [`texel_lanes`], which give the same bits for such a group.
///
/// # Panics
/// If one of the pixels is empty.
#[inline]
fn row_texel_lanes<const ATTRIBUTES: u8>(
    row: &[Visibility],
    triangles: &TriangleStore,
    x: &[u32; LANES],
    y: u32,
) -> TexelLanes {
    let first = x[0] as usize;
    let neighbours = (0..LANES).all(|i| x[i] as usize == first + i);
    if neighbours && first + LANES <= row.len() {
        let run = &row[first..first + LANES];
        let id = run[0].triangle;
        if id != EMPTY && run.iter().all(|v| v.triangle == id) {
            let t = triangles.get(id);
            return divide_x8::<ATTRIBUTES>(&t.values_x8::<ATTRIBUTES>(x, y), [t.source; LANES]);
        }
    }
    texel_lanes::<ATTRIBUTES>(gather_triangles(row, triangles, x, y), x, y)
}

/// The triangles seen at pixels `x` of a row (`row` starts at the row's first pixel).
///
/// # Panics
/// If one of the pixels is empty.
#[inline]
fn gather_triangles<'t>(
    row: &[Visibility],
    triangles: &'t TriangleStore,
    x: &[u32; LANES],
    y: u32,
) -> [&'t ScreenTriangle; LANES] {
    let triangle = |x: u32| {
        let v = row[x as usize];
        assert!(v.triangle != EMPTY, "pixel ({x}, {y}) is empty");
        triangles.get(v.triangle)
    };
    let mut gathered = [triangle(x[0]); LANES];
    for (slot, &x) in gathered.iter_mut().zip(x).skip(1) {
        *slot = triangle(x);
    }
    gathered
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

/// A vertex projected to the screen: what triangle set-up needs of it.
#[derive(Clone, Copy, Debug, Default)]
struct Projected {
    /// Fixed-point pixel coordinates (`y` down).
    xy: [i64; 2],
    /// Window depth.
    depth: f32,
    /// `1/w`.
    inv_w: f32,
    /// The pixel coordinates are finite.
    finite: bool,
    /// In front of the near plane (`z_clip ≥ 0`): triangles with all three vertices in front
    /// need no clipping.
    in_front: bool,
}

/// The viewport transform of one clip-space vertex, snapped to the sub-pixel grid.
#[inline]
fn project(c: Vec4, width: f32, height: f32) -> Projected {
    let ndc = c.xyz() / c.w;
    let px = 0.5 * (ndc.x + 1.0) * width;
    let py = 0.5 * (1.0 - ndc.y) * height;
    Projected {
        xy: [
            (f64::from(px) * SUBPIXEL as f64).round() as i64,
            (f64::from(py) * SUBPIXEL as f64).round() as i64,
        ],
        depth: ndc.z,
        inv_w: 1.0 / c.w,
        finite: px.is_finite() && py.is_finite(),
        in_front: c.z >= 0.0,
    }
}

/// Sets up a triangle from its projected corners: culls it by facing, orients it clockwise on
/// screen and bounds it; `attributes` is only read for the triangles kept.
fn setup(
    v: [Projected; 3],
    attributes: impl FnOnce() -> [Attributes; 3],
    camera: &Camera,
    faces: Faces,
    depth_interpolation: DepthInterpolation,
    source: u32,
) -> Option<ScreenTriangle> {
    if !(v[0].finite && v[1].finite && v[2].finite) {
        return None;
    }
    let mut xy = [v[0].xy, v[1].xy, v[2].xy];
    let mut depth = [v[0].depth, v[1].depth, v[2].depth];
    let mut inv_w = [v[0].inv_w, v[1].inv_w, v[2].inv_w];
    // In pixel coordinates (y down) a positive edge function means clockwise on screen; a
    // triangle wound counter-clockwise seen from outside appears counter-clockwise on screen
    // (negative) when it faces the camera, clockwise through a mirrored camera.
    let area = edge(xy[0], xy[1], xy[2]);
    let front = (area < 0) != camera.is_mirrored();
    let culled = match faces {
        Faces::Front => !front,
        Faces::Back => front,
        Faces::Both => false,
    };
    if area == 0 || culled {
        return None;
    }
    let mut area = area;
    let mut attributes = attributes();
    if area < 0 {
        xy.swap(1, 2);
        depth.swap(1, 2);
        inv_w.swap(1, 2);
        attributes.swap(1, 2);
        area = -area;
    }
    let lo = |k: usize| xy[0][k].min(xy[1][k]).min(xy[2][k]);
    let hi = |k: usize| xy[0][k].max(xy[1][k]).max(xy[2][k]);
    let size = [camera.width() as i64, camera.height() as i64];
    // Pixels whose centre (x + ½) can lie inside [lo, hi].
    let first = |k: usize| {
        let n = lo(k) - SUBPIXEL / 2;
        (n.div_euclid(SUBPIXEL) + i64::from(n.rem_euclid(SUBPIXEL) != 0)).max(0)
    };
    let last = |k: usize| ((hi(k) - SUBPIXEL / 2).div_euclid(SUBPIXEL)).min(size[k] - 1);
    let (x0, x1, y0, y1) = (first(0), last(0), first(1), last(1));
    if x0 > x1 || y0 > y1 {
        return None;
    }
    let (min, max) = ([x0, y0], [x1, y1]);
    // The pixel holding the centroid (in `i128`: corners far off screen), inside the bounds.
    let anchor = |k: usize| {
        let sum: i128 = xy.iter().map(|v| i128::from(v[k])).sum();
        let pixel = (sum / 3).div_euclid(i128::from(SUBPIXEL));
        pixel.clamp(i128::from(min[k]), i128::from(max[k])) as i64
    };
    let anchor = [anchor(0), anchor(1)];
    let l = barycentric_planes(xy, area, anchor);
    Some(ScreenTriangle {
        xy,
        inv_area: 1.0 / area as f64,
        depth,
        depth_plane: (depth_interpolation == DepthInterpolation::Plane)
            .then(|| Plane::of(depth.map(f64::from), &l)),
        anchor: [anchor[0] as i32, anchor[1] as i32],
        planes: attribute_planes(&l, inv_w, &attributes),
        min: [x0 as u32, y0 as u32],
        max: [x1 as u32, y1 as u32],
        source,
    })
}

/// The screen-space barycentrics `λₖ = eₖ / area` of a triangle with corners `xy` (clockwise,
/// twice its area `area` in fixed point) as planes about the pixel `anchor`, in `f64`: each
/// `[λₖ at the anchor, per pixel right, per row down]` (edge functions exact at the anchor).
fn barycentric_planes(xy: [[i64; 2]; 3], area: i64, anchor: [i64; 2]) -> [[f64; 3]; 3] {
    let [a, b, c] = xy;
    let q = [
        anchor[0] * SUBPIXEL + SUBPIXEL / 2,
        anchor[1] * SUBPIXEL + SUBPIXEL / 2,
    ];
    let inv_area = 1.0 / area as f64;
    let s = SUBPIXEL as f64;
    // Edge `from → to` at the anchor, and per pixel right (−Δy) and down (+Δx), over the area.
    let barycentric = |from: [i64; 2], to: [i64; 2]| {
        [
            edge(from, to, q) as f64 * inv_area,
            -((to[1] - from[1]) as f64) * s * inv_area,
            (to[0] - from[0]) as f64 * s * inv_area,
        ]
    };
    [barycentric(b, c), barycentric(c, a), barycentric(a, b)]
}

/// A triangle's attribute planes from its barycentric planes `l`: each as `Σₖ vₖ·λₖ`, `1/w`
/// with `vₖ = 1/wₖ` and every attribute `a` with `vₖ = aₖ/wₖ`.
fn attribute_planes(
    l: &[[f64; 3]; 3],
    inv_w: [f32; 3],
    attributes: &[Attributes; 3],
) -> AttributePlanes {
    let iw = inv_w.map(f64::from);
    let over_w = |v: [f32; 3]| Plane::of([0, 1, 2].map(|k| f64::from(v[k]) * iw[k]), l);
    let over_w3 = |v: [Vec3; 3]| {
        [
            over_w(v.map(|v| v.x)),
            over_w(v.map(|v| v.y)),
            over_w(v.map(|v| v.z)),
        ]
    };
    AttributePlanes {
        inv_w: Plane::of(iw, l),
        p_ws: over_w3(attributes.map(|a| a.p_ws)),
        n_ws: over_w3(attributes.map(|a| a.n_ws)),
        scalar: over_w(attributes.map(|a| a.scalar)),
        bary: over_w3(attributes.map(|a| a.bary)),
    }
}

/// The set-up triangles of one frame, stored per input chunk (the chunks' memory is reused
/// from frame to frame).
#[derive(Clone, Debug, Default)]
struct TriangleStore {
    chunks: Vec<Vec<ScreenTriangle>>,
}

impl TriangleStore {
    #[inline]
    fn get(&self, id: u32) -> &ScreenTriangle {
        &self.chunks[(id / CHUNK_SLOTS) as usize][(id % CHUNK_SLOTS) as usize]
    }

    /// Projects, clips and sets up every triangle of `mesh`, in parallel, keeping index order.
    fn set_up(
        &mut self,
        mesh: &RasterMesh<'_>,
        clip: &[Vec4],
        projected: &[Projected],
        camera: &Camera,
        faces: Faces,
    ) {
        let (width, height) = (camera.width() as f32, camera.height() as f32);
        let depth = mesh.depth;
        let chunks = mesh.triangles.len().div_ceil(CHUNK_TRIANGLES);
        self.chunks.resize_with(chunks, Vec::new);
        self.chunks
            .par_iter_mut()
            .zip(mesh.triangles.par_chunks(CHUNK_TRIANGLES))
            .enumerate()
            .for_each(|(c, (out, chunk))| {
                out.clear();
                let mut polygon = Vec::with_capacity(4);
                for (k, tri) in chunk.iter().enumerate() {
                    let source = (c * CHUNK_TRIANGLES + k) as u32;
                    let corners = tri.map(|i| projected[i as usize]);
                    if corners.iter().all(|v| v.in_front) {
                        let attributes = || {
                            [0, 1, 2].map(|k| {
                                let i = tri[k] as usize;
                                Attributes {
                                    p_ws: mesh.positions[i],
                                    n_ws: mesh.normals[i],
                                    scalar: mesh.scalar(i as u32),
                                    bary: CORNER_BARYCENTRICS[k],
                                }
                            })
                        };
                        out.extend(setup(corners, attributes, camera, faces, depth, source));
                        continue;
                    }
                    // Crossing the near plane: clip, then set up the pieces.
                    let v = [0, 1, 2].map(|k| {
                        let i = tri[k] as usize;
                        ClipVertex {
                            clip: clip[i],
                            p_ws: mesh.positions[i],
                            n_ws: mesh.normals[i],
                            scalar: mesh.scalar(i as u32),
                            bary: CORNER_BARYCENTRICS[k],
                        }
                    });
                    clip_near(v, &mut polygon);
                    for k in 1..polygon.len().saturating_sub(1) {
                        let piece = [polygon[0], polygon[k], polygon[k + 1]];
                        let attributes = || {
                            piece.map(|v| Attributes {
                                p_ws: v.p_ws,
                                n_ws: v.n_ws,
                                scalar: v.scalar,
                                bary: v.bary,
                            })
                        };
                        let corners = piece.map(|v| project(v.clip, width, height));
                        out.extend(setup(corners, attributes, camera, faces, depth, source));
                    }
                }
            });
    }

    /// Every triangle with its id, in index order.
    fn iter(&self) -> impl Iterator<Item = (u32, &ScreenTriangle)> {
        self.chunks.iter().enumerate().flat_map(|(c, chunk)| {
            chunk
                .iter()
                .enumerate()
                .map(move |(i, t)| (c as u32 * CHUNK_SLOTS + i as u32, t))
        })
    }
}

/// Per-pixel surface data of one pass, row-major from the top: which fragment survived the
/// depth test at each pixel, with its attributes interpolated on demand.
///
/// The buffer keeps all its memory between frames: after the first frame at a resolution,
/// rasterising into it allocates nothing.
#[derive(Clone, Debug, Default)]
pub struct SurfaceBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    visibility: Vec<Visibility>,
    /// Per row, the pixels `[first, end)` between its first and last covered pixel
    /// (`[u32::MAX, 0]` for an empty row).
    extents: Vec<[u32; 2]>,
    triangles: TriangleStore,
    /// Scratch: clip-space and projected vertex positions, and the per-band triangle lists.
    clip: Vec<Vec4>,
    projected: Vec<Projected>,
    bins: Vec<Vec<u32>>,
    /// The frame shape and depth test whose cleared value every pixel outside its row's
    /// extent holds (`None`: unknown, clear everything): the next frame of that shape clears
    /// only the last frame's extents.
    cleared_for: Option<(u32, u32, DepthTest)>,
}

impl SurfaceBuffer {
    /// An empty buffer (no pixels).
    pub fn new() -> Self {
        Self::default()
    }

    /// The fragment covering pixel `index` (row-major), or `None` where the pixel is empty.
    #[inline]
    pub fn texel(&self, index: usize) -> Option<Texel> {
        let v = self.visibility.get(index)?;
        (v.triangle != EMPTY).then(|| {
            let (x, y) = (index as u32 % self.width, index as u32 / self.width);
            self.triangles.get(v.triangle).texel(x, y)
        })
    }

    /// The fragments covering eight pixels of row `y` (`x[i]`), all of which must be covered
    /// (see [`Self::is_covered`]); each is [`Self::texel`]'s, bit for bit.
    ///
    /// # Panics
    /// If one of the pixels is empty or outside the buffer.
    pub fn texels_x8(&self, x: &[u32; LANES], y: u32) -> [Texel; LANES] {
        self.attribute_lanes::<{ Attribute::ALL }>(x, y).to_texels()
    }

    /// [`Self::texels_x8`] as lanes, with only the position, the normal and the
    /// [`Attribute`]s in `ATTRIBUTES` (the others zero): the same bits for those, less work.
    ///
    /// # Panics
    /// If one of the pixels is empty or outside the buffer.
    #[inline]
    pub fn attribute_lanes<const ATTRIBUTES: u8>(&self, x: &[u32; LANES], y: u32) -> TexelLanes {
        let row = (y * self.width) as usize;
        row_texel_lanes::<ATTRIBUTES>(&self.visibility[row..], &self.triangles, x, y)
    }

    /// The pixels of row `y` between its first and last covered pixel: no pixel outside is
    /// covered (empty when the row is).
    #[inline]
    pub fn covered_span(&self, y: u32) -> Range<u32> {
        span(self.extents[y as usize])
    }

    /// Whether pixel `index` (row-major) is covered.
    #[inline]
    pub fn is_covered(&self, index: usize) -> bool {
        self.visibility
            .get(index)
            .is_some_and(|v| v.triangle != EMPTY)
    }
}

/// The rows of one band right after they were rasterised, for per-pixel work while they are in
/// cache (see [`rasterize_bands`]).
pub struct Band<'a> {
    /// The first row of the band (rows `first_row..first_row + rows()`).
    pub first_row: u32,
    width: u32,
    visibility: &'a [Visibility],
    extents: &'a [[u32; 2]],
    triangles: &'a TriangleStore,
}

/// A row extent as a range (empty rows: `0..0`).
#[inline]
fn span([first, end]: [u32; 2]) -> Range<u32> {
    if first < end { first..end } else { 0..0 }
}

impl Band<'_> {
    /// The image width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Whether pixel `(x, y)` (`y` an image row inside this band) is covered.
    #[inline]
    pub fn is_covered(&self, x: u32, y: u32) -> bool {
        self.visibility[((y - self.first_row) * self.width + x) as usize].triangle != EMPTY
    }

    /// The fragment covering pixel `(x, y)` (`y` an image row inside this band), as
    /// [`SurfaceBuffer::texel`] computes it.
    #[inline]
    pub fn texel(&self, x: u32, y: u32) -> Option<Texel> {
        let v = self.visibility[((y - self.first_row) * self.width + x) as usize];
        (v.triangle != EMPTY).then(|| self.triangles.get(v.triangle).texel(x, y))
    }

    /// The window depth of the fragment covering pixel `(x, y)` (`y` an image row inside this
    /// band), `None` where the pixel is empty: no interpolation.
    #[inline]
    pub fn depth(&self, x: u32, y: u32) -> Option<f32> {
        let v = self.visibility[((y - self.first_row) * self.width + x) as usize];
        (v.triangle != EMPTY).then_some(v.depth)
    }

    /// The number of rows of this band.
    pub fn rows(&self) -> u32 {
        (self.visibility.len() / self.width as usize) as u32
    }

    /// [`SurfaceBuffer::attribute_lanes`] for eight pixels of row `y` of this band.
    #[inline]
    pub fn attribute_lanes<const ATTRIBUTES: u8>(&self, x: &[u32; LANES], y: u32) -> TexelLanes {
        let row = ((y - self.first_row) * self.width) as usize;
        row_texel_lanes::<ATTRIBUTES>(&self.visibility[row..], self.triangles, x, y)
    }

    /// The pixels of row `y` (an image row inside this band) between its first and last
    /// covered pixel: no pixel outside is covered (empty when the row is).
    #[inline]
    pub fn covered_span(&self, y: u32) -> Range<u32> {
        span(self.extents[(y - self.first_row) as usize])
    }
}

/// The number of pixels in a full band at `width` (the chunk size of per-band outputs for
/// [`rasterize_bands`]).
pub fn band_pixels(width: u32) -> usize {
    (BAND_ROWS * width) as usize
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
    let bands = camera.height().div_ceil(BAND_ROWS) as usize;
    rasterize_bands(
        mesh,
        camera,
        faces,
        test,
        buffer,
        rayon::iter::repeat_n((), bands),
        |_, ()| {},
    );
}

/// [`rasterize_into`], then `per_band(band, output)` for each band of [`BAND_ROWS`] rows as
/// soon as it is rasterised, on the task that rasterised it. `outputs` yields one item per band
/// in order, e.g. `pixels.par_chunks_mut(band_pixels(width))`.
///
/// # Panics
/// If `outputs` does not have one item per band (`height.div_ceil(BAND_ROWS)`).
pub fn rasterize_bands<O, F>(
    mesh: &RasterMesh<'_>,
    camera: &Camera,
    faces: Faces,
    test: DepthTest,
    buffer: &mut SurfaceBuffer,
    outputs: O,
    per_band: F,
) where
    O: IndexedParallelIterator,
    F: Fn(&Band<'_>, O::Item) + Sync + Send,
{
    rasterize_bands_above(mesh, camera, faces, test, buffer, None, outputs, per_band);
}

/// [`rasterize_into`] keeping at each pixel only fragments deeper than `floor[pixel]` (window
/// depth, row-major, one per pixel; `+∞` rejects every fragment): one step of depth peeling
/// (Everitt 2001), as the distance-map layers beyond the first use it.
///
/// # Panics
/// If `floor` does not have one value per pixel.
pub fn rasterize_peel_into(
    mesh: &RasterMesh<'_>,
    camera: &Camera,
    faces: Faces,
    floor: &[f32],
    buffer: &mut SurfaceBuffer,
) {
    assert_eq!(
        floor.len(),
        (camera.width() * camera.height()) as usize,
        "one floor depth per pixel"
    );
    let bands = camera.height().div_ceil(BAND_ROWS) as usize;
    rasterize_bands_above(
        mesh,
        camera,
        faces,
        DepthTest::Nearest,
        buffer,
        Some(floor),
        rayon::iter::repeat_n((), bands),
        |_, ()| {},
    );
}

// The one worker behind `rasterize_bands` and `rasterize_peel_into`: their parameters plus the
// peeling floor; a struct would only rename them.
#[allow(clippy::too_many_arguments)]
fn rasterize_bands_above<O, F>(
    mesh: &RasterMesh<'_>,
    camera: &Camera,
    faces: Faces,
    test: DepthTest,
    buffer: &mut SurfaceBuffer,
    floor: Option<&[f32]>,
    outputs: O,
    per_band: F,
) where
    O: IndexedParallelIterator,
    F: Fn(&Band<'_>, O::Item) + Sync + Send,
{
    let (width, height) = (camera.width(), camera.height());
    let bands = height.div_ceil(BAND_ROWS) as usize;
    assert_eq!(outputs.len(), bands, "one output per band of rows");
    let SurfaceBuffer {
        width: buffer_width,
        height: buffer_height,
        visibility,
        extents,
        triangles,
        clip,
        projected,
        bins,
        cleared_for,
    } = buffer;
    *buffer_width = width;
    *buffer_height = height;

    let world_to_clip = camera.world_to_clip();
    clip.resize(mesh.positions.len(), Vec4::ZERO);
    let (w, h) = (width as f32, height as f32);
    projected.resize(mesh.positions.len(), Projected::default());
    clip.par_iter_mut()
        .zip(projected.par_iter_mut())
        .zip(mesh.positions.par_iter())
        .for_each(|((c, v), p)| {
            *c = world_to_clip * p.extend(1.0);
            *v = project(*c, w, h);
        });
    triangles.set_up(mesh, clip, projected, camera, faces);

    // Bin into bands of rows, preserving triangle order within each band.
    bins.resize_with(bands, Vec::new);
    bins.iter_mut().for_each(Vec::clear);
    for (id, t) in triangles.iter() {
        for band in t.min[1] / BAND_ROWS..=t.max[1] / BAND_ROWS {
            bins[band as usize].push(id);
        }
    }

    visibility.resize((width * height) as usize, test.cleared());
    extents.resize(height as usize, EMPTY_EXTENT);
    // Outside the last frame's extents the pixels still hold the cleared value when it was
    // the same shape and test; otherwise (and once a frame panicked) every pixel is cleared.
    let clear_extents_only = cleared_for.take() == Some((width, height, test));
    let triangles = &*triangles;
    visibility
        .par_chunks_mut(band_pixels(width))
        .zip(extents.par_chunks_mut(BAND_ROWS as usize))
        .zip(bins.par_iter())
        .zip(outputs)
        .enumerate()
        .for_each(|(band, (((rows, extents), bin), output))| {
            let first_row = band as u32 * BAND_ROWS;
            if clear_extents_only {
                for (row, extent) in rows.chunks_exact_mut(width as usize).zip(&*extents) {
                    let run = span(*extent);
                    row[run.start as usize..run.end as usize].fill(test.cleared());
                }
            } else {
                rows.fill(test.cleared());
            }
            extents.fill(EMPTY_EXTENT);
            let floor = floor.map(|f| &f[(first_row * width) as usize..][..rows.len()]);
            let target = BandTarget {
                first_row,
                width,
                rows,
                extents,
            };
            rasterize_band(triangles, bin, target, test, mesh.depth, floor);
            let band = Band {
                first_row,
                width,
                visibility: rows,
                extents,
                triangles,
            };
            per_band(&band, output);
        });
    *cleared_for = Some((width, height, test));
}

/// Triangles wider than this many pixels have each row's inside run solved ([`inside_run`]);
/// narrower ones test each pixel of their bounds.
const RUN_MIN_COLUMNS: i64 = 8;

/// The pixels `i` of a row (`0 ≤ i < columns`, from the triangle's left bound) whose centres
/// are inside: `eₖ + biasₖ + stepₖ·i ≥ 0` for the three edges, where `eₖ` is edge `k` at pixel
/// 0. Each inequality is linear in `i`, so the solution is one run `first..=last` (`None`:
/// empty), solved exactly in integers: the same pixels as testing each one.
#[inline]
fn inside_run(e: [i64; 3], step: [i64; 3], bias: [i64; 3], columns: i64) -> Option<(i64, i64)> {
    let (mut first, mut last) = (0, columns - 1);
    for k in 0..3 {
        let v = e[k] + bias[k];
        let s = step[k];
        if s > 0 {
            // v + s·i ≥ 0 ⇔ i ≥ ⌈−v / s⌉ (only binding while v < 0).
            if v < 0 {
                first = first.max((-v + s - 1) / s);
            }
        } else if v < 0 {
            return None; // s ≤ 0: the edge only falls to the right
        } else if s < 0 {
            // v + s·i ≥ 0 ⇔ i ≤ ⌊v / −s⌋.
            last = last.min(v / -s);
        }
    }
    (first <= last).then_some((first, last))
}

/// The extent of a row without a covered pixel.
const EMPTY_EXTENT: [u32; 2] = [u32::MAX, 0];

/// The rows of one band being rasterised: their visibility (full width, from `first_row`) and
/// the extent of each row's covered pixels.
struct BandTarget<'r> {
    first_row: u32,
    width: u32,
    rows: &'r mut [Visibility],
    extents: &'r mut [[u32; 2]],
}

/// Scan-converts the triangles of `bin` into `target`: per pixel an edge test and, inside, a
/// depth compare; each row's extent grows to the pixels written.
fn rasterize_band(
    triangles: &TriangleStore,
    bin: &[u32],
    target: BandTarget<'_>,
    test: DepthTest,
    depth: DepthInterpolation,
    floor: Option<&[f32]>,
) {
    // One loop per depth test, peeling and depth interpolation, so that the per-pixel loop has
    // no branch on them.
    let plane = depth == DepthInterpolation::Plane;
    match (test, floor, plane) {
        (DepthTest::Nearest, None, false) => {
            scan_convert::<false, false, false>(triangles, bin, target, &[]);
        }
        (DepthTest::Furthest, None, false) => {
            scan_convert::<true, false, false>(triangles, bin, target, &[]);
        }
        (DepthTest::Nearest, None, true) => {
            scan_convert::<false, false, true>(triangles, bin, target, &[]);
        }
        (DepthTest::Furthest, None, true) => {
            scan_convert::<true, false, true>(triangles, bin, target, &[]);
        }
        (DepthTest::Nearest, Some(floor), false) => {
            scan_convert::<false, true, false>(triangles, bin, target, floor);
        }
        (DepthTest::Furthest, Some(floor), false) => {
            scan_convert::<true, true, false>(triangles, bin, target, floor);
        }
        (DepthTest::Nearest, Some(floor), true) => {
            scan_convert::<false, true, true>(triangles, bin, target, floor);
        }
        (DepthTest::Furthest, Some(floor), true) => {
            scan_convert::<true, true, true>(triangles, bin, target, floor);
        }
    }
}

/// [`rasterize_band`] for one depth test (`FURTHEST`: Greater, else Less), with or without
/// a peeling `floor` (`PEEL`; else `floor` is not read), and the depth from the triangles'
/// depth planes (`PLANE_DEPTH`: the mesh's [`DepthInterpolation::Plane`], so every triangle
/// has one) or from the exact edge functions.
fn scan_convert<const FURTHEST: bool, const PEEL: bool, const PLANE_DEPTH: bool>(
    triangles: &TriangleStore,
    bin: &[u32],
    target: BandTarget<'_>,
    floor: &[f32],
) {
    let BandTarget {
        first_row,
        width,
        rows,
        extents,
    } = target;
    let last_row = first_row + (rows.len() as u32 / width) - 1;
    for &id in bin {
        let t = triangles.get(id);
        let [a, b, c] = t.xy;
        let (tl0, tl1, tl2) = (is_top_left(b, c), is_top_left(c, a), is_top_left(a, b));
        // Edge functions step by −Δy·SUBPIXEL per pixel to the right (exact integer arithmetic).
        // A pixel centre on an edge is inside when the edge is top-left: for integers,
        // `e > 0 || (e == 0 && top_left)` is `e + bias ≥ 0` with bias −1, or 0 on a top-left
        // edge. Each row's inside pixels are one run; on wide triangles it is found from the
        // three edges at once ([`inside_run`]), so the loop below visits only them.
        let step = t.edge_steps();
        let bias = [tl0, tl1, tl2].map(|tl| i64::from(tl) - 1);
        let columns = i64::from(t.max[0] - t.min[0]) + 1;
        for y in t.min[1].max(first_row)..=t.max[1].min(last_row) {
            let e = t.edges_at(t.min[0], y);
            // Narrow triangles (dense meshes: a few pixels a row) test each pixel; solving the run
            // (three divisions) pays from about a group of eight pixels up.
            let solved = columns > RUN_MIN_COLUMNS;
            let (first, last) = if solved {
                match inside_run(e, step, bias, columns) {
                    Some(run) => run,
                    None => continue,
                }
            } else {
                (0, columns - 1)
            };
            let row = &mut rows[((y - first_row) * width) as usize..][..width as usize];
            let (mut first_written, mut last_written) = (u32::MAX, 0);
            // The depth test and write of an inside pixel with edge values `f`.
            // Set up from the same mesh as `PLANE_DEPTH`: a plane exactly when it is set.
            debug_assert_eq!(PLANE_DEPTH, t.depth_plane.is_some());
            let depth_plane = t.depth_plane.unwrap_or_default();
            let row_depth = depth_plane.row((y as i32 - t.anchor[1]) as f32);
            let mut fragment = |x: u32, f: [i64; 3]| {
                let depth = match PLANE_DEPTH {
                    true => depth_plane.at(row_depth, (x as i32 - t.anchor[0]) as f32),
                    false => t.depth_from_edges(f),
                };
                if depth > 1.0 {
                    return; // beyond the far plane (the near plane is clipped geometrically)
                }
                if PEEL && depth <= floor[((y - first_row) * width + x) as usize] {
                    return; // peeled: at or in front of the previous layer
                }
                let stored = &mut row[x as usize];
                let passes = if FURTHEST {
                    depth > stored.depth
                } else {
                    depth < stored.depth
                };
                if passes {
                    *stored = Visibility {
                        depth,
                        triangle: id,
                    };
                    first_written = first_written.min(x);
                    last_written = x;
                }
            };
            let mut e = [0, 1, 2].map(|k| e[k] + step[k] * first);
            let pixels = t.min[0] + first as u32..=t.min[0] + last as u32;
            if solved {
                // Every pixel of a solved run is inside: no edge test.
                for x in pixels {
                    fragment(x, e);
                    e = [e[0] + step[0], e[1] + step[1], e[2] + step[2]];
                }
            } else {
                for x in pixels {
                    let f = e;
                    e = [e[0] + step[0], e[1] + step[1], e[2] + step[2]];
                    // All three `e + bias ≥ 0` exactly when their bitwise OR is (no sign bit
                    // set).
                    if ((f[0] + bias[0]) | (f[1] + bias[1]) | (f[2] + bias[2])) >= 0 {
                        fragment(x, f);
                    }
                }
            }
            if first_written <= last_written {
                let extent = &mut extents[(y - first_row) as usize];
                *extent = [
                    extent[0].min(first_written),
                    extent[1].max(last_written + 1),
                ];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The pixels of a row inside by testing each one: what [`inside_run`] must find.
    fn inside_by_pixel(e: [i64; 3], step: [i64; 3], bias: [i64; 3], columns: i64) -> Vec<i64> {
        (0..columns)
            .filter(|&i| (0..3).all(|k| e[k] + bias[k] + step[k] * i >= 0))
            .collect()
    }

    proptest! {
        /// The run solved from the three edges is exactly the set of pixels each passing the
        /// edge test, whatever the signs of the steps (edges rising, falling, horizontal) and
        /// the top-left biases, including runs clipped by the row's bounds and empty rows.
        #[test]
        fn inside_run_is_the_pixels_that_pass_the_edge_tests(
            e in proptest::array::uniform3(-40_000i64..40_000),
            step in proptest::array::uniform3(-3_000i64..3_000),
            bias in proptest::array::uniform3(-1i64..=0),
            columns in 1i64..64,
        ) {
            let expected = inside_by_pixel(e, step, bias, columns);
            let run = inside_run(e, step, bias, columns);
            match run {
                None => prop_assert!(expected.is_empty(), "missed {:?}", expected),
                Some((first, last)) => {
                    prop_assert_eq!(expected, (first..=last).collect::<Vec<_>>());
                }
            }
        }
    }

    /// A screen triangle with corners `xy` (fixed point, made clockwise), its planes set up
    /// from the corners' depths, `1/w` and attributes; `None` when the corners are collinear.
    fn triangle(
        mut xy: [[i64; 2]; 3],
        inv_w: [f32; 3],
        mut attributes: [Attributes; 3],
        plane_depth: bool,
    ) -> Option<ScreenTriangle> {
        let mut inv_w = inv_w;
        let mut area = edge(xy[0], xy[1], xy[2]);
        if area == 0 {
            return None;
        }
        if area < 0 {
            xy.swap(1, 2);
            inv_w.swap(1, 2);
            attributes.swap(1, 2);
            area = -area;
        }
        let depth = [0.25, 0.5, 0.75];
        let pixel = |k: usize| (xy[0][k] / SUBPIXEL).clamp(0, 4000);
        let anchor = [pixel(0), pixel(1)];
        let l = barycentric_planes(xy, area, anchor);
        Some(ScreenTriangle {
            xy,
            inv_area: 1.0 / area as f64,
            depth,
            depth_plane: plane_depth.then(|| Plane::of(depth.map(f64::from), &l)),
            anchor: [anchor[0] as i32, anchor[1] as i32],
            planes: attribute_planes(&l, inv_w, &attributes),
            min: [0, 0],
            max: [4000, 4000],
            source: 7,
        })
    }

    /// Corner attributes from three seeds in `[-1, 1]³`.
    fn corners(seed: [[f32; 3]; 3]) -> [Attributes; 3] {
        let v = |s: [f32; 3]| Vec3::from_array(s);
        [0, 1, 2].map(|k| Attributes {
            p_ws: 10.0 * v(seed[k]),
            n_ws: v(seed[(k + 1) % 3]) + Vec3::new(0.0, 0.0, 2.0),
            scalar: 1.0 + seed[k][0],
            bary: CORNER_BARYCENTRICS[k],
        })
    }

    proptest! {
        /// Eight pixels' texels at once (any eight pixels of a row, all attributes, and only
        /// some) have the scalar function's bits: the planes evaluated with the same
        /// operations lane by lane.
        #[test]
        fn eight_texels_equal_the_scalar_ones(
            xy in proptest::array::uniform3(proptest::array::uniform2(0i64..(1 << 18))),
            inv_w in proptest::array::uniform3(0.05f32..20.0),
            seed in proptest::array::uniform3(proptest::array::uniform3(-1.0f32..1.0)),
            x0 in 0u32..1000,
            offsets in proptest::array::uniform8(0u32..24),
            y in 0u32..1000,
            plane_depth in proptest::bool::ANY,
        ) {
            let Some(t) = triangle(xy, inv_w, corners(seed), plane_depth) else { return Ok(()) };
            let x = offsets.map(|o| x0 + o);
            let all = divide_x8::<{ Attribute::ALL }>(&t.values_x8::<{ Attribute::ALL }>(&x, y), [t.source; LANES]);
            let some = divide_x8::<{ Attribute::SCALAR }>(&t.values_x8::<{ Attribute::SCALAR }>(&x, y), [t.source; LANES]);
            for (i, (lane, some)) in all.to_texels().iter().zip(some.to_texels()).enumerate() {
                let scalar = t.texel(x[i], y);
                prop_assert_eq!(format!("{lane:?}"), format!("{scalar:?}"));
                prop_assert_eq!(
                    format!("{:?}", (some.p_ws, some.n_ws, some.scalar)),
                    format!("{:?}", (scalar.p_ws, scalar.n_ws, scalar.scalar))
                );
            }
        }
    }

    proptest! {
        /// Eight lanes on eight triangles (the gathered path, and the paths of two or three
        /// triangles when seeds repeat) have the scalar texels' bits.
        #[test]
        fn texels_of_eight_triangles_equal_the_scalar_ones(
            xy in proptest::array::uniform8(proptest::array::uniform3(proptest::array::uniform2(0i64..(1 << 18)))),
            inv_w in proptest::array::uniform3(0.05f32..20.0),
            seed in proptest::array::uniform3(proptest::array::uniform3(-1.0f32..1.0)),
            pick in proptest::array::uniform8(0usize..8),
            x0 in 0u32..1000,
            offsets in proptest::array::uniform8(0u32..24),
            y in 0u32..1000,
            plane_depth in proptest::array::uniform8(proptest::bool::ANY),
        ) {
            let fallback = [[0, 0], [1 << 12, 0], [0, 1 << 12]];
            let all: [ScreenTriangle; LANES] = core::array::from_fn(|i| {
                triangle(xy[i], inv_w, corners(seed), plane_depth[i])
                    .or_else(|| triangle(fallback, inv_w, corners(seed), plane_depth[i]))
                    .expect("a triangle")
            });
            let triangles: [&ScreenTriangle; LANES] = core::array::from_fn(|i| &all[pick[i]]);
            let x = offsets.map(|o| x0 + o);
            let lanes = texel_lanes::<{ Attribute::ALL }>(triangles, &x, y).to_texels();
            for (i, lane) in lanes.iter().enumerate() {
                let scalar = triangles[i].texel(x[i], y);
                prop_assert_eq!(format!("{lane:?}"), format!("{scalar:?}"));
            }
        }
    }

    proptest! {
        /// The planes interpolate perspective-correctly: at pixels inside a triangle, the
        /// texel's position, scalar, barycentrics and depth agree with the interpolation
        /// written out in `f64` from the exact edge functions (`λₖ = eₖ/area`, weights
        /// `λₖ/wₖ` normalised; depth `Σ λₖ·depthₖ`) to a few `f32` roundings of the
        /// attributes' scale.
        #[test]
        fn planes_interpolate_perspective_correctly(
            xy in proptest::array::uniform3(proptest::array::uniform2(0i64..(1 << 18))),
            inv_w in proptest::array::uniform3(0.2f32..5.0),
            seed in proptest::array::uniform3(proptest::array::uniform3(-1.0f32..1.0)),
            at in proptest::array::uniform3(0.0f64..1.0),
            plane_depth in proptest::bool::ANY,
        ) {
            let attributes = corners(seed);
            let Some(t) = triangle(xy, inv_w, attributes, plane_depth) else { return Ok(()) };
            // The pixel holding the point with barycentrics `at` (normalised).
            let sum = at.iter().sum::<f64>().max(1e-9);
            let point = |k: usize| (0..3).map(|i| at[i] / sum * t.xy[i][k] as f64).sum::<f64>();
            let (x, y) = ((point(0) / SUBPIXEL as f64) as u32, (point(1) / SUBPIXEL as f64) as u32);
            let area = edge(t.xy[0], t.xy[1], t.xy[2]) as f64;
            let e = t.edges_at(x, y).map(|e| e as f64 / area);
            if e.iter().any(|&l| l < 0.0) {
                return Ok(()); // rounded to a pixel centre outside a thin triangle
            }
            // The inputs in the triangle's (clockwise) corner order, as `triangle` swaps them.
            let mut order = [0, 1, 2];
            if edge(xy[0], xy[1], xy[2]) < 0 {
                order.swap(1, 2);
            }
            let iw = order.map(|k| f64::from(inv_w[k]));
            let a = order.map(|k| attributes[k]);
            let pw = [0, 1, 2].map(|k| e[k] * iw[k]);
            let den: f64 = pw.iter().sum();
            let lerp = |f: &dyn Fn(&Attributes) -> f64| {
                (0..3).map(|k| pw[k] * f(&a[k])).sum::<f64>() / den
            };
            // The rounding error of a plane's evaluation: a few `f32` roundings of its terms'
            // magnitudes (the coefficients' rounding, the two products and sums).
            let (dx, dy) = t.offsets(x, y);
            let bound = |p: Plane| {
                4.0 * f64::from(f32::EPSILON / 2.0)
                    * f64::from(p.at_anchor.abs() + (p.dy * dy).abs() + (p.dx * dx).abs())
            };
            let planes = t.planes;
            // A quotient of planes (an attribute over `w` by `1/w`).
            let check = |value: f32, over_w: Plane, exact: f64| {
                let error = (f64::from(value) - exact).abs();
                let tolerance = (bound(over_w) + exact.abs() * bound(planes.inv_w)) / den
                    + 2.0 * f64::from(f32::EPSILON) * exact.abs()
                    + 1e-12;
                (error <= tolerance, format!("{value} vs {exact}: {error:e} > {tolerance:e}"))
            };
            let texel = t.texel(x, y);
            for (value, plane, exact) in [
                (texel.p_ws.x, planes.p_ws[0], lerp(&|a| f64::from(a.p_ws.x))),
                (texel.p_ws.z, planes.p_ws[2], lerp(&|a| f64::from(a.p_ws.z))),
                (texel.scalar, planes.scalar, lerp(&|a| f64::from(a.scalar))),
                (texel.barycentrics.y, planes.bary[1], lerp(&|a| f64::from(a.bary.y))),
            ] {
                let (ok, message) = check(value, plane, exact);
                prop_assert!(ok, "{}", message);
            }
            let depth: f64 = (0..3).map(|k| e[k] * [0.25, 0.5, 0.75][k]).sum();
            let error = (f64::from(texel.depth) - depth).abs();
            // The depth from the exact barycentrics (three roundings of values below 1), or from
            // its plane.
            let tolerance = match plane_depth {
                true => bound(t.depth_plane.expect("a depth plane")) + 1e-12,
                false => 4e-7,
            };
            prop_assert!(error <= tolerance, "depth {} vs {depth}", texel.depth);
        }
    }

    /// The depth the scan conversion stored at each covered pixel is the texel's depth, bit for
    /// bit, with either depth interpolation, for the nearest and the furthest surface; and the
    /// two interpolations agree to a few `f32` roundings.
    #[test]
    fn stored_depth_is_the_texel_depth() {
        let mesh = refract_geometry::shapes::uv_sphere(24, 12, 1.0).expect("sphere");
        let camera = Camera::new(refract_core::CameraDesc {
            width: 96,
            height: 80,
            ..refract_core::CameraDesc::default()
        })
        .expect("camera");
        let mut depths: [Vec<f32>; 2] = [Vec::new(), Vec::new()];
        for (k, depth) in [DepthInterpolation::Exact, DepthInterpolation::Plane]
            .into_iter()
            .enumerate()
        {
            for test in [DepthTest::Nearest, DepthTest::Furthest] {
                let raster = RasterMesh::new(&mesh).with_depth(depth);
                let mut buffer = SurfaceBuffer::new();
                let bands = 80u32.div_ceil(BAND_ROWS) as usize;
                let checked = std::sync::atomic::AtomicUsize::new(0);
                rasterize_bands(
                    &raster,
                    &camera,
                    Faces::Both,
                    test,
                    &mut buffer,
                    rayon::iter::repeat_n((), bands),
                    |band, ()| {
                        for y in band.first_row..band.first_row + band.rows() {
                            for x in 0..band.width() {
                                if let Some(stored) = band.depth(x, y) {
                                    let texel = band.texel(x, y).expect("covered");
                                    assert_eq!(
                                        stored.to_bits(),
                                        texel.depth.to_bits(),
                                        "({x}, {y})"
                                    );
                                    checked.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                                }
                            }
                        }
                    },
                );
                assert!(checked.into_inner() > 1000);
                if test == DepthTest::Nearest {
                    depths[k] = (0..96 * 80)
                        .filter_map(|i| buffer.texel(i).map(|t| t.depth))
                        .collect();
                }
            }
        }
        assert_eq!(depths[0].len(), depths[1].len());
        for (exact, plane) in depths[0].iter().zip(&depths[1]) {
            assert!((exact - plane).abs() <= 1e-6, "{exact} vs {plane}");
        }
    }

    /// Steps of zero (an edge parallel to the rows) keep or drop the whole row.
    #[test]
    fn a_horizontal_edge_keeps_or_drops_the_row() {
        assert_eq!(
            inside_run([0, 5, 5], [0, 1, -1], [0, 0, 0], 4),
            Some((0, 3))
        );
        assert_eq!(inside_run([0, 5, 5], [0, 1, -1], [-1, 0, 0], 4), None);
    }
}
