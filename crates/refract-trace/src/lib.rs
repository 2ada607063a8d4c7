//! # refract-trace
//!
//! The exact reference every approximate method is judged against: recursive ray tracing
//! through the refractor mesh (BVH from refract-geometry), Snell at every interface with the
//! same interpolated shading normals as the other methods, total internal reflection as
//! internal reflection, and per-pixel ground truth ([`PathRecord`], written as the AOV layers
//! of a [`refract_scene::Frame`]).
//!
//! * [`tracer`]: `transmission` and `full` (Fresnel-split) modes, stratified supersampling,
//!   deterministic parallel rendering.
//! * [`renderer`]: the tracer as a [`refract_scene::Renderer`] (method `reference`).
//! * [`sampling`]: stratified pixel samples.
//!
//! Exact math only: environment lookups use libm's `atan2f`
//! ([`refract_scene::Environment::radiance_exact`]), never an approximation a backend uses
//! (a test over this crate's sources holds it to that).

pub mod renderer;
pub mod sampling;
pub mod tracer;

pub use renderer::ReferenceRenderer;
pub use tracer::{
    PathRecord, PathSampler, Tracer, render, render_into, render_with, spectral_lighting,
};
