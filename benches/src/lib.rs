//! Inputs shared by refract's criterion benches (`cargo bench -p refract-benches`).
//!
//! Benches of real meshes read `../shared/data/meshes` (or `REFRACT_DATA_DIR`) and skip a
//! mesh with a notice when the file is absent.

use refract_eval::{LoadOptions, load_mesh};
use refract_geometry::Mesh;

/// The real meshes the geometry benches run on: `(label, file in meshes/)`.
pub const BENCH_MESHES: [(&str, &str); 3] = [
    ("cow", "cow.obj"),
    ("bunny", "stanford-bunny.obj"),
    ("horse", "horse.obj"),
];

/// Loads a mesh of `../shared/data/meshes`, normalised, or prints why it is skipped.
pub fn load_shared_mesh(file: &str) -> Option<Mesh> {
    let path = refract_tests::shared_data_dir().join("meshes").join(file);
    match load_mesh(&path, &LoadOptions::default()) {
        Ok(loaded) => Some(loaded.mesh),
        Err(err) => {
            eprintln!("skipped {file}: {err}");
            None
        }
    }
}

/// The scene of a bench mesh at `ior` in the procedural environment, seen by the default camera.
pub fn bench_scene(label: &str, mesh: Mesh, ior: f32) -> std::sync::Arc<refract_scene::Scene> {
    let refractor = refract_scene::Refractor::new(mesh, ior).expect("valid ior");
    std::sync::Arc::new(refract_scene::Scene::new(
        label,
        refractor,
        refract_scene::Environment::Procedural,
    ))
}

/// The camera of the benches: the default camera at `res`².
pub fn bench_camera(res: u32) -> refract_core::Camera {
    refract_core::Camera::new(refract_core::CameraDesc {
        width: res,
        height: res,
        ..refract_core::CameraDesc::default()
    })
    .expect("camera")
}
