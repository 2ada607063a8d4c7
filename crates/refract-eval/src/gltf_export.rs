//! A scene as glTF 2.0, for the engines' own renderers (`refract export --format gltf`).
//!
//! What refract renders, in the form the engines read:
//!
//! * `scene.gltf` + `scene.bin`: every mesh after loading, normalisation and transforms, with
//!   the vertex normals refract renders; the camera (`yfov`, `znear`, `zfar`; the viewport sets
//!   the aspect ratio); every refractor (nodes `refractor`, `refractor-1`, …: [`refractor_name`])
//!   as glass: `KHR_materials_transmission` 1, `KHR_materials_ior`, `KHR_materials_volume` with
//!   the thickness the engine methods use by default (`thickness=auto`: the file's thickness or
//!   the mean `d_N`, in world units, on a node of scale 1) and its attenuation, its roughness,
//!   metalness 0, white. A conductor refractor is a metal of the conductor's normal-incidence
//!   reflectance. glTF has no surrounding medium: a refractor inside another (water in a glass)
//!   keeps its own IOR, which is what the engines refract with.
//! * Opaque objects as `KHR_materials_unlit`: the colour refract shades them with,
//!   `albedo(uv) × (ambient + |N·L| radiance)`, as the base colour texture (the albedo, baked
//!   at [`ALBEDO_TEXELS`]² over the object's uv range, nearest filtering; a constant albedo is
//!   the base colour factor) times `COLOR_0` (the light term at each vertex). Exact on planes
//!   (one normal); per-vertex light on curved objects.
//! * `environment.hdr`: the lat-long environment as refract samples it (times its intensity),
//!   in refract's orientation (`u = atan2(x, −z) / 2π`, `v = acos(y) / π`, Mitsuba's), for the
//!   engines' image-based lighting and background; each engine's page rotates it into its own
//!   convention. A procedural sky is baked at [`BAKED_ENVIRONMENT_WIDTH`] wide.
//! * `position-coded.gltf` (same `scene.bin`): lookup studies. Every opaque object is unlit
//!   with `COLOR_0 = 0.1 + 0.8 (p − lo) / (hi − lo)` over the objects' bounds (recorded in
//!   the scene's `extras.refract.position_code`), so a pixel's colour names the world point it
//!   shows; the glass has `KHR_materials_specular` factor 0 (no Fresnel weight on the
//!   transmitted code); no environment.
//! * `direction-coded.hdr`: the environment `0.5 + 0.4 d` for a pixel that sees direction
//!   `d`, for a second, object-free lookup pass.
//!
//! Everything here is in memory ([`GltfExport`]); [`GltfExport::write`] writes the files.

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec2, Vec3};
use refract_core::environment::latlong_to_direction;
use refract_geometry::Mesh;
use refract_scene::{Albedo, Environment, Material, Refractor, Scene, SceneError};
use serde_json::{Value, json};

use crate::atomic_write::{write_atomically, write_text_atomically};

/// Texels per side of a baked albedo texture.
pub const ALBEDO_TEXELS: u32 = 1024;
/// Width of a baked procedural sky or of `direction-coded.hdr` (height half of it).
pub const BAKED_ENVIRONMENT_WIDTH: u32 = 2048;
/// The position code's offset: codes lie in `[OFFSET, OFFSET + SCALE]`, black is a miss.
pub const POSITION_CODE_OFFSET: f32 = 0.1;
/// The position code's scale.
pub const POSITION_CODE_SCALE: f32 = 0.8;
/// The direction code's scale: `0.5 + DIRECTION_CODE_SCALE · d`.
pub const DIRECTION_CODE_SCALE: f32 = 0.4;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const NEAREST: u32 = 9728;
const CLAMP_TO_EDGE: u32 = 33071;

/// A lat-long image: `width × height` linear RGB texels, row-major from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct LatLongImage {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// The texels.
    pub texels: Vec<Vec3>,
}

/// An RGB8 texture (sRGB-encoded, as glTF's base colour textures are).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// File name beside the glTF.
    pub name: String,
    /// Side in texels.
    pub side: u32,
    /// `side²` RGB8 texels, row-major from the top (uv `(0, 0)` is the first texel).
    pub rgb8: Vec<u8>,
}

