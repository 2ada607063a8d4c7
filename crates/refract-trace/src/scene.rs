//! What the reference tracer renders: one refractor, nearby opaque objects, a directional light
//! and a distant environment.

use glam::{Vec2, Vec3};
use refract_geometry::{Mesh, MeshBvh};

use crate::environment::Environment;
use crate::error::TraceError;

/// The dielectric object every method refracts through.
#[derive(Clone, Debug)]
pub struct Refractor {
    /// Its mesh (outward winding and normals).
    pub mesh: Mesh,
    /// Its BVH.
    pub bvh: MeshBvh,
    ior: f32,
}

impl Refractor {
    /// A refractor of index `ior` (the outside is 1).
    pub fn new(mesh: Mesh, ior: f32) -> Result<Self, TraceError> {
        if !(ior > 0.0 && ior.is_finite()) {
            return Err(TraceError::Parameter {
                field: "ior",
                value: ior.to_string(),
                expected: "a finite index of refraction greater than 0",
            });
        }
        let bvh = MeshBvh::build(&mesh);
        Ok(Self { mesh, bvh, ior })
    }

    /// Index of refraction.
    pub fn ior(&self) -> f32 {
        self.ior
    }
}

/// The reflectance of an opaque diffuse surface.
#[derive(Clone, Debug, PartialEq)]
pub enum Albedo {
    /// One colour.
    Constant(Vec3),
    /// A checkerboard of two colours with `squares` squares per unit of uv (or of world `x`/`z`
    /// when the mesh has no uvs).
    Checker {
        /// First colour.
        a: Vec3,
        /// Second colour.
        b: Vec3,
        /// Squares per unit.
        squares: f32,
    },
    /// A 6 × 4 colour chart over the uv square (approximate linear-sRGB values of the 24
    /// patches of the classic ColorChecker), grey elsewhere.
    ColorChart,
}

/// Linear sRGB of the 24 ColorChecker patches, row by row (approximate published values).
const COLOR_CHART: [[f32; 3]; 24] = [
    [0.173, 0.085, 0.059],
    [0.554, 0.300, 0.222],
    [0.117, 0.195, 0.335],
    [0.107, 0.148, 0.058],
    [0.236, 0.221, 0.432],
    [0.132, 0.515, 0.409],
    [0.680, 0.198, 0.025],
    [0.072, 0.103, 0.386],
    [0.545, 0.085, 0.117],
    [0.109, 0.045, 0.142],
    [0.327, 0.503, 0.049],
    [0.741, 0.364, 0.020],
    [0.030, 0.046, 0.287],
    [0.066, 0.291, 0.066],
    [0.428, 0.031, 0.040],
    [0.816, 0.578, 0.010],
    [0.505, 0.083, 0.288],
    [0.000, 0.235, 0.383],
    [0.887, 0.887, 0.869],
    [0.588, 0.591, 0.590],
    [0.361, 0.367, 0.368],
    [0.191, 0.191, 0.192],
    [0.088, 0.089, 0.090],
    [0.031, 0.032, 0.032],
];

impl Albedo {
    /// The albedo at texture coordinates `uv` (or world `xz` for meshes without uvs).
    pub fn at(&self, uv: Vec2) -> Vec3 {
        match *self {
            Self::Constant(c) => c,
            Self::Checker { a, b, squares } => {
                let cell = (uv * squares).floor();
                if (cell.x + cell.y).rem_euclid(2.0) < 1.0 {
                    a
                } else {
                    b
                }
            }
            Self::ColorChart => {
                if !(0.0..1.0).contains(&uv.x) || !(0.0..1.0).contains(&uv.y) {
                    return Vec3::splat(0.18);
                }
                let (col, row) = ((uv.x * 6.0) as usize, (uv.y * 4.0) as usize);
                Vec3::from_array(COLOR_CHART[row * 6 + col])
            }
        }
    }
}

/// An opaque diffuse object near the refractor (Wyman 2005b's "nearby geometry").
#[derive(Clone, Debug)]
pub struct Object {
    /// Its mesh.
    pub mesh: Mesh,
    /// Its BVH.
    pub bvh: MeshBvh,
    /// Its reflectance.
    pub albedo: Albedo,
}

impl Object {
    /// Builds the BVH of an object.
    pub fn new(mesh: Mesh, albedo: Albedo) -> Self {
        let bvh = MeshBvh::build(&mesh);
        Self { mesh, bvh, albedo }
    }
}

/// View-independent lighting of opaque objects: `albedo × (ambient + max(0, N·L) · radiance)`.
/// No shadows: image-space methods that store nearby geometry in a texture (Wyman 2005b) see
/// exactly this, so the comparison stays fair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalLight {
    /// Unit direction toward the light.
    pub direction: Vec3,
    /// Radiance scale of the light.
    pub radiance: Vec3,
    /// Ambient term.
    pub ambient: Vec3,
}

impl Default for DirectionalLight {
    fn default() -> Self {
        Self {
            direction: Vec3::new(0.4, 0.6, -0.7).normalize(),
            radiance: Vec3::splat(0.8),
            ambient: Vec3::splat(0.25),
        }
    }
}

impl DirectionalLight {
    /// Diffuse radiance leaving a surface of `albedo` with unit normal `n`, seen from either side.
    pub fn shade(&self, albedo: Vec3, n: Vec3) -> Vec3 {
        albedo * (self.ambient + n.dot(self.direction).abs() * self.radiance)
    }
}

/// Everything the reference tracer renders.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The refractor.
    pub refractor: Refractor,
    /// Opaque objects near it.
    pub objects: Vec<Object>,
    /// Distant lighting.
    pub environment: Environment,
    /// The light of the opaque objects.
    pub light: DirectionalLight,
}

impl Scene {
    /// A refractor alone in an environment.
    pub fn new(refractor: Refractor, environment: Environment) -> Self {
        Self {
            refractor,
            objects: Vec::new(),
            environment,
            light: DirectionalLight::default(),
        }
    }
}
