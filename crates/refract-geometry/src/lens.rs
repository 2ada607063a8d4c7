//! Spectacle lenses (Kakimoto et al. 2007 §4.5): two spherical caps on a common axis, their
//! vertices on concentric rings triangulated with spade's constrained Delaunay triangulation
//! of the disk, closed by a cylindrical rim into a watertight mesh.
//!
//! Axis and signs: the lens axis is `z`; the front surface (vertex at `z = +t/2`) faces `+z`, the
//! back surface (vertex at `z = −t/2`) faces `−z`, and light travels along `−z` (from a camera on
//! `+z`). A radius is positive when its centre of curvature lies on the `−z` side of its
//! surface, the usual optics convention for light travelling that way: a biconvex lens has
//! `R1 > 0 > R2`, a biconcave one `R1 < 0 < R2`, a meniscus radii of one sign. A flat surface
//! has an infinite radius.

use std::f32::consts::TAU;

use glam::{Vec2, Vec3};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use crate::error::GeometryError;
use crate::mesh::Mesh;

/// A spherical spectacle lens.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensDesc {
    /// Front radius of curvature `R1` (signed, see the module docs; `f32::INFINITY` for flat).
    pub front_radius: f32,
    /// Back radius of curvature `R2` (signed; `f32::INFINITY` for flat).
    pub back_radius: f32,
    /// Thickness on the axis, `t > 0`.
    pub center_thickness: f32,
    /// Diameter of the rim, `D > 0`, at most `2 |R|` for both caps.
    pub diameter: f32,
    /// Concentric rings of vertices from the axis to the rim (the rim is the last ring).
    pub rings: u32,
    /// Vertices on the rim ring; inner rings get proportionally fewer (at least 6).
    pub rim_segments: u32,
}

impl LensDesc {
    /// The built-in biconvex lens: `R1 = 2`, `R2 = −2`, `t = 0.5`, `D = 1.8` (edge thickness
    /// 0.072), 12 rings, 88 rim vertices: about 1,100 triangles per cap, like the 2,000-triangle
    /// lens of Kakimoto et al. §4.5.
    pub const BICONVEX: Self = Self {
        front_radius: 2.0,
        back_radius: -2.0,
        center_thickness: 0.5,
        diameter: 1.8,
        rings: 12,
        rim_segments: 88,
    };

    /// Sagitta of a cap of signed radius `R` at distance `r` from the axis,
    /// `s(R, r) = R − sign(R) √(R² − r²)` (0 for a flat cap). The surface through the vertex
    /// `z0` is `z(r) = z0 − s(R, r)`.
    pub fn sagitta(radius: f32, r: f32) -> f32 {
        if radius.is_infinite() {
            0.0
        } else {
            radius - radius.signum() * (radius * radius - r * r).max(0.0).sqrt()
        }
    }

    /// `z` of the front surface at distance `r` from the axis: `t/2 − s(R1, r)`.
    pub fn front_z(&self, r: f32) -> f32 {
        0.5 * self.center_thickness - Self::sagitta(self.front_radius, r)
    }

    /// `z` of the back surface at distance `r` from the axis: `−t/2 − s(R2, r)`.
    pub fn back_z(&self, r: f32) -> f32 {
        -0.5 * self.center_thickness - Self::sagitta(self.back_radius, r)
    }

    /// Thickness at the rim, `front_z(D/2) − back_z(D/2)`.
    pub fn edge_thickness(&self) -> f32 {
        self.front_z(0.5 * self.diameter) - self.back_z(0.5 * self.diameter)
    }

    /// Thick-lens focal length in air (lensmaker's equation):
    /// `1/f = (n − 1) [1/R1 − 1/R2 + (n − 1) t / (n R1 R2)]`.
    pub fn focal_length(&self, ior: f32) -> f32 {
        let (r1, r2, t, n) = (
            self.front_radius,
            self.back_radius,
            self.center_thickness,
            ior,
        );
        let power = (n - 1.0) * (1.0 / r1 - 1.0 / r2 + (n - 1.0) * t / (n * r1 * r2));
        1.0 / power
    }

