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
//!
//! The stages, one module each, in the order a frame runs them: `setup` (near-plane clipping,
//! projection to the sub-pixel grid, culling, the triangle store), `triangle` (one set-up
//! triangle: edge functions, the top-left rule, its planes), `scan` (the entry points, bands in
//! parallel, scan conversion and the depth test), `buffer` ([`SurfaceBuffer`] and its
//! [`Band`]s), `resolve` (the surviving fragments' attributes, eight pixels at a time).

use glam::Vec3;
use refract_geometry::Mesh;

mod buffer;
mod resolve;
mod scan;
mod setup;
mod triangle;

pub use buffer::{Band, SurfaceBuffer, band_pixels};
pub use resolve::TexelLanes;
pub(crate) use resolve::at_most_three;
pub use scan::{rasterize, rasterize_bands, rasterize_into, rasterize_peel_into};

/// Depth peeling keeps surfaces farther from the reference point (a cube map's centre, the
/// eye) than the previous layer by this relative margin: the distance maps' layers and
/// `depth-peel`'s.
pub const PEEL_MARGIN: f32 = 1e-3;

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

#[cfg(test)]
mod tests {
    use refract_core::Camera;
    use refract_core::lanes::LANES;

    use super::resolve::{divide_x8, texel_lanes};
    use super::scan::inside_run;
    use super::setup::{attribute_planes, barycentric_planes};
    use super::triangle::{Attributes, CORNER_BARYCENTRICS, Plane, ScreenTriangle, edge};
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