/// A scene exported as glTF, in memory.
#[derive(Clone, Debug)]
pub struct GltfExport {
    /// `scene.gltf`.
    pub scene_gltf: Value,
    /// `position-coded.gltf`.
    pub position_coded_gltf: Value,
    /// `scene.bin`, the one buffer of both.
    pub bin: Vec<u8>,
    /// `environment.hdr`.
    pub environment: LatLongImage,
    /// `direction-coded.hdr`.
    pub direction_coded: LatLongImage,
    /// The baked albedo textures.
    pub textures: Vec<Texture>,
}

/// The buffer under construction: views, accessors and bytes.
#[derive(Default)]
struct Buffer {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Buffer {
    /// Appends `values` as a view and an accessor of `kind` (`VEC3`, `VEC2`, `SCALAR`), with
    /// `min`/`max` when `bounds`; returns the accessor's index.
    fn push_f32(&mut self, values: &[f32], kind: &str, components: usize, bounds: bool) -> usize {
        let offset = self.bytes.len();
        self.bytes
            .extend(values.iter().flat_map(|v| v.to_le_bytes()));
        self.views.push(json!({
            "buffer": 0, "byteOffset": offset, "byteLength": values.len() * 4,
            "target": ARRAY_BUFFER,
        }));
        let mut accessor = json!({
            "bufferView": self.views.len() - 1, "componentType": FLOAT,
            "count": values.len() / components, "type": kind,
        });
        if bounds {
            let (mut lo, mut hi) = (
                vec![f32::INFINITY; components],
                vec![f32::NEG_INFINITY; components],
            );
            for chunk in values.chunks_exact(components) {
                for (k, &v) in chunk.iter().enumerate() {
                    lo[k] = lo[k].min(v);
                    hi[k] = hi[k].max(v);
                }
            }
            accessor["min"] = json!(lo);
            accessor["max"] = json!(hi);
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    fn push_vec3(&mut self, values: &[Vec3], bounds: bool) -> usize {
        let flat: Vec<f32> = values.iter().flat_map(|v| v.to_array()).collect();
        self.push_f32(&flat, "VEC3", 3, bounds)
    }

    fn push_indices(&mut self, triangles: &[[u32; 3]]) -> usize {
        let offset = self.bytes.len();
        self.bytes
            .extend(triangles.iter().flatten().flat_map(|i| i.to_le_bytes()));
        self.views.push(json!({
            "buffer": 0, "byteOffset": offset, "byteLength": triangles.len() * 12,
            "target": ELEMENT_ARRAY_BUFFER,
        }));
        self.accessors.push(json!({
            "bufferView": self.views.len() - 1, "componentType": UNSIGNED_INT,
            "count": triangles.len() * 3, "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }
}

/// The accessors of one mesh: what both files share.
struct MeshAccessors {
    position: usize,
    normal: usize,
    indices: usize,
}

impl MeshAccessors {
    fn push(buffer: &mut Buffer, mesh: &Mesh) -> Self {
        Self {
            position: buffer.push_vec3(&mesh.positions, true),
            normal: buffer.push_vec3(&mesh.normals, false),
            indices: buffer.push_indices(&mesh.triangles),
        }
    }

    fn attributes(&self) -> Value {
        json!({ "POSITION": self.position, "NORMAL": self.normal })
    }
}

/// The uv refract shades an object's vertex with: the mesh's uv, or world `(x, z)` without
/// uvs ([`refract_scene::Object::uv_at`]).
fn vertex_uvs(mesh: &Mesh) -> Vec<Vec2> {
    if mesh.uvs.is_empty() {
        mesh.positions.iter().map(|p| Vec2::new(p.x, p.z)).collect()
    } else {
        mesh.uvs.clone()
    }
}

/// Linear to an sRGB-encoded byte.
fn srgb8(linear: f32) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let encoded = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (encoded * 255.0).round() as u8
}

/// `albedo` baked over the uv rectangle `[lo, hi]`: texel `(i, j)` holds the albedo at its
/// centre.
fn bake_albedo(albedo: &Albedo, lo: Vec2, hi: Vec2, name: String) -> Texture {
    let side = ALBEDO_TEXELS;
    let mut rgb8 = Vec::with_capacity((side * side * 3) as usize);
    for j in 0..side {
        for i in 0..side {
            let t = Vec2::new(
                (i as f32 + 0.5) / side as f32,
                (j as f32 + 0.5) / side as f32,
            );
            let c = albedo.at(lo + t * (hi - lo));
            rgb8.extend([srgb8(c.x), srgb8(c.y), srgb8(c.z)]);
        }
    }
    Texture { name, side, rgb8 }
}

/// The camera node's local-to-world transform: refract's view-to-world (its cameras, like
/// glTF's, look along −z with +y up).
fn camera_matrix(scene: &Scene) -> Result<Mat4, SceneError> {
    Ok(scene.camera(1, 1)?.view_to_world())
}

/// The environment as refract samples it, as a lat-long image in refract's orientation.
fn environment_image(environment: &Environment) -> LatLongImage {
    match environment {
        Environment::LatLong { map, intensity } => LatLongImage {
            width: map.width,
            height: map.height,
            texels: map.texels.iter().map(|&t| t * *intensity).collect(),
        },
        other => bake_latlong(BAKED_ENVIRONMENT_WIDTH, |dir| other.radiance(dir)),
    }
}

/// A lat-long image of `width × width/2` texels, each `radiance` along its centre's direction.
fn bake_latlong(width: u32, radiance: impl Fn(Vec3) -> Vec3) -> LatLongImage {
    let height = width / 2;
    let texels = (0..height)
        .flat_map(|j| (0..width).map(move |i| (i, j)))
        .map(|(i, j)| {
            let uv = Vec2::new(
                (i as f32 + 0.5) / width as f32,
                (j as f32 + 0.5) / height as f32,
            );
            radiance(latlong_to_direction(uv))
        })
        .collect();
    LatLongImage {
        width,
        height,
        texels,
    }
}

/// The bounds the position code spans: the opaque objects', or the refractor's when the
/// scene has none; with no zero extent.
pub fn position_code_bounds(scene: &Scene) -> (Vec3, Vec3) {
    let meshes: Vec<&Mesh> = if scene.objects.is_empty() {
        vec![scene.refractor.mesh()]
    } else {
        scene.objects.iter().map(|o| o.mesh()).collect()
    };
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for mesh in meshes {
        let (a, b) = mesh.bounds();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    // A flat object (the chart) has zero extent along one axis: give it one so the code's
    // division is defined (the code is then constant along it).
    let extent = (hi - lo).max(Vec3::splat(1e-3));
    (lo, lo + extent)
}

/// The position code of a world point: `OFFSET + SCALE (p − lo) / (hi − lo)`.
pub fn position_code(p_ws: Vec3, (lo, hi): (Vec3, Vec3)) -> Vec3 {
    Vec3::splat(POSITION_CODE_OFFSET) + POSITION_CODE_SCALE * (p_ws - lo) / (hi - lo)
}

/// The world point a position code names (the inverse of [`position_code`]).
pub fn position_from_code(code: Vec3, (lo, hi): (Vec3, Vec3)) -> Vec3 {
    lo + (code - Vec3::splat(POSITION_CODE_OFFSET)) / POSITION_CODE_SCALE * (hi - lo)
}

/// The name of refractor `index`'s mesh, node and material: `refractor` for the first,
/// `refractor-1`, `refractor-2`, … for the others.
pub fn refractor_name(index: usize) -> String {
    match index {
        0 => "refractor".to_owned(),
        k => format!("refractor-{k}"),
    }
}

/// The glass material of a dielectric refractor (`specular`: the `KHR_materials_specular`
/// factor, 1 in the colour file, 0 in the position-coded one). glTF has no medium around a
/// refractor: a refractor inside another keeps its own index, as the engines read it.
fn glass_material(name: &str, refractor: &Refractor, specular: f32) -> Value {
    let mut volume = json!({ "thicknessFactor": refractor.auto_thickness() });
    if let Some(a) = refractor.attenuation() {
        volume["attenuationColor"] = json!(a.color.to_array());
        volume["attenuationDistance"] = json!(a.distance);
    }
    let mut extensions = json!({
        "KHR_materials_transmission": { "transmissionFactor": 1.0 },
        "KHR_materials_ior": { "ior": refractor.ior() },
        "KHR_materials_volume": volume,
    });
    if specular != 1.0 {
        extensions["KHR_materials_specular"] = json!({ "specularFactor": specular });
    }
    if refractor.is_dispersive() {
        extensions["KHR_materials_dispersion"] = json!({ "dispersion": 20.0 / refractor.abbe() });
    }
    json!({
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [1.0, 1.0, 1.0, 1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": refractor.roughness(),
        },
        "extensions": extensions,
    })
}

/// A conductor's normal-incidence reflectance per channel: `((η−1)² + k²) / ((η+1)² + k²)`.
fn conductor_f0(eta: Vec3, k: Vec3) -> Vec3 {
    let k2 = k * k;
    ((eta - 1.0) * (eta - 1.0) + k2) / ((eta + 1.0) * (eta + 1.0) + k2)
}

fn metal_material(name: &str, f0: Vec3, roughness: f32) -> Value {
    json!({
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [f0.x, f0.y, f0.z, 1.0],
            "metallicFactor": 1.0,
            "roughnessFactor": roughness,
        },
    })
}

fn unlit_material(name: &str, base_color: Vec3, texture: Option<usize>) -> Value {
    let mut pbr = json!({
        "baseColorFactor": [base_color.x, base_color.y, base_color.z, 1.0],
        "metallicFactor": 0.0,
        "roughnessFactor": 1.0,
    });
    if let Some(index) = texture {
        pbr["baseColorTexture"] = json!({ "index": index });
    }
    json!({
        "name": name,
        "pbrMetallicRoughness": pbr,
        "extensions": { "KHR_materials_unlit": {} },
    })
}

/// The two documents' shared top level: asset, scene, nodes (meshes in order, then the
/// camera), camera, buffer, views, accessors.
fn document(
    scene: &Scene,
    buffer: &Buffer,
    meshes: Vec<Value>,
    materials: Vec<Value>,
    extras: Value,
    extensions_used: &[&str],
    camera: Mat4,
) -> Value {
    let c = &scene.camera;
    let mut extensions_used = extensions_used.to_vec();
    if scene.has_dispersion() {
        extensions_used.push("KHR_materials_dispersion");
    }
    let mut nodes: Vec<Value> = (0..meshes.len())
        .map(|k| json!({ "mesh": k, "name": meshes[k]["name"] }))
        .collect();
    nodes.push(json!({
        "name": "camera",
        "camera": 0,
        "matrix": camera.to_cols_array(),
    }));
    json!({
        "asset": { "version": "2.0", "generator": concat!("refract ", env!("CARGO_PKG_VERSION")) },
        "extensionsUsed": extensions_used,
        "scene": 0,
        "scenes": [{ "name": scene.name, "nodes": (0..nodes.len()).collect::<Vec<_>>(), "extras": extras }],
        "nodes": nodes,
        "cameras": [{
            "type": "perspective",
            "perspective": { "yfov": c.fov_y, "znear": c.near, "zfar": c.far },
        }],
        "meshes": meshes,
        "materials": materials,
        "buffers": [{ "uri": "scene.bin", "byteLength": buffer.bytes.len() }],
        "bufferViews": buffer.views,
        "accessors": buffer.accessors,
    })
}

/// Exports `scene` (see the module docs); an error only for a camera refract cannot build.
pub fn export_gltf(scene: &Scene) -> Result<GltfExport, SceneError> {
    let camera = camera_matrix(scene)?;
    let mut buffer = Buffer::default();
    let bounds = position_code_bounds(scene);

    // The colour file's and the position-coded file's meshes and materials, built side by side:
    // the refractors first (mesh and material k for refractor k), then the objects.
    let mut meshes = Vec::new();
    let mut materials = Vec::new();
    let mut coded_materials = Vec::new();
    for (k, refractor) in scene.refractors().enumerate() {
        let name = refractor_name(k);
        let accessors = MeshAccessors::push(&mut buffer, refractor.mesh());
        meshes.push(json!({
            "name": name,
            "primitives": [{ "attributes": accessors.attributes(), "indices": accessors.indices, "material": k }],
        }));
        let (glass, coded_glass) = match refractor.conductor() {
            Some(c) => {
                let metal = metal_material(&name, conductor_f0(c.eta, c.k), refractor.roughness());
                (metal.clone(), metal)
            }
            None => (
                glass_material(&name, refractor, 1.0),
                glass_material(&name, refractor, 0.0),
            ),
        };
        materials.push(glass);
        coded_materials.push(coded_glass);
    }
    let mut coded_meshes = meshes.clone();
    let refractor_count = meshes.len();
    let mut textures = Vec::new();
    for (k, object) in scene.objects.iter().enumerate() {
        let mesh = object.mesh();
        let name = format!("object-{k}");
        let accessors = MeshAccessors::push(&mut buffer, mesh);
        let mut attributes = accessors.attributes();
        match &object.material {
            Material::Diffuse(albedo) => {
                let light: Vec<Vec3> = mesh
                    .normals
                    .iter()
                    .map(|&n| scene.light.shade(Vec3::ONE, n))
                    .collect();
                attributes["COLOR_0"] = json!(buffer.push_vec3(&light, false));
                let (base_color, texture) = match albedo {
                    Albedo::Constant(c) => (*c, None),
                    _ => {
                        let uvs = vertex_uvs(mesh);
                        let lo = uvs.iter().fold(Vec2::INFINITY, |a, &b| a.min(b));
                        let hi = uvs.iter().fold(Vec2::NEG_INFINITY, |a, &b| a.max(b));
                        let hi = lo + (hi - lo).max(Vec2::splat(1e-6));
                        let texcoords: Vec<f32> = uvs
                            .iter()
                            .flat_map(|&uv| ((uv - lo) / (hi - lo)).to_array())
                            .collect();
                        attributes["TEXCOORD_0"] =
                            json!(buffer.push_f32(&texcoords, "VEC2", 2, false));
                        textures.push(bake_albedo(albedo, lo, hi, format!("{name}-albedo.png")));
                        (Vec3::ONE, Some(textures.len() - 1))
                    }
                };
                materials.push(unlit_material(&name, base_color, texture));
            }
            Material::Conductor(c) => {
                materials.push(metal_material(
                    &name,
                    conductor_f0(c.eta, c.k),
                    object.roughness(),
                ));
            }
        }
        let codes: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|&p| position_code(p, bounds))
            .collect();
        let mut coded_attributes = accessors.attributes();
        coded_attributes["COLOR_0"] = json!(buffer.push_vec3(&codes, false));
        let primitive = |attributes: Value| json!({ "name": name, "primitives": [{ "attributes": attributes, "indices": accessors.indices, "material": refractor_count + k }] });
        meshes.push(primitive(attributes));
        coded_meshes.push(primitive(coded_attributes));
        coded_materials.push(unlit_material(&name, Vec3::ONE, None));
    }

    let environment = environment_image(&scene.environment);
    let refract_extras = |variant: &str| {
        json!({ "refract": {
            "variant": variant,
            "environment": if variant == "color" { "environment.hdr" } else { "direction-coded.hdr" },
            "environment_orientation": "u = atan2(x, -z) / 2 pi, v = acos(y) / pi (Mitsuba 3's envmap)",
            "position_code": {
                "lo": bounds.0.to_array(), "hi": bounds.1.to_array(),
                "offset": POSITION_CODE_OFFSET, "scale": POSITION_CODE_SCALE,
            },
            "direction_code_scale": DIRECTION_CODE_SCALE,
            "ior": scene.refractor.ior(),
        }})
    };
    let mut scene_gltf = document(
        scene,
        &buffer,
        meshes,
        materials,
        refract_extras("color"),
        &[
            "KHR_materials_transmission",
            "KHR_materials_ior",
            "KHR_materials_volume",
            "KHR_materials_unlit",
        ],
        camera,
    );
    if !textures.is_empty() {
        scene_gltf["samplers"] = json!([{
            "magFilter": NEAREST, "minFilter": NEAREST,
            "wrapS": CLAMP_TO_EDGE, "wrapT": CLAMP_TO_EDGE,
        }]);
        scene_gltf["images"] = json!(
            textures
                .iter()
                .map(|t| json!({ "uri": t.name }))
                .collect::<Vec<_>>()
        );
        scene_gltf["textures"] = json!(
            (0..textures.len())
                .map(|k| json!({ "sampler": 0, "source": k }))
                .collect::<Vec<_>>()
        );
    }
    let position_coded_gltf = document(
        scene,
        &buffer,
        coded_meshes,
        coded_materials,
        refract_extras("position-coded"),
        &[
            "KHR_materials_transmission",
            "KHR_materials_ior",
            "KHR_materials_volume",
            "KHR_materials_specular",
            "KHR_materials_unlit",
        ],
        camera,
    );
    Ok(GltfExport {
        scene_gltf,
        position_coded_gltf,
        bin: buffer.bytes,
        environment,
        direction_coded: bake_latlong(BAKED_ENVIRONMENT_WIDTH, |d| {
            Vec3::splat(0.5) + DIRECTION_CODE_SCALE * d
        }),
        textures,
    })
}

impl GltfExport {
    /// Writes every file into `dir` (which exists), each atomically; returns their paths.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, SceneError> {
        let mut written = Vec::new();
        let mut text = |name: &str, value: &Value| -> Result<(), SceneError> {
            let path = dir.join(name);
            let json = serde_json::to_string_pretty(value).map_err(|err| SceneError::Format {
                path: path.clone(),
                message: err.to_string(),
            })?;
            write_text_atomically(&path, &json)?;
            written.push(path);
            Ok(())
        };
        text("scene.gltf", &self.scene_gltf)?;
        text("position-coded.gltf", &self.position_coded_gltf)?;
        let path = dir.join("scene.bin");
        write_atomically(&path, "the glTF buffer", |w| {
            std::io::Write::write_all(w, &self.bin)
        })?;
        written.push(path);
        for (name, image) in [
            ("environment.hdr", &self.environment),
            ("direction-coded.hdr", &self.direction_coded),
        ] {
            let path = dir.join(name);
            write_hdr(&path, image)?;
            written.push(path);
        }
        for texture in &self.textures {
            let path = dir.join(&texture.name);
            crate::atomic_write::write_png_rgb8(&path, texture.side, texture.side, &texture.rgb8)?;
            written.push(path);
        }
        Ok(written)
    }
}

/// `image` as a Radiance RGBE `.hdr` file.
fn write_hdr(path: &Path, image: &LatLongImage) -> Result<(), SceneError> {
    let pixels: Vec<image::Rgb<f32>> = image
        .texels
        .iter()
        .map(|t| image::Rgb(t.max(Vec3::ZERO).to_array()))
        .collect();
    write_atomically(path, "the HDR image", |w| {
        image::codecs::hdr::HdrEncoder::new(w).encode(
            &pixels,
            image.width as usize,
            image.height as usize,
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chart() -> Scene {
        crate::load_scene("chart").expect("chart").scene
    }

    /// The files are glTF the gltf crate validates, and hold what refract renders, bit for bit:
    /// the refractor's positions and normals, every object, the camera, the IOR and the
    /// thickness; refract's own loader reads the glass back.
    #[test]
    fn the_export_is_valid_gltf_holding_the_scene() {
        let scene = chart();
        let dir = tempfile::tempdir().expect("tempdir");
        export_gltf(&scene)
            .expect("export")
            .write(dir.path())
            .expect("write");
        for file in ["scene.gltf", "position-coded.gltf"] {
            let (document, buffers, images) =
                gltf::import(dir.path().join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
            assert_eq!(document.meshes().count(), 1 + scene.objects.len(), "{file}");
            let refractor = document.meshes().next().expect("refractor");
            let primitive = refractor.primitives().next().expect("primitive");
            let reader = primitive.reader(|b| Some(&buffers[b.index()]));
            let positions: Vec<Vec3> = reader
                .read_positions()
                .expect("POSITION")
                .map(Vec3::from)
                .collect();
            let normals: Vec<Vec3> = reader
                .read_normals()
                .expect("NORMAL")
                .map(Vec3::from)
                .collect();
            let mesh = scene.refractor.mesh();
            assert_eq!(positions, mesh.positions, "{file}");
            assert_eq!(normals, mesh.normals, "{file}");
            let material = primitive.material();
            assert_eq!(material.ior(), Some(scene.refractor.ior()), "{file}");
            let thickness = scene.refractor.auto_thickness();
            assert_eq!(
                material.volume().map(|v| v.thickness_factor()),
                Some(thickness),
                "{file}"
            );
            let camera = document.cameras().next().expect("camera");
            let gltf::camera::Projection::Perspective(p) = camera.projection() else {
                panic!("{file}: an orthographic camera")
            };
            assert_eq!(p.yfov(), scene.camera.fov_y, "{file}");
            assert_eq!(p.znear(), scene.camera.near, "{file}");
            assert_eq!(p.zfar(), Some(scene.camera.far), "{file}");
            let patterned = scene
                .objects
                .iter()
                .filter(|o| matches!(&o.material, Material::Diffuse(a) if !matches!(a, Albedo::Constant(_))))
                .count();
            let expected = if file == "scene.gltf" { patterned } else { 0 };
            assert_eq!(
                images.len(),
                expected,
                "{file}: the chart's and the floor's albedo"
            );
        }
        let loaded = crate::load_mesh(
            &dir.path().join("scene.gltf"),
            &crate::LoadOptions {
                normalize: false,
                weld_relative_epsilon: None,
            },
        )
        .expect("refract reads its export");
        let triangles: usize = std::iter::once(scene.refractor.mesh())
            .chain(scene.objects.iter().map(|o| o.mesh()))
            .map(|m| m.triangles.len())
            .sum();
        assert_eq!(loaded.mesh.triangles.len(), triangles);
        let glass = loaded.material.expect("the glass material");
        assert_eq!(glass.ior, Some(scene.refractor.ior()));
        assert_eq!(glass.transmission, Some(1.0));
    }

    /// The camera node sits at the eye, looks along glTF's −z at the target, with +y up.
    #[test]
    fn the_camera_node_looks_from_the_eye_at_the_target() {
        let scene = chart();
        let m = camera_matrix(&scene).expect("camera");
        let c = &scene.camera;
        assert!(m.transform_point3(Vec3::ZERO).abs_diff_eq(c.eye, 1e-5));
        let forward = m.transform_vector3(-Vec3::Z);
        assert!(
            forward.abs_diff_eq((c.target - c.eye).normalize(), 1e-5),
            "{forward}"
        );
        let up = m.transform_vector3(Vec3::Y);
        assert!(up.dot(c.up) > 0.0 && up.dot(forward).abs() < 1e-5, "{up}");
    }

    #[test]
    fn position_codes_name_their_point() {
        let bounds = (Vec3::new(-2.0, -1.0, -3.0), Vec3::new(2.0, 0.5, 1.0));
        for k in 0..1000 {
            let t = Vec3::new(
                (k % 10) as f32 / 9.0,
                (k / 10 % 10) as f32 / 9.0,
                (k / 100) as f32 / 9.0,
            );
            let p = bounds.0 + t * (bounds.1 - bounds.0);
            let code = position_code(p, bounds);
            assert!(code.min_element() >= POSITION_CODE_OFFSET - 1e-6, "{code}");
            assert!(code.max_element() <= POSITION_CODE_OFFSET + POSITION_CODE_SCALE + 1e-6);
            assert!(position_from_code(code, bounds).abs_diff_eq(p, 1e-5));
        }
    }

    /// The baked albedo read with glTF's nearest sampling at an object's texture coordinates is
    /// refract's albedo at its uv (a transposed or flipped texture fails everywhere): on the
    /// chart object, 97 % of 10,000 points inside its triangles (the rest lie within a texel
    /// of a patch edge).
    #[test]
    fn the_baked_albedo_is_refracts_under_nearest_sampling() {
        let scene = chart();
        let export = export_gltf(&scene).expect("export");
        let (k, object) = scene
            .objects
            .iter()
            .enumerate()
            .find(|(_, o)| matches!(o.material, Material::Diffuse(Albedo::ColorChart)))
            .expect("the colour chart");
        let texture = export
            .textures
            .iter()
            .find(|t| t.name == format!("object-{k}-albedo.png"))
            .expect("its texture");
        let Material::Diffuse(albedo) = &object.material else {
            unreachable!()
        };
        let mesh = object.mesh();
        let uvs = vertex_uvs(mesh);
        let lo = uvs.iter().fold(Vec2::INFINITY, |a, &b| a.min(b));
        let hi = uvs.iter().fold(Vec2::NEG_INFINITY, |a, &b| a.max(b));
        let (mut same, mut total) = (0, 0);
        for s in 0..10_000u32 {
            let [a, b, c] =
                mesh.triangles[s as usize % mesh.triangles.len()].map(|i| uvs[i as usize]);
            let (r1, r2) = (
                ((s * 7919) % 997) as f32 / 997.0,
                ((s * 104_729) % 991) as f32 / 991.0,
            );
            let (r1, r2) = if r1 + r2 > 1.0 {
                (1.0 - r1, 1.0 - r2)
            } else {
                (r1, r2)
            };
            let uv = a + r1 * (b - a) + r2 * (c - a);
            let t = (uv - lo) / (hi - lo) * texture.side as f32;
            let (i, j) = (
                (t.x as u32).min(texture.side - 1),
                (t.y as u32).min(texture.side - 1),
            );
            let at = ((j * texture.side + i) * 3) as usize;
            let expected = albedo.at(uv);
            total += 1;
            if texture.rgb8[at..at + 3] == [srgb8(expected.x), srgb8(expected.y), srgb8(expected.z)]
            {
                same += 1;
            }
        }
        assert!(
            same * 100 >= total * 97,
            "{same} of {total} texels are refract's albedo"
        );
    }
}