    fn validate(&self) -> Result<(), GeometryError> {
        let fail = |m: String| Err(GeometryError::Lens(m));
        let half = 0.5 * self.diameter;
        if !(self.diameter > 0.0 && self.diameter.is_finite()) {
            return fail(format!(
                "diameter {}: expected a finite number > 0",
                self.diameter
            ));
        }
        if !(self.center_thickness > 0.0 && self.center_thickness.is_finite()) {
            return fail(format!(
                "center thickness {}: expected a finite number > 0",
                self.center_thickness
            ));
        }
        for (name, radius) in [("front", self.front_radius), ("back", self.back_radius)] {
            if radius.is_nan() || radius == 0.0 || radius.abs() < half {
                return fail(format!(
                    "{name} radius {radius}: expected |R| ≥ D/2 = {half} (or infinite for a flat face)"
                ));
            }
        }
        if self.rings < 1 || self.rim_segments < 6 {
            return fail(format!(
                "rings {} and rim segments {}: expected at least 1 ring and 6 rim segments",
                self.rings, self.rim_segments
            ));
        }
        let min_thickness = (0..=64)
            .map(|k| half * k as f32 / 64.0)
            .map(|r| self.front_z(r) - self.back_z(r))
            .fold(f32::INFINITY, f32::min);
        if min_thickness <= 0.0 {
            return fail(format!(
                "the faces cross (thinnest {min_thickness:.4} at edge thickness {:.4}): increase the centre thickness",
                self.edge_thickness()
            ));
        }
        Ok(())
    }

    /// Builds the watertight lens mesh: front cap, back cap (mirror winding) and rim, with
    /// analytic normals (spherical on the caps, radial on the rim; the rim has its own vertices so
    /// that the crease stays sharp).
    pub fn build(&self) -> Result<Mesh, GeometryError> {
        self.validate()?;
        let disk = disk_triangulation(0.5 * self.diameter, self.rings, self.rim_segments)?;
        let n = disk.points.len() as u32;
        let (mut positions, mut normals) = (Vec::new(), Vec::new());
        for &p in &disk.points {
            let r = p.length();
            positions.push(Vec3::new(p.x, p.y, self.front_z(r)));
            normals.push(cap_normal(p, self.front_radius, 1.0));
        }
        for &p in &disk.points {
            let r = p.length();
            positions.push(Vec3::new(p.x, p.y, self.back_z(r)));
            normals.push(cap_normal(p, self.back_radius, -1.0));
        }
        let mut triangles: Vec<[u32; 3]> = disk.triangles.clone();
        triangles.extend(
            disk.triangles
                .iter()
                .map(|&[a, b, c]| [a + n, c + n, b + n]),
        );

        // Rim: its own copies of the boundary positions, with radial normals.
        let rim_base = positions.len() as u32;
        let m = disk.rim.len() as u32;
        for &i in &disk.rim {
            let radial = disk.points[i as usize].extend(0.0).normalize();
            positions.push(positions[i as usize]);
            normals.push(radial);
            positions.push(positions[(i + n) as usize]);
            normals.push(radial);
        }
        for j in 0..m {
            let (front_j, back_j) = (rim_base + 2 * j, rim_base + 2 * j + 1);
            let (front_k, back_k) = (
                rim_base + 2 * ((j + 1) % m),
                rim_base + 2 * ((j + 1) % m) + 1,
            );
            triangles.push([front_j, back_j, back_k]);
            triangles.push([front_j, back_k, front_k]);
        }
        Mesh::new("lens", positions, Some(normals), vec![], triangles)
    }
}

/// Outward normal of a cap at disk point `p`: `facing` is `+1` for the front (faces `+z`), `−1`
/// for the back. For a sphere of signed radius `R` the centre is `z0 − R` along the axis, so the
/// unit normal is `facing · (p − c)/R` in the plane of the cap's profile.
fn cap_normal(p: Vec2, radius: f32, facing: f32) -> Vec3 {
    if radius.is_infinite() {
        return Vec3::new(0.0, 0.0, facing);
    }
    let r2 = p.length_squared();
    let dz = radius.signum() * (radius * radius - r2).max(0.0).sqrt();
    (facing * Vec3::new(p.x, p.y, dz) / radius).normalize()
}

struct Disk {
    points: Vec<Vec2>,
    triangles: Vec<[u32; 3]>,
    /// Indices of the rim points, in counter-clockwise order.
    rim: Vec<u32>,
}

