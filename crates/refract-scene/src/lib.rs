//! # refract-scene
//!
//! The API every renderer of refract consumes and produces, so that the CPU backend, the GPU
//! backend, the exact reference, the experiments, the tests and the benches share one
//! definition. It links no file format, no TOML and no FLIP: scene files, built-in scenes,
//! image writers and metrics live in refract-eval, above it.
//!
//! * [`scene`]: [`Scene`]: camera, refractors (mesh, BVH, `d_N`, IOR, absorption, each built once), opaque
//!   objects (mesh, BVH, material), light, environment.
//! * [`environment`]: lat-long maps, constant and procedural environments, looked up with the
//!   backends' or the exact `atan2`.
//! * [`registry`]: every method (id, paper, parameters with ranges, AOVs, backends) and
//!   [`MethodParams`].
//! * [`pvrr`]: the per-frame plan of Kakimoto et al. 2007 (per-vertex rays by BVH, views,
//!   texture coordinates) both backends draw.
//! * [`renderer`]: the [`Renderer`] interface the three renderers implement.
//! * [`frame`]: [`Frame`], linear colour plus named AOV layers.
//! * [`tonemap`]: the display encoding of every PNG.

pub mod dispersive_frame;
pub mod environment;
pub mod error;
pub mod frame;
pub mod pvrr;
pub mod registry;
pub mod renderer;
pub mod scene;
pub mod spectral;
pub mod tonemap;

pub use dispersive_frame::{dispersion_bins, render_dispersive};
pub use environment::{Environment, EnvironmentReport, LatLongMap};
pub use error::{SceneError, full_message};
pub use frame::{Aov, AovKind, Frame, Layer, LayerValue, MAX_FRAME_SIZE, PixelLayers};
pub use registry::{
    BackendId, DepthPeelParams, DistanceMapParams, EngineParams, Family, FamilyParams,
    ImageSpaceMethod, InterfaceRule, MAX_SPP, MethodId, MethodInfo, MethodParams, NearbyParams,
    ParamValue, PvrrParams, REGISTRY, ROUGH_MIN_SPP, TraceMode, TraceSettings, TwoInterfaceParams,
    scene_support,
};
pub use renderer::{FrameOutputs, FrameTiming, PassTime, RenderError, Renderer, TimingSource};
pub use scene::{
    Albedo, Attenuation, COLOR_CHART, CONDUCTORS, Conductor, DirectionalLight, MAX_REFRACTORS,
    Material, Object, Refractor, Scene, SceneMesh, SurfaceTexel, conductor_name,
};
