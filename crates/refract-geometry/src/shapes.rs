//! Procedural shapes: the embedded default scenes need no file. All are counter-clockwise wound
//! (outward normals), centred at the origin, with analytic unit normals.

use std::collections::HashMap;
use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use crate::error::GeometryError;
use crate::mesh::Mesh;

fn require(shape: &'static str, ok: bool, message: &str) -> Result<(), GeometryError> {
    if ok {
        Ok(())
    } else {
        Err(GeometryError::Shape {
            shape,
            message: message.to_owned(),
        })
    }
}

/// A UV sphere of `radius` around the `y` axis: two poles and `rings − 1` latitude circles of
/// `segments` vertices, `2 · segments · (rings − 1)` triangles (40 × 21 gives the 1,600 of
/// Wyman 2005a's sphere). Seam vertices are shared, so the mesh is closed.
pub fn uv_sphere(segments: u32, rings: u32, radius: f32) -> Result<Mesh, GeometryError> {
    require(
        "uv_sphere",
        segments >= 3 && rings >= 2,
        "expected segments ≥ 3 and rings ≥ 2",
    )?;
    require(
        "uv_sphere",
        radius > 0.0 && radius.is_finite(),
        "expected a finite radius > 0",
    )?;
    let mut normals = vec![Vec3::Y];
    for k in 1..rings {
        let theta = PI * k as f32 / rings as f32;
        for j in 0..segments {
            let phi = TAU * j as f32 / segments as f32;
            normals.push(Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            ));
        }
    }
    normals.push(Vec3::NEG_Y);
    let south = normals.len() as u32 - 1;
    let ring = |k: u32, j: u32| 1 + (k - 1) * segments + j % segments;
    let mut triangles = Vec::with_capacity(2 * (segments * (rings - 1)) as usize);
    for j in 0..segments {
        triangles.push([0, ring(1, j), ring(1, j + 1)]);
    }
    for k in 1..rings - 1 {
        for j in 0..segments {
            let (a, b, c, d) = (
                ring(k, j),
                ring(k + 1, j),
                ring(k + 1, j + 1),
                ring(k, j + 1),
            );
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    for j in 0..segments {
        triangles.push([south, ring(rings - 1, j + 1), ring(rings - 1, j)]);
    }
    let positions = normals.iter().map(|n| radius * *n).collect();
    Mesh::new(
        format!("uv_sphere({segments}x{rings})"),
        positions,
        Some(normals),
        vec![],
        triangles,
    )
}

/// An icosphere: the icosahedron with each triangle split in four `subdivisions` times and the
/// vertices pushed onto the sphere, `20 · 4^subdivisions` near-uniform triangles.
pub fn icosphere(subdivisions: u32, radius: f32) -> Result<Mesh, GeometryError> {
    require(
        "icosphere",
        subdivisions <= 7,
        "expected at most 7 subdivisions (327,680 triangles)",
    )?;
    require(
        "icosphere",
        radius > 0.0 && radius.is_finite(),
        "expected a finite radius > 0",
    )?;
    let g = (1.0 + 5f32.sqrt()) / 2.0;
    let mut normals: Vec<Vec3> = [
        (-1.0, g, 0.0),
        (1.0, g, 0.0),
        (-1.0, -g, 0.0),
        (1.0, -g, 0.0),
        (0.0, -1.0, g),
        (0.0, 1.0, g),
        (0.0, -1.0, -g),
        (0.0, 1.0, -g),
        (g, 0.0, -1.0),
        (g, 0.0, 1.0),
        (-g, 0.0, -1.0),
        (-g, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, normals: &mut Vec<Vec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                normals.push((normals[a as usize] + normals[b as usize]).normalize());
                normals.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(triangles.len() * 4);
        for [a, b, c] in triangles {
            let ab = midpoint(a, b, &mut normals);
            let bc = midpoint(b, c, &mut normals);
            let ca = midpoint(c, a, &mut normals);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    let positions = normals.iter().map(|n| radius * *n).collect();
    Mesh::new(
        format!("icosphere({subdivisions})"),
        positions,
        Some(normals),
        vec![],
        triangles,
    )
}

/// A torus around the `y` axis with tube centre radius `major` and tube radius `minor`,
/// `segments` around the axis and `sides` around the tube (`2 · segments · sides` triangles).
pub fn torus(major: f32, minor: f32, segments: u32, sides: u32) -> Result<Mesh, GeometryError> {
    require(
        "torus",
        segments >= 3 && sides >= 3,
        "expected segments ≥ 3 and sides ≥ 3",
    )?;
    require(
        "torus",
        minor > 0.0 && major > minor && major.is_finite(),
        "expected 0 < minor < major",
    )?;
    let (mut positions, mut normals) = (Vec::new(), Vec::new());
    for i in 0..segments {
        let phi = TAU * i as f32 / segments as f32;
        let radial = Vec3::new(phi.cos(), 0.0, -phi.sin());
        for j in 0..sides {
            let psi = TAU * j as f32 / sides as f32;
            let normal = psi.cos() * radial + psi.sin() * Vec3::Y;
            positions.push(major * radial + minor * normal);
            normals.push(normal);
        }
    }
    let index = |i: u32, j: u32| (i % segments) * sides + j % sides;
    let mut triangles = Vec::with_capacity((2 * segments * sides) as usize);
    for i in 0..segments {
        for j in 0..sides {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    Mesh::new(
        format!("torus({major},{minor})"),
        positions,
        Some(normals),
        vec![],
        triangles,
    )
}

/// An axis-aligned box with the given half extents, each face a grid of `subdivisions²` quads
/// with flat normals (faces have their own vertices; the box is closed by position).
pub fn cuboid(half_extents: Vec3, subdivisions: u32) -> Result<Mesh, GeometryError> {
    require(
        "box",
        half_extents.cmpgt(Vec3::ZERO).all() && half_extents.is_finite() && subdivisions >= 1,
        "expected half extents > 0 and subdivisions ≥ 1",
    )?;
    let (mut positions, mut normals, mut triangles) = (Vec::new(), Vec::new(), Vec::new());
    let n = subdivisions + 1;
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            let mut normal = Vec3::ZERO;
            normal[axis] = sign;
            // Two tangents with u × v = normal, so the grid is counter-clockwise from outside.
            let u = Vec3::from_array(std::array::from_fn(|k| {
                if k == (axis + 1) % 3 { 1.0 } else { 0.0 }
            }));
            let v = normal.cross(u);
            let base = positions.len() as u32;
            for k in 0..n {
                for j in 0..n {
                    // (2j − s)/s is odd-symmetric in floating point (one rounding of an exact
                    // integer), so faces meeting at an edge compute bit-identical positions.
                    let grid =
                        |i: u32| (2 * i as i32 - subdivisions as i32) as f32 / subdivisions as f32;
                    let (su, sv) = (grid(j), grid(k));
                    positions.push((normal + su * u + sv * v) * half_extents);
                    normals.push(normal);
                }
            }
            for k in 0..subdivisions {
                for j in 0..subdivisions {
                    let a = base + k * n + j;
                    triangles.push([a, a + 1, a + n + 1]);
                    triangles.push([a, a + n + 1, a + n]);
                }
            }
        }
    }
    Mesh::new("box", positions, Some(normals), vec![], triangles)
}

/// A straight prism of equilateral cross-section (apex angle 60°, the dispersion prism of the
/// textbooks) along `y`, `height` tall, its triangle's vertices at distance `circumradius` from
/// the axis, one of them toward `+x`; flat faces with their own vertices (three rectangles, each
/// a grid of `subdivisions²` quads so that most vertices have a `d_N` of their own, and the two
/// end triangles), closed by position.
pub fn prism(circumradius: f32, height: f32, subdivisions: u32) -> Result<Mesh, GeometryError> {
    require(
        "prism",
        circumradius > 0.0
            && circumradius.is_finite()
            && height > 0.0
            && height.is_finite()
            && subdivisions >= 1,
        "expected a circumradius and a height > 0 and subdivisions ≥ 1",
    )?;
    let corner = |k: u32| {
        let a = k as f32 * core::f32::consts::TAU / 3.0;
        Vec3::new(a.cos(), 0.0, -a.sin()) * circumradius
    };
    let half = 0.5 * height;
    let (mut positions, mut normals, mut triangles) = (Vec::new(), Vec::new(), Vec::new());
    let n = subdivisions + 1;
    for k in 0..3 {
        let (a, b) = (corner(k), corner(k + 1));
        let outward = (a + b).normalize();
        let base = positions.len() as u32;
        for row in 0..n {
            for col in 0..n {
                let t = col as f32 / subdivisions as f32;
                let y = -half + height * row as f32 / subdivisions as f32;
                positions.push(a.lerp(b, t) + y * Vec3::Y);
                normals.push(outward);
            }
        }
        // Counter-clockwise seen from outside, whichever way a → b runs.
        let (p0, p1, p2) = (
            positions[base as usize],
            positions[base as usize + 1],
            positions[(base + n) as usize],
        );
        let flip = (p1 - p0).cross(p2 - p0).dot(outward) < 0.0;
        for row in 0..subdivisions {
            for col in 0..subdivisions {
                let q = base + row * n + col;
                let (t1, t2) = ([q, q + 1, q + n + 1], [q, q + n + 1, q + n]);
                if flip {
                    triangles.push([t1[0], t1[2], t1[1]]);
                    triangles.push([t2[0], t2[2], t2[1]]);
                } else {
                    triangles.push(t1);
                    triangles.push(t2);
                }
            }
        }
    }
    for (y, normal) in [(half, Vec3::Y), (-half, Vec3::NEG_Y)] {
        let base = positions.len() as u32;
        let cap = [0, 1, 2].map(|k| corner(k) + y * Vec3::Y);
        positions.extend_from_slice(&cap);
        normals.extend([normal; 3]);
        let wound = (cap[1] - cap[0]).cross(cap[2] - cap[0]).dot(normal) > 0.0;
        triangles.push(if wound {
            [base, base + 1, base + 2]
        } else {
            [base, base + 2, base + 1]
        });
    }
    Mesh::new("prism", positions, Some(normals), vec![], triangles)
}

/// `count` vertical strips in the `xy` plane facing `+z`, each `width` wide and `height` tall,
/// their centres evenly spaced over `[−span/2, span/2]` in `x`: the bright slits of a
/// dispersion test, before a dark wall.
pub fn slits(count: u32, width: f32, span: f32, height: f32) -> Result<Mesh, GeometryError> {
    require(
        "slits",
        count >= 1
            && width > 0.0
            && span >= 0.0
            && height > 0.0
            && [width, span, height].iter().all(|v| v.is_finite())
            && (count == 1 || width < span / (count - 1) as f32),
        "expected at least one slit, width and height > 0, and slits narrower than their spacing",
    )?;
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    for k in 0..count {
        let x = if count == 1 {
            0.0
        } else {
            span * (k as f32 / (count - 1) as f32 - 0.5)
        };
        let base = positions.len() as u32;
        let (l, r, h) = (x - 0.5 * width, x + 0.5 * width, 0.5 * height);
        positions.extend([
            Vec3::new(l, -h, 0.0),
            Vec3::new(r, -h, 0.0),
            Vec3::new(r, h, 0.0),
            Vec3::new(l, h, 0.0),
        ]);
        triangles.push([base, base + 1, base + 2]);
        triangles.push([base, base + 2, base + 3]);
    }
    let normals = vec![Vec3::Z; positions.len()];
    Mesh::new("slits", positions, Some(normals), vec![], triangles)
}

/// A square in the `xz` plane facing `+y`, side `size`, `subdivisions²` quads, with uvs in
/// `[0, 1]²` (`u` along `+x`, `v` along `+z`) for textured ground planes.
pub fn plane(size: f32, subdivisions: u32) -> Result<Mesh, GeometryError> {
    require(
        "plane",
        subdivisions >= 1 && size > 0.0 && size.is_finite(),
        "expected size > 0 and subdivisions ≥ 1",
    )?;
    let n = subdivisions + 1;
    let (mut positions, mut uvs) = (Vec::new(), Vec::new());
    for k in 0..n {
        for j in 0..n {
            let uv = Vec2::new(j as f32, k as f32) / subdivisions as f32;
            positions.push(Vec3::new((uv.x - 0.5) * size, 0.0, (uv.y - 0.5) * size));
            uvs.push(uv);
        }
    }
    let mut triangles = Vec::new();
    for k in 0..subdivisions {
        for j in 0..subdivisions {
            let (a, b, c, d) = (
                k * n + j,
                k * n + j + 1,
                (k + 1) * n + j + 1,
                (k + 1) * n + j,
            );
            triangles.push([a, c, b]);
            triangles.push([a, d, c]);
        }
    }
    let normals = vec![Vec3::Y; positions.len()];
    Mesh::new("plane", positions, Some(normals), uvs, triangles)
}

/// A square mirror patch facing `+z`, side `size`, on a sphere of signed radius of curvature
/// `radius` (`> 0` convex, bulging toward `+z`; `< 0` concave; infinite: flat), as a grid of
/// `vertices × vertices` (Kakimoto et al. Fig. 9; 7 × 7 = 49 vertices is their car mirror),
/// keeping the grid columns `columns` only (`0..vertices` for the whole patch; two ranges that
/// share a column are the adjacent mirrors of Fig. 7, with the shared vertices identical).
/// Surface `z = −s(R, r)` with `s` the sagitta ([`crate::LensDesc::sagitta`]), analytic normals.
pub fn mirror_patch(
    size: f32,
    radius: f32,
    vertices: u32,
    columns: core::ops::Range<u32>,
) -> Result<Mesh, GeometryError> {
    let half = 0.5 * size;
    require(
        "mirror patch",
        vertices >= 2
            && size > 0.0
            && size.is_finite()
            && !radius.is_nan()
            && radius != 0.0
            && (radius.is_infinite() || radius.abs() > half * core::f32::consts::SQRT_2)
            && columns.start + 1 < columns.end
            && columns.end <= vertices,
        "expected size > 0, |radius| > the half-diagonal, at least 2 vertices per side and 2 columns",
    )?;
    let width = columns.end - columns.start;
    let (mut positions, mut normals, mut uvs) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..vertices {
        for j in columns.clone() {
            let uv = Vec2::new(j as f32, k as f32) / (vertices - 1) as f32;
            let (x, y) = ((uv.x - 0.5) * size, (0.5 - uv.y) * size);
            let r = (x * x + y * y).sqrt();
            let z = -crate::LensDesc::sagitta(radius, r);
            let normal = if radius.is_infinite() {
                Vec3::Z
            } else {
                // The centre of curvature lies at (0, 0, −R).
                (Vec3::new(x, y, z) - Vec3::new(0.0, 0.0, -radius)).normalize() * radius.signum()
            };
            positions.push(Vec3::new(x, y, z));
            normals.push(normal);
            uvs.push(uv);
        }
    }
    let mut triangles = Vec::new();
    for k in 0..vertices - 1 {
        for j in 0..width - 1 {
            let (a, b, c, d) = (
                k * width + j,
                k * width + j + 1,
                (k + 1) * width + j + 1,
                (k + 1) * width + j,
            );
            triangles.push([a, d, c]);
            triangles.push([a, c, b]);
        }
    }
    Mesh::new("mirror patch", positions, Some(normals), uvs, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirror_patches_face_plus_z_with_their_curvature() {
        for radius in [1.5, f32::INFINITY, -1.5] {
            let mesh = mirror_patch(1.3, radius, 7, 0..7).expect("test value");
            assert_eq!(mesh.positions.len(), 49);
            for (i, _) in mesh.triangles.iter().enumerate() {
                let [a, b, c] = mesh.triangle_positions(i);
                assert!((b - a).cross(c - a).z > 0.0, "winding toward +z");
            }
            let corner = mesh.positions[0];
            let expected = -crate::LensDesc::sagitta(radius, corner.truncate().length());
            assert!((corner.z - expected).abs() < 1e-6);
            // Convex: the corner normal leans outward (same sign as its position); concave: inward.
            let lean = mesh.normals[0].x * corner.x;
            assert_eq!(lean > 1e-6, radius > 0.0 && radius.is_finite(), "{radius}");
        }
        let left = mirror_patch(1.3, 1.5, 7, 0..4).expect("test value");
        let right = mirror_patch(1.3, 1.5, 7, 3..7).expect("test value");
        assert_eq!(left.positions[3], right.positions[0], "the shared column");
        assert!(mirror_patch(1.3, 0.5, 7, 0..7).is_err());
    }

    fn assert_closed_and_outward(mesh: &Mesh, volume: f32, tolerance: f32) {
        let facts = mesh.facts();
        assert!(facts.watertight, "{}: {facts:?}", mesh.name);
        assert!(
            (facts.signed_volume - volume).abs() < tolerance * volume,
            "{}: {facts:?} vs {volume}",
            mesh.name
        );
        // Winding and normals agree.
        for (i, tri) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = mesh.triangle_positions(i);
            let face = (b - a).cross(c - a);
            let n = mesh.normals[tri[0] as usize]
                + mesh.normals[tri[1] as usize]
                + mesh.normals[tri[2] as usize];
            assert!(
                face.dot(n) > 0.0,
                "{}: triangle {i} winds against its normals",
                mesh.name
            );
        }
    }

    #[test]
    fn builtin_sphere_has_the_papers_1600_triangles() {
        let sphere = uv_sphere(40, 21, 1.0).expect("sphere");
        assert_eq!(sphere.triangles.len(), 1600);
        // Inscribed polyhedron: volume a little below 4π/3.
        assert_closed_and_outward(&sphere, 4.0 * PI / 3.0, 0.03);
    }

    #[test]
    fn icosphere_torus_and_box_are_closed_with_their_volumes() {
        let ico = icosphere(3, 1.0).expect("icosphere");
        assert_eq!(ico.triangles.len(), 1280);
        assert_closed_and_outward(&ico, 4.0 * PI / 3.0, 0.02);
        let torus = torus(0.7, 0.3, 96, 48).expect("torus");
        assert_closed_and_outward(&torus, 2.0 * PI * PI * 0.7 * 0.09, 0.01);
        let cube = cuboid(Vec3::new(0.5, 1.0, 1.5), 3).expect("box");
        assert_closed_and_outward(&cube, 8.0 * 0.5 * 1.0 * 1.5, 1e-5);
    }

    /// The prism is closed and wound outward (its signed volume is `(3√3/4) r² h`), each face's
    /// normal points away from the axis or along it, and its apex angle is 60°.
    #[test]
    fn prism_is_closed_with_flat_outward_faces() {
        let (r, h) = (0.45, 1.4);
        let m = prism(r, h, 3).expect("prism");
        let volume = 3.0 * 3f32.sqrt() / 4.0 * r * r * h;
        assert!((m.signed_volume() - volume).abs() < 1e-5 * volume.max(1.0));
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let n = (b - a).cross(c - a).normalize();
            for i in t {
                assert!((m.normals[*i as usize] - n).length() < 1e-5, "flat faces");
            }
            assert!(n.dot((a + b + c) / 3.0) > 0.0, "outward");
        }
        let side_normals: Vec<Vec3> = m.normals.iter().filter(|n| n.y == 0.0).copied().collect();
        assert_eq!(side_normals.len(), 3 * 16);
        let angle = side_normals[0].angle_between(side_normals[16]).to_degrees();
        assert!(
            (angle - 120.0).abs() < 1e-3,
            "faces 120° apart: apex 60°, got {angle}"
        );
        assert!(
            slits(3, 0.5, 1.0, 1.0).is_err(),
            "slits wider than their spacing"
        );
        assert_eq!(
            slits(15, 0.012, 1.4, 1.4).expect("slits").triangles.len(),
            30
        );
    }

    #[test]
    fn plane_faces_up_with_uvs() {
        let plane = plane(2.0, 4).expect("plane");
        assert_eq!((plane.triangles.len(), plane.uvs.len()), (32, 25));
        let [a, b, c] = plane.triangle_positions(0);
        assert!((b - a).cross(c - a).y > 0.0);
        assert_eq!(plane.facts().boundary_edges, 16);
    }

    #[test]
    fn bad_parameters_are_errors() {
        assert!(uv_sphere(2, 5, 1.0).is_err());
        assert!(torus(0.3, 0.7, 8, 8).is_err());
        assert!(cuboid(Vec3::new(1.0, 0.0, 1.0), 1).is_err());
        assert!(icosphere(9, 1.0).is_err());
    }
}
