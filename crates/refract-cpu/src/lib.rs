//! # refract-cpu
//!
//! The CPU backend: it produces the same image-space buffers a GPU rasteriser produces
//! ([`raster`]: a visibility-buffer rasteriser with pixel centres, the top-left rule,
//! perspective-correct interpolation, near-plane clipping, parallel deterministic bands of
//! rows), then runs refract-core's kernels for the methods `single`, `wyman`, `wyman-dv` and
//! `wyman-dn` (Wyman 2005a) eight pixels at a time with their bit-identical lane twins
//! ([`render`]: [`CpuRenderer`] shades each band of rows right after rasterising it).

pub mod buffers;
mod pixel_group;
pub mod raster;
pub mod render;
mod shade;

pub use buffers::{BackFaces, PreparedRefractor, front_faces, front_faces_into};
pub use raster::{
    BAND_ROWS, Band, DepthTest, Faces, SurfaceBuffer, Texel, band_pixels, rasterize,
    rasterize_bands, rasterize_into,
};
pub use render::{
    CpuError, CpuRenderer, FrameBuffers, FrameOutputs, MethodAov, MethodFrame, MethodParams,
    render_buffers, render_buffers_into, render_method, shade, shade_into,
};
