//! The per-frame image-space buffers of Wyman 2005a §4: the front faces (P1, N1, d_N) and
//! the back faces (normal and distance of the furthest or second surface).

use glam::{Vec2, Vec3};
use refract_core::kernel::{BackFaceSample, BackFaceSampler};
use refract_core::{BackSurface, Camera};
use refract_geometry::Mesh;

use crate::raster::{DepthTest, Faces, RasterMesh, SurfaceBuffer, rasterize};

/// A refractor prepared for the CPU backend: its mesh and per-vertex `d_N`.
pub struct PreparedRefractor<'a> {
    /// The mesh.
    pub mesh: &'a Mesh,
    /// `d_N` per vertex (Wyman 2005a §3.1).
    pub d_n: &'a [f32],
}

impl PreparedRefractor<'_> {
    fn raster_mesh(&self) -> RasterMesh<'_> {
        RasterMesh {
            positions: &self.mesh.positions,
            normals: &self.mesh.normals,
            scalars: self.d_n,
            triangles: &self.mesh.triangles,
        }
    }
}

/// The nearest front faces: `P1`, `N1` and interpolated `d_N` per pixel.
pub fn front_faces(refractor: &PreparedRefractor<'_>, camera: &Camera) -> SurfaceBuffer {
    rasterize(
        &refractor.raster_mesh(),
        camera,
        Faces::Front,
        DepthTest::Nearest,
    )
}

/// The back-face buffer read through [`BackFaceSampler`] at the nearest texel.
pub struct BackFaces {
    buffer: SurfaceBuffer,
    eye: Vec3,
}

impl BackFaces {
    /// Rasterises the back faces: the furthest (depth Greater) or the second surface (the
    /// nearest back face, depth Less), Wyman 2005a §3.2.
    pub fn render(
        refractor: &PreparedRefractor<'_>,
        camera: &Camera,
        surface: BackSurface,
    ) -> Self {
        let test = match surface {
            BackSurface::Furthest => DepthTest::Furthest,
            BackSurface::Second => DepthTest::Nearest,
        };
        let buffer = rasterize(&refractor.raster_mesh(), camera, Faces::Back, test);
        Self {
            buffer,
            eye: camera.eye(),
        }
    }

    /// The underlying buffer.
    pub fn buffer(&self) -> &SurfaceBuffer {
        &self.buffer
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
        let i = uv_px.y as usize * self.buffer.width as usize + uv_px.x as usize;
        self.buffer.covered[i].then(|| BackFaceSample {
            n_ws: self.buffer.n_ws[i],
            distance: (self.buffer.p_ws[i] - self.eye).length(),
        })
    }
}
