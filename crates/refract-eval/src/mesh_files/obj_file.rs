//! Wavefront OBJ through tobj: every object of the file merged into one mesh, polygons
//! triangulated, per-vertex normals used when the file has them.

use std::path::Path;

use glam::{Vec2, Vec3};

use super::RawMesh;
use refract_geometry::GeometryError;
use refract_geometry::Mesh;

pub(super) fn read(path: &Path) -> Result<RawMesh, GeometryError> {
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let bytes = std::fs::read(path).map_err(|source| GeometryError::Io {
        path: path.to_owned(),
        source,
    })?;
    let obj_error = |message: String| GeometryError::Obj {
        path: path.to_owned(),
        message,
    };
    let text = utf8_text(&bytes).map_err(obj_error)?;
    // Materials (.mtl) are irrelevant to a refractor; they are not even opened.
    let (models, _materials) = tobj::load_obj_buf(&mut text.as_bytes(), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|err| {
        obj_error(match first_malformed_line(&text) {
            Some((line, content)) => format!("line {line}: cannot read `{content}` ({err})"),
            None => err.to_string(),
        })
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
        notes: vec![],
    })
}

/// The file as text: comments (`#` lines) may hold any bytes (they are replaced), other lines
/// must be UTF-8; the first that is not is named by its number.
fn utf8_text(bytes: &[u8]) -> Result<String, String> {
    let mut text = String::with_capacity(bytes.len());
    for (k, line) in bytes.split(|&b| b == b'\n').enumerate() {
        match std::str::from_utf8(line) {
            Ok(line) => text.push_str(line),
            Err(_) if line.trim_ascii_start().starts_with(b"#") => {
                text.push_str(&String::from_utf8_lossy(line));
            }
            Err(_) => {
                return Err(format!(
                    "line {}: not UTF-8 text; expected an OBJ file",
                    k + 1
                ));
            }
        }
        text.push('\n');
    }
    Ok(text)
}

/// The first `v`/`vn`/`vt`/`f` line whose fields do not parse, for error messages.
fn first_malformed_line(text: &str) -> Option<(usize, String)> {
    text.lines().enumerate().find_map(|(k, line)| {
        let mut fields = line.split_whitespace();
        let ok = match fields.next() {
            Some("v" | "vn" | "vt") => {
                let values: Vec<_> = fields.collect();
                !values.is_empty() && values.iter().all(|v| v.parse::<f32>().is_ok())
            }
            Some("f") => {
                let corners: Vec<_> = fields.collect();
                corners.len() >= 3
                    && corners.iter().all(|c| {
                        c.split('/')
                            .all(|i| i.is_empty() || i.parse::<i64>().is_ok())
                    })
            }
            _ => true,
        };
        (!ok).then(|| {
            let shown: String = line.chars().take(60).collect();
            (k + 1, shown)
        })
    })
}
