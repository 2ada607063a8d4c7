//! The built-in procedural shapes, addressed as `builtin:NAME` in scene files and on the
//! command line. None needs a file.

use glam::Vec3;

use crate::error::GeometryError;
use crate::lens::LensDesc;
use crate::mesh::Mesh;
use crate::shapes;

/// The built-in shapes and a line about each.
pub const CATALOG: &[(&str, &str)] = &[
    (
        "sphere",
        "UV sphere, 40 segments x 21 rings = 1,600 triangles (Wyman 2005a's sphere)",
    ),
    (
        "icosphere",
        "icosphere, 3 subdivisions = 1,280 near-uniform triangles",
    ),
    (
        "torus",
        "torus R = 0.7, r = 0.3, 64 x 32 = 4,096 triangles (concave)",
    ),
    (
        "box",
        "cube inscribed in the unit sphere, flat faces, 12 triangles",
    ),
    (
        "plane",
        "square ground plane (side sqrt 2) facing +y with uvs, 16 x 16 quads",
    ),
    (
        "lens",
        "biconvex spectacle lens R1 = 2, R2 = -2, t = 0.5, D = 1.8 (Kakimoto et al. 4.5)",
    ),
    (
        "lens-concave",
        "biconcave spectacle lens R1 = -2, R2 = 2, t = 0.08, D = 1.8 (Kakimoto et al. Fig. 12 right, 14)",
    ),
    (
        "mirror-convex",
        "convex square mirror, side 1.1, R = 4, 7 x 7 = 49 vertices facing +z (Kakimoto et al. Fig. 1, 9)",
    ),
    (
        "mirror-flat",
        "flat square mirror, side 1.1, 7 x 7 = 49 vertices facing +z (Kakimoto et al. Fig. 9)",
    ),
    (
        "mirror-concave",
        "concave square mirror, side 1.1, R = -8 (focal length 4: the eye of the built-in scenes inside it), 7 x 7 = 49 vertices facing +z (Kakimoto et al. Fig. 8(b), 9)",
    ),
    (
        "mirror-left",
        "left 4 of the 7 columns of mirror-convex (Kakimoto et al. Fig. 7: shares 7 vertices with mirror-right)",
    ),
    (
        "mirror-right",
        "right 4 of the 7 columns of mirror-convex (Kakimoto et al. Fig. 7)",
    ),
    (
        "prism",
        "equilateral (60 deg) prism along y, circumradius 0.45, height 1.4, flat faces (sides 6 x 6 quads), 218 triangles",
    ),
    (
        "slits",
        "15 vertical strips 0.012 wide and 1.4 tall over 1.4 in x, facing +z (a dispersion test's bright slits)",
    ),
];

/// The names in [`CATALOG`].
pub const NAMES: [&str; 14] = [
    "sphere",
    "icosphere",
    "torus",
    "box",
    "plane",
    "lens",
    "lens-concave",
    "mirror-convex",
    "mirror-flat",
    "mirror-concave",
    "mirror-left",
    "mirror-right",
    "prism",
    "slits",
];

/// The mirrors' side and radius of curvature (`mirror-*`).
pub const MIRROR_SIZE: f32 = 1.1;
/// See [`MIRROR_SIZE`].
pub const MIRROR_RADIUS: f32 = 4.0;

/// The built-in biconcave lens.
pub const BICONCAVE: LensDesc = LensDesc {
    front_radius: -2.0,
    back_radius: 2.0,
    center_thickness: 0.08,
    ..LensDesc::BICONVEX
};

/// The prefix that marks a built-in shape in a mesh path.
pub const PREFIX: &str = "builtin:";

/// Builds a built-in shape by name (`sphere` or `builtin:sphere`). All fit in the unit sphere.
pub fn mesh(name: &str) -> Result<Mesh, GeometryError> {
    let short = name.strip_prefix(PREFIX).unwrap_or(name);
    let mut mesh = match short {
        "sphere" => shapes::uv_sphere(40, 21, 1.0),
        "icosphere" => shapes::icosphere(3, 1.0),
        "torus" => shapes::torus(0.7, 0.3, 64, 32),
        "box" => shapes::cuboid(Vec3::splat(1.0 / 3f32.sqrt()), 1),
        "plane" => shapes::plane(2f32.sqrt(), 16),
        "lens" => LensDesc::BICONVEX.build(),
        "lens-concave" => BICONCAVE.build(),
        "mirror-convex" => shapes::mirror_patch(MIRROR_SIZE, MIRROR_RADIUS, 7, 0..7),
        "mirror-flat" => shapes::mirror_patch(MIRROR_SIZE, f32::INFINITY, 7, 0..7),
        "mirror-concave" => shapes::mirror_patch(MIRROR_SIZE, -2.0 * MIRROR_RADIUS, 7, 0..7),
        "mirror-left" => shapes::mirror_patch(MIRROR_SIZE, MIRROR_RADIUS, 7, 0..4),
        "mirror-right" => shapes::mirror_patch(MIRROR_SIZE, MIRROR_RADIUS, 7, 3..7),
        "prism" => shapes::prism(0.45, 1.4, 6),
        "slits" => shapes::slits(15, 0.012, 1.4, 1.4),
        _ => {
            return Err(GeometryError::UnknownBuiltin {
                name: name.to_owned(),
                valid: NAMES.map(|n| format!("{PREFIX}{n}")).join(", "),
            });
        }
    }?;
    mesh.name = format!("{PREFIX}{short}");
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_builds_and_fits_the_unit_sphere() {
        assert_eq!(CATALOG.len(), NAMES.len());
        for (name, _) in CATALOG {
            let mesh = mesh(name).expect(name);
            let sphere = mesh.bounding_sphere();
            assert!(
                sphere.center.length() + sphere.radius <= 1.0 + 1e-5,
                "{name}: {sphere:?}"
            );
            assert_eq!(mesh.name, format!("builtin:{name}"));
        }
        assert!(
            mesh("builtin:teapot")
                .expect_err("unknown")
                .to_string()
                .contains("builtin:torus")
        );
    }
}
