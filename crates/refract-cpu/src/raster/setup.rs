//! From mesh triangles to set-up triangles: near-plane clipping, projection to the sub-pixel
//! grid, culling, the attribute planes (set up in `f64`), and the store of a frame's set-up
//! triangles in chunks.

use glam::{Vec3, Vec4, Vec4Swizzles};
use rayon::prelude::*;
use refract_core::Camera;

use super::triangle::{
    AttributePlanes, Attributes, CORNER_BARYCENTRICS, ClipVertex, Plane, ScreenTriangle, edge,
};
use super::{CHUNK_SLOTS, CHUNK_TRIANGLES, DepthInterpolation, Faces, RasterMesh, SUBPIXEL};

/// Clips a triangle against the near plane `z_clip ≥ 0` (Sutherland–Hodgman): 0, 3 or 4
/// vertices, attributes interpolated linearly in clip space.
pub(super) fn clip_near(v: [ClipVertex; 3], out: &mut Vec<ClipVertex>) {
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
pub(super) struct Projected {
    /// Fixed-point pixel coordinates (`y` down).
    pub(super) xy: [i64; 2],
    /// Window depth.
    pub(super) depth: f32,
    /// `1/w`.
    pub(super) inv_w: f32,
    /// The pixel coordinates are finite.
    pub(super) finite: bool,
    /// In front of the near plane (`z_clip ≥ 0`): triangles with all three vertices in front
    /// need no clipping.
    pub(super) in_front: bool,
}

/// The viewport transform of one clip-space vertex, snapped to the sub-pixel grid.
#[inline]
pub(super) fn project(c: Vec4, width: f32, height: f32) -> Projected {
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
pub(super) fn setup(
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
pub(super) fn barycentric_planes(xy: [[i64; 2]; 3], area: i64, anchor: [i64; 2]) -> [[f64; 3]; 3] {
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
pub(super) fn attribute_planes(
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
pub(super) struct TriangleStore {
    pub(super) chunks: Vec<Vec<ScreenTriangle>>,
}

impl TriangleStore {
    #[inline]
    pub(super) fn get(&self, id: u32) -> &ScreenTriangle {
        &self.chunks[(id / CHUNK_SLOTS) as usize][(id % CHUNK_SLOTS) as usize]
    }

    /// Projects, clips and sets up every triangle of `mesh`, in parallel, keeping index order.
    pub(super) fn set_up(
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
    pub(super) fn iter(&self) -> impl Iterator<Item = (u32, &ScreenTriangle)> {
        self.chunks.iter().enumerate().flat_map(|(c, chunk)| {
            chunk
                .iter()
                .enumerate()
                .map(move |(i, t)| (c as u32 * CHUNK_SLOTS + i as u32, t))
        })
    }
}
