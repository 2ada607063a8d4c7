// The `depth-peel` pass, the twin of crates/refract-cpu/src/families/depth_peel.rs: per pixel
// depth_peel.wgsl's path from the nearest peeled layer, the colour it ends on (the opaque
// objects' screen texture, object_texture.wgsl, or the environment) times its transmittance,
// and the AOVs. The layers are three texture arrays, layer k in slice k, written by raster.wgsl's
// fs_surface (layer 0, both orientations) and fs_surface_peel (the others): P, (N, covered),
// (uv, refractor index, covered).

@group(0) @binding(1) var layer_p: texture_2d_array<f32>;
@group(0) @binding(2) var layer_n: texture_2d_array<f32>;
@group(0) @binding(3) var layer_object: texture_2d_array<f32>;
@group(0) @binding(5) var<storage, read_write> out_color: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> out_t2: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> out_p2: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> out_flags: array<vec4<f32>>;

override WRITE_AOVS: bool = true;

fn layer_position(texel: vec2<i32>, layer: u32) -> vec4<f32> {
    if layer >= peel.layers || textureLoad(layer_n, texel, i32(layer), 0).w < 0.5 {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(textureLoad(layer_p, texel, i32(layer), 0).xyz, 1.0);
}

fn layer_normal(texel: vec2<i32>, layer: u32) -> vec3<f32> {
    return textureLoad(layer_n, texel, i32(layer), 0).xyz;
}

fn layer_refractor(texel: vec2<i32>, layer: u32) -> u32 {
    return u32(round(textureLoad(layer_object, texel, i32(layer), 0).z));
}

// The nearest layer's view depth (F32_MAX where empty).
fn nearest_depth(texel: vec2<i32>) -> f32 {
    let p = layer_position(texel, 0u);
    if p.w < 0.5 {
        return F32_MAX;
    }
    return ng_view_depth(p.xyz);
}

fn opaque_position(texel: vec2<i32>) -> vec4<f32> {
    if !(peel.scene_bound.w > 0.0) {
        return vec4<f32>(0.0);
    }
    return ng_surface(texel);
}

fn opaque_normal(texel: vec2<i32>) -> vec3<f32> {
    return textureLoad(ng_n, texel, 0).xyz;
}

// The view depth of the opaque objects at `texel` (F32_MAX where none is drawn).
fn opaque_depth(texel: vec2<i32>) -> f32 {
    let p = opaque_position(texel);
    if p.w < 0.5 {
        return F32_MAX;
    }
    return ng_view_depth(p.xyz);
}

// What the screen texture shows at `texel`: the object drawn there or the environment along
// the texel's eye ray.
fn peel_screen_color(texel: vec2<i32>) -> vec3<f32> {
    if peel.scene_bound.w > 0.0 && ng_surface(texel).w > 0.5 {
        return ng_color(texel);
    }
    return environment_radiance(pixel_ray_dir(vec2<f32>(texel) + vec2<f32>(0.5)));
}

@compute @workgroup_size(8, 8)
fn shade_depth_peel(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.width || id.y >= frame.height {
        return;
    }
    let i = id.y * frame.width + id.x;
    let texel = vec2<i32>(i32(id.x), i32(id.y));
    if !(nearest_depth(texel) < opaque_depth(texel)) {
        out_color[i] = vec4<f32>(peel_screen_color(texel), f32(COVERAGE_BACKGROUND));
        if WRITE_AOVS {
            out_t2[i] = vec4<f32>(0.0);
            out_p2[i] = vec4<f32>(0.0);
            out_flags[i] = vec4<f32>(0.0);
            out_p_geom[i] = vec4<f32>(0.0);
            out_ng[i] = vec4<f32>(0.0);
        }
        return;
    }
    let p1 = textureLoad(layer_p, texel, 0, 0).xyz;
    let path = peel_path(p1, layer_normal(texel, 0u), layer_refractor(texel, 0u));
    var color: vec3<f32>;
    if path.opaque {
        color = peel_screen_color(path.opaque_texel);
    } else {
        color = environment_radiance(path.dir);
    }
    out_color[i] = vec4<f32>(path.transmittance * color, f32(COVERAGE_PATH));
    if WRITE_AOVS {
        let exit = select(0.0, 1.0, path.has_exit);
        out_t2[i] = vec4<f32>(path.t2, exit);
        out_p2[i] = vec4<f32>(path.p2, exit);
        out_flags[i] = vec4<f32>(
            select(0.0, 1.0, path.end == PEEL_END_OFF_SCREEN),
            select(0.0, 1.0, path.end == PEEL_END_LOST),
            select(0.0, 1.0, path.reflections > 0u),
            f32(path.interfaces),
        );
        out_p_geom[i] = vec4<f32>(path.p_geom, select(0.0, 1.0, path.opaque));
        out_ng[i] = vec4<f32>(path.dir, bitcast<f32>(path.refractors_met));
    }
}
