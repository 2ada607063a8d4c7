//! # refract-gpu
//!
//! The wgpu backend of refract: the methods `single`, `wyman`, `wyman-dv` and `wyman-dn` with
//! the passes of Wyman 2005a §4 (back faces and front faces rasterised into float targets, the
//! per-pixel kernel as a compute pass), WGSL in `shaders/` held to refract-core by conformance
//! tests, readback into the CPU backend's [`refract_cpu::MethodFrame`].
//!
//! Headless; runs on any Vulkan/Metal/DX12/GL adapter, including lavapipe (Mesa's CPU Vulkan
//! driver). `WGPU_BACKEND` and `WGPU_ADAPTER_NAME` choose the adapter.

pub mod conformance;
pub mod context;
pub mod renderer;
pub mod shaders;

pub use context::{GpuContext, GpuError, list_adapters};
pub use renderer::{GpuFrame, GpuRenderer, GpuScene, GpuTiming, render_method};
