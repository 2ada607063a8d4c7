//! Scene files (TOML, `docs/scenes.md`) and the built-in scenes, turned into the [`Scene`] every
//! renderer renders. Relative paths are relative to the scene file.

use std::path::{Path, PathBuf};

use glam::{Affine3A, EulerRot, Quat, Vec3};
use refract_core::CameraDesc;
use refract_geometry::{Mesh, builtin};

use crate::mesh_files::{LoadOptions, load_gltf_scene, load_mesh};
use serde::Deserialize;

use refract_scene::Environment;

use crate::environment_files::load_latlong;
use refract_scene::SceneError;
use refract_scene::{Albedo, Material, Object, Refractor, Scene};

/// The room of the distance-map scenes (Umenhoffer et al. 2007 Figs. 17-7 to 17-9): a box of
/// diffuse walls `x ∈ [−3, 3]`, `y ∈ [−1, 3]`, `z ∈ [−3, 5]` facing inward (red left, green
/// right, a checker floor), an orange torus, the camera inside. Scenes append their specular
/// object and more objects.
macro_rules! room {
    () => {
        r#"[camera]
eye = [0.0, 1.0, 4.2]
target = [0.0, 0.0, -0.5]
fov_y_deg = 50.0
near = 0.05
far = 20.0

[[objects]]
mesh = "builtin:plane"
texture = "checker"
scale = 5.657
translate = [0.0, -1.0, 1.0]

[[objects]]
mesh = "builtin:plane"
color = [0.7, 0.7, 0.7]
scale = 5.657
rotate_deg = [180.0, 0.0, 0.0]
translate = [0.0, 3.0, 1.0]

[[objects]]
mesh = "builtin:plane"
color = [0.7, 0.7, 0.65]
scale = 5.657
rotate_deg = [90.0, 0.0, 0.0]
translate = [0.0, 1.0, -3.0]

[[objects]]
mesh = "builtin:plane"
color = [0.55, 0.6, 0.7]
scale = 5.657
rotate_deg = [-90.0, 0.0, 0.0]
translate = [0.0, 1.0, 5.0]

[[objects]]
mesh = "builtin:plane"
color = [0.63, 0.07, 0.05]
scale = 5.657
rotate_deg = [0.0, 0.0, -90.0]
translate = [-3.0, 1.0, 1.0]

[[objects]]
mesh = "builtin:plane"
color = [0.14, 0.45, 0.09]
scale = 5.657
rotate_deg = [0.0, 0.0, 90.0]
translate = [3.0, 1.0, 1.0]

[[objects]]
mesh = "builtin:torus"
color = [0.9, 0.45, 0.1]
scale = 0.55
rotate_deg = [70.0, 0.0, 0.0]
translate = [1.5, -0.45, 0.4]
"#
    };
}

macro_rules! mirror_stage {
    () => {
        r#"[camera]
eye = [0.0, 0.35, 3.2]
target = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
near = 0.05
far = 40.0

[[objects]]
mesh = "builtin:plane"
texture = "checker"
scale = 14.0
translate = [0.0, -1.0, 0.0]

[[objects]]
mesh = "builtin:plane"
texture = "color-chart"
scale = 3.0
rotate_deg = [90.0, 0.0, 120.0]
translate = [3.4, 0.2, 2.1]

[[objects]]
mesh = "builtin:sphere"
color = [0.8, 0.1, 0.08]
scale = 0.35
translate = [1.3, -0.65, 1.9]

[[objects]]
mesh = "builtin:box"
color = [0.1, 0.25, 0.8]
scale = 0.6
rotate_deg = [0.0, 30.0, 0.0]
translate = [-1.5, -0.65, 1.5]

[[objects]]
mesh = "builtin:torus"
color = [0.9, 0.65, 0.1]
scale = 0.45
rotate_deg = [70.0, 0.0, 0.0]
translate = [0.6, -0.75, 2.6]
"#
    };
}

/// The built-in scenes: name, one line, TOML. They need no file.
pub const BUILTIN_SCENES: [(&str, &str, &str); 17] = [
    (
        "sphere",
        "the paper's 1,600-triangle sphere, IOR 1.5, procedural environment",
        "[refractor]\nmesh = \"builtin:sphere\"\nior = 1.5\n",
    ),
    (
        "torus",
        "a torus (concave, depth complexity 4), IOR 1.33 (water)",
        "[refractor]\nmesh = \"builtin:torus\"\nior = 1.33\nrotate_deg = [60.0, 0.0, 0.0]\n",
    ),
    (
        "lens",
        "a spade-built biconvex spectacle lens, IOR 1.5, seen along its axis",
        "[camera]\neye = [0.0, 0.3, 3.0]\n\n[refractor]\nmesh = \"builtin:lens\"\nior = 1.5\n",
    ),
    (
        "chart",
        "Wyman 2005b Fig. 5: a glass sphere, IOR 1.5, before a colour chart, on a wood floor",
        CHART_SCENE,
    ),
    (
        "engine-failures",
        "the engines' known failures side by side: a glass torus (IOR 1.5: glass behind glass, TIR in its thick parts) behind an opaque grey ball (foreground leak), a red box just off screen on the left, a colour chart and a wood floor",
        ENGINE_FAILURES_SCENE,
    ),
    (
        "mirror-room",
        "Umenhoffer et al. Fig. 17-8: a mirror sphere before a planar mirror in a room of diffuse walls",
        concat!(
            room!(),
            r#"
[[objects]]
mesh = "builtin:plane"
material = "mirror"
scale = 2.4
rotate_deg = [90.0, 0.0, 0.0]
translate = [-0.3, 0.6, -2.9]

[refractor]
mesh = "builtin:sphere"
material = "mirror"
scale = 0.8
translate = [-0.5, -0.2, -0.6]
"#
        ),
    ),
    (
        "glass-room",
        "Umenhoffer et al. Fig. 17-9: a glass sphere (IOR 1.5) that reflects and refracts, in the room",
        concat!(
            room!(),
            r#"
[refractor]
mesh = "builtin:sphere"
ior = 1.5
scale = 0.8
translate = [-0.3, -0.2, -0.2]
"#
        ),
    ),
    (
        "convex-mirror",
        "Kakimoto et al. Fig. 1, 9: a convex mirror of 49 vertices (R = 4) beside a chart, balls and a box",
        concat!(
            mirror_stage!(),
            r#"
[refractor]
mesh = "builtin:mirror-convex"
material = "mirror"
normalize = false
rotate_deg = [0.0, 30.0, 0.0]
"#
        ),
    ),
    (
        "concave-mirror",
        "Kakimoto et al. Fig. 8(b), 9: the concave mirror (R = -8) in the same stage: magnified, upright (the eye inside the focal length)",
        concat!(
            mirror_stage!(),
            r#"
[refractor]
mesh = "builtin:mirror-concave"
material = "mirror"
normalize = false
rotate_deg = [0.0, 30.0, 0.0]
"#
        ),
    ),
    (
        "adjacent-mirrors",
        "Kakimoto et al. Fig. 7: the convex mirror cut into two mirrors sharing 7 vertices, each with its own viewpoint and map",
        concat!(
            mirror_stage!(),
            r#"
[refractor]
mesh = "builtin:mirror-left"
material = "mirror"
normalize = false
rotate_deg = [0.0, 30.0, 0.0]

[[objects]]
mesh = "builtin:mirror-right"
material = "mirror"
rotate_deg = [0.0, 30.0, 0.0]
"#
        ),
    ),
    (
        "mirror-stack",
        "Kakimoto et al. Fig. 11: the stage seen in a flat mirror, seen in the convex mirror (a stack of two maps)",
        concat!(
            mirror_stage!(),
            r#"
[refractor]
mesh = "builtin:mirror-convex"
material = "mirror"
normalize = false
rotate_deg = [0.0, 30.0, 0.0]

[[objects]]
mesh = "builtin:mirror-flat"
material = "mirror"
scale = 1.4
rotate_deg = [0.0, -120.0, 0.0]
translate = [2.0, -0.1, 1.2]
"#
        ),
    ),
    (
        "spectacles",
        "Kakimoto et al. Fig. 12, 15: the biconvex lens (about 2,200 triangles) before the eye, the chart behind it (dispersion=10: 1.60/1.61/1.62)",
        r#"[camera]
eye = [0.0, 0.0, 1.1]
target = [0.0, 0.0, 0.0]
fov_y_deg = 70.0
near = 0.05
far = 40.0

[refractor]
mesh = "builtin:lens"
ior = 1.61
scale = 0.9

[[objects]]
mesh = "builtin:plane"
texture = "color-chart"
scale = 4.0
rotate_deg = [90.0, 0.0, 0.0]
translate = [0.0, 0.0, -2.0]

[[objects]]
mesh = "builtin:plane"
texture = "checker"
scale = 14.0
translate = [0.0, -1.4, 0.0]

[[objects]]
mesh = "builtin:sphere"
color = [0.8, 0.1, 0.08]
scale = 0.3
translate = [0.5, -0.9, -1.0]
"#,
    ),
    (
        "glass-behind-glass",
        "two glass spheres (IOR 1.5), the smaller one in front, partly before the larger, on the chart's floor before the colour chart",
        GLASS_BEHIND_GLASS_SCENE,
    ),
    (
        "vessel",
        "a hollow glass cube (IOR 1.5, walls 0.15 thick, air inside): four interfaces on most rays, TIR in the walls",
        VESSEL_SCENE,
    ),
    (
        "liquid",
        "water (IOR 1.33) filling a round glass flask (IOR 1.5, walls 0.16 thick), before the colour chart",
        LIQUID_SCENE,
    ),
    (
        "rough-glass",
        "four glass spheres (IOR 1.5) of roughness 0, 0.1, 0.3 and 0.6 side by side before the colour chart (after glTF's TransmissionRoughnessTest)",
        ROUGH_GLASS_SCENE,
    ),
    (
        "prism",
        "a 60-degree glass prism (IOR 1.5, Abbe number 30) before bright slits on a black wall (after glTF's DispersionTest)",
        PRISM_SCENE,
    ),
];

