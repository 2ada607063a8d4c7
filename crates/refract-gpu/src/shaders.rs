//! The WGSL modules of the GPU backend, composed from the files in `shaders/` (WGSL has no
//! includes) after the constant header generated from Rust ([`refract_core::gpu::wgsl_constants`]).

use refract_core::gpu::wgsl_constants;

/// Every `.wgsl` file, by name: the core twin from `refract_core::wgsl`, the passes and
/// methods from `shaders/`.
pub const FILES: [(&str, &str); 13] = [
    ("core.wgsl", refract_core::wgsl::CORE),
    ("procedural_sky.wgsl", refract_core::wgsl::PROCEDURAL_SKY),
    ("frame.wgsl", include_str!("../../../shaders/frame.wgsl")),
    (
        "environment.wgsl",
        include_str!("../../../shaders/environment.wgsl"),
    ),
    ("raster.wgsl", include_str!("../../../shaders/raster.wgsl")),
    (
        "pvrr_raster.wgsl",
        include_str!("../../../shaders/pvrr_raster.wgsl"),
    ),
    (
        "image_space.wgsl",
        include_str!("../../../shaders/image_space.wgsl"),
    ),
    (
        "materials.wgsl",
        include_str!("../../../shaders/materials.wgsl"),
    ),
    (
        "distance_search.wgsl",
        include_str!("../../../shaders/distance_search.wgsl"),
    ),
    (
        "distance_map.wgsl",
        include_str!("../../../shaders/distance_map.wgsl"),
    ),
    (
        "nearby_geometry.wgsl",
        include_str!("../../../shaders/nearby_geometry.wgsl"),
    ),
    ("pvrr.wgsl", include_str!("../../../shaders/pvrr.wgsl")),
    (
        "conformance.wgsl",
        include_str!("../../../shaders/conformance.wgsl"),
    ),
];

fn file(name: &str) -> &'static str {
    FILES
        .iter()
        .find(|(n, _)| *n == name)
        .map_or("", |(_, s)| s)
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

fn compose(parts: &[&str]) -> String {
    let mut source = wgsl_constants();
    source.push_str(&color_chart_constant());
    for part in parts {
        source.push_str(&format!("\n// ---- {part} ----\n"));
        source.push_str(file(part));
    }
    source
}

/// The modules the backend compiles: `(name, files it is made of)`.
pub const MODULES: [(&str, &[&str]); 6] = [
    (
        "raster",
        &["core.wgsl", "frame.wgsl", "raster.wgsl", "pvrr_raster.wgsl"],
    ),
    (
        "image_space",
        &[
            "core.wgsl",
            "procedural_sky.wgsl",
            "frame.wgsl",
            "environment.wgsl",
            "image_space.wgsl",
        ],
    ),
    (
        "nearby_geometry",
        &[
            "core.wgsl",
            "procedural_sky.wgsl",
            "frame.wgsl",
            "environment.wgsl",
            "image_space.wgsl",
            "materials.wgsl",
            "nearby_geometry.wgsl",
        ],
    ),
    (
        "distance_map",
        &[
            "core.wgsl",
            "procedural_sky.wgsl",
            "frame.wgsl",
            "environment.wgsl",
            "materials.wgsl",
            "distance_search.wgsl",
            "distance_map.wgsl",
        ],
    ),
    (
        "pvrr",
        &[
            "core.wgsl",
            "procedural_sky.wgsl",
            "frame.wgsl",
            "environment.wgsl",
            "materials.wgsl",
            "pvrr.wgsl",
        ],
    ),
    (
        "conformance",
        &[
            "core.wgsl",
            "procedural_sky.wgsl",
            "distance_search.wgsl",
            "conformance.wgsl",
        ],
    ),
];

/// The full source of a module of [`MODULES`].
pub fn module_source(name: &str) -> String {
    let parts = MODULES
        .iter()
        .find(|(n, _)| *n == name)
        .map_or(&[][..], |(_, p)| p);
    compose(parts)
}
