//! # refract-core
//!
//! The pure per-pixel mathematics of the classic real-time refraction techniques, shared by
//! every backend of `refract` (CPU, WGSL twin) and reusable in your own renderer.
//!
//! * [`optics`]: Snell refraction, reflection, critical angle (glam/WGSL conventions).
//! * [`fresnel`]: exact unpolarised dielectric Fresnel, Schlick, conductor Schlick.
//! * [`interpolated_distance`]: Wyman 2005a §3.1, the distance `d~` from `P1` to `P2`.
//! * [`exit`]: Wyman 2005a §3.2–3.3, the exit normal and the second-interface TIR policy.
//! * [`kernel`]: the one- and two-interface per-pixel kernels, generic over [`kernel::BackFaceSampler`].
//! * [`real`]: the number traits every per-pixel leaf is written over once (`f32`/`Vec3`, and
//!   the eight-lane types of [`lanes`]).
//! * [`kernel_x8`], [`lanes`]: the kernels on eight pixels at once (SIMD) through the same
//!   leaves, bit-identical.
//! * [`microfacet`]: rough interfaces: GGX, Smith masking, visible-normal sampling (Walter et al. 2007, Heitz 2018).
//! * [`shading`]: the opaque objects' albedos and directional light.
//! * [`screen_mips`]: the engines' mip-mapped screen texture and three.js's rough transmission lookup in it.
//! * [`spectral`]: dispersion: wavelengths, the CIE observer, RGB↔spectrum (Jakob–Hanika), `KHR_materials_dispersion`'s IOR.
//! * [`arctangent`]: the inlined `atan2` of the per-pixel paths.
//! * [`distance_map`]: Umenhoffer et al. 2007, rays traced in layered distance maps (linear + secant search, min-max, multiple bounces).
//! * [`engine`]: the refraction today's engines ship (Godot, three.js, Bevy, Unity HDRP, Filament): exit models and screen lookups.
//! * [`depth_peel`]: refraction through any number of interfaces in depth-peeled layers (glass behind glass, nested media).
//! * [`pvrr`]: Kakimoto et al. 2007, per-vertex reflection and refraction (virtual viewpoint, view volume, texture coordinates, map lookup).
//! * [`back_surface`]: which back surface the back-face pass keeps (Wyman 2005a §3.2).
//! * [`camera`]: world ↔ view ↔ clip ↔ pixel transforms and pixel-centre rays.
//! * [`environment`]: lat-long environment lookup (Mitsuba 3's convention), bilinear, generic
//!   over the `atan2` ([`environment::Polynomial`] for backends, [`environment::Exact`] for the reference).
//! * [`procedural_sky`]: the built-in procedural environment, scalar and eight lanes.
//! * [`gpu`]: the `#[repr(C)]` uniform block and enum codes shared with the WGSL twin.
//! * [`vector`]: robust normalisation and well-conditioned angles.
//! * [`wgsl`]: the WGSL twin of these functions, to prepend to your own shaders.
//!
//! Public on purpose and stable: `optics`, `fresnel`, `interpolated_distance`, `exit`, `kernel`,
//! `camera`, `environment`, `procedural_sky`, `shading`, `back_surface`, `vector`, `wgsl`.
//! Public for the refract backends and subject to change: `real`, `kernel_x8`, `lanes`,
//! `arctangent`, `gpu`.
//!
//! Conventions (see `docs/conventions.md`): right-handed world, y up; unit vectors; incident
//! directions point *toward* the surface; normals point *outward* from the refractor;
//! `eta = n_i / n_t`; `refract` returns the zero vector on total internal reflection (TIR),
//! exactly like WGSL's and glam's `refract`.
//!
//! The crate has no I/O, no threads, no GPU and allocates nothing in its per-pixel paths. It is
//! `#![no_std]` (with `alloc`, for the WGSL constant header) without its default `std`
//! feature: `--no-default-features --features libm` takes the `f32` math from the `libm`
//! crate, e.g. for embedded or `rust-gpu` targets (`tests/tests/dependency_rule.rs` builds it
//! so, for `thumbv7em-none-eabihf` when that target is installed).

#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("refract-core needs its `std` feature (the default) or, without std, `libm`");

pub mod arctangent;
pub mod back_surface;
pub mod camera;
pub mod depth_peel;
pub mod distance_map;
pub mod engine;
pub mod engine_dispersion;
pub mod environment;
pub mod exit;
pub mod fresnel;
pub mod gpu;
pub mod interpolated_distance;
pub mod kernel;
pub mod kernel_x8;
pub mod lanes;
mod math;
pub mod microfacet;
pub mod nearby_geometry;
pub mod nearby_geometry_x8;
pub mod optics;
pub mod procedural_sky;
pub mod pvrr;
pub mod real;
pub mod screen_mips;
pub mod shading;
pub mod spectral;
pub mod vector;
pub mod wgsl;

pub use back_surface::BackSurface;
pub use camera::{Camera, CameraDesc, CameraError, CubeFace, Ray};
pub use exit::{ExitNormalSource, TirPolicy};
pub use interpolated_distance::DistanceMode;
pub use kernel::{
    BackFaceSample, BackFaceSampler, DegenerateInput, FrontSurface, ImageSpaceParams, InvalidIor,
    OneInterfacePath, TwoInterfacePath,
};
