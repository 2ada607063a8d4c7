//! The WGSL twin of refract-core as a public asset: every core function in WGSL, line by line
//! the Rust function of the same name (same formulas, same branches), held to it by the
//! conformance tests of `refract-gpu` (a compute shader evaluates each on proptest inputs).
//!
//! WGSL has no includes: put [`library`] in front of your own shader source.
//!
//! ```
//! let source = format!("{}\n{}", refract_core::wgsl::library(), "
//!     @compute @workgroup_size(1)
//!     fn main() {
//!         let t1 = refract_dir(vec3<f32>(0.0, -1.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), 1.0 / 1.5);
//!     }");
//! assert!(source.contains("fn refract_dir"));
//! ```
//!
//! What the functions expect: no bindings, no uniforms, no override constants; only the
//! `const` header of [`constants`] (policy and mode codes, tolerances), which [`library`]
//! includes. Conventions are the Rust ones: unit vectors, incident directions toward the
//! surface, outward normals, `eta = n_i / n_t`, the zero vector on TIR. Functions that can fail
//! return a `vec4` whose `w` is 1 when valid (e.g. `robust_normalize`). Names: `refract_dir`
//! and `reflect_dir` (the Rust `refract`, `reflect`; WGSL's built-ins of those names differ in
//! how they keep digits near grazing), `face_forward_shading_normal`, `angle_between`,
//! `approximate_distance`, `exit_normal_outside_silhouette`, `refract_exit`,
//! `fresnel_dielectric`, `direction_to_latlong`, `procedural_radiance` and more (see the
//! sources). In wgpu: `ShaderSource::Wgsl(format!("{}{your_source}", library()).into())`; in
//! Bevy, register the same string as a shader asset and `#import` nothing: prepend it.

use alloc::format;
use alloc::string::String;

/// The core functions (`wgsl/core.wgsl`): vectors, optics, Fresnel, `d~`, exit normals.
pub const CORE: &str = include_str!("../wgsl/core.wgsl");

/// The procedural environment (`wgsl/procedural_sky.wgsl`): `procedural_radiance`.
pub const PROCEDURAL_SKY: &str = include_str!("../wgsl/procedural_sky.wgsl");

/// The spectral functions (`wgsl/spectral.wgsl`): the CIE tables, hero wavelengths, sigmoid
/// spectra, `KHR_materials_dispersion`'s index ([`crate::spectral`]).
pub const SPECTRAL: &str = include_str!("../wgsl/spectral.wgsl");

/// The `const` declarations the functions use, generated from the Rust values
/// ([`crate::gpu::wgsl_constants`]).
pub fn constants() -> String {
    crate::gpu::wgsl_constants()
}

/// The constants header, [`CORE`], [`PROCEDURAL_SKY`] and [`SPECTRAL`], ready to prepend to a
/// shader.
pub fn library() -> String {
    format!("{}\n{CORE}\n{PROCEDURAL_SKY}\n{SPECTRAL}", constants())
}
