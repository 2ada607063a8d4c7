//! # refract-cpu
//!
//! The CPU backend: it produces the same image-space buffers a GPU rasteriser produces
//! ([`raster`]: a visibility-buffer rasteriser of any mesh from any camera, with pixel centres,
//! the top-left rule, perspective-correct interpolation, near-plane clipping, parallel
//! deterministic bands of rows), then runs refract-core's kernels eight pixels at a time with
//! their bit-identical lane twins. [`CpuRenderer`] is the backend behind
//! [`refract_scene::Renderer`]; one module per method family:
//!
//! * [`image_space`]: Wyman 2005a, `single`, `wyman`, `wyman-dv`, `wyman-dn` (each band of
//!   rows shaded right after it is rasterised).
//! * [`nearby_geometry`]: Wyman 2005b, `kay-greenberg`, `ray-plane`, `iterative`,
//!   `iterative-seeded` (the NG texture of the opaque objects, then the lookups per pixel).
//! * [`distance_map`]: Umenhoffer et al. 2007, `distance-map` (layered distance cube maps
//!   rebuilt per frame, then a path per pixel that sees a specular surface).
//!
//! [`surfaces`] rasterises any mesh of the scene from any camera (cube-map faces included) with
//! its uv and object id.

pub mod buffers;
pub mod families;
pub mod family;
pub mod instruction_set;
pub mod object_surfaces;
mod pixel_group;
mod prefetch;
pub mod raster;
pub mod renderer;
pub mod scene_meshes;
pub mod screen_pyramid;
mod shade;
pub mod surfaces;

pub use buffers::{BackFaces, front_faces, front_faces_into};
pub use families::{distance_map, image_space, nearby_geometry, pvrr};
pub use family::{CpuFamily, FrameCx};
pub use image_space::{
    FrameBuffers, ImageSpacePasses, render_buffers, render_buffers_into, shade_into,
};
pub use instruction_set::{UnsupportedCpu, check_instruction_set};
pub use raster::{
    BAND_ROWS, Band, DepthInterpolation, DepthTest, Faces, RasterMesh, SurfaceBuffer, Texel,
    band_pixels, rasterize, rasterize_bands, rasterize_into,
};
pub use renderer::CpuRenderer;
pub use surfaces::rasterize_surface;
