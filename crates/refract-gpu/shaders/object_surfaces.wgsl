// The opaque objects' surfaces seen from a camera (crates/refract-gpu/src/passes/object_surfaces.rs):
// the surface pass (raster.wgsl fs_surface) of every opaque object, (P, 0), (N, covered),
// (uv, object id, 1), from the nearby-geometry (NG) camera of Wyman 2005b or from the eye (the
// engines' screen texture, the objects over an image-space frame); its uniforms, the outputs
// of the kernels that read it, and its readers. Colours are shaded here from the object's
// material (refract_scene::Albedo, Object::shade) at the texel that is used.

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

@group(0) @binding(9) var<storage, read_write> out_p_geom: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> out_ng: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read> materials: array<Material>;
@group(0) @binding(12) var ng_p: texture_2d<f32>;
@group(0) @binding(13) var ng_n: texture_2d<f32>;
@group(0) @binding(14) var ng_uv_object: texture_2d<f32>;
@group(0) @binding(15) var<uniform> nearby: NearbyUniforms;

// The NG texel at integer coordinates: xyz = P, w = 1 when covered.
fn ng_surface(texel: vec2<i32>) -> vec4<f32> {
    let covered = textureLoad(ng_n, texel, 0).w >= 0.5;
    return vec4<f32>(textureLoad(ng_p, texel, 0).xyz, select(0.0, 1.0, covered));
}

// Object::shade at an NG texel: albedo × (ambient + |N·L| radiance).
fn ng_color(texel: vec2<i32>) -> vec3<f32> {
    let n = textureLoad(ng_n, texel, 0).xyz;
    let uv_object = textureLoad(ng_uv_object, texel, 0);
    let m = materials[u32(round(uv_object.z)) - 1u];
    var uv = uv_object.xy;
    if m.world_uv != 0u {
        let p = textureLoad(ng_p, texel, 0).xyz;
        uv = vec2<f32>(p.x, p.z);
    }
    let shading = nearby.light_ambient.xyz + abs(dot(n, nearby.light_direction.xyz)) * nearby.light_radiance.xyz;
    return albedo(m, uv) * shading;
}

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

