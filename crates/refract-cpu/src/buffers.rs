//! The per-frame image-space buffers of Wyman 2005a §4: the front faces (P1, N1, d_N) and
//! the back faces (normal and distance of the furthest or second surface).

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use refract_core::kernel::{BackFaceLanes, BackFaceSample, BackFaceSampler};
use refract_core::lanes::{F32x8, LANES, Mask, Vec2x8, Vec3x8};
use refract_core::real::Vector3;
use refract_core::{BackSurface, Camera};
use refract_scene::Refractor;

use crate::pixel_group::PixelGroup;
use crate::raster::{
    Band, DepthInterpolation, DepthTest, Faces, RasterMesh, SurfaceBuffer, band_pixels, rasterize,
    rasterize_bands, rasterize_into,
};

/// The refractor's mesh with its `d_N` as the interpolated scalar, its depth as a plane (the
/// image-space buffers' depth only decides visibility).
pub(crate) fn raster_mesh(refractor: &Refractor) -> RasterMesh<'_> {
    RasterMesh::with_scalars(refractor.mesh(), refractor.d_n())
        .with_depth(DepthInterpolation::Plane)
}

/// The nearest front faces: `P1`, `N1` and interpolated `d_N` per pixel.
pub fn front_faces(refractor: &Refractor, camera: &Camera) -> SurfaceBuffer {
    rasterize(
        &raster_mesh(refractor),
        camera,
        Faces::Front,
        DepthTest::Nearest,
    )
}

/// The back-face buffer (Wyman 2005a §3.2, "BackfaceNormals" and "BackfaceZBuf"): the
/// rasterised back faces, resolved right after each band is rasterised into what the kernel
/// reads, the outward normal and the distance from the eye (16 bytes a pixel).
#[derive(Clone, Debug, Default)]
pub struct BackFaces {
    buffer: SurfaceBuffer,
    resolved: Vec<BackTexel>,
}

/// One resolved back-face texel; a negative distance marks an empty pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
struct BackTexel {
    n_ws: Vec3,
    distance: f32,
}

impl BackTexel {
    const EMPTY: Self = Self {
        n_ws: Vec3::ZERO,
        distance: -1.0,
    };
}

impl BackFaces {
    /// Rasterises the back faces into this buffer's memory: the furthest (depth Greater) or the
    /// second surface (the nearest back face, depth Less), Wyman 2005a §3.2.
    pub fn render_into(&mut self, refractor: &Refractor, camera: &Camera, surface: BackSurface) {
        let test = match surface {
            BackSurface::Furthest => DepthTest::Furthest,
            BackSurface::Second => DepthTest::Nearest,
        };
        let eye = camera.eye();
        let width = camera.width();
        self.resolved
            .resize((width * camera.height()) as usize, BackTexel::EMPTY);
        rasterize_bands(
            &raster_mesh(refractor),
            camera,
            Faces::Back,
            test,
            &mut self.buffer,
            self.resolved.par_chunks_mut(band_pixels(width)),
            |band, resolved| {
                for (row, resolved) in resolved.chunks_exact_mut(width as usize).enumerate() {
                    resolve_row(band, band.first_row + row as u32, eye, resolved);
                }
            },
        );
    }

    /// The underlying buffer.
    pub fn buffer(&self) -> &SurfaceBuffer {
        &self.buffer
    }
}

/// Resolves row `y` of a band of back faces into normals and distances from `eye`; covered
/// pixels are resolved eight at a time (the distance `‖p − eye‖` on lanes, glam's operations),
/// and only the row's covered span is visited.
/// Texels outside the span are not written: [`BackFaces::back_face`] never reads them.
fn resolve_row(band: &Band<'_>, y: u32, eye: Vec3, resolved: &mut [BackTexel]) {
    let span = band.covered_span(y);
    let eye = Vec3x8::splat(eye);
    let resolve = |group: &PixelGroup, resolved: &mut [BackTexel]| {
        let texels = band.attribute_lanes::<0>(&group.x, y);
        let distance = (texels.p_ws - eye).length().to_array();
        let n_ws = texels.n_ws.to_lanes();
        for i in 0..group.len {
            resolved[group.x[i] as usize] = BackTexel {
                n_ws: n_ws[i],
                distance: distance[i],
            };
        }
    };
    let mut group = PixelGroup::new();
    for x in span {
        if !band.is_covered(x, y) {
            resolved[x as usize] = BackTexel::EMPTY;
        } else if group.push(x) {
            resolve(&group, resolved);
            group.len = 0;
        }
    }
    if group.len > 0 {
        group.pad();
        resolve(&group, resolved);
    }
}

impl BackFaceSampler for BackFaces {
    /// Nearest-texel lookup (no filtering across the silhouette; empty texels stay empty).
    #[inline]
    fn back_face(&self, uv_px: Vec2) -> Option<BackFaceSample> {
        let (w, h) = (self.buffer.width as f32, self.buffer.height as f32);
        if !(uv_px.x >= 0.0 && uv_px.y >= 0.0 && uv_px.x < w && uv_px.y < h) {
            return None;
        }
        let (x, y) = (uv_px.x as u32, uv_px.y as u32);
        // Outside the row's covered span the resolved texels are stale: the pixel is empty.
        if !self.buffer.covered_span(y).contains(&x) {
            return None;
        }
        let texel = self.resolved[(y * self.buffer.width + x) as usize];
        (texel.distance >= 0.0).then_some(BackFaceSample {
            n_ws: texel.n_ws,
            distance: texel.distance,
        })
    }