/// Centre + concentric rings, the rim polygon as constraint edges, triangulated by spade.
fn disk_triangulation(radius: f32, rings: u32, rim_segments: u32) -> Result<Disk, GeometryError> {
    let mut points = vec![Vec2::ZERO];
    let mut rim = Vec::new();
    for k in 1..=rings {
        let rho = radius * k as f32 / rings as f32;
        let count = if k == rings {
            rim_segments
        } else {
            ((rim_segments * k) as f32 / rings as f32).round().max(6.0) as u32
        };
        // Alternate rings are rotated by half a step for better-shaped triangles.
        let offset = if k % 2 == 0 { 0.5 } else { 0.0 };
        for j in 0..count {
            let phi = TAU * (j as f32 + offset) / count as f32;
            if k == rings {
                rim.push(points.len() as u32);
            }
            points.push(rho * Vec2::new(phi.cos(), phi.sin()));
        }
    }
    let vertices: Vec<Point2<f64>> = points
        .iter()
        .map(|p| Point2::new(f64::from(p.x), f64::from(p.y)))
        .collect();
    let edges: Vec<[usize; 2]> = (0..rim.len())
        .map(|j| [rim[j] as usize, rim[(j + 1) % rim.len()] as usize])
        .collect();
    let cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::bulk_load_cdt(vertices, edges)
        .map_err(|err| GeometryError::Lens(format!("triangulating the disk failed: {err:?}")))?;
    if cdt.num_vertices() != points.len() {
        return Err(GeometryError::Lens(
            "triangulating the disk merged duplicate points".to_owned(),
        ));
    }
    let triangles = cdt
        .inner_faces()
        .map(|face| face.vertices().map(|v| v.fix().index() as u32))
        .collect();
    Ok(Disk {
        points,
        triangles,
        rim,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(desc: &LensDesc) -> Mesh {
        let lens = desc.build().expect("valid lens");
        let facts = lens.facts();
        assert!(facts.watertight, "{facts:?}");
        assert!(facts.signed_volume > 0.0, "outward winding: {facts:?}");
        // Thickness on the axis.
        let on_axis: Vec<f32> = lens
            .positions
            .iter()
            .filter(|p| p.x == 0.0 && p.y == 0.0)
            .map(|p| p.z)
            .collect();
        let thickness = on_axis.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b))
            - on_axis.iter().fold(f32::INFINITY, |a, &b| a.min(b));
        assert!(
            (thickness - desc.center_thickness).abs() < 1e-6,
            "{thickness}"
        );
        // Curvature: every front-cap vertex lies on the sphere of radius |R1| about its centre.
        if desc.front_radius.is_finite() {
            let centre = Vec3::new(0.0, 0.0, 0.5 * desc.center_thickness - desc.front_radius);
            let n = (lens.positions.len() - 2 * desc.rim_segments as usize) / 2;
            for p in &lens.positions[..n] {
                let err = (p.distance(centre) - desc.front_radius.abs()).abs();
                assert!(err < 1e-5, "front vertex {p} off the sphere by {err}");
            }
        }
        lens
    }

    #[test]
    fn biconvex_lens_is_watertight_with_its_thickness_and_curvature() {
        let lens = check(&LensDesc::BICONVEX);
        let per_cap = (lens.triangles.len() - 2 * 88) / 2;
        assert!(
            (900..=1300).contains(&per_cap),
            "{per_cap} triangles per cap"
        );
        assert!((LensDesc::BICONVEX.edge_thickness() - 0.0717).abs() < 1e-3);
    }

    #[test]
    fn biconcave_and_meniscus_lenses_are_watertight() {
        check(&LensDesc {
            front_radius: -1.5,
            back_radius: 1.5,
            center_thickness: 0.1,
            ..LensDesc::BICONVEX
        });
        check(&LensDesc {
            front_radius: 1.0,
            back_radius: 2.0,
            center_thickness: 0.3,
            diameter: 1.6,
            ..LensDesc::BICONVEX
        });
        check(&LensDesc {
            front_radius: f32::INFINITY,
            back_radius: -1.5,
            ..LensDesc::BICONVEX
        });
    }

    #[test]
    fn lensmaker_focal_length_of_a_thin_symmetric_lens() {
        // Thin-lens limit: 1/f = (n − 1)(2/R), f = R / (2 (n − 1)) = 2 for R = 2, n = 1.5.
        let thin = LensDesc {
            center_thickness: 1e-4,
            ..LensDesc::BICONVEX
        };
        assert!((thin.focal_length(1.5) - 2.0).abs() < 1e-3);
    }

    #[test]
    fn impossible_lenses_are_errors() {
        assert!(
            LensDesc {
                front_radius: 0.5,
                ..LensDesc::BICONVEX
            }
            .build()
            .is_err()
        );
        assert!(
            LensDesc {
                center_thickness: 0.05,
                ..LensDesc::BICONVEX
            }
            .build()
            .is_err()
        );
        assert!(
            LensDesc {
                diameter: f32::NAN,
                ..LensDesc::BICONVEX
            }
            .build()
            .is_err()
        );
    }
}
