// The camera the opaque objects' surfaces are seen from (crates/refract-gpu/src/passes/
// object_surfaces.rs): the nearby-geometry (NG) camera of Wyman 2005b or the eye (the engines'
// screen texture, the objects over an image-space frame), with the scene's light and the
// lookups' planes and settings; projecting a point to its texel, a point's view depth.

struct NearbyUniforms {
    world_to_clip: mat4x4<f32>,
    eye: vec4<f32>,
    look_dir: vec4<f32>,
    light_direction: vec4<f32>,
    light_radiance: vec4<f32>,
    light_ambient: vec4<f32>,
    planes: array<vec4<f32>, 8>,
    width: u32,
    height: u32,
    pad_x: u32,
    pad_y: u32,
    plane_count: u32,
    iterations: u32,
    seeds: u32,
    spacing: u32,
}

@group(0) @binding(15) var<uniform> nearby: NearbyUniforms;

// nearby_geometry.rs: texel_of. xy = texel, z = 1 when inside the NG view.
fn ng_texel_of(p: vec3<f32>) -> vec3<i32> {
    let clip = nearby.world_to_clip * vec4<f32>(p, 1.0);
    if !(clip.w > 0.0) {
        return vec3<i32>(0);
    }
    let ndc = clip.xyz * (1.0 / clip.w);
    let w = f32(nearby.width);
    let h = f32(nearby.height);
    let q = vec3<f32>(0.5 * (ndc.x + 1.0) * w, 0.5 * (1.0 - ndc.y) * h, ndc.z);
    let inside = q.x >= 0.0 && q.x < w && q.y >= 0.0 && q.y < h && q.z >= 0.0 && q.z <= 1.0;
    return vec3<i32>(i32(q.x), i32(q.y), select(0, 1, inside));
}

fn ng_view_depth(p: vec3<f32>) -> f32 {
    return dot(p - nearby.eye.xyz, nearby.look_dir.xyz);
}

