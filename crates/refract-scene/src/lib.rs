//! # refract-scene
//!
//! What every renderer of refract consumes and produces, so that the CPU backend, the GPU
//! backend, the exact reference, the CLI, the tests and the benches share one definition:
//!
//! * [`scene`]: [`Scene`]: camera, refractor (mesh, BVH, `d_N`, IOR, each built once), opaque
//!   objects (mesh, BVH, material), light, environment.
//! * [`environment`]: lat-long `.exr`/`.hdr` maps and their loaders (negatives clamped and
//!   counted), constant and procedural environments, looked up with the backends' or the exact
//!   `atan2`.
//! * [`scene_file`]: TOML scene files and the built-in scenes (`docs/scenes.md`).
//! * [`registry`]: every method (id, paper, parameters with ranges, AOVs, backends) and
//!   [`MethodParams`].
//! * [`pvrr`]: the per-frame plan of Kakimoto et al. 2007 (per-vertex rays by BVH, views,
//!   texture coordinates) both backends draw.
//! * [`renderer`]: the [`Renderer`] interface the three renderers implement.
//! * [`frame`]: [`Frame`], linear colour plus named AOV layers, EXR/PNG output.
//! * [`metrics`]: error metrics of a frame against the reference (design.md, "Measuring").
//! * [`tonemap`]: the display encoding of every PNG.
//! * [`atomic_write`]: the one way files are written (temporary file, flush, rename).

pub mod atomic_write;
pub mod environment;
pub mod error;
pub mod frame;
pub mod metrics;
pub mod pvrr;
pub mod registry;
pub mod renderer;
pub mod scene;
pub mod scene_file;
pub mod tonemap;

pub use environment::{Environment, EnvironmentReport, LatLongMap, load_latlong};
pub use error::SceneError;
pub use frame::{Aov, AovKind, Frame, Layer};
pub use registry::{
    BackendId, DistanceMapParams, Family, InterfaceRule, MethodId, MethodInfo, MethodParams,
    NearbyParams, PvrrParams, REGISTRY, TraceMode, TraceSettings, TwoInterfaceParams,
    scene_support,
};
pub use renderer::{FrameOutputs, FrameTiming, RenderError, Renderer, TimingSource};
pub use scene::{
    Albedo, COLOR_CHART, CONDUCTORS, Conductor, DirectionalLight, Material, Object, Refractor,
    Scene, SceneMesh, SurfaceTexel, conductor_name,
};
pub use scene_file::{BUILTIN_SCENES, LoadedScene, load_scene, load_scene_str};
