//! The WGSL modules of the GPU backend, composed from the files in `shaders/` (WGSL has no
//! includes) after the constant header generated from Rust ([`refract_core::gpu::wgsl_constants`]).
//! The shared files and modules (the raster passes, the conformance harness) are here; each
//! method family declares its own module (its file and the shared files it needs) beside its
//! pipelines, so a new family edits nothing here.

use refract_core::gpu::wgsl_constants;

/// A WGSL file: its name in `shaders/` (or `refract_core::wgsl`) and its text.
pub type WgslFile = (&'static str, &'static str);

/// The core twin (`refract_core::wgsl`).
pub const CORE: WgslFile = ("core.wgsl", refract_core::wgsl::CORE);
/// The procedural sky (`refract_core::wgsl`).
pub const PROCEDURAL_SKY: WgslFile = ("procedural_sky.wgsl", refract_core::wgsl::PROCEDURAL_SKY);
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
/// The exact reference's transmission path (`refract_gpu::reference`).
pub const REFERENCE: WgslFile = ("reference.wgsl", include_str!("../shaders/reference.wgsl"));
/// The ray-query module's enable directive (its first file).
pub const RAY_QUERY_ENABLE: WgslFile = (
    "ray_query_enable.wgsl",
    include_str!("../shaders/ray_query_enable.wgsl"),
);
/// Closest hits by the adapter's ray queries, `bvh.wgsl`'s interface.
pub const BVH_RAY_QUERY: WgslFile = (
    "bvh_ray_query.wgsl",
    include_str!("../shaders/bvh_ray_query.wgsl"),
);
/// The BVH's batch kernel (`refract_gpu::bvh::GpuBvh::closest_hits`).
pub const BVH_TRACE: WgslFile = ("bvh_trace.wgsl", include_str!("../shaders/bvh_trace.wgsl"));
/// The conformance harness's entry points.
pub const CONFORMANCE: WgslFile = (
    "conformance.wgsl",
    include_str!("../shaders/conformance.wgsl"),
);

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

/// The conformance harness (`refract_gpu::conformance`).
pub const CONFORMANCE_MODULE: ShaderModule = ShaderModule {
    name: "conformance",
    files: &[CORE, PROCEDURAL_SKY, DISTANCE_SEARCH, CONFORMANCE],
};

/// The whole-kernel conformance harness: the one- and two-interface kernels over an analytic
/// back-face buffer and the frame uniforms (`refract_gpu::conformance::evaluate_kernel`).
pub const CONFORMANCE_KERNELS: WgslFile = (
    "conformance_kernels.wgsl",
    include_str!("../shaders/conformance_kernels.wgsl"),
);

/// The module of [`CONFORMANCE_KERNELS`].
pub const CONFORMANCE_KERNELS_MODULE: ShaderModule = ShaderModule {
    name: "conformance-kernels",
    files: &[CORE, FRAME, TWO_INTERFACE, CONFORMANCE_KERNELS],
};

/// Closest-hit queries against a flattened BVH (`refract_gpu::bvh`).
pub const BVH_MODULE: ShaderModule = ShaderModule {
    name: "bvh",
    files: &[BVH, BVH_TRACE],
};

/// The exact reference on the GPU (`refract_gpu::reference`).
pub const REFERENCE_MODULE: ShaderModule = ShaderModule {
    name: "reference",
    files: &[
        CORE,
        PROCEDURAL_SKY,
        FRAME,
        ENVIRONMENT,
        MATERIALS,
        BVH,
        REFERENCE,
    ],
};

/// The exact reference over the adapter's ray queries (`refract_gpu::reference`, where the
/// adapter has `EXPERIMENTAL_RAY_QUERY`).
pub const REFERENCE_RAY_QUERY_MODULE: ShaderModule = ShaderModule {
    name: "reference-ray-query",
    files: &[
        RAY_QUERY_ENABLE,
        CORE,
        PROCEDURAL_SKY,
        FRAME,
        ENVIRONMENT,
        MATERIALS,
        BVH_RAY_QUERY,
        REFERENCE,
    ],
};

/// Every module the backend compiles: the shared ones, then each family's.
pub fn modules() -> Vec<ShaderModule> {
    let mut modules = vec![
        RASTER_MODULE,
        CONFORMANCE_MODULE,
        CONFORMANCE_KERNELS_MODULE,
        BVH_MODULE,
        REFERENCE_MODULE,
        REFERENCE_RAY_QUERY_MODULE,
    ];
    modules.extend_from_slice(crate::methods::SHADERS);
    modules
}

/// The full source of the module called `name`, `None` for no such module.
pub fn module_source(name: &str) -> Option<String> {
    modules()
        .into_iter()
        .find(|m| m.name == name)
        .map(|m| m.source())
}

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
