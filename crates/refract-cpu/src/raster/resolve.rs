//! Resolving the surviving fragments: the attributes a caller names ([`Attribute`]), interpolated
//! from their triangles' planes eight pixels at a time ([`TexelLanes`]), planes gathered lane by
//! lane where a group covers more than three triangles.

use glam::Vec3;
use refract_core::lanes::{F32x8, LANES, Vec3x8, mask_from_lanes};
use refract_core::real::Vector3;

use super::setup::TriangleStore;
use super::triangle::{AttributePlanes, Plane, PlaneValuesX8, ScreenTriangle};
use super::{Attribute, EMPTY, Texel, Visibility};

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
pub(super) fn texel_lanes<const ATTRIBUTES: u8>(
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
pub(super) fn gathered(
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
pub(super) fn divide_x8<const ATTRIBUTES: u8>(
    v: &PlaneValuesX8,
    source: [u32; LANES],
) -> TexelLanes {
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
pub(super) fn row_texel_lanes<const ATTRIBUTES: u8>(
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
pub(super) fn gather_triangles<'t>(
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
