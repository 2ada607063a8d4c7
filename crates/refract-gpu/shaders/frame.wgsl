// The per-frame uniforms: the WGSL side of refract_core::gpu::FrameUniforms (same fields, same
// offsets; checked by tests/shaders.rs).

struct FrameUniforms {
    world_to_clip: mat4x4<f32>,
    view_to_world: mat4x4<f32>,
    eye: vec4<f32>,
    look_dir: vec4<f32>,
    environment_constant: vec4<f32>,
    width: u32,
    height: u32,
    tan_half_fov_y: f32,
    aspect: f32,
    ior: f32,
    tir_policy: u32,
    environment_kind: u32,
    environment_width: u32,
    environment_height: u32,
    environment_intensity: f32,
    _padding: vec2<u32>,
}

@group(0) @binding(0) var<uniform> frame: FrameUniforms;

// camera.rs: Camera::pixel_ray direction.
fn pixel_ray_dir(uv_px: vec2<f32>) -> vec3<f32> {
    let ndc = vec2<f32>(2.0 * uv_px.x / f32(frame.width) - 1.0, 1.0 - 2.0 * uv_px.y / f32(frame.height));
    let dir_vs = vec3<f32>(ndc.x * frame.aspect * frame.tan_half_fov_y, ndc.y * frame.tan_half_fov_y, -1.0);
    return normalize((frame.view_to_world * vec4<f32>(dir_vs, 0.0)).xyz);
}

// camera.rs: Camera::world_to_pixel. xyz = (u_px, v_px, depth), w = 1 when in front of the eye.
fn world_to_pixel(p_ws: vec3<f32>) -> vec4<f32> {
    let clip = frame.world_to_clip * vec4<f32>(p_ws, 1.0);
    if !(clip.w > 0.0) {
        return vec4<f32>(0.0);
    }
    let ndc = clip.xyz / clip.w;
    return vec4<f32>(
        0.5 * (ndc.x + 1.0) * f32(frame.width),
        0.5 * (1.0 - ndc.y) * f32(frame.height),
        ndc.z,
        1.0,
    );
}

// What a pixel shows when its pipeline was built with a method code the shader does not know
// (an override constant out of range): magenta, never another method's result.
const UNKNOWN_CODE_COLOR: vec3<f32> = vec3<f32>(1.0, 0.0, 1.0);
