//! glTF 2.0 (`.gltf` with external or embedded buffers, and `.glb`) through the gltf crate:
//! every triangle primitive of the default scene (or of every node when there is no scene),
//! with node transforms applied, and the glass parameters of the Khronos extensions.

use std::path::Path;

use glam::{Affine3A, Mat4, Vec2, Vec3};
use gltf::mesh::Mode;

use super::RawMesh;
use refract_geometry::GeometryError;
use refract_geometry::Mesh;

/// Glass parameters of a glTF material (`KHR_materials_ior`, `KHR_materials_transmission`,
/// `KHR_materials_volume`); absent extensions are `None`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlassMaterial {
    /// Index of refraction (`KHR_materials_ior`, glTF default 1.5).
    pub ior: Option<f32>,
    /// Transmission factor in `[0, 1]` (`KHR_materials_transmission`).
    pub transmission: Option<f32>,
    /// Thickness (`KHR_materials_volume`'s `thicknessFactor`, given in the mesh's units) times
    /// the scale of the node that carries the material (`∛|det M|`: the node's uniform scale;
    /// the extension says the node's transform applies to the thickness, which three.js
    /// applies per axis and Bevy along the normal, both equal for a uniform scale), so in the
    /// file's world units, before any normalisation.
    pub thickness: Option<f32>,
    /// `KHR_materials_volume`'s `attenuationColor` and `attenuationDistance` (the distance
    /// scaled by the node's uniform scale like `thickness`), when the distance is finite
    /// (glTF's default, infinity, absorbs nothing).
    pub attenuation: Option<(Vec3, f32)>,
    /// `pbrMetallicRoughness.roughnessFactor` in `[0, 1]` (glTF's default 1 when absent).
    pub roughness: f32,
    /// The Abbe number `20 / dispersion` of `KHR_materials_dispersion` (`None` without the
    /// extension; infinite for `dispersion = 0`; NaN for a value that is not a number ≥ 0, which
    /// the scene loader refuses).
    pub abbe: Option<f32>,
}

/// A glTF document with its buffers, checked (accessor indices and bounds, required
/// extensions) and validated.
fn open(path: &Path) -> Result<(gltf::Document, Vec<gltf::buffer::Data>), GeometryError> {
    let error = |message: String| GeometryError::Gltf {
        path: path.to_owned(),
        message,
    };
    let bytes = std::fs::read(path).map_err(|source| GeometryError::Io {
        path: path.to_owned(),
        source,
    })?;
    // Parsed without gltf's validation first: its primitive hook indexes `accessors` without a
    // bounds check and panics on a primitive naming a missing accessor. Those indices are
    // checked here, then the document is validated.
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(&bytes).map_err(|err| error(err.to_string()))?;
    let mut json = document.into_json();
    // glTF 1.0 is another format (materials as techniques, no accessor-based meshes as 2.0
    // reads them): refused by name rather than read as if it were 2.0.
    if !json.asset.version.starts_with("2.") {
        return Err(error(format!(
            "glTF {} (asset.version); expected a glTF 2.0 file",
            json.asset.version
        )));
    }
    check_accessor_indices(&json).map_err(error)?;
    check_required_extensions(&mut json).map_err(error)?;
    let document = gltf::Document::from_json(json).map_err(|err| error(err.to_string()))?;
    let buffers = gltf::import_buffers(&document, path.parent(), blob)
        .map_err(|err| error(format!("cannot load its buffers: {err}")))?;
    check_accessor_bounds(&document, &buffers).map_err(error)?;
    Ok((document, buffers))
}

