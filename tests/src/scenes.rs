//! Small scenes and one-call renders shared by the cross-crate tests, all through
//! refract-scene's [`Scene`] and [`Renderer`] (no test assembles its own scene).

use std::sync::Arc;

use refract_core::{Camera, CameraDesc};
use refract_eval::{LoadOptions, load_mesh};
use refract_geometry::{Mesh, builtin};
use refract_scene::{
    Environment, Frame, FrameOutputs, MethodId, MethodParams, Refractor, Renderer, Scene,
};

/// The scene of `mesh` at `ior` in `environment`, seen by the default camera.
pub fn with_mesh(mesh: Mesh, ior: f32, environment: Environment) -> Arc<Scene> {
    let refractor = Refractor::new(mesh, ior).expect("valid ior");
    Arc::new(Scene::new("test", refractor, environment))
}

/// A built-in shape in the procedural environment.
pub fn builtin(name: &str, ior: f32) -> Arc<Scene> {
    with_mesh(
        builtin::mesh(name).expect("builtin"),
        ior,
        Environment::Procedural,
    )
}

/// A mesh of `../shared/data/meshes`, normalised, in the procedural environment.
pub fn shared(data: &std::path::Path, file: &str, ior: f32) -> Arc<Scene> {
    let mesh = load_mesh(&data.join("meshes").join(file), &LoadOptions::default())
        .expect(file)
        .mesh;
    with_mesh(mesh, ior, Environment::Procedural)
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

/// The default parameters of `id`.
pub fn method(id: MethodId) -> MethodParams {
    MethodParams::defaults(id)
}

/// Prepares `scene` and renders one frame with colour and AOVs.
pub fn render(
    renderer: &mut dyn Renderer,
    scene: &Arc<Scene>,
    camera: &Camera,
    method: &MethodParams,
) -> Frame {
    renderer.prepare(scene).expect("prepare");
    let mut frame = Frame::default();
    renderer
        .render(camera, method, FrameOutputs::ColorAndAovs, &mut frame)
        .expect("render");
    frame
}

/// Built-in scene `name` as a white furnace: its opaque objects removed, a constant white
/// environment.
pub fn white_furnace(name: &str) -> Arc<Scene> {
    let mut scene = refract_eval::load_scene(name).expect("built-in").scene;
    scene.objects.clear();
    scene.environment = Environment::Constant(glam::Vec3::ONE);
    Arc::new(scene)
}

/// The largest channel value and the mean channel value over the pixels `frame` covers, and
/// how many channel values there are.
pub fn covered_radiance(frame: &Frame) -> (f32, f64, usize) {
    let covered = frame
        .flag(refract_scene::Aov::Covered)
        .expect("covered layer");
    let values: Vec<f32> = (0..frame.pixel_count())
        .filter(|&i| covered[i])
        .flat_map(|i| frame.color[i].to_array())
        .collect();
    let max = values.iter().copied().fold(0.0f32, f32::max);
    let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len().max(1) as f64;
    (max, mean, values.len())
}
