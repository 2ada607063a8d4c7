//! Loading meshes from files (OBJ via tobj, glTF 2.0 via gltf) and the cleanup every loaded
//! mesh goes through.

mod gltf_file;
mod obj_file;

use std::path::Path;

use glam::Affine3A;

use refract_geometry::GeometryError;
use refract_geometry::Mesh;

pub use gltf_file::{GlassMaterial, GltfCamera};

/// How to prepare a loaded mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadOptions {
    /// Centre and scale into the unit bounding sphere (design.md); the transform is reported.
    pub normalize: bool,
    /// Merge vertices closer than this (relative to the bounding-sphere radius) before computing
    /// normals. `None` keeps the file's vertices.
    pub weld_relative_epsilon: Option<f32>,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            normalize: true,
            weld_relative_epsilon: None,
        }
    }
}

/// Where the shading normals came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalSource {
    /// Read from the file (normalised).
    File,
    /// Computed: angle-weighted vertex normals.
    Computed,
}

/// What loading did to the file's content. `warnings` are the lines a user should see.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadReport {
    /// Vertices as read.
    pub source_vertices: usize,
    /// Triangles as read (after triangulating polygons).
    pub source_triangles: usize,
    /// Degenerate triangles removed.
    pub degenerate_removed: usize,
    /// Coincident duplicate triangles removed ([`Mesh::remove_duplicate_triangles`]).
    pub duplicates_removed: usize,
    /// Vertices merged by welding.
    pub welded: usize,
    /// Where the normals came from.
    pub normal_source: NormalSource,
    /// File normals that were not unit length (normalised).
    pub non_unit_normals: usize,
    /// The mesh was closed with a negative signed volume and was turned outside out.
    pub flipped_inside_out: bool,
    /// The file's normals pointed inward (against the winding) and were negated.
    pub flipped_file_normals: bool,
    /// The transform applied by normalisation (identity without it).
    pub normalization: Affine3A,
    /// Human-readable warnings about the file's quirks.
    pub warnings: Vec<String>,
}

/// A mesh loaded from a file, with the glass parameters the file carried (glTF only).
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedMesh {
    /// The cleaned-up mesh.
    pub mesh: Mesh,
    /// `KHR_materials_ior` / `_transmission` / `_volume` of the first material that has them.
    pub material: Option<GlassMaterial>,
    /// What loading did.
    pub report: LoadReport,
}

/// Loads `.obj`, `.gltf` or `.glb` and prepares the mesh (degenerates removed, normals made
/// unit or computed, inside-out closed meshes turned, optional normalisation; see [`LoadReport`]).
pub fn load_mesh(path: &Path, options: &LoadOptions) -> Result<LoadedMesh, GeometryError> {
    let metadata = std::fs::metadata(path).map_err(|source| GeometryError::Io {
        path: path.to_owned(),
        source,
    })?;
    if metadata.len() == 0 {
        return Err(GeometryError::EmptyFile {
            path: path.to_owned(),
        });
    }
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let (raw, material) = match extension.as_deref() {
        Some("obj") => (obj_file::read(path)?, None),
        Some("gltf" | "glb") => gltf_file::read(path)?,
        _ => {
            return Err(GeometryError::UnsupportedFormat {
                path: path.to_owned(),
            });
        }
    };
    let (mesh, report) = prepare(raw, options)?;
    Ok(LoadedMesh {
        mesh,
        material,
        report,
    })
}

/// One part of a glTF scene ([`load_gltf_scene`]): the triangles of one node that share a
/// material, in the file's world space, cleaned up like every loaded mesh (not normalised).
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedPart {
    /// `` node `name` (node 3), material `glass` (material 1) ``, for messages.
    pub label: String,
    /// The cleaned-up mesh.
    pub mesh: Mesh,
    /// The glass parameters when the material transmits (`KHR_materials_transmission` above 0):
    /// the part is a refractor. `None`: an opaque object.
    pub glass: Option<GlassMaterial>,
    /// The material's `baseColorFactor` (linear RGB).
    pub base_color: glam::Vec3,
    /// What loading did.
    pub report: LoadReport,
}

/// A glTF file read as a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedGltfScene {
    /// One part per node and material, in the order of the scene's nodes (depth first).
    pub parts: Vec<LoadedPart>,
    /// The first perspective camera of the scene's nodes, if any.
    pub camera: Option<GltfCamera>,
    /// Material properties read but not modelled, one line each.
    pub notes: Vec<String>,
}

