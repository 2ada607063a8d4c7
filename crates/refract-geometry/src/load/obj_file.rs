//! Wavefront OBJ through tobj: every object of the file merged into one mesh, polygons
//! triangulated, per-vertex normals used when the file has them.

use std::path::Path;

use glam::{Vec2, Vec3};

use super::RawMesh;
use crate::error::GeometryError;
use crate::mesh::Mesh;

pub(super) fn read(path: &Path) -> Result<RawMesh, GeometryError> {
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    // Materials (.mtl) are irrelevant to a refractor; a missing .mtl is not an error.
    let (models, _materials) =
        tobj::load_obj(path, &options).map_err(|err| GeometryError::Obj {
            path: path.to_owned(),
            message: err.to_string(),
        })?;

    let all_have_normals = models
        .iter()
        .all(|m| !m.mesh.normals.is_empty() && m.mesh.normals.len() == m.mesh.positions.len());
    let all_have_uvs = models.iter().all(|m| {
        !m.mesh.texcoords.is_empty() && 2 * m.mesh.texcoords.len() == 3 * m.mesh.positions.len()
    });
    let (mut positions, mut normals, mut uvs, mut triangles) = (vec![], vec![], vec![], vec![]);
    for model in &models {
        let mesh = &model.mesh;
        if !mesh.indices.len().is_multiple_of(3) {
            return Err(GeometryError::Obj {
                path: path.to_owned(),
                message: format!("object `{}` has a face that is not a polygon", model.name),
            });
        }
        let base = positions.len() as u32;
        positions.extend(
            mesh.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        if all_have_normals {
            normals.extend(
                mesh.normals
                    .chunks_exact(3)
                    .map(|n| Vec3::new(n[0], n[1], n[2])),
            );
        }
        if all_have_uvs {
            uvs.extend(
                mesh.texcoords
                    .chunks_exact(2)
                    .map(|t| Vec2::new(t[0], t[1])),
            );
        }
        triangles.extend(
            mesh.indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]].map(|i| i + base)),
        );
    }
    if triangles.is_empty() {
        return Err(GeometryError::NoTriangles {
            source_name: path.display().to_string(),
            degenerate: 0,
        });
    }
    let has_file_normals = all_have_normals && !positions.is_empty();
    let non_unit_normals = super::count_non_unit(&normals);
    let mesh = Mesh::new(
        path.display().to_string(),
        positions,
        has_file_normals.then_some(normals),
        uvs,
        triangles,
    )?;
    Ok(RawMesh {
        mesh,
        has_file_normals,
        non_unit_normals,
    })
}
