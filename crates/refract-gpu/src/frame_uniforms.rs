//! The per-frame uniform block (`refract_core::gpu::FrameUniforms`) of a camera, a scene's
//! environment and a method's index of refraction and TIR policy.

use refract_core::gpu::{FrameUniforms, tir_policy_code};
use refract_core::{Camera, TirPolicy};

use crate::scene_buffers::EnvironmentUniforms;

/// The uniforms of one frame.
pub(crate) fn frame_uniforms(
    camera: &Camera,
    environment: &EnvironmentUniforms,
    ior: f32,
    tir: TirPolicy,
) -> FrameUniforms {
    let (width, height) = (camera.width(), camera.height());
    FrameUniforms {
        world_to_clip: camera.world_to_clip().to_cols_array_2d(),
        view_to_world: camera.view_to_world().to_cols_array_2d(),
        eye: camera.eye().extend(1.0).to_array(),
        look_dir: camera.look_dir().extend(0.0).to_array(),
        environment_constant: environment.constant,
        width,
        height,
        tan_half_fov_y: (0.5 * camera.desc().fov_y).tan(),
        aspect: if camera.is_mirrored() { -1.0 } else { 1.0 } * width as f32 / height as f32,
        ior,
        tir_policy: tir_policy_code(tir),
        environment_kind: environment.kind,
        environment_width: environment.width,
        environment_height: environment.height,
        environment_intensity: environment.intensity,
        _padding: [0; 2],
    }
}
