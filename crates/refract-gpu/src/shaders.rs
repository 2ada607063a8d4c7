//! The WGSL modules of the GPU backend, composed from the files in `shaders/` (WGSL has no
//! includes) after the constant header generated from Rust ([`refract_core::gpu::wgsl_constants`]).
//! The files that several modules include live in `shaders/` and are declared here, with the
//! shared raster module; a file that one Rust module includes (a family's kernel, the
//! reference's path, the conformance harness) lives beside that module, which declares its own
//! [`ShaderModule`] from its file and the shared ones, so a new family edits nothing here.
//! [`crate::shader_modules`] lists every module for naga's validation.

use refract_core::gpu::wgsl_constants;

/// A WGSL file: its name in `shaders/` (or `refract_core::wgsl`) and its text.
pub type WgslFile = (&'static str, &'static str);

/// The core twin (`refract_core::wgsl`).
pub const CORE: WgslFile = ("core.wgsl", refract_core::wgsl::CORE);
/// The procedural sky (`refract_core::wgsl`).
pub const PROCEDURAL_SKY: WgslFile = ("procedural_sky.wgsl", refract_core::wgsl::PROCEDURAL_SKY);
/// refract-core's spectral functions (`refract_core::wgsl::SPECTRAL`).
pub const SPECTRAL: WgslFile = ("spectral.wgsl", refract_core::wgsl::SPECTRAL);
/// The frame uniforms, coverage codes, the unknown-code colour.
pub const FRAME: WgslFile = ("frame.wgsl", include_str!("../shaders/frame.wgsl"));
/// The environment lookup.
pub const ENVIRONMENT: WgslFile = (
    "environment.wgsl",
    include_str!("../shaders/environment.wgsl"),
);
/// Diffuse materials and conductors.
pub const MATERIALS: WgslFile = ("materials.wgsl", include_str!("../shaders/materials.wgsl"));
/// The raster passes (any mesh, any camera).
pub const RASTER: WgslFile = ("raster.wgsl", include_str!("../shaders/raster.wgsl"));
/// The raster passes of `pvrr`'s views.
pub const PVRR_RASTER: WgslFile = (
    "pvrr_raster.wgsl",
    include_str!("../shaders/pvrr_raster.wgsl"),
);
/// The image-space kernels (Wyman 2005a), also the first part of the nearby-geometry kernel.
pub const TWO_INTERFACE: WgslFile = (
    "two_interface.wgsl",
    include_str!("../shaders/two_interface.wgsl"),
);
/// The camera the opaque objects' surfaces are seen from: its uniforms, texels and view depth
/// (`crate::passes::object_surfaces`).
pub const OBJECT_SURFACES: WgslFile = (
    "object_surfaces.wgsl",
    include_str!("../shaders/object_surfaces.wgsl"),
);
/// The opaque objects' surfaces (the NG or screen texture), their readers, the outputs of the
/// kernels that read them (`crate::passes::object_surfaces`).
pub const OBJECT_TEXTURE: WgslFile = (
    "object_texture.wgsl",
    include_str!("../shaders/object_texture.wgsl"),
);
/// The image-space methods' passes over the back-face texture (Wyman 2005a).
pub const IMAGE_SPACE: WgslFile = (
    "image_space.wgsl",
    include_str!("../shaders/image_space.wgsl"),
);
/// The distance-map search (Umenhoffer et al. 2007), also run by the conformance harness.
pub const DISTANCE_SEARCH: WgslFile = (
    "distance_search.wgsl",
    include_str!("../shaders/distance_search.wgsl"),
);
/// Closest hits against a flattened BVH (the exact reference's traversal, issue 32).
pub const BVH: WgslFile = ("bvh.wgsl", include_str!("../shaders/bvh.wgsl"));

/// A module the backend compiles: its name and the files it is made of, in order.
#[derive(Clone, Copy, Debug)]
pub struct ShaderModule {
    /// Its name (the pipelines' labels).
    pub name: &'static str,
    /// Its files, after the generated constant header.
    pub files: &'static [WgslFile],
}

impl ShaderModule {
    /// The full source: the files' `enable` directives (WGSL wants them before every
    /// declaration), the constant header, then every file.
    pub fn source(&self) -> String {
        let is_directive = |line: &&str| line.trim_start().starts_with("enable ");
        let mut source: String = self
            .files
            .iter()
            .flat_map(|(_, text)| text.lines().filter(is_directive))
            .map(|line| format!("{line}\n"))
            .collect();
        source.push_str(&wgsl_constants());
        source.push_str(&color_chart_constant());
        source.push_str(&format!(
            "const MAX_REFRACTORS: u32 = {}u;\n",
            refract_scene::MAX_REFRACTORS
        ));
        for (name, text) in self.files {
            source.push_str(&format!("\n// ---- {name} ----\n"));
            for line in text.lines().filter(|line| !is_directive(line)) {
                source.push_str(line);
                source.push('\n');
            }
        }
        source
    }
}

/// The raster passes.
pub const RASTER_MODULE: ShaderModule = ShaderModule {
    name: "raster",
    files: &[CORE, FRAME, RASTER, PVRR_RASTER],
};

/// `COLOR_CHART`, the 24 patches of [`refract_scene::Albedo::ColorChart`], as a WGSL constant.
fn color_chart_constant() -> String {
    let patches: Vec<String> = refract_scene::COLOR_CHART
        .iter()
        .map(|[r, g, b]| format!("vec3<f32>({r:?}, {g:?}, {b:?})"))
        .collect();
    format!(
        "const COLOR_CHART = array<vec3<f32>, 24>({});\n",
        patches.join(", ")
    )
}