    /// [`Self::back_face`] on eight lanes: the bounds tested and the pixel indices computed on
    /// lanes, then each lane's row extent checked and its texel loaded (inlined into the
    /// kernel: a call would make it spill its live lanes around each lookup).
    #[inline(always)]
    fn back_faces_x8(&self, uv_px: Vec2x8, active: Mask) -> BackFaceLanes {
        let (w, h) = (self.buffer.width, self.buffer.height);
        let zero = F32x8::ZERO;
        let inside = active
            & uv_px.x.simd_ge(zero)
            & uv_px.y.simd_ge(zero)
            & uv_px.x.simd_lt(F32x8::splat(w as f32))
            & uv_px.y.simd_lt(F32x8::splat(h as f32));
        let bits = inside.to_bitmask();
        let mut texels = [BackTexel::EMPTY; LANES];
        if bits != 0 {
            // Inside the image the truncation is `as u32`'s.
            let (x, y) = (
                uv_px.x.trunc_int().to_array(),
                uv_px.y.trunc_int().to_array(),
            );
            for (i, texel) in texels.iter_mut().enumerate() {
                let (x, y) = (x[i] as u32, y[i] as u32);
                if bits & (1 << i) != 0 && self.buffer.covered_span(y).contains(&x) {
                    *texel = self.resolved[(y * w + x) as usize];
                }
            }
        }
        let (mut n_ws, mut distance) = ([Vec3::ZERO; LANES], [0.0; LANES]);
        for (i, texel) in texels.iter().enumerate() {
            (n_ws[i], distance[i]) = (texel.n_ws, texel.distance);
        }
        let distance = F32x8::new(distance);
        BackFaceLanes {
            n_ws: Vec3x8::from_lanes(&n_ws),
            distance,
            found: distance.simd_ge(zero),
        }
    }
}

/// [`front_faces`] into an existing buffer, reusing its memory.
pub fn front_faces_into(refractor: &Refractor, camera: &Camera, buffer: &mut SurfaceBuffer) {
    rasterize_into(
        &raster_mesh(refractor),
        camera,
        Faces::Front,
        DepthTest::Nearest,
        buffer,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use refract_core::CameraDesc;
    use refract_geometry::shapes::uv_sphere;

    /// The lane lookups are the scalar ones lane by lane: inside and outside the silhouette,
    /// off the image, on pixel edges, NaN, and lanes left inactive.
    #[test]
    fn eight_lane_lookups_equal_the_scalar_lookups() {
        let refractor = Refractor::new(uv_sphere(24, 12, 1.0).expect("sphere"), 1.5).expect("ok");
        let desc = CameraDesc {
            width: 61,
            height: 47,
            ..CameraDesc::default()
        };
        let camera = Camera::new(desc).expect("camera");
        // First a closer view, so that texels outside this frame's row extents hold stale
        // samples the lookups must not return.
        let closer = Camera::new(CameraDesc {
            eye: desc.eye * 0.5,
            ..desc
        })
        .expect("camera");
        let mut back = BackFaces::default();
        back.render_into(&refractor, &closer, BackSurface::Furthest);
        back.render_into(&refractor, &camera, BackSurface::Furthest);
        // A golden-ratio walk over [−8, 69) × [−8, 55) hits every case many times.
        let position = |k: usize| {
            let (a, b) = (0.618_034 * k as f32, 0.754_877_7 * k as f32);
            Vec2::new(77.0 * a.fract() - 8.0, 63.0 * b.fract() - 8.0)
        };
        let specials = [
            Vec2::new(f32::NAN, 3.0),
            Vec2::new(30.0, f32::NAN),
            Vec2::new(61.0, 20.0),
            Vec2::new(30.0, 47.0),
            Vec2::new(-0.0, 0.0),
            Vec2::new(30.0, 23.0),
            Vec2::new(30.999_998, 23.5),
            Vec2::new(f32::INFINITY, 1.0),
        ];
        let (mut found, mut missed) = (0, 0);
        for group in 0..600 {
            let uv: [Vec2; LANES] = if group == 0 {
                specials
            } else {
                core::array::from_fn(|i| position(group * LANES + i))
            };
            let active: [bool; LANES] = core::array::from_fn(|i| (group + i) % 5 != 0);
            let lanes = back.back_faces_x8(
                Vec2x8::from_lanes(&uv),
                refract_core::lanes::mask_from_lanes(active),
            );
            let (n, d) = (lanes.n_ws.to_lanes(), lanes.distance.to_array());
            let hit = refract_core::lanes::mask_lanes(lanes.found);
            for i in 0..LANES {
                let scalar = active[i].then(|| back.back_face(uv[i])).flatten();
                assert_eq!(hit[i], scalar.is_some(), "lane {i} at {}", uv[i]);
                if let Some(s) = scalar {
                    assert_eq!((n[i], d[i]), (s.n_ws, s.distance), "at {}", uv[i]);
                    found += 1;
                } else {
                    missed += 1;
                }
            }
        }
        assert!(found > 500 && missed > 500, "{found} found, {missed} not");
    }
}