/// Reads a `.gltf` or `.glb` file as a scene: every node's triangle primitives grouped by
/// material, a refractor part where the material transmits (`KHR_materials_transmission`,
/// with `_ior` and `_volume`), an opaque part otherwise, each cleaned up like [`load_mesh`]
/// does (never normalised: the parts keep their places), and the first perspective camera.
pub fn load_gltf_scene(path: &Path) -> Result<LoadedGltfScene, GeometryError> {
    let scene = gltf_file::read_scene(path)?;
    let mut parts = Vec::with_capacity(scene.parts.len());
    for part in scene.parts {
        let (mesh, report) = prepare(
            part.raw,
            &LoadOptions {
                normalize: false,
                weld_relative_epsilon: None,
            },
        )?;
        parts.push(LoadedPart {
            label: part.label,
            mesh,
            glass: part.glass,
            base_color: part.base_color,
            report,
        });
    }
    Ok(LoadedGltfScene {
        parts,
        camera: scene.camera,
        notes: scene.notes,
    })
}

/// A mesh as read from a file, before cleanup.
pub(crate) struct RawMesh {
    pub mesh: Mesh,
    pub has_file_normals: bool,
    /// File normals that were not unit length (before `Mesh::new` normalised them).
    pub non_unit_normals: usize,
    /// What the reader read but does not use (glTF glass properties refract does not model),
    /// one warning each.
    pub notes: Vec<String>,
}

/// Normals whose length differs from 1 by more than 1e-3.
pub(crate) fn count_non_unit(normals: &[glam::Vec3]) -> usize {
    normals
        .iter()
        .filter(|n| (n.length() - 1.0).abs() > 1e-3)
        .count()
}

/// The cleanup of every loaded mesh: remove degenerate triangles, optionally weld, make normals
/// unit (or compute angle-weighted ones), turn closed inside-out meshes (negative signed volume)
/// outside in, make file normals agree with the winding, and normalise into the unit sphere.
pub(crate) fn prepare(
    raw: RawMesh,
    options: &LoadOptions,
) -> Result<(Mesh, LoadReport), GeometryError> {
    let RawMesh {
        mut mesh,
        has_file_normals,
        non_unit_normals,
        notes,
    } = raw;
    let mut warnings = notes;
    let source_vertices = mesh.positions.len();
    let source_triangles = mesh.triangles.len();
    let degenerate_removed = mesh.remove_degenerate_triangles()?;
    if degenerate_removed > 0 {
        warnings.push(format!("removed {degenerate_removed} degenerate triangles"));
    }
    let duplicates_removed = mesh.remove_duplicate_triangles();
    if duplicates_removed > 0 {
        warnings.push(format!(
            "removed {duplicates_removed} coincident duplicate triangles"
        ));
    }
    if non_unit_normals > 0 {
        warnings.push(format!(
            "normalised {non_unit_normals} file normals that were not unit length"
        ));
    }
    let welded = match options.weld_relative_epsilon {
        Some(eps) => {
            let radius = mesh.bounding_sphere().radius.max(f32::MIN_POSITIVE);
            let welded = mesh.weld(eps * radius);
            mesh.remove_degenerate_triangles()?;
            welded
        }
        None => 0,
    };
    if !has_file_normals && welded > 0 {
        mesh.compute_vertex_normals();
    }

    let facts = mesh.facts();
    let flipped_inside_out = facts.watertight && facts.signed_volume < 0.0;
    if flipped_inside_out {
        // Turns the winding and negates the normals together.
        mesh.flip_inside_out();
        warnings.push(format!(
            "closed mesh had negative signed volume {:.4}: winding flipped to face outward",
            facts.signed_volume
        ));
    }
    let flipped_file_normals = has_file_normals && file_normals_point_inward(&mesh);
    if flipped_file_normals {
        for n in &mut mesh.normals {
            *n = -*n;
        }
        warnings.push("file normals pointed against the winding: negated".to_owned());
    }

    let normalization = if options.normalize {
        mesh.normalize_to_unit_sphere()
    } else {
        Affine3A::IDENTITY
    };
    let report = LoadReport {
        source_vertices,
        source_triangles,
        degenerate_removed,
        duplicates_removed,
        welded,
        normal_source: if has_file_normals {
            NormalSource::File
        } else {
            NormalSource::Computed
        },
        non_unit_normals,
        flipped_inside_out,
        flipped_file_normals,
        normalization,
        warnings,
    };
    Ok((mesh, report))
}

/// True when most vertex normals disagree with the angle-weighted normals of the winding.
fn file_normals_point_inward(mesh: &Mesh) -> bool {
    let mut from_winding = mesh.clone();
    from_winding.compute_vertex_normals();
    let against = mesh
        .normals
        .iter()
        .zip(&from_winding.normals)
        .filter(|(n, w)| n.dot(**w) < 0.0)
        .count();
    2 * against > mesh.normals.len()
}