pub(super) fn read(path: &Path) -> Result<(RawMesh, Option<GlassMaterial>), GeometryError> {
    let error = |message: String| GeometryError::Gltf {
        path: path.to_owned(),
        message,
    };
    let (document, buffers) = open(path)?;
    let mut collector = Collector::default();
    match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => for_each_node(&document, scene, &error, |node, world| match node.mesh() {
            Some(mesh) => collector.add_mesh(&mesh, world, &buffers, &error),
            None => Ok(()),
        })?,
        None => {
            for mesh in document.meshes() {
                collector.add_mesh(&mesh, Mat4::IDENTITY, &buffers, &error)?;
            }
        }
    }
    if collector.triangles.is_empty() {
        return Err(GeometryError::NoTriangles {
            source_name: path.display().to_string(),
            degenerate: 0,
        });
    }
    let material = collector.material;
    let mut dropped = std::mem::take(&mut collector.dropped);
    if !collector.other_glass.is_empty() {
        dropped.push(format!(
            "glass: {} also transmissive; refract reads the first glass material for the whole \
             mesh",
            std::mem::take(&mut collector.other_glass)
                .into_iter()
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    let raw = collector.into_raw_mesh(path.display().to_string(), dropped)?;
    Ok((raw, material))
}

struct Collector {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    triangles: Vec<[u32; 3]>,
    all_have_normals: bool,
    all_have_uvs: bool,
    material: Option<GlassMaterial>,
    /// The index of the glass material read (`None` inside: the default material).
    material_index: Option<Option<usize>>,
    /// Other glass materials, by name or index, which are not read.
    other_glass: std::collections::BTreeSet<String>,
    /// What of the glass material read is not modelled, one line each.
    dropped: Vec<String>,
}

impl Default for Collector {
    fn default() -> Self {
        Self {
            positions: vec![],
            normals: vec![],
            uvs: vec![],
            triangles: vec![],
            all_have_normals: true,
            all_have_uvs: true,
            material: None,
            material_index: None,
            other_glass: Default::default(),
            dropped: vec![],
        }
    }
}

/// The extensions a file may require: those the gltf crate reads with refract's features,
/// and `KHR_materials_volume`, which it reads (feature `KHR_materials_volume`) but leaves off
/// the list its validation accepts in `extensionsRequired` (gltf-json 1.4).
fn readable_extensions() -> impl Iterator<Item = &'static str> {
    gltf::json::extensions::ENABLED_EXTENSIONS
        .iter()
        .copied()
        .chain(["KHR_materials_volume"])
}

/// Refuses a file that requires an extension refract cannot read, naming it; the accepted ones
/// are taken off `extensionsRequired` so that gltf's validation, which does not know
/// `KHR_materials_volume` there, accepts the document.
fn check_required_extensions(json: &mut gltf::json::Root) -> Result<(), String> {
    if let Some(unread) = json
        .extensions_required
        .iter()
        .find(|name| !readable_extensions().any(|known| known == name.as_str()))
    {
        return Err(format!(
            "extensionsRequired lists {unread}, which refract cannot read (it reads {})",
            readable_extensions().collect::<Vec<_>>().join(", ")
        ));
    }
    json.extensions_required.clear();
    Ok(())
}

/// Every accessor a mesh primitive names (attributes, indices, morph targets) exists.
/// A material as messages name it: `` `name` (material 3) ``.
fn material_label(material: &gltf::Material<'_>) -> String {
    match (material.name(), material.index()) {
        (Some(name), Some(index)) => format!("`{name}` (material {index})"),
        (None, Some(index)) => format!("material {index}"),
        (_, None) => "the default material".to_owned(),
    }
}

/// What refract does not model of a glass material (issue 54 #16: dropped without a word):
/// textures of the transmission and the thickness, partial transmission.
fn unmodelled(material: &gltf::Material<'_>) -> Vec<String> {
    let label = material_label(material);
    let mut dropped = Vec::new();
    if let Some(transmission) = material.transmission() {
        if transmission.transmission_texture().is_some() {
            dropped.push("its transmissionTexture (the factor alone is read)".to_owned());
        }
        let factor = transmission.transmission_factor();
        if factor < 1.0 {
            dropped.push(format!(
                "transmissionFactor {factor} (refract's glass transmits fully)"
            ));
        }
    }
    if material
        .volume()
        .is_some_and(|v| v.thickness_texture().is_some())
    {
        dropped.push("its thicknessTexture (thicknessFactor alone is read)".to_owned());
    }
    if material
        .pbr_metallic_roughness()
        .metallic_roughness_texture()
        .is_some()
    {
        dropped.push("its metallicRoughnessTexture (roughnessFactor alone is read)".to_owned());
    }
    dropped
        .into_iter()
        .map(|what| format!("glass {label}: {what} is not modelled"))
        .collect()
}

fn check_accessor_indices(json: &gltf::json::Root) -> Result<(), String> {
    let count = json.accessors.len();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let targets = primitive
                .targets
                .iter()
                .flatten()
                .flat_map(|t| [t.positions, t.normals, t.tangents].into_iter().flatten());
            let named = primitive
                .attributes
                .values()
                .copied()
                .chain(primitive.indices)
                .chain(targets);
            for index in named {
                if index.value() >= count {
                    return Err(format!(
                        "meshes[{m}].primitives[{p}] names accessor {}, but the file has {count} accessors",
                        index.value()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Every accessor a triangle primitive reads fits its buffer view, and every such view its
/// buffer, so that a short file is reported as such (not as a missing POSITION or a wrong
/// triangle count, which is what the gltf reader's silent `None` turned into).
fn check_accessor_bounds(
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
    for mesh in document.meshes() {
        for (p, primitive) in mesh.primitives().enumerate() {
            let accessors = primitive
                .attributes()
                .map(|(semantic, a)| (format!("{semantic:?}"), a))
                .chain(primitive.indices().map(|a| ("indices".to_owned(), a)));
            for (what, accessor) in accessors {
                let Some(view) = accessor.view() else {
                    continue; // sparse or zero-filled: nothing to overrun
                };
                let count = accessor.count();
                let size = accessor.size();
                let stride = view.stride().unwrap_or(size);
                let needed = if count == 0 {
                    0
                } else {
                    accessor.offset() + stride * (count - 1) + size
                };
                let mesh_name = mesh.name().unwrap_or("?");
                if needed > view.length() {
                    return Err(format!(
                        "mesh `{mesh_name}` primitive {p} {what}: accessor {} needs {needed} bytes of buffer view {}, which has {}",
                        accessor.index(),
                        view.index(),
                        view.length()
                    ));
                }
                let buffer_length = buffers.get(view.buffer().index()).map_or(0, |b| b.0.len());
                if view.offset() + view.length() > buffer_length {
                    return Err(format!(
                        "buffer view {} ends at byte {}, but buffer {} has {buffer_length} bytes",
                        view.index(),
                        view.offset() + view.length(),
                        view.buffer().index()
                    ));
                }
            }
        }
    }
    Ok(())
}

impl Collector {
    /// The collected vertices and triangles as a mesh named `name`, with `notes`: normals and
    /// texture coordinates only where every primitive had them.
    fn into_raw_mesh(self, name: String, notes: Vec<String>) -> Result<RawMesh, GeometryError> {
        let non_unit_normals = if self.all_have_normals {
            super::count_non_unit(&self.normals)
        } else {
            0
        };
        let mesh = Mesh::new(
            name,
            self.positions,
            self.all_have_normals.then_some(self.normals),
            if self.all_have_uvs { self.uvs } else { vec![] },
            self.triangles,
        )?;
        Ok(RawMesh {
            mesh,
            has_file_normals: self.all_have_normals,
            non_unit_normals,
            notes,
        })
    }

    /// Appends one primitive's vertices and triangles; normals and texture coordinates are kept
    /// only while every primitive has them.
    fn push(&mut self, data: PrimitiveData) {
        let base = self.positions.len() as u32;
        self.positions.extend(&data.positions);
        match data.normals {
            Some(normals) if self.all_have_normals => self.normals.extend(normals),
            _ => self.all_have_normals = false,
        }
        match data.uvs {
            Some(uvs) if self.all_have_uvs => self.uvs.extend(uvs),
            _ => self.all_have_uvs = false,
        }
        self.triangles.extend(
            data.triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }

    fn add_mesh(
        &mut self,
        mesh: &gltf::Mesh<'_>,
        world: Mat4,
        buffers: &[gltf::buffer::Data],
        error: &impl Fn(String) -> GeometryError,
    ) -> Result<(), GeometryError> {
        for primitive in mesh.primitives() {
            let Some(data) = read_primitive(mesh, &primitive, world, buffers, error)? else {
                continue;
            };
            self.push(data);
            let material = primitive.material();
            let glass = glass_material(&material, world);
            if glass.is_some()
                && self.material.is_some()
                && self.material_index != Some(material.index())
            {
                self.other_glass.insert(material_label(&material));
            }
            if self.material.is_none() && glass.is_some() {
                self.material_index = Some(material.index());
                self.dropped = unmodelled(&material);
                self.material = glass;
            }
        }
        Ok(())
    }
}

/// The glass parameters of `material` on a node with local-to-world `world`, or `None` when
/// the material has none of the glass extensions.
fn glass_material(material: &gltf::Material<'_>, world: Mat4) -> Option<GlassMaterial> {
    let glass = material.ior().is_some()
        || material.transmission().is_some()
        || material.volume().is_some();
    // KHR_materials_dispersion (the gltf crate has no type for it): `dispersion`, default 0.
    let abbe = material
        .extension_value("KHR_materials_dispersion")
        .map(|ext| match ext.get("dispersion") {
            None => f32::INFINITY,
            Some(d) => match d.as_f64() {
                Some(d) if d >= 0.0 => refract_core::spectral::abbe_from_dispersion(d as f32),
                _ => f32::NAN,
            },
        });
    // KHR_materials_volume: lengths are in the mesh's units, and the node's transform applies.
    let node_scale = Affine3A::from_mat4(world)
        .matrix3
        .determinant()
        .abs()
        .cbrt();
    glass.then(|| GlassMaterial {
        ior: material.ior(),
        transmission: material.transmission().map(|t| t.transmission_factor()),
        thickness: material.volume().map(|v| v.thickness_factor() * node_scale),
        roughness: material.pbr_metallic_roughness().roughness_factor(),
        abbe,
        attenuation: material.volume().and_then(|v| {
            v.attenuation_distance().is_finite().then(|| {
                (
                    Vec3::from(v.attenuation_color()),
                    v.attenuation_distance() * node_scale,
                )
            })
        }),
    })
}

/// One triangle primitive's vertices in world space (`None` for points, lines and strips,
/// which are not surfaces to refract through): positions, normals through the inverse
/// transpose, texture coordinates 0, and triangles indexing these vertices from 0, their
/// winding turned where the transform mirrors.
struct PrimitiveData {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    triangles: Vec<[u32; 3]>,
}

fn read_primitive(
    mesh: &gltf::Mesh<'_>,
    primitive: &gltf::Primitive<'_>,
    world: Mat4,
    buffers: &[gltf::buffer::Data],
    error: &impl Fn(String) -> GeometryError,
) -> Result<Option<PrimitiveData>, GeometryError> {
    if primitive.mode() != Mode::Triangles {
        return Ok(None);
    }
    let transform = Affine3A::from_mat4(world);
    let normal_matrix = transform.matrix3.inverse().transpose();
    let mirrored = transform.matrix3.determinant() < 0.0;
    let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| d.0.as_slice()));
    let Some(positions) = reader.read_positions() else {
        return Err(error(format!(
            "mesh `{}` has a primitive without POSITION",
            mesh.name().unwrap_or("?")
        )));
    };
    let positions: Vec<Vec3> = positions
        .map(|p| transform.transform_point3(Vec3::from(p)))
        .collect();
    let count = positions.len();
    let normals = reader.read_normals().map(|normals| {
        normals
            .map(|n| Vec3::from(normal_matrix * glam::Vec3A::from(Vec3::from(n))))
            .collect()
    });
    let uvs = reader
        .read_tex_coords(0)
        .map(|uvs| uvs.into_f32().map(Vec2::from).collect());
    let indices: Vec<u32> = match reader.read_indices() {
        Some(indices) => indices.into_u32().collect(),
        None => (0..count as u32).collect(),
    };
    if let Some(&index) = indices.iter().find(|&&i| i as usize >= count) {
        return Err(error(format!(
            "mesh `{}`: index {index} out of range for a primitive of {count} vertices",
            mesh.name().unwrap_or("?")
        )));
    }
    if !indices.len().is_multiple_of(3) {
        return Err(error(format!(
            "{} indices is not a whole number of triangles",
            indices.len()
        )));
    }
    let triangles = indices
        .chunks_exact(3)
        .map(|t| {
            if mirrored {
                [t[0], t[2], t[1]]
            } else {
                [t[0], t[1], t[2]]
            }
        })
        .collect();
    Ok(Some(PrimitiveData {
        positions,
        normals,
        uvs,
        triangles,
    }))
}

/// The scene's node trees, depth first with an explicit stack (no recursion: a chain of
/// 50,000 nodes is fine), `visit` called with each node and its local-to-world transform
/// (its own composed with its parent's). A node reached twice (a cycle, or a child shared by
/// two parents, both invalid glTF) is an error.
fn for_each_node<'a>(
    document: &'a gltf::Document,
    scene: gltf::Scene<'a>,
    error: &impl Fn(String) -> GeometryError,
    mut visit: impl FnMut(gltf::Node<'a>, Mat4) -> Result<(), GeometryError>,
) -> Result<(), GeometryError> {
    let mut seen = vec![false; document.nodes().len()];
    let mut stack: Vec<(gltf::Node<'_>, Mat4)> =
        scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(error(format!(
                "node {} is reached twice: node hierarchies must be trees (a cycle or a shared child)",
                node.index()
            )));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let children: Vec<_> = node.children().collect();
        visit(node, world)?;
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    Ok(())
}

/// A glTF file read as a scene ([`read_scene`]).
pub(crate) struct GltfScene {
    /// One part per node and material, in the order of the scene's nodes (depth first) and of
    /// each node's primitives.
    pub parts: Vec<ScenePart>,
    /// The first node with a perspective camera, if any.
    pub camera: Option<GltfCamera>,
    /// What was read but is not modelled, one line each.
    pub notes: Vec<String>,
}

/// The triangle primitives of one node that share one material.
pub(crate) struct ScenePart {
    /// `` node `name` (node 3), material `glass` (material 1) ``, for messages.
    pub label: String,
    pub raw: RawMesh,
    /// The glass parameters when the material transmits (`KHR_materials_transmission` with a
    /// factor above 0): the part is a refractor. `None`: an opaque object.
    pub glass: Option<GlassMaterial>,
    /// The material's `baseColorFactor` (linear RGB), which an opaque part is shaded with.
    pub base_color: Vec3,
}

/// A glTF perspective camera placed by its node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfCamera {
    /// The node's local-to-world transform: the camera looks down its −z with +y up.
    pub camera_to_world: Mat4,
    /// `yfov` in radians.
    pub fov_y: f32,
    /// `znear`.
    pub near: f32,
    /// `zfar`; `None`: an infinite projection.
    pub far: Option<f32>,
}

/// Reads `path` as a scene: every node's triangle primitives grouped by material, each group a
/// [`ScenePart`] (a refractor when its material transmits, an opaque object otherwise), and
/// the first perspective camera.
pub(super) fn read_scene(path: &Path) -> Result<GltfScene, GeometryError> {
    let error = |message: String| GeometryError::Gltf {
        path: path.to_owned(),
        message,
    };
    let (document, buffers) = open(path)?;
    let mut parts = Vec::new();
    let mut camera = None;
    let mut notes = std::collections::BTreeSet::new();
    let mut visit = |node: gltf::Node<'_>, world: Mat4| -> Result<(), GeometryError> {
        if let (None, Some(node_camera)) = (&camera, node.camera())
            && let gltf::camera::Projection::Perspective(p) = node_camera.projection()
        {
            camera = Some(GltfCamera {
                camera_to_world: world,
                fov_y: p.yfov(),
                near: p.znear(),
                far: p.zfar(),
            });
        }
        let Some(mesh) = node.mesh() else {
            return Ok(());
        };
        // Material index (None: the default material) to the part it fills, for this node.
        let mut groups: Vec<(Option<usize>, usize)> = Vec::new();
        for primitive in mesh.primitives() {
            let Some(data) = read_primitive(&mesh, &primitive, world, &buffers, &error)? else {
                continue;
            };
            let material = primitive.material();
            let part = match groups.iter().find(|(m, _)| *m == material.index()) {
                Some(&(_, part)) => part,
                None => {
                    let transmits = material
                        .transmission()
                        .is_some_and(|t| t.transmission_factor() > 0.0);
                    let glass = transmits
                        .then(|| glass_material(&material, world))
                        .flatten();
                    if glass.is_some() {
                        notes.extend(unmodelled(&material));
                    } else if material
                        .pbr_metallic_roughness()
                        .base_color_texture()
                        .is_some()
                    {
                        notes.insert(format!(
                            "{}: its baseColorTexture is not read (the factor is)",
                            material_label(&material)
                        ));
                    }
                    let node_label = match node.name() {
                        Some(name) => format!("node `{name}` (node {})", node.index()),
                        None => format!("node {}", node.index()),
                    };
                    let [r, g, b, _] = material.pbr_metallic_roughness().base_color_factor();
                    parts.push(PartBuilder {
                        label: format!("{node_label}, {}", material_label(&material)),
                        mesh_name: format!("{}: {node_label}", path.display()),
                        collector: Collector::default(),
                        glass,
                        base_color: Vec3::new(r, g, b),
                    });
                    groups.push((material.index(), parts.len() - 1));
                    parts.len() - 1
                }
            };
            parts[part].collector.push(data);
        }
        Ok(())
    };
    match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => for_each_node(&document, scene, &error, &mut visit)?,
        None => {
            return Err(error(
                "it has no scene: a glTF read as a scene needs one (its nodes place the meshes)"
                    .to_owned(),
            ));
        }
    }
    let parts = parts
        .into_iter()
        .filter(|p| !p.collector.triangles.is_empty())
        .map(PartBuilder::finish)
        .collect::<Result<_, _>>()?;
    Ok(GltfScene {
        parts,
        camera,
        notes: notes.into_iter().collect(),
    })
}

/// A [`ScenePart`] being read: its primitives' vertices in a [`Collector`].
struct PartBuilder {
    label: String,
    mesh_name: String,
    collector: Collector,
    glass: Option<GlassMaterial>,
    base_color: Vec3,
}

impl PartBuilder {
    fn finish(self) -> Result<ScenePart, GeometryError> {
        let raw = self.collector.into_raw_mesh(self.mesh_name, vec![])?;
        Ok(ScenePart {
            label: self.label,
            raw,
            glass: self.glass,
            base_color: self.base_color,
        })
    }
}