/// The chart stage of the many-refractor scenes (issue 49): `chart`'s camera, colour chart and
/// wood floor (`y = −0.8`); each scene adds its refractors.
macro_rules! chart_stage {
    () => {
        r#"[camera]
eye = [0.0, 0.9, 4.2]
target = [0.0, -0.15, 0.0]
fov_y_deg = 40.0
near = 0.05
far = 12.0

[[objects]]
mesh = "builtin:plane"
texture = "color-chart"
scale = 4.0
rotate_deg = [90.0, 0.0, 0.0]
translate = [0.0, 0.9, -3.2]

[[objects]]
mesh = "builtin:plane"
texture = "wood"
scale = 6.0
translate = [0.0, -0.8, 0.6]
"#
    };
}

/// `glass-behind-glass`: a sphere of radius 0.5 in front (refractor 0, the one the
/// one-refractor methods follow) and one of radius 0.75 behind it and to the right, both resting
/// on the floor; seen from the camera they overlap by about a third of the smaller one.
const GLASS_BEHIND_GLASS_SCENE: &str = concat!(
    chart_stage!(),
    r#"
[[refractor]]
mesh = "builtin:sphere"
ior = 1.5
scale = 0.5
translate = [-0.3, -0.3, 1.0]

[[refractor]]
mesh = "builtin:sphere"
ior = 1.5
scale = 0.75
translate = [0.35, -0.05, -0.6]
"#
);

/// `vessel`: a glass cube (half edge 0.52) with a cube of air (half edge 0.375) inside it, both
/// turned alike, so the walls are 0.145 thick and parallel; it floats just above the floor.
const VESSEL_SCENE: &str = concat!(
    chart_stage!(),
    r#"
[[refractor]]
mesh = "builtin:box"
ior = 1.5
scale = 0.9
rotate_deg = [20.0, 35.0, 0.0]
translate = [0.0, 0.1, 0.0]

[[refractor]]
mesh = "builtin:box"
ior = 1.0
scale = 0.65
rotate_deg = [20.0, 35.0, 0.0]
translate = [0.0, 0.1, 0.0]
"#
);

/// `liquid`: a glass sphere of radius 0.8 on the floor, filled with a water sphere of radius
/// 0.64 (Mitsuba: the outer surface `int_ior = 1.5, ext_ior = 1`, the inner one
/// `int_ior = 1.33, ext_ior = 1.5`).
const LIQUID_SCENE: &str = concat!(
    chart_stage!(),
    r#"
[[refractor]]
mesh = "builtin:sphere"
ior = 1.5
scale = 0.8

[[refractor]]
mesh = "builtin:sphere"
ior = 1.33
scale = 0.64
"#
);

/// `rough-glass`: four spheres of radius 0.32 resting on the floor, 0.75 apart, roughness
/// rising from left (0, refractor 0) to right (0.6).
const ROUGH_GLASS_SCENE: &str = concat!(
    chart_stage!(),
    r#"
[[refractor]]
mesh = "builtin:sphere"
ior = 1.5
scale = 0.32
translate = [-1.125, -0.48, 0.0]

[[refractor]]
mesh = "builtin:sphere"
ior = 1.5
roughness = 0.1
scale = 0.32
translate = [-0.375, -0.48, 0.0]

[[refractor]]
mesh = "builtin:sphere"
ior = 1.5
roughness = 0.3
scale = 0.32
translate = [0.375, -0.48, 0.0]

[[refractor]]
mesh = "builtin:sphere"
ior = 1.5
roughness = 0.6
scale = 0.32
translate = [1.125, -0.48, 0.0]
"#
);

