//! One triangle after set-up: its integer edge functions on the sub-pixel grid, the top-left
//! rule, its window depth and its attributes as planes in screen space (`1/w` and each attribute
//! over `w`), evaluated at a pixel or eight pixels of a row.

use glam::{Vec3, Vec4};
use refract_core::lanes::{F32x8, LANES, Mask, Vec3x8};
use refract_core::real::Vector3;

use super::{Attribute, SUBPIXEL, Texel};

/// The barycentric weights of a triangle's three vertices.
pub(super) const CORNER_BARYCENTRICS: [Vec3; 3] = [Vec3::X, Vec3::Y, Vec3::Z];

/// A vertex after projection, with the attributes to interpolate.
#[derive(Clone, Copy, Debug)]
pub(super) struct ClipVertex {
    pub(super) clip: Vec4,
    pub(super) p_ws: Vec3,
    pub(super) n_ws: Vec3,
    pub(super) scalar: f32,
    /// Barycentric weights in the mesh triangle (a unit vector at its vertices).
    pub(super) bary: Vec3,
}

impl ClipVertex {
    pub(super) fn lerp(self, other: Self, t: f32) -> Self {
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
pub(super) struct Attributes {
    pub(super) p_ws: Vec3,
    pub(super) n_ws: Vec3,
    pub(super) scalar: f32,
    /// Barycentric weights of the corner in the mesh triangle.
    pub(super) bary: Vec3,
}

/// A per-pixel quantity of a triangle as an affine function of the pixel centre: its value at
/// the centre of the triangle's anchor pixel and what it gains per pixel to the right (`dx`)
/// and per row down (`dy`). Set up in `f64` and rounded once; evaluated in `f32` as
/// `(at_anchor + dy·Δy) + dx·Δx`, one row value shared by the row's pixels, the same
/// operations in the scalar and the eight-lane paths.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Plane {
    pub(super) at_anchor: f32,
    pub(super) dx: f32,
    pub(super) dy: f32,
}

impl Plane {
    /// `Σₖ vₖ·λₖ` over the corners' values `v` and the barycentric planes `l` (`f64`).
    pub(super) fn of(v: [f64; 3], l: &[[f64; 3]; 3]) -> Self {
        let sum = |i: usize| v[0] * l[0][i] + v[1] * l[1][i] + v[2] * l[2][i];
        Self {
            at_anchor: sum(0) as f32,
            dx: sum(1) as f32,
            dy: sum(2) as f32,
        }
    }

    /// The value at the anchor's column of the row `dy` rows below the anchor.
    #[inline(always)]
    pub(super) fn row(self, dy: f32) -> f32 {
        self.at_anchor + self.dy * dy
    }

    /// The value `dx` pixels right of the anchor's column, from the row's value.
    #[inline(always)]
    pub(super) fn at(self, row: f32, dx: f32) -> f32 {
        row + self.dx * dx
    }

