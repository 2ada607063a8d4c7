//! # refract-eval
//!
//! Everything around the renderer API of refract-scene that touches files or judges a frame,
//! so that the renderers link none of it:
//!
//! * [`mesh_files`]: meshes from OBJ (tobj) and glTF 2.0 (gltf) files, cleaned up.
//! * [`scene_file`]: TOML scene files and the built-in scenes (`docs/scenes.md`).
//! * [`environment_files`]: lat-long `.exr`/`.hdr` maps (negatives clamped and counted).
//! * [`gltf_export`]: a scene as glTF 2.0 for the engines' own renderers, with a
//!   position-coded variant for lookup studies.
//! * [`frame_files`]: a [`refract_scene::Frame`] as an EXR (colour and every AOV layer) or a PNG.
//! * [`images`]: tonemapped colour PNGs, false-colour error maps with a colour bar, TIR masks,
//!   the report's RGBE images.
//! * [`metrics`]: error metrics of a frame against the reference (design.md, "Measuring").
//! * [`atomic_write`]: the one way files are written (temporary file, flush, rename).

pub mod atomic_write;
pub mod environment_files;
pub mod frame_files;
pub mod gltf_export;
pub mod images;
pub mod mesh_files;
pub mod metrics;
pub mod scene_file;
#[cfg(test)]
mod test_files;

pub use environment_files::load_latlong;
pub use frame_files::FrameFiles;
pub use mesh_files::{LoadOptions, LoadReport, LoadedMesh, load_mesh};
pub use scene_file::{BUILTIN_SCENES, LoadedScene, load_scene, load_scene_str};
