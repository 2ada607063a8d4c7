//! Small scenes shared by the cross-crate tests: a refractor with its BVH and d_N, ready for
//! the CPU backend and the reference tracer.

use refract_core::{Camera, CameraDesc};
use refract_geometry::{LoadOptions, Mesh, MeshBvh, builtin, load_mesh, normal_distances};
use refract_trace::{Environment, Refractor, Scene};

/// A refractor with everything the backends and the reference need.
pub struct TestScene {
    /// The reference's scene (mesh, BVH, IOR, environment).
    pub scene: Scene,
    /// Per-vertex d_N.
    pub d_n: Vec<f32>,
}

impl TestScene {
    /// Builds the scene of `mesh` at `ior` in `environment`.
    pub fn new(mesh: Mesh, ior: f32, environment: Environment) -> Self {
        let bvh = MeshBvh::build(&mesh);
        let d_n = normal_distances(&mesh, &bvh).values;
        let scene = Scene::new(Refractor::new(mesh, ior).expect("valid ior"), environment);
        Self { scene, d_n }
    }

    /// A built-in shape.
    pub fn builtin(name: &str, ior: f32) -> Self {
        Self::new(
            builtin::mesh(name).expect("builtin"),
            ior,
            Environment::Procedural,
        )
    }

    /// A mesh of `../shared/data/meshes`, normalised.
    pub fn shared(data: &std::path::Path, file: &str, ior: f32) -> Self {
        let mesh = load_mesh(&data.join("meshes").join(file), &LoadOptions::default())
            .expect(file)
            .mesh;
        Self::new(mesh, ior, Environment::Procedural)
    }

    /// The CPU backend's view of the refractor.
    pub fn prepared(&self) -> refract_cpu::PreparedRefractor<'_> {
        refract_cpu::PreparedRefractor {
            mesh: &self.scene.refractor.mesh,
            d_n: &self.d_n,
        }
    }
}

/// The default camera (eye at z = 3, 40°) at `res`².
pub fn camera(res: u32) -> Camera {
    Camera::new(CameraDesc {
        width: res,
        height: res,
        ..CameraDesc::default()
    })
    .expect("camera")
}
