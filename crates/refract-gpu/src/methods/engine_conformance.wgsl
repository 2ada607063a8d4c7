// Whole-path conformance of the engine family: engine_path.wgsl over an analytic screen, held to
// refract_core::engine::engine_path over the same screen (crates/refract-gpu/tests/conformance.rs,
// `engine_path_agrees`). The frame uniforms (binding 0) carry the camera and the IOR, the engine
// uniforms (binding 16) the model's amount and switches; ENGINE_MODEL is the pipeline's override.
// Then the models' leaves one by one (`engine_models_agree`).

@group(0) @binding(1) var<storage, read> in_a: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> in_b: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> out_v: array<vec4<f32>>;

// The analytic screen: the environment (F32_MAX) on every fifth column, elsewhere an opaque
// surface at view depth 1.5 + 0.25 (y mod 7), exact in f32, so that the depth tests of the
// models (Godot's guard, Bevy's rejection, HDRP's "in front" test) go both ways.
fn screen_depth(texel: vec2<i32>) -> f32 {
    if texel.x % 5 == 0 {
        return F32_MAX;
    }
    return 1.5 + 0.25 * f32(texel.y % 7);
}

// The path of row i: a = (P1, _), b = (N1, u_px + 4096 v_px) at the pixel's centre.
fn row_path(i: u32) -> EnginePath {
    let packed = in_b[i].w;
    let v = floor(packed / 4096.0);
    let uv = vec2<f32>(packed - 4096.0 * v, v) + vec2<f32>(0.5);
    return engine_path(uv, in_a[i].xyz, in_b[i].xyz, frame.ior, engine.amount);
}

// -> (texel.x, texel.y, screen weight, 1 off screen + 2 has an exit)
@compute @workgroup_size(64)
fn test_engine_path_texel(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let path = row_path(i);
    let flags = select(0.0, 1.0, path.off_screen) + select(0.0, 2.0, path.has_exit);
    out_v[i] = vec4<f32>(vec2<f32>(path.texel), path.screen_weight, flags);
}

// -> (P2, _)
@compute @workgroup_size(64)
fn test_engine_path_p2(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(row_path(i).p2, 0.0);
}

// -> (T2, _)
@compute @workgroup_size(64)
fn test_engine_path_t2(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(row_path(i).t2, 0.0);
}

// -> (the environment direction, _)
@compute @workgroup_size(64)
fn test_engine_path_environment(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(row_path(i).environment_dir, 0.0);
}

// The engine models' leaves (core.wgsl), engine.rs's exit models at P = 0:
// a = (N, ior), b = (I, d) -> (sphere P1, sphere R2.x)
@compute @workgroup_size(64)
fn test_proxy_sphere_point(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let e = proxy_sphere_exit(vec3<f32>(0.0), in_a[i].xyz, in_b[i].xyz, in_a[i].w, in_b[i].w);
    out_v[i] = vec4<f32>(e.p, 0.0);
}

// a = (N, ior), b = (I, d) -> (sphere R2, _)
@compute @workgroup_size(64)
fn test_proxy_sphere_dir(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let e = proxy_sphere_exit(vec3<f32>(0.0), in_a[i].xyz, in_b[i].xyz, in_a[i].w, in_b[i].w);
    out_v[i] = vec4<f32>(e.dir, 0.0);
}

// a = (N, ior), b = (I, d) -> (box P1, _)
@compute @workgroup_size(64)
fn test_proxy_box(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let e = proxy_box_exit(vec3<f32>(0.0), in_a[i].xyz, in_b[i].xyz, in_a[i].w, in_b[i].w);
    out_v[i] = vec4<f32>(e.p, 0.0);
}

// a = (N, ior), b = (I, d) -> (volume X, _)
@compute @workgroup_size(64)
fn test_volume_exit(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let e = volume_exit(vec3<f32>(0.0), in_a[i].xyz, in_b[i].xyz, in_a[i].w, in_b[i].w);
    out_v[i] = vec4<f32>(e.p, 0.0);
}

// a = (n_view, scale), b = (u, v, x, _) with (u, v) in [0, 1]² -> (screen_offset_px for a
// 640 x 480 frame, hdrp_edge_fade(u, v), smoothstep01(x))
@compute @workgroup_size(64)
fn test_engine_screen(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let o = screen_offset_px(in_a[i].xyz, in_a[i].w, vec2<f32>(640.0, 480.0));
    out_v[i] = vec4<f32>(o, hdrp_edge_fade(in_b[i].xy), smoothstep01(in_b[i].z));
}

// The analytic screen pyramid of `test_sample_threejs` (exact in f32; the twin of
// `AnalyticMips` in tests/engine_conformance.rs): no level is the mean of the one below, so
// every level's texels tell apart which level and which texel were read.
fn mip_texel(level: u32, texel: vec2<u32>) -> vec3<f32> {
    return vec3<f32>(
        f32((texel.x * 7u + texel.y * 3u + level * 5u) % 11u),
        0.5 * f32((texel.x ^ texel.y) % 13u),
        f32(level) + 0.25 * f32(texel.x % 4u),
    );
}

// a = (u, v, lod, _) -> (three.js's blurred sample, _), the frame's size level 0's.
@compute @workgroup_size(64)
fn test_sample_threejs(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(sample_threejs(in_a[i].xy, in_a[i].z), 0.0);
}

// a = (u, v, lod, _) -> (the trilinear sample of Godot and HDRP, _).
@compute @workgroup_size(64)
fn test_sample_trilinear(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(sample_trilinear(in_a[i].xy, in_a[i].z), 0.0);
}

// a = (u, v, roughness, fragment depth), b = (frag x, frag y, _, _) -> (Bevy's taps: colour
// sum over the taps, accepted share) over the analytic pyramid and screen.
@compute @workgroup_size(64)
fn test_bevy_blurred(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = bevy_blurred(in_b[i].xy, in_a[i].xy, in_a[i].z, in_a[i].w);
}

