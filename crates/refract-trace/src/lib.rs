//! # refract-trace
//!
//! The exact reference every approximate method is judged against: recursive ray tracing
//! through the refractor mesh (BVH from refract-geometry), Snell at every interface with the
//! same interpolated shading normals as the other methods, total internal reflection as
//! internal reflection, and per-pixel ground truth ([`PixelAov`]) written as a multi-channel EXR.
//!
//! * [`environment`]: lat-long `.exr`/`.hdr` maps (negatives clamped and counted), constant and
//!   procedural environments.
//! * [`scene`]: refractor, nearby opaque objects with view-independent diffuse shading, light.
//! * [`tracer`]: `transmission` and `full` (Fresnel-split) modes, stratified supersampling,
//!   deterministic parallel rendering.
//! * [`frame`]: radiance + AOVs, EXR output and input, tonemapped sRGB PNG output.
//! * [`tonemap`]: the display encoding of every PNG (ACES filmic fit + sRGB).

pub mod environment;
pub mod error;
pub mod frame;
pub mod sampling;
pub mod scene;
pub mod tonemap;
pub mod tracer;

pub use environment::{Environment, EnvironmentReport, LatLongMap, load_latlong};
pub use error::TraceError;
pub use frame::{Frame, PixelAov};
pub use scene::{Albedo, DirectionalLight, Object, Refractor, Scene};
pub use tracer::{TraceMode, TraceSettings, Tracer, render};
