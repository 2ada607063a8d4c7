//! # refract-gpu
//!
//! The wgpu backend of refract behind [`refract_scene::Renderer`] ([`GpuRenderer`]): the same
//! passes as the CPU backend in WGSL, held to refract-core by conformance tests, results read
//! back into a [`refract_scene::Frame`].
//!
//! * [`context`]: adapter and device, headless, with clear errors.
//! * `scene_buffers`: a scene uploaded once (every mesh, the environment).
//! * `passes`: what several families use: rasterising any mesh from any camera (back faces,
//!   front faces, surfaces), the refractor's targets, the opaque objects seen from a camera,
//!   the kernels' outputs, pipelines per registry row.
//! * `methods`: one module per method family, its WGSL beside it (`image_space`: Wyman 2005a;
//!   `reference`: the exact reference), and the backend's one list of families.
//! * [`shaders`]: the WGSL files several modules include (`shaders/`), composed after the
//!   constants header from Rust; [`shader_modules`] lists every module.
//! * [`conformance`]: the harness that evaluates WGSL functions and whole kernels on rows of
//!   inputs, the shared ones and each family's own module.
//!
//! Headless; runs on any Vulkan/Metal/DX12/GL adapter, including lavapipe (Mesa's CPU Vulkan
//! driver). `WGPU_BACKEND` and `WGPU_ADAPTER_NAME` choose the adapter.

mod bindings;
pub mod bvh;
pub mod conformance;
pub mod context;
mod family;
mod frame_uniforms;
mod methods;
mod passes;
pub mod reference;
pub mod renderer;
mod scene_buffers;
pub mod shaders;
mod timestamps;

pub use context::{AdapterSummary, GpuContext, GpuError, RayQueryPolicy, list_adapters};
pub use refract_scene::PassTime;
pub use renderer::{GpuFrame, GpuRenderer};

use shaders::ShaderModule;

/// Every WGSL module the backend compiles: the shared ones, then each family's (the list
/// `tests/shaders.rs` validates with naga). Here, at the crate's root, so that the modules that
/// declare them import the shared files from [`shaders`] without a circle.
pub fn shader_modules() -> Vec<ShaderModule> {
    let mut modules = vec![
        shaders::RASTER_MODULE,
        crate::conformance::CONFORMANCE_MODULE,
        crate::conformance::CONFORMANCE_KERNELS_MODULE,
        crate::bvh::BVH_MODULE,
    ];
    modules.extend(crate::methods::shaders());
    modules
}

/// The full source of the module called `name`, `None` for no such module.
pub fn shader_source(name: &str) -> Option<String> {
    shader_modules()
        .into_iter()
        .find(|m| m.name == name)
        .map(|m| m.source())
}