/// `prism`: an equilateral prism standing on its end (axis vertical), turned so that the
/// camera's rays pass it near minimum deviation (37° at IOR 1.5), 3 units before a black wall
/// that carries fifteen white slits 0.1 wide and 0.81 apart; through the prism the slits
/// appear shifted sideways and spread into spectra (`n(400 nm) − n(700 nm) = 0.037` at
/// Abbe number 30: a fringe about 0.14 wide on the wall).
const PRISM_SCENE: &str = r#"[camera]
eye = [0.0, 0.2, 4.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
near = 0.05
far = 20.0

[refractor]
mesh = "builtin:prism"
ior = 1.5
abbe = 30.0
rotate_deg = [0.0, 18.6, 0.0]

[[objects]]
mesh = "builtin:plane"
color = [0.0, 0.0, 0.0]
scale = 10.0
rotate_deg = [90.0, 0.0, 0.0]
translate = [0.0, 0.0, -3.0]

[[objects]]
mesh = "builtin:slits"
color = [1.0, 1.0, 1.0]
scale = 8.0
translate = [0.0, 0.0, -2.98]
"#;

/// The `engine-failures` scene (issue 28): what the engines' screen-space refraction cannot
/// show, each where a pixel count can find it. The torus (tilted 60°, left of centre) has glass
/// behind glass where its ring overlaps itself and TIR in its thick parts; the grey ball in
/// front of its lower ring is an opaque foreground object (what three.js's lookup leaks into
/// the glass); the red box at `x = −3` is just outside the frame on the left, where the
/// torus's left side refracts toward it; the chart and the floor are what is behind.
const ENGINE_FAILURES_SCENE: &str = r#"[camera]
eye = [0.0, 0.6, 4.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
near = 0.05
far = 12.0

[refractor]
mesh = "builtin:torus"
ior = 1.5
rotate_deg = [60.0, 0.0, 0.0]
translate = [-0.45, 0.0, 0.0]

[[objects]]
mesh = "builtin:icosphere"
color = [0.55, 0.55, 0.6]
scale = 0.22
translate = [-0.2, -0.5, 1.0]

[[objects]]
mesh = "builtin:box"
color = [0.85, 0.1, 0.08]
scale = 0.6
translate = [-3.0, 0.0, -1.0]

[[objects]]
mesh = "builtin:plane"
texture = "color-chart"
scale = 4.0
rotate_deg = [90.0, 0.0, 0.0]
translate = [0.0, 0.9, -3.2]

[[objects]]
mesh = "builtin:plane"
texture = "wood"
scale = 6.0
translate = [0.0, -1.0, 0.6]
"#;

/// Kakimoto et al. 2007 Fig. 13's far convex lens: the built-in biconvex lens (IOR 1.61) 4.5
/// units before the eye, the colour chart 14 units behind it, beyond its focal length, so the
/// lens shows the chart reversed. Not a built-in scene (the default job does not render it):
/// claim K13 and `a_far_convex_lens_reverses_the_image` load it with [`load_scene_str`].
pub const MAGNIFIER_SCENE: &str = r#"
[camera]
eye = [0.0, 0.0, 4.5]
target = [0.0, 0.0, 0.0]
fov_y_deg = 30.0
near = 0.05
far = 60.0

[refractor]
mesh = "builtin:lens"
ior = 1.61
scale = 0.9

[[objects]]
mesh = "builtin:plane"
texture = "color-chart"
scale = 16.0
rotate_deg = [90.0, 0.0, 0.0]
translate = [0.0, 0.0, -14.0]
"#;

/// The `chart` scene (Wyman 2005b Fig. 5): a glass sphere of radius 0.8 resting on a wood floor
/// (`y = −0.8`), a colour chart (5.7 wide) 3.2 behind its centre facing the camera; the far
/// plane at 12 so the NG texture's depth range fits the scene.
const CHART_SCENE: &str = r#"[camera]
eye = [0.0, 0.9, 4.2]
target = [0.0, -0.15, 0.0]
fov_y_deg = 40.0
near = 0.05
far = 12.0

[refractor]
mesh = "builtin:sphere"
ior = 1.5
scale = 0.8

[[objects]]
mesh = "builtin:plane"
texture = "color-chart"
scale = 4.0
rotate_deg = [90.0, 0.0, 0.0]
translate = [0.0, 0.9, -3.2]

[[objects]]
mesh = "builtin:plane"
texture = "wood"
scale = 6.0
translate = [0.0, -0.8, 0.6]
"#;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile<R> {
    #[serde(default)]
    camera: CameraSection,
    #[serde(default)]
    environment: EnvironmentSection,
    /// One `[refractor]` table (`R = RefractorSection`) or `[[refractor]]` tables
    /// (`R = Vec<RefractorSection>`): [`parse_scene_file`].
    refractor: R,
    #[serde(default)]
    objects: Vec<ObjectSection>,
}

/// Refractor sections with the names their messages use.
type NamedRefractors = Vec<(String, RefractorSection)>;

/// The scene file in `text` with its refractors, each with the name its messages use:
/// `[refractor]` for the one table of a single-refractor file, `refractor[k]` for the tables of
/// `[[refractor]]`. The file is deserialised directly in either form, so that TOML errors keep
/// their key and line.
fn parse_scene_file(
    text: &str,
    origin: &str,
) -> Result<(SceneFile<()>, NamedRefractors), SceneError> {
    let parse_error = |err: toml::de::Error| SceneError::Parse {
        origin: origin.to_owned(),
        message: err.to_string().trim_end().to_owned(),
    };
    let many = matches!(
        toml::from_str::<toml::Table>(text)
            .map_err(parse_error)?
            .get("refractor"),
        Some(toml::Value::Array(_))
    );
    if many {
        let file: SceneFile<Vec<RefractorSection>> = toml::from_str(text).map_err(parse_error)?;
        if file.refractor.is_empty() {
            return Err(SceneError::field(
                origin,
                "refractor",
                "an empty array",
                "one [refractor] table or one or more [[refractor]] tables",
            ));
        }
        let refractors = file
            .refractor
            .into_iter()
            .enumerate()
            .map(|(k, r)| (format!("refractor[{k}]"), r))
            .collect();
        let rest = SceneFile {
            camera: file.camera,
            environment: file.environment,
            refractor: (),
            objects: file.objects,
        };
        Ok((rest, refractors))
    } else {
        let file: SceneFile<RefractorSection> = toml::from_str(text).map_err(parse_error)?;
        let rest = SceneFile {
            camera: file.camera,
            environment: file.environment,
            refractor: (),
            objects: file.objects,
        };
        Ok((rest, vec![("[refractor]".to_owned(), file.refractor)]))
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct CameraSection {
    eye: [f32; 3],
    target: [f32; 3],
    up: [f32; 3],
    fov_y_deg: f32,
    near: f32,
    far: f32,
}

impl Default for CameraSection {
    fn default() -> Self {
        let d = CameraDesc::default();
        Self {
            eye: d.eye.into(),
            target: d.target.into(),
            up: d.up.into(),
            fov_y_deg: d.fov_y.to_degrees(),
            near: d.near,
            far: d.far,
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvironmentSection {
    file: Option<String>,
    #[serde(default = "one")]
    intensity: f32,
}

impl Default for EnvironmentSection {
    fn default() -> Self {
        Self {
            file: None,
            intensity: 1.0,
        }
    }
}

fn one() -> f32 {
    1.0
}

fn yes() -> bool {
    true
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RefractorSection {
    mesh: String,
    #[serde(default = "default_ior")]
    ior: f32,
    /// `glass` (default), a named conductor or `conductor` with `eta` and `k`.
    material: Option<String>,
    eta: Option<[f32; 3]>,
    k: Option<[f32; 3]>,
    #[serde(default = "yes")]
    normalize: bool,
    #[serde(default)]
    translate: [f32; 3],
    #[serde(default = "one")]
    scale: f32,
    #[serde(default)]
    rotate_deg: [f32; 3],
    /// `KHR_materials_volume`'s `attenuationColor`: the fraction of each channel left after
    /// `attenuation_distance` (each in (0, 1]); with `attenuation_distance`, or neither.
    attenuation_color: Option<[f32; 3]>,
    /// `attenuationDistance` in world units (> 0).
    attenuation_distance: Option<f32>,
    /// The surface's roughness in [0, 1] (glTF's `roughnessFactor`; GGX α = roughness²); the
    /// glTF material's when the mesh is a glTF file with one, else 0 (smooth).
    roughness: Option<f32>,
    /// The glass's Abbe number `V_d` (≥ 1; glass 20–90), or `inf` for none; not with
    /// `dispersion`. The glTF material's `KHR_materials_dispersion` when neither is given.
    abbe: Option<f32>,
    /// glTF's `KHR_materials_dispersion` `dispersion` (≥ 0; `20 / V_d`, 0: none); not with `abbe`.
    dispersion: Option<f32>,
}

fn default_ior() -> f32 {
    1.5
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectSection {
    mesh: String,
    #[serde(default)]
    normalize: bool,
    #[serde(default)]
    translate: [f32; 3],
    #[serde(default = "one")]
    scale: f32,
    #[serde(default)]
    rotate_deg: [f32; 3],
    /// Linear RGB albedo (default 0.6 grey) when no texture is given.
    color: Option<[f32; 3]>,
    /// `checker` or `color-chart`.
    texture: Option<String>,
    /// `diffuse` (default), a named conductor or `conductor` with `eta` and `k`.
    material: Option<String>,
    eta: Option<[f32; 3]>,
    k: Option<[f32; 3]>,
    /// A conductor's roughness in [0, 1] (default 0: mirror-smooth); not for diffuse objects.
    roughness: Option<f32>,
}

/// `roughness` of `section` in [`refract_scene::scene::ROUGHNESS_RANGE`], or an error naming it.
fn check_roughness(origin: &str, section: &str, roughness: f32) -> Result<f32, SceneError> {
    if refract_scene::scene::roughness_in_range(roughness) {
        Ok(roughness)
    } else {
        Err(SceneError::field(
            origin,
            format!("{section} roughness"),
            roughness,
            refract_scene::scene::ROUGHNESS_EXPECTED,
        ))
    }
}

/// The Abbe number of a `dispersion` value: `20 / dispersion` (∞ for 0); NaN for a negative
/// or NaN one, which [`check_abbe`] refuses.
fn dispersion_to_abbe(dispersion: f32) -> f32 {
    if dispersion >= 0.0 {
        refract_core::spectral::abbe_from_dispersion(dispersion)
    } else {
        f32::NAN
    }
}

/// `abbe` of `section` (from its `key`) at least 1 or infinite, or an error naming it.
fn check_abbe(origin: &str, section: &str, key: &str, abbe: f32) -> Result<f32, SceneError> {
    if abbe >= refract_scene::scene::ABBE_MIN {
        Ok(abbe)
    } else {
        let expected = if key == "dispersion" {
            "a dispersion from 0 (none) to 20 (20 / Abbe number)"
        } else {
            refract_scene::scene::ABBE_EXPECTED
        };
        Err(SceneError::field(
            origin,
            format!("{section} {key}"),
            abbe,
            expected,
        ))
    }
}

/// The largest real part `n` of a conductor's index in scene files.
const MAX_CONDUCTOR_ETA: f32 = 10.0;
/// The largest extinction coefficient `k` in scene files.
const MAX_CONDUCTOR_K: f32 = 20.0;

/// The conductor a `material` key names (`None` for the section's non-conductor default,
/// `plain`: `glass` or `diffuse`), with `eta`/`k` for `conductor`.
fn parse_conductor(
    origin: &str,
    section: &str,
    plain: &str,
    material: Option<&str>,
    eta: Option<[f32; 3]>,
    k: Option<[f32; 3]>,
) -> Result<Option<refract_scene::scene::Conductor>, SceneError> {
    let name = material.unwrap_or(plain);
    let custom = name == "conductor";
    if !custom && (eta.is_some() || k.is_some()) {
        return Err(SceneError::field(
            origin,
            format!("{section} eta/k"),
            name,
            "material = \"conductor\" when eta and k are given",
        ));
    }
    if name == plain {
        return Ok(None);
    }
    if custom {
        let (Some(eta), Some(k)) = (eta, k) else {
            return Err(SceneError::field(
                origin,
                format!("{section} material"),
                "\"conductor\"",
                "eta = [r, g, b] and k = [r, g, b] beside it",
            ));
        };
        check_vector(
            origin,
            &format!("{section} eta"),
            eta,
            0.0,
            MAX_CONDUCTOR_ETA,
        )?;
        check_vector(origin, &format!("{section} k"), k, 0.0, MAX_CONDUCTOR_K)?;
        return Ok(Some(refract_scene::scene::Conductor {
            eta: Vec3::from(eta),
            k: Vec3::from(k),
        }));
    }
    refract_scene::scene::CONDUCTORS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, c)| Some(*c))
        .ok_or_else(|| {
            let names: Vec<String> = refract_scene::scene::CONDUCTORS
                .iter()
                .map(|(n, _)| format!("\"{n}\""))
                .collect();
            SceneError::field(
                origin,
                format!("{section} material"),
                format!("\"{name}\""),
                format!("\"{plain}\", {} or \"conductor\"", names.join(", ")),
            )
        })
}

/// The names of the built-in scenes, comma-separated.
pub fn builtin_names() -> String {
    BUILTIN_SCENES.map(|s| s.0).join(", ")
}

/// A scene ready to render, and what loading it had to fix.
#[derive(Debug)]
pub struct LoadedScene {
    /// Camera, refractor (mesh, BVH, `d_N`, IOR), objects, environment, light.
    pub scene: Scene,
    /// Lines to show the user (mesh and environment quirks fixed on load).
    pub warnings: Vec<String>,
}

/// A built-in scene name, a path to a `.toml` scene file, or a path to a `.gltf`/`.glb` file
/// read as a scene (see [`build_gltf`]). The path may be any the OS takes, not only UTF-8 (`&str`, `String`, `Path`, `OsStr`); messages show it lossily.
pub fn load_scene(spec: impl AsRef<std::ffi::OsStr>) -> Result<LoadedScene, SceneError> {
    let spec = spec.as_ref();
    if let Some((name, _, toml)) = BUILTIN_SCENES
        .iter()
        .find(|(name, _, _)| spec.to_str() == Some(*name))
    {
        return build(
            name,
            toml,
            Path::new("."),
            &format!("built-in scene {name}"),
        );
    }
    let path = PathBuf::from(spec);
    let name = path
        .file_stem()
        .map_or_else(|| "scene".to_owned(), |s| s.to_string_lossy().into_owned());
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if matches!(extension.as_deref(), Some("gltf" | "glb")) {
        return build_gltf(&name, &path);
    }
    if extension.as_deref() != Some("toml") {
        return Err(SceneError::UnknownScene {
            name: spec.to_string_lossy().into_owned(),
            builtins: builtin_names(),
        });
    }
    let text = std::fs::read_to_string(&path).map_err(|source| SceneError::Io {
        path: path.clone(),
        action: "cannot read the scene file",
        source,
    })?;
    let base = path.parent().map(Path::to_owned).unwrap_or_default();
    build(&name, &text, &base, &path.display().to_string())
}

/// A scene from TOML text: `name` names it, relative paths are relative to `base`, and errors
/// name `origin` (e.g. the embedding program's description of the text).
pub fn load_scene_str(
    name: &str,
    toml: &str,
    base: &Path,
    origin: &str,
) -> Result<LoadedScene, SceneError> {
    build(name, toml, base, origin)
}

/// The largest magnitude of a coordinate (`translate`, `eye`, `target`), documented in
/// `docs/scenes.md`: the refractor is normalised into the unit sphere, so a million units
/// away is already far beyond any useful scene, and `f32` keeps its precision.
pub const MAX_COORDINATE: f32 = 1e6;
/// The smallest `[camera] near`.
pub const MIN_NEAR: f32 = 1e-4;
/// The largest ratio `far / near` (depth precision of a 32-bit float depth buffer stays useful).
pub const MAX_FAR_OVER_NEAR: f32 = 1e7;
/// The range of `scale`.
pub const SCALE_RANGE: (f32, f32) = (1e-6, 1e6);
/// The largest magnitude of a `rotate_deg` angle.
pub const MAX_ANGLE_DEG: f32 = 3600.0;
/// The largest environment `intensity`.
pub const MAX_INTENSITY: f32 = 1e6;

/// `value` in `lo..=hi` (finite), or a [`SceneError::Field`] naming the file and key.
fn check_range(origin: &str, field: &str, value: f32, lo: f32, hi: f32) -> Result<(), SceneError> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(SceneError::field(
            origin,
            field,
            value,
            format!("a finite number from {lo} to {hi}"),
        ))
    }
}

fn check_vector(
    origin: &str,
    field: &str,
    v: [f32; 3],
    lo: f32,
    hi: f32,
) -> Result<(), SceneError> {
    for (axis, value) in ["x", "y", "z"].iter().zip(v) {
        check_range(origin, &format!("{field}.{axis}"), value, lo, hi)?;
    }
    Ok(())
}

/// The ranges of a placement (`translate`, `scale`, `rotate_deg`) of `[section]`.
fn check_placement(
    origin: &str,
    section: &str,
    translate: [f32; 3],
    scale: f32,
    rotate_deg: [f32; 3],
) -> Result<(), SceneError> {
    let m = MAX_COORDINATE;
    check_vector(origin, &format!("{section} translate"), translate, -m, m)?;
    let (lo, hi) = SCALE_RANGE;
    check_range(origin, &format!("{section} scale"), scale, lo, hi)?;
    let a = MAX_ANGLE_DEG;
    check_vector(origin, &format!("{section} rotate_deg"), rotate_deg, -a, a)
}

/// The camera keys one by one, so that each fault names its key.
fn check_camera(origin: &str, c: &CameraSection) -> Result<(), SceneError> {
    let m = MAX_COORDINATE;
    check_vector(origin, "[camera] eye", c.eye, -m, m)?;
    check_vector(origin, "[camera] target", c.target, -m, m)?;
    check_vector(origin, "[camera] up", c.up, -m, m)?;
    if !(c.fov_y_deg > 0.0 && c.fov_y_deg < 180.0) {
        return Err(SceneError::field(
            origin,
            "[camera] fov_y_deg",
            c.fov_y_deg,
            "a vertical field of view strictly between 0 and 180 degrees",
        ));
    }
    if !(c.near >= MIN_NEAR && c.near <= MAX_COORDINATE) {
        return Err(SceneError::field(
            origin,
            "[camera] near",
            c.near,
            format!("a near-plane distance from {MIN_NEAR} to {MAX_COORDINATE}"),
        ));
    }
    if !(c.far > c.near && c.far <= MAX_FAR_OVER_NEAR * c.near && c.far <= MAX_COORDINATE) {
        return Err(SceneError::field(
            origin,
            "[camera] far",
            c.far,
            format!(
                "a far-plane distance greater than near ({}), at most {MAX_FAR_OVER_NEAR} × near and at most {MAX_COORDINATE}",
                c.near
            ),
        ));
    }
    let (eye, target, up) = (Vec3::from(c.eye), Vec3::from(c.target), Vec3::from(c.up));
    if (target - eye).length() <= 1e-6 * (1.0 + eye.abs().max_element()) {
        return Err(SceneError::field(
            origin,
            "[camera] target",
            format!("{target}"),
            "a point different from the eye",
        ));
    }
    let look = (target - eye).normalize();
    if up.length() == 0.0 || look.cross(up.normalize()).length() < 1e-6 {
        return Err(SceneError::field(
            origin,
            "[camera] up",
            format!("{up}"),
            "a non-zero direction not parallel to target − eye",
        ));
    }
    Ok(())
}

fn build(name: &str, text: &str, base: &Path, origin: &str) -> Result<LoadedScene, SceneError> {
    let (file, refractor_sections) = parse_scene_file(text, origin)?;
    check_camera(origin, &file.camera)?;
    check_range(
        origin,
        "[environment] intensity",
        file.environment.intensity,
        0.0,
        MAX_INTENSITY,
    )?;
    for (k, object) in file.objects.iter().enumerate() {
        let section = format!("objects[{k}]");
        check_placement(
            origin,
            &section,
            object.translate,
            object.scale,
            object.rotate_deg,
        )?;
        if let Some(color) = object.color {
            check_vector(origin, &format!("{section} color"), color, 0.0, 1.0)?;
        }
    }
    let mut warnings = Vec::new();
    let mut refractors = Vec::new();
    for (section, r) in refractor_sections {
        refractors.push(build_refractor(origin, &section, &r, base, &mut warnings)?);
    }

    let mut environment_file = None;
    let environment = match &file.environment.file {
        None => Environment::Procedural,
        Some(env) => {
            let path = base.join(env);
            environment_file = Some(path.canonicalize().unwrap_or_else(|_| path.clone()));
            let (map, report) = load_latlong(&path)?;
            if report.negative_clamped + report.non_finite_replaced > 0 {
                warnings.push(format!(
                    "{}: clamped {} negative and {} non-finite texel values to 0",
                    path.display(),
                    report.negative_clamped,
                    report.non_finite_replaced
                ));
            }
            Environment::LatLong {
                map,
                intensity: file.environment.intensity,
            }
        }
    };

    let mut objects = Vec::new();
    for (k, object) in file.objects.iter().enumerate() {
        let (mut mesh, _) =
            load_mesh_spec(&object.mesh, object.normalize, base, origin, &mut warnings)?;
        mesh.transform(&affine(object.translate, object.scale, object.rotate_deg));
        let albedo = match object.texture.as_deref() {
            None => Albedo::Constant(object.color.map_or(Vec3::splat(0.6), Vec3::from)),
            Some("checker") => Albedo::Checker {
                a: Vec3::splat(0.8),
                b: Vec3::splat(0.1),
                squares: 8.0,
            },
            Some("color-chart") => Albedo::ColorChart,
            Some("wood") => Albedo::WOOD,
            Some(other) => {
                return Err(SceneError::field(
                    origin,
                    format!("objects[{k}].texture"),
                    format!("\"{other}\""),
                    "\"checker\", \"color-chart\" or \"wood\"",
                ));
            }
        };
        let section = format!("objects[{k}]");
        let material = match parse_conductor(
            origin,
            &section,
            "diffuse",
            object.material.as_deref(),
            object.eta,
            object.k,
        )? {
            Some(conductor) => Material::Conductor(conductor),
            None => Material::Diffuse(albedo),
        };
        let roughness = match object.roughness {
            Some(r) if !matches!(material, Material::Conductor(_)) => {
                return Err(SceneError::field(
                    origin,
                    format!("{section}.roughness"),
                    r,
                    "roughness only on a conductor (a diffuse surface has none)",
                ));
            }
            Some(r) => check_roughness(origin, &section, r)?,
            None => 0.0,
        };
        let mut object = Object::new(mesh, material)?;
        object.set_roughness(roughness)?;
        objects.push(object);
    }

    let c = &file.camera;
    let camera = CameraDesc {
        eye: Vec3::from(c.eye),
        target: Vec3::from(c.target),
        up: Vec3::from(c.up),
        fov_y: c.fov_y_deg.to_radians(),
        near: c.near,
        far: c.far,
        ..CameraDesc::default()
    };
    let mut scene =
        Scene::with_refractors(name, refractors, environment).map_err(|err| SceneError::Parse {
            origin: origin.to_owned(),
            message: err.to_string(),
        })?;
    scene.objects = objects;
    scene.camera = camera;
    scene.environment_file = environment_file;
    Ok(LoadedScene { scene, warnings })
}

/// The refractor of section `section` (`[refractor]` or `refractor[k]`): its ranges checked,
/// its mesh loaded and placed, its material, `d_N` (with warnings for vertices it missed).
fn build_refractor(
    origin: &str,
    section: &str,
    r: &RefractorSection,
    base: &Path,
    warnings: &mut Vec<String>,
) -> Result<Refractor, SceneError> {
    check_placement(origin, section, r.translate, r.scale, r.rotate_deg)?;
    refract_scene::scene::check_ior(r.ior).map_err(|_| {
        SceneError::field(
            origin,
            format!("{section} ior"),
            r.ior,
            refract_scene::scene::IOR_EXPECTED,
        )
    })?;
    let attenuation = match (r.attenuation_color, r.attenuation_distance) {
        (None, None) => None,
        (Some(color), Some(distance)) => {
            let field = |name: &str, value: String, expected: &str| {
                SceneError::field(origin, format!("{section} {name}"), value, expected)
            };
            Some(
                refract_scene::Attenuation::new(Vec3::from(color), distance).map_err(|_| {
                    if Vec3::from(color).cmpgt(Vec3::ZERO).all()
                        && Vec3::from(color).cmple(Vec3::ONE).all()
                    {
                        field(
                            "attenuation_distance",
                            distance.to_string(),
                            refract_scene::scene::ATTENUATION_DISTANCE_EXPECTED,
                        )
                    } else {
                        field(
                            "attenuation_color",
                            format!("{color:?}"),
                            refract_scene::scene::ATTENUATION_COLOR_EXPECTED,
                        )
                    }
                })?,
            )
        }
        _ => {
            return Err(SceneError::field(
                origin,
                format!("{section} attenuation_color/attenuation_distance"),
                "one of the two",
                "both keys, or neither",
            ));
        }
    };
    let (mesh, glass) = load_mesh_spec(&r.mesh, r.normalize, base, origin, warnings)?;
    let mut mesh = mesh;
    mesh.transform(&affine(r.translate, r.scale, r.rotate_deg));
    // Warnings name the section when the file has several refractors.
    let label = if section.starts_with('[') {
        String::new()
    } else {
        format!("{section}: ")
    };
    let ior = r.ior;
    let (glass_ior, glass_thickness, glass_attenuation, glass_roughness, glass_abbe) = glass
        .map_or((None, None, None, None, None), |g| {
            (g.ior, g.thickness, g.attenuation, g.roughness, g.abbe)
        });
    if let Some(glass) = glass_ior.filter(|g| (g - ior).abs() > 1e-6) {
        warnings.push(format!(
            "{label}the glTF material's IOR is {glass}; the scene's ior = {ior} is used"
        ));
    }
    let conductor = parse_conductor(origin, section, "glass", r.material.as_deref(), r.eta, r.k)?;
    if conductor.is_some() && attenuation.is_some() {
        return Err(SceneError::field(
            origin,
            format!("{section} attenuation_color"),
            "given for a conductor",
            "absorption only for glass (a conductor has no inside)",
        ));
    }
    // The section's attenuation keys, else the glTF material's KHR_materials_volume.
    let attenuation = match (attenuation, glass_attenuation) {
        (Some(a), _) => Some(a),
        (None, Some((color, distance))) if conductor.is_none() => Some(gltf_attenuation(
            origin,
            &format!("{section} mesh"),
            color,
            distance * r.scale,
        )?),
        _ => None,
    };
    // The section's roughness, else the glTF material's roughnessFactor.
    let roughness = match r.roughness {
        Some(value) => check_roughness(origin, section, value)?,
        None => glass_roughness.unwrap_or(0.0),
    };
    // The section's abbe or dispersion, else the glTF material's KHR_materials_dispersion.
    let abbe = match (r.abbe, r.dispersion) {
        (Some(_), Some(_)) => {
            return Err(SceneError::field(
                origin,
                format!("{section} abbe"),
                "given with dispersion",
                "one of abbe (V_d) and dispersion (20 / V_d)",
            ));
        }
        (Some(abbe), None) => check_abbe(origin, section, "abbe", abbe)?,
        (None, Some(d)) => check_abbe(origin, section, "dispersion", dispersion_to_abbe(d))?,
        (None, None) => glass_abbe.unwrap_or(f32::INFINITY),
    };
    if abbe.is_finite() && conductor.is_some() {
        return Err(SceneError::field(
            origin,
            format!("{section} abbe"),
            abbe,
            "dispersion only for glass (a conductor does not refract)",
        ));
    }
    let mut refractor = Refractor::new(mesh, ior)?;
    refractor.set_conductor(conductor);
    refractor.set_attenuation(attenuation);
    refractor.set_roughness(roughness)?;
    refractor.set_abbe(abbe)?;
    // KHR_materials_volume: the node's transform applies to the thickness, so does ours.
    refractor.set_volume_thickness(glass_thickness.map(|d| d * r.scale));
    warn_of_d_n(&label, &refractor, warnings);
    Ok(refractor)
}

/// The warnings of `refractor`'s `d_N` (vertices whose normal ray missed or crossed too many
/// triangles), each prefixed by `label`.
fn warn_of_d_n(label: &str, refractor: &Refractor, warnings: &mut Vec<String>) {
    let d_n = refractor.normal_distances();
    // d_N serves refraction only: a conductor (an open mirror) has no use for it.
    if d_n.misses > 0 && refractor.is_dielectric() {
        warnings.push(format!(
            "{label}d_N: {} of {} vertices missed (an open mesh, or a ray along an edge); they use {:.4}",
            d_n.misses,
            d_n.values.len(),
            d_n.fallback
        ));
    }
    if d_n.over_budget > 0 {
        warnings.push(format!(
            "{label}d_N: {} of {} vertices' rays crossed more than {} triangles (near-coincident \
             triangles); they use {:.4}",
            d_n.over_budget,
            d_n.values.len(),
            refract_geometry::distance_along_normal::RAY_BUDGET,
            d_n.fallback
        ));
    }
}

/// What a glTF material says about the glass: its IOR and its volume thickness in the
/// normalised mesh's units (before the section's own `scale`).
struct GlassFacts {
    ior: Option<f32>,
    thickness: Option<f32>,
    /// `attenuationColor` and `attenuationDistance` (normalised like the thickness).
    attenuation: Option<(Vec3, f32)>,
    /// `roughnessFactor` (glTF's default 1 when the material does not give one).
    roughness: Option<f32>,
    /// The Abbe number of `KHR_materials_dispersion` (`None`: the extension is absent).
    abbe: Option<f32>,
}

/// A glTF material's `KHR_materials_volume` absorption as an [`refract_scene::Attenuation`],
/// or an error naming `field` of `origin` when it is out of range.
fn gltf_attenuation(
    origin: &str,
    field: &str,
    color: Vec3,
    distance: f32,
) -> Result<refract_scene::Attenuation, SceneError> {
    refract_scene::Attenuation::new(color, distance).map_err(|_| {
        SceneError::field(
            origin,
            format!("{field}: KHR_materials_volume attenuationColor/attenuationDistance"),
            format!("{color:?} / {distance}"),
            format!(
                "{}; {}",
                refract_scene::scene::ATTENUATION_COLOR_EXPECTED,
                refract_scene::scene::ATTENUATION_DISTANCE_EXPECTED
            ),
        )
    })
}

fn load_mesh_spec(
    spec: &str,
    normalize: bool,
    base: &Path,
    origin: &str,
    warnings: &mut Vec<String>,
) -> Result<(Mesh, Option<GlassFacts>), SceneError> {
    let geometry = |source| SceneError::Geometry {
        origin: origin.to_owned(),
        source,
    };
    if spec.starts_with(builtin::PREFIX) {
        let mut mesh = builtin::mesh(spec).map_err(geometry)?;
        if normalize {
            mesh.normalize_to_unit_sphere();
        }
        return Ok((mesh, None));
    }
    let path = base.join(spec);
    let loaded = load_mesh(
        &path,
        &LoadOptions {
            normalize,
            ..LoadOptions::default()
        },
    )
    .map_err(geometry)?;
    warnings.extend(
        loaded
            .report
            .warnings
            .iter()
            .map(|w| format!("{}: {w}", path.display())),
    );
    let scale = loaded
        .report
        .normalization
        .matrix3
        .determinant()
        .abs()
        .cbrt();
    let glass = loaded.material.map(|m| GlassFacts {
        ior: m.ior,
        thickness: m.thickness.map(|d| d * scale),
        attenuation: m.attenuation.map(|(color, d)| (color, d * scale)),
        roughness: Some(m.roughness),
        abbe: m.abbe,
    });
    Ok((loaded.mesh, glass))
}

/// A `.gltf`/`.glb` file as a scene (`docs/scenes.md`, "glTF files as scenes"): every part
/// whose material transmits (`KHR_materials_transmission` above 0) is a refractor with the
/// material's `KHR_materials_ior` (glTF's default 1.5), `KHR_materials_volume` thickness and
/// attenuation; every other part is a diffuse object of its `baseColorFactor`; the first
/// perspective camera is the camera (else the built-in scenes' camera). The whole scene is
/// moved and scaled together so that the refractors' bounding sphere is the unit sphere, as
/// the built-in scenes' refractors are. Nested glass (water in a glass) nests by geometry
/// ([`Scene::with_refractors`]); the environment is the procedural sky.
fn build_gltf(name: &str, path: &Path) -> Result<LoadedScene, SceneError> {
    let origin = path.display().to_string();
    let loaded = load_gltf_scene(path).map_err(|source| SceneError::Geometry {
        origin: origin.clone(),
        source,
    })?;
    let mut warnings: Vec<String> = loaded
        .notes
        .iter()
        .map(|note| format!("{origin}: {note}"))
        .collect();
    for part in &loaded.parts {
        warnings.extend(
            part.report
                .warnings
                .iter()
                .map(|w| format!("{origin}: {}: {w}", part.label)),
        );
    }
    // One transform for every part: the refractors' joint bounding sphere to the unit sphere.
    let glass_positions = loaded
        .parts
        .iter()
        .filter(|p| p.glass.is_some())
        .flat_map(|p| p.mesh.positions.iter().copied());
    let (lo, hi) = glass_positions.clone().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    if lo.x > hi.x {
        return Err(SceneError::Parse {
            origin,
            message: format!(
                "no transmissive material (KHR_materials_transmission above 0) among its {} \
                 parts: a glTF read as a scene needs a glass part to refract through",
                loaded.parts.len()
            ),
        });
    }
    let center = 0.5 * (lo + hi);
    let radius = glass_positions
        .map(|p| f64::from(p.distance(center)))
        .fold(0.0_f64, f64::max) as f32;
    let scale = if radius > 0.0 { 1.0 / radius } else { 1.0 };
    let normalization =
        Affine3A::from_scale(Vec3::splat(scale)) * Affine3A::from_translation(-center);

    let mut refractors = Vec::new();
    let mut objects = Vec::new();
    for part in loaded.parts {
        let mut mesh = part.mesh;
        mesh.transform(&normalization);
        let section = part.label;
        match part.glass {
            Some(glass) => {
                let ior = glass.ior.unwrap_or(DEFAULT_GLTF_IOR);
                refract_scene::scene::check_ior(ior).map_err(|_| {
                    SceneError::field(
                        &origin,
                        format!("{section}: KHR_materials_ior ior"),
                        ior,
                        refract_scene::scene::IOR_EXPECTED,
                    )
                })?;
                let attenuation = glass
                    .attenuation
                    .map(|(color, distance)| {
                        gltf_attenuation(&origin, &section, color, distance * scale)
                    })
                    .transpose()?;
                let mut refractor = Refractor::new(mesh, ior)?;
                refractor.set_attenuation(attenuation);
                refractor.set_volume_thickness(glass.thickness.map(|d| d * scale));
                refractor.set_roughness(glass.roughness).map_err(|_| {
                    SceneError::field(
                        &origin,
                        format!("{section}: pbrMetallicRoughness roughnessFactor"),
                        glass.roughness,
                        refract_scene::scene::ROUGHNESS_EXPECTED,
                    )
                })?;
                if let Some(abbe) = glass.abbe {
                    refractor.set_abbe(abbe).map_err(|_| {
                        SceneError::field(
                            &origin,
                            format!("{section}: KHR_materials_dispersion dispersion"),
                            20.0 / abbe,
                            "a dispersion from 0 (none) to 20 (20 / Abbe number)",
                        )
                    })?;
                }
                let label = format!("{origin}: refractor[{}] ({section}): ", refractors.len());
                warn_of_d_n(&label, &refractor, &mut warnings);
                refractors.push(refractor);
            }
            None => {
                let color = part.base_color.clamp(Vec3::ZERO, Vec3::ONE);
                objects.push(Object::new(
                    mesh,
                    Material::Diffuse(Albedo::Constant(color)),
                )?);
            }
        }
    }

    let camera = match loaded.camera {
        None => CameraDesc::default(),
        Some(c) => {
            let to_world = normalization * Affine3A::from_mat4(c.camera_to_world);
            let eye = to_world.transform_point3(Vec3::ZERO);
            let look = to_world.transform_vector3(-Vec3::Z).normalize_or_zero();
            let up = to_world.transform_vector3(Vec3::Y).normalize_or_zero();
            let near = c.near * scale;
            // An infinite projection: twice the distance to the furthest vertex of the scene.
            let furthest = refractors
                .iter()
                .map(Refractor::mesh)
                .chain(objects.iter().map(Object::mesh))
                .flat_map(|m| m.positions.iter())
                .map(|p| p.distance(eye))
                .fold(0.0_f32, f32::max);
            let far = c.far.map_or(2.0 * furthest, |f| f * scale).max(2.0 * near);
            let section = CameraSection {
                eye: eye.into(),
                target: (eye + look).into(),
                up: up.into(),
                fov_y_deg: c.fov_y.to_degrees(),
                near,
                far,
            };
            check_camera(
                &format!("{origin} (its camera, scaled by {scale})"),
                &section,
            )?;
            CameraDesc {
                eye,
                target: eye + look,
                up,
                fov_y: c.fov_y,
                near,
                far,
                ..CameraDesc::default()
            }
        }
    };
    let mut scene =
        Scene::with_refractors(name, refractors, Environment::Procedural).map_err(|err| {
            SceneError::Parse {
                origin: origin.clone(),
                message: err.to_string(),
            }
        })?;
    scene.objects = objects;
    scene.camera = camera;
    Ok(LoadedScene { scene, warnings })
}

/// The IOR of a glTF glass material without `KHR_materials_ior` (the extension's default).
const DEFAULT_GLTF_IOR: f32 = 1.5;

/// `x' = T · R_xyz · S · x`: scale, then XYZ Euler rotation, then translation.
fn affine(translate: [f32; 3], scale: f32, rotate_deg: [f32; 3]) -> Affine3A {
    let [rx, ry, rz] = rotate_deg.map(f32::to_radians);
    Affine3A::from_scale_rotation_translation(
        Vec3::splat(scale),
        Quat::from_euler(EulerRot::XYZ, rx, ry, rz),
        Vec3::from(translate),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_scenes_load() {
        for (name, _, _) in BUILTIN_SCENES {
            let scene = load_scene(name).expect(name).scene;
            assert_eq!(scene.name, name);
            assert!(scene.refractor.d_n().iter().all(|d| d.is_finite()));
        }
    }

    /// `abbe` and `dispersion` (issue 52): either sets the Abbe number (`dispersion = 20 / V_d`),
    /// both at once, a value out of range or dispersion on a conductor is an error naming the
    /// key; `prism` disperses with V_d = 30 and no other built-in scene does.
    #[test]
    fn abbe_and_dispersion_are_read_and_checked() {
        let load = |extra: &str| {
            let text = format!("[refractor]\nmesh = \"builtin:sphere\"\n{extra}");
            load_scene_str("d", &text, Path::new("."), "d.toml").map(|l| l.scene)
        };
        let abbe = |extra: &str| load(extra).expect(extra).refractor.abbe();
        assert_eq!(abbe(""), f32::INFINITY);
        assert_eq!(abbe("abbe = 40.0\n"), 40.0);
        assert_eq!(abbe("dispersion = 0.5\n"), 40.0);
        assert_eq!(abbe("dispersion = 0.0\n"), f32::INFINITY);
        assert_eq!(abbe("abbe = inf\n"), f32::INFINITY);
        for (bad, key) in [
            ("abbe = 0.5\n", "abbe"),
            ("abbe = nan\n", "abbe"),
            ("dispersion = -1.0\n", "dispersion"),
            ("dispersion = 25.0\n", "dispersion"),
            ("abbe = 30.0\ndispersion = 0.5\n", "abbe"),
            ("material = \"gold\"\nabbe = 30.0\n", "abbe"),
        ] {
            let err = refract_scene::full_message(&load(bad).expect_err(bad));
            assert!(err.contains("d.toml") && err.contains(key), "{bad}: {err}");
        }
        for (name, _, _) in BUILTIN_SCENES {
            let scene = load_scene(name).expect(name).scene;
            assert_eq!(scene.has_dispersion(), name == "prism", "{name}");
        }
        assert_eq!(
            load_scene("prism").expect("prism").scene.refractor.abbe(),
            30.0
        );
    }

    /// An open mirror as the specular object misses d_N everywhere; d_N serves refraction only,
    /// so loading it warns about nothing (it warned "49 of 49 vertices missed").
    #[test]
    fn a_mirror_specular_object_has_no_d_n_warning() {
        for name in ["convex-mirror", "adjacent-mirrors"] {
            let loaded = load_scene(name).expect(name);
            assert!(
                loaded.scene.refractor.normal_distances().misses > 0,
                "{name}: open mesh"
            );
            assert!(loaded.warnings.is_empty(), "{name}: {:?}", loaded.warnings);
        }
    }

    /// `[[refractor]]` files load every table, and their errors keep the key and the line.
    #[test]
    fn refractor_arrays_load_and_their_errors_name_the_key() {
        let two = "[[refractor]]\nmesh = \"builtin:sphere\"\n\n[[refractor]]\nmesh = \"builtin:sphere\"\nscale = 0.5\nior = 1.33\n";
        let scene = load_scene_str("two", two, Path::new("."), "two.toml")
            .expect("two refractors")
            .scene;
        assert_eq!(scene.refractor_count(), 2);
        assert_eq!(
            scene.outside_ior(1),
            1.5,
            "the small sphere lies in the large one"
        );
        let wrong = two.replace("ior = 1.33", "ior = \"water\"");
        let err = load_scene_str("wrong", &wrong, Path::new("."), "wrong.toml")
            .expect_err("wrong type")
            .to_string();
        assert!(
            err.contains("wrong.toml") && err.contains("ior") && err.contains("line 7"),
            "{err}"
        );
        let half = two.replace("ior = 1.33", "attenuation_distance = 2.0");
        let err = load_scene_str("half", &half, Path::new("."), "half.toml")
            .expect_err("attenuation without its colour")
            .to_string();
        assert!(
            err.contains("refractor[1]") && err.contains("both"),
            "{err}"
        );
    }

    /// `roughness` (issue 52): read on refractors and conductor objects, in [0, 1], refused on
    /// a diffuse object; `rough-glass` has the four roughnesses its description names.
    #[test]
    fn roughness_is_read_checked_and_refused_on_diffuse_objects() {
        let load = |text: &str| load_scene_str("r", text, Path::new("."), "r.toml");
        let glass = "[refractor]\nmesh = \"builtin:sphere\"\nroughness = 0.25\n";
        assert_eq!(
            load(glass)
                .expect("rough glass")
                .scene
                .refractor
                .roughness(),
            0.25
        );
        for bad in ["-0.1", "1.5", "nan"] {
            let err = load(&glass.replace("0.25", bad))
                .expect_err("out of range")
                .to_string();
            assert!(
                err.contains("r.toml") && err.contains("roughness") && err.contains("from 0"),
                "{bad}: {err}"
            );
        }
        let metal = "[refractor]\nmesh = \"builtin:sphere\"\n\n[[objects]]\nmesh = \"builtin:plane\"\nmaterial = \"gold\"\nroughness = 0.4\n";
        let scene = load(metal).expect("rough gold").scene;
        assert_eq!(scene.objects[0].roughness(), 0.4);
        assert!(scene.has_roughness());
        let err = load(&metal.replace("material = \"gold\"\n", ""))
            .expect_err("a rough diffuse object")
            .to_string();
        assert!(
            err.contains("objects[0].roughness") && err.contains("conductor"),
            "{err}"
        );
        let rough = load_scene("rough-glass").expect("rough-glass").scene;
        let roughness: Vec<f32> = rough.refractors().map(|r| r.roughness()).collect();
        assert_eq!(roughness, [0.0, 0.1, 0.3, 0.6]);
        assert!(!load_scene("chart").expect("chart").scene.has_roughness());
    }

    #[test]
    fn scene_file_errors_name_the_file_and_key() {
        let dir = tempfile::tempdir().expect("tempdir");
        let write = |name: &str, text: &str| {
            let path = dir.path().join(name);
            std::fs::write(&path, text).expect("write");
            path.display().to_string()
        };
        let unknown = write(
            "unknown.toml",
            "[refractor]\nmesh = \"builtin:sphere\"\nshininess = 3\n",
        );
        let err = load_scene(&unknown).expect_err("unknown key").to_string();
        assert!(
            err.contains("unknown.toml") && err.contains("shininess"),
            "{err}"
        );
        let wrong = write(
            "wrong.toml",
            "[refractor]\nmesh = \"builtin:sphere\"\nior = \"glass\"\n",
        );
        let err = load_scene(&wrong).expect_err("wrong type").to_string();
        assert!(err.contains("wrong.toml") && err.contains("ior"), "{err}");
        let missing = write("missing.toml", "[refractor]\nmesh = \"nowhere.obj\"\n");
        let err = refract_scene::full_message(&load_scene(&missing).expect_err("missing mesh"));
        assert!(err.contains("nowhere.obj"), "{err}");
        let bad_ior = write(
            "bad_ior.toml",
            "[refractor]\nmesh = \"builtin:sphere\"\nior = -1.0\n",
        );
        let err = refract_scene::full_message(&load_scene(&bad_ior).expect_err("bad ior"));
        assert!(err.contains("bad_ior.toml") && err.contains("ior"), "{err}");
        let err = load_scene("teapot-in-space")
            .expect_err("unknown")
            .to_string();
        assert!(err.contains("sphere, torus, lens"), "{err}");
        let texture = write(
            "texture.toml",
            "[refractor]\nmesh = \"builtin:sphere\"\n[[objects]]\nmesh = \"builtin:plane\"\ntexture = \"marble\"\n",
        );
        let err = load_scene(&texture).expect_err("texture").to_string();
        assert!(
            err.contains("objects[0].texture") && err.contains("wood"),
            "{err}"
        );
    }

    /// `[camera] near` and `far` reach the scene's camera (the NG texture's depth range,
    /// Wyman 2005b §4.3's `d_far`); the defaults are the camera's.
    #[test]
    fn camera_clip_planes_are_read() {
        let chart = load_scene("chart").expect("chart").scene;
        assert_eq!((chart.camera.near, chart.camera.far), (0.05, 12.0));
        assert_eq!(chart.objects.len(), 2);
        assert_eq!(chart.objects[1].material, Material::Diffuse(Albedo::WOOD));
        let sphere = load_scene("sphere").expect("sphere").scene;
        let d = CameraDesc::default();
        assert_eq!((sphere.camera.near, sphere.camera.far), (d.near, d.far));
    }

    /// Every numeric field has a range checked where the file is parsed; each fault is one
    /// error naming the file and the key (before: panics inside obvhs for non-finite or huge
    /// transforms, NaN images for a NaN intensity, a misleading "open mesh" for scale 0).
    #[test]
    fn out_of_range_numbers_are_errors_naming_file_and_key() {
        let dir = tempfile::tempdir().expect("tempdir");
        let cases = [
            (
                "[refractor]\nmesh = \"builtin:sphere\"\nscale = nan\n",
                "scale",
            ),
            (
                "[refractor]\nmesh = \"builtin:sphere\"\nscale = 0.0\n",
                "scale",
            ),
            (
                "[refractor]\nmesh = \"builtin:sphere\"\nscale = 1e21\n",
                "scale",
            ),
            (
                "[refractor]\nmesh = \"builtin:sphere\"\ntranslate = [inf, 0.0, 0.0]\n",
                "translate.x",
            ),
            (
                "[refractor]\nmesh = \"builtin:sphere\"\ntranslate = [0.0, 1e39, 0.0]\n",
                "translate",
            ),
            (
                "[refractor]\nmesh = \"builtin:sphere\"\nrotate_deg = [0.0, 0.0, nan]\n",
                "rotate_deg.z",
            ),
            (
                "[refractor]\nmesh = \"builtin:sphere\"\nior = 1e20\n",
                "ior",
            ),
            (
                "[environment]\nintensity = nan\n[refractor]\nmesh = \"builtin:sphere\"\n",
                "intensity",
            ),
            (
                "[environment]\nintensity = -1.0\n[refractor]\nmesh = \"builtin:sphere\"\n",
                "intensity",
            ),
            (
                "[environment]\nintensity = inf\n[refractor]\nmesh = \"builtin:sphere\"\n",
                "intensity",
            ),
            (
                "[refractor]\nmesh = \"builtin:sphere\"\n[[objects]]\nmesh = \"builtin:plane\"\nscale = inf\n",
                "objects[0] scale",
            ),
            (
                "[refractor]\nmesh = \"builtin:sphere\"\n[[objects]]\nmesh = \"builtin:plane\"\ncolor = [nan, 0.5, 0.5]\n",
                "objects[0] color.x",
            ),
            (
                "[camera]\nfov_y_deg = 0.0\n[refractor]\nmesh = \"builtin:sphere\"\n",
                "fov_y_deg",
            ),
            (
                "[camera]\nnear = 0.0\n[refractor]\nmesh = \"builtin:sphere\"\n",
                "[camera] near",
            ),
            (
                "[camera]\nnear = nan\n[refractor]\nmesh = \"builtin:sphere\"\n",
                "[camera] near",
            ),
            (
                "[camera]\nnear = 1.0\nfar = 0.5\n[refractor]\nmesh = \"builtin:sphere\"\n",
                "[camera] far",
            ),
            (
                "[camera]\nnear = 1e-4\nfar = 1e5\n[refractor]\nmesh = \"builtin:sphere\"\n",
                "[camera] far",
            ),
            (
                "[camera]\nfar = inf\n[refractor]\nmesh = \"builtin:sphere\"\n",
                "[camera] far",
            ),
            (
                "[camera]\neye = [0.0, 0.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\n[refractor]\nmesh = \"builtin:sphere\"\n",
                "[camera] target",
            ),
            (
                "[camera]\nup = [0.0, 0.0, 1.0]\n[refractor]\nmesh = \"builtin:sphere\"\n",
                "[camera] up",
            ),
            (
                "[camera]\neye = [nan, 0.0, 3.0]\n[refractor]\nmesh = \"builtin:sphere\"\n",
                "[camera] eye.x",
            ),
        ];
        for (k, (text, key)) in cases.iter().enumerate() {
            let path = dir.path().join(format!("case{k}.toml"));
            std::fs::write(&path, text).expect("write");
            let err = load_scene(&path).expect_err(text);
            let message = err.to_string();
            assert!(
                message.contains(&format!("case{k}.toml")) && message.contains(key),
                "{text}: {message}"
            );
        }
    }

    /// A mesh kept at its file's scale (`normalize = false`) with coordinates of 1e30 is an
    /// error naming the limit, not a panic inside the BVH builder (exit 101 before).
    #[test]
    fn huge_unnormalised_meshes_are_errors() {
        let dir = tempfile::tempdir().expect("tempdir");
        std::fs::write(
            dir.path().join("huge.obj"),
            "v 0 0 0\nv 1e30 0 0\nv 0 1e30 0\nv 0 0 1e30\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
        )
        .expect("write");
        for section in [
            "[refractor]",
            "[refractor]\nmesh = \"builtin:sphere\"\n[[objects]]",
        ] {
            let path = dir.path().join("scene.toml");
            std::fs::write(
                &path,
                format!("{section}\nmesh = \"huge.obj\"\nnormalize = false\n"),
            )
            .expect("write");
            let err = refract_scene::full_message(&load_scene(&path).expect_err("huge"));
            assert!(err.contains("huge.obj") && err.contains("1e18"), "{err}");
        }
    }

    #[test]
    fn objects_and_transforms_are_read() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("scene.toml");
        std::fs::write(
            &path,
            "[camera]\neye = [0.0, 1.0, 4.0]\nfov_y_deg = 30.0\n\n[refractor]\nmesh = \"builtin:icosphere\"\nior = 1.2\n\
             translate = [0.0, 0.5, 0.0]\nscale = 0.5\n\n[[objects]]\nmesh = \"builtin:plane\"\ntexture = \"checker\"\n\
             translate = [0.0, -1.0, 0.0]\nscale = 3.0\n",
        )
        .expect("write");
        let scene = load_scene(&path).expect("scene").scene;
        assert_eq!(scene.objects.len(), 1);
        let sphere = scene.refractor.mesh().bounding_sphere();
        assert!(
            (sphere.center - Vec3::new(0.0, 0.5, 0.0)).length() < 1e-5
                && (sphere.radius - 0.5).abs() < 1e-5
        );
        assert!((scene.camera.fov_y.to_degrees() - 30.0).abs() < 1e-4);
    }

    /// Materials: named conductors on the refractor and on objects, custom `eta`/`k`, and
    /// errors naming the file, the key and the choices (regression guard for issue 17's
    /// scenes).
    #[test]
    fn materials_are_read_and_checked() {
        use refract_scene::scene::Conductor;
        let load = |text: &str| load_scene_str("m", text, Path::new("."), "m.toml");
        let scene = load(
            "[refractor]\nmesh = \"builtin:sphere\"\nmaterial = \"copper\"\n\
             [[objects]]\nmesh = \"builtin:plane\"\nmaterial = \"mirror\"\n\
             [[objects]]\nmesh = \"builtin:plane\"\nmaterial = \"conductor\"\neta = [0.2, 0.3, 0.4]\nk = [3.0, 2.0, 1.0]\n\
             [[objects]]\nmesh = \"builtin:plane\"\n",
        )
        .expect("materials")
        .scene;
        assert_eq!(scene.refractor.conductor(), Some(Conductor::COPPER));
        assert_eq!(
            scene.objects[0].material,
            Material::Conductor(Conductor::MIRROR)
        );
        assert_eq!(
            scene.objects[2].material,
            Material::Diffuse(Albedo::Constant(Vec3::splat(0.6)))
        );
        let Material::Conductor(custom) = &scene.objects[1].material else {
            panic!("a conductor");
        };
        assert_eq!(custom.k, Vec3::new(3.0, 2.0, 1.0));
        for (text, needle) in [
            (
                "[refractor]\nmesh = \"builtin:sphere\"\nmaterial = \"brass\"\n",
                "gold",
            ),
            (
                "[refractor]\nmesh = \"builtin:sphere\"\nmaterial = \"conductor\"\neta = [0.2, 0.3, 0.4]\n",
                "k = [r, g, b]",
            ),
            (
                "[refractor]\nmesh = \"builtin:sphere\"\nmaterial = \"conductor\"\neta = [0.2, 0.3, 11.0]\nk = [1.0, 1.0, 1.0]\n",
                "eta",
            ),
            (
                "[refractor]\nmesh = \"builtin:sphere\"\n[[objects]]\nmesh = \"builtin:plane\"\neta = [0.2, 0.3, 0.4]\n",
                "objects[0] eta/k",
            ),
        ] {
            let err = refract_scene::full_message(&load(text).expect_err(needle));
            assert!(err.contains("m.toml") && err.contains(needle), "{err}");
        }
    }
}