    /// [`Self::at`] on eight lanes: each lane `row + dx·Δxᵢ`, the same bits.
    #[inline(always)]
    pub(super) fn at_x8(self, row: f32, dx: F32x8) -> F32x8 {
        F32x8::splat(row) + F32x8::splat(self.dx) * dx
    }
}

/// A triangle's attributes as [`Plane`]s for perspective-correct interpolation: `1/w` and each
/// attribute over `w` (`a/w` is affine in screen space), so that a pixel's attribute is
/// `(a/w)(x, y) / (1/w)(x, y)`: one division per pixel, whatever the number of attributes.
/// (The window depth is a separate, optional plane: see [`ScreenTriangle::depth_at`].)
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct AttributePlanes {
    pub(super) inv_w: Plane,
    pub(super) p_ws: [Plane; 3],
    /// The normal over `w`; normalised without the division, which only scales it.
    pub(super) n_ws: [Plane; 3],
    pub(super) scalar: Plane,
    pub(super) bary: [Plane; 3],
}

/// A triangle set up for scan conversion: fixed-point screen positions (`y` down) for the
/// coverage test and the depth, and its attributes as planes about an anchor pixel.
#[derive(Clone, Copy, Debug)]
pub(super) struct ScreenTriangle {
    /// Fixed-point pixel coordinates of the corners, in clockwise-on-screen order.
    pub(super) xy: [[i64; 2]; 3],
    /// `1 / (twice the area in fixed point)`.
    pub(super) inv_area: f64,
    /// Window depth of each corner.
    pub(super) depth: [f32; 3],
    /// The window depth as a plane, for a mesh with [`DepthInterpolation::Plane`].
    pub(super) depth_plane: Option<Plane>,
    /// The pixel the planes are set up about: the one holding the corners' centroid,
    /// clamped to the bounds (near every pixel the triangle covers, so that the planes are
    /// evaluated without large cancellations).
    pub(super) anchor: [i32; 2],
    pub(super) planes: AttributePlanes,
    /// Pixel bounds, inclusive.
    pub(super) min: [u32; 2],
    pub(super) max: [u32; 2],
    /// The mesh triangle it was set up from (clipped pieces share it).
    pub(super) source: u32,
}

pub(super) fn edge(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// Top-left rule for clockwise-on-screen (y down) triangles: a pixel centre exactly on an edge
/// belongs to the triangle if the edge is a top edge (horizontal, going right) or a left edge
/// (going up), so that pixels on a shared edge are drawn exactly once.
pub(super) fn is_top_left(a: [i64; 2], b: [i64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    (dy == 0 && dx > 0) || dy < 0
}

/// The fixed-point position of the centre of pixel `(x, y)`.
#[inline]
pub(super) fn pixel_center_fixed(x: u32, y: u32) -> [i64; 2] {
    [
        i64::from(x) * SUBPIXEL + SUBPIXEL / 2,
        i64::from(y) * SUBPIXEL + SUBPIXEL / 2,
    ]
}

/// A triangle's quantities at pixel centres, before the perspective division (position,
/// normal, scalar and barycentrics over `w`).
#[derive(Clone, Copy, Debug)]
pub(super) struct PlaneValues {
    pub(super) depth: f32,
    pub(super) inv_w: f32,
    pub(super) p_ws: Vec3,
    pub(super) n_ws: Vec3,
    pub(super) scalar: f32,
    pub(super) bary: Vec3,
}

/// [`PlaneValues`] of eight pixels, as lanes; the attributes not asked for are zero.
#[derive(Clone, Copy, Debug)]
pub(super) struct PlaneValuesX8 {
    pub(super) depth: F32x8,
    pub(super) inv_w: F32x8,
    pub(super) p_ws: Vec3x8,
    pub(super) n_ws: Vec3x8,
    pub(super) scalar: F32x8,
    pub(super) bary: Vec3x8,
}

impl PlaneValuesX8 {
    /// `a`'s lanes where `take_a` is set, `b`'s elsewhere.
    #[inline(always)]
    pub(super) fn select(take_a: Mask, a: &Self, b: &Self) -> Self {
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
    pub(super) fn offsets(&self, x: u32, y: u32) -> (f32, f32) {
        (
            (x as i32 - self.anchor[0]) as f32,
            (y as i32 - self.anchor[1]) as f32,
        )
    }

    /// The three edge functions at the centre of pixel `(x, y)` (exact integers).
    #[inline]
    pub(super) fn edges_at(&self, x: u32, y: u32) -> [i64; 3] {
        let [a, b, c] = self.xy;
        let q = pixel_center_fixed(x, y);
        [edge(b, c, q), edge(c, a, q), edge(a, b, q)]
    }

    /// What each edge function gains from one pixel to the next on its right: `−Δy·SUBPIXEL`.
    #[inline]
    pub(super) fn edge_steps(&self) -> [i64; 3] {
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
    pub(super) fn depth_at(&self, x: u32, y: u32) -> f32 {
        if let Some(plane) = self.depth_plane {
            let (dx, dy) = self.offsets(x, y);
            return plane.at(plane.row(dy), dx);
        }
        self.depth_from_edges(self.edges_at(x, y))
    }

    /// [`Self::depth_at`] from the edge functions `e` at the pixel.
    #[inline]
    pub(super) fn depth_from_edges(&self, e: [i64; 3]) -> f32 {
        let l = |e: i64| (e as f64 * self.inv_area) as f32;
        l(e[0]) * self.depth[0] + l(e[1]) * self.depth[1] + l(e[2]) * self.depth[2]
    }

    /// Every quantity at the centre of pixel `(x, y)`, before the perspective division.
    #[inline]
    pub(super) fn values(&self, x: u32, y: u32) -> PlaneValues {
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
    pub(super) fn values_x8<const ATTRIBUTES: u8>(
        &self,
        x: &[u32; LANES],
        y: u32,
    ) -> PlaneValuesX8 {
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
    pub(super) fn texel(&self, x: u32, y: u32) -> Texel {
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
