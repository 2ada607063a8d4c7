// The opaque objects' surfaces seen from object_surfaces.wgsl's camera: the surface pass
// (raster.wgsl fs_surface) of every opaque object, (P, 0), (N, covered), (uv, object id, 1), and
// its readers; the outputs of the kernels that read it. Colours are shaded here from the
// object's material (refract_scene::Albedo, Object::shade) at the texel that is used.

@group(0) @binding(9) var<storage, read_write> out_p_geom: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> out_ng: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read> materials: array<Material>;
@group(0) @binding(12) var ng_p: texture_2d<f32>;
@group(0) @binding(13) var ng_n: texture_2d<f32>;
@group(0) @binding(14) var ng_uv_object: texture_2d<f32>;

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

