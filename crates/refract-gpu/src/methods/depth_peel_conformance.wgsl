// Whole-path conformance of `depth-peel`: depth_peel.wgsl over analytic layers, held to
// refract_core::depth_peel::peel_path over the same layers (crates/refract-gpu/tests/
// depth_peel_conformance.rs). The layers at a texel are the hits of its centre ray with two
// spheres (refractor 0: the unit sphere at the origin; refractor 1: radius 0.6 at
// (0.3, 0.2, -2.2)) sorted by view depth; the opaque objects are a wall at z = -4. The frame
// uniforms (binding 0) carry the camera, the peel uniforms and media (16, 17) the settings.

@group(0) @binding(1) var<storage, read> in_a: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> in_b: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> out_v: array<vec4<f32>>;

struct AnalyticHits {
    depth: array<f32, 4>,
    surface: array<vec4<f32>, 4>,
}

fn analytic_sphere(k: u32) -> vec4<f32> {
    if k == 0u {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    return vec4<f32>(0.3, 0.2, -2.2, 0.6);
}

fn analytic_hits(texel: vec2<i32>) -> AnalyticHits {
    var hits: AnalyticHits;
    for (var j = 0u; j < 4u; j++) {
        hits.depth[j] = F32_MAX;
        hits.surface[j] = vec4<f32>(0.0, 0.0, 1.0, 0.0);
    }
    let origin = frame.eye.xyz;
    let dir = pixel_ray_dir(vec2<f32>(texel) + vec2<f32>(0.5));
    var n = 0u;
    for (var k = 0u; k < 2u; k++) {
        let s = analytic_sphere(k);
        let oc = origin - s.xyz;
        let b = dot(oc, dir);
        let disc = b * b - (dot(oc, oc) - s.w * s.w);
        if disc > 0.0 {
            let root = sqrt(disc);
            for (var e = 0u; e < 2u; e++) {
                let t = select(-b + root, -b - root, e == 0u);
                let p = origin + t * dir;
                hits.depth[n] = dot(p - frame.eye.xyz, frame.look_dir.xyz);
                hits.surface[n] = vec4<f32>((p - s.xyz) / s.w, f32(k));
                n += 1u;
            }
        }
    }
    // Insertion sort by depth (at most four).
    for (var i = 1u; i < 4u; i++) {
        var j = i;
        while j > 0u && hits.depth[j - 1u] > hits.depth[j] {
            let d = hits.depth[j];
            hits.depth[j] = hits.depth[j - 1u];
            hits.depth[j - 1u] = d;
            let s = hits.surface[j];
            hits.surface[j] = hits.surface[j - 1u];
            hits.surface[j - 1u] = s;
            j -= 1u;
        }
    }
    return hits;
}

fn layer_position(texel: vec2<i32>, layer: u32) -> vec4<f32> {
    if layer >= min(peel.layers, 4u) {
        return vec4<f32>(0.0);
    }
    let hits = analytic_hits(texel);
    if hits.depth[layer] >= F32_MAX {
        return vec4<f32>(0.0);
    }
    let s = analytic_sphere(u32(hits.surface[layer].w));
    return vec4<f32>(s.xyz + s.w * hits.surface[layer].xyz, 1.0);
}

fn layer_normal(texel: vec2<i32>, layer: u32) -> vec3<f32> {
    return analytic_hits(texel).surface[min(layer, 3u)].xyz;
}

fn layer_refractor(texel: vec2<i32>, layer: u32) -> u32 {
    return u32(analytic_hits(texel).surface[min(layer, 3u)].w);
}

fn opaque_position(texel: vec2<i32>) -> vec4<f32> {
    let dir = pixel_ray_dir(vec2<f32>(texel) + vec2<f32>(0.5));
    let t = (-4.0 - frame.eye.z) / dir.z;
    if !(t > 0.0) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(frame.eye.xyz + t * dir, 1.0);
}

fn opaque_normal(texel: vec2<i32>) -> vec3<f32> {
    return vec3<f32>(0.0, 0.0, 1.0);
}

// The path of row i: a = (texel x, texel y, _, _); the texel must be covered by layer 0.
fn row_path(i: u32) -> PeelPath {
    let texel = vec2<i32>(i32(in_a[i].x), i32(in_a[i].y));
    let hits = analytic_hits(texel);
    let origin = frame.eye.xyz;
    let dir = pixel_ray_dir(vec2<f32>(texel) + vec2<f32>(0.5));
    let p1 = origin + dir * (hits.depth[0] / dot(dir, frame.look_dir.xyz));
    return peel_path(p1, hits.surface[0].xyz, u32(hits.surface[0].w));
}

// -> (origin, end code)
@compute @workgroup_size(64)
fn test_peel_origin(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let path = row_path(i);
    out_v[i] = vec4<f32>(path.origin, f32(path.end));
}

// -> (direction, interfaces + 16 reflections)
@compute @workgroup_size(64)
fn test_peel_dir(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let path = row_path(i);
    out_v[i] = vec4<f32>(path.dir, f32(path.interfaces + 16u * path.reflections));
}

// -> (the opaque hit, 1 where there is one)
@compute @workgroup_size(64)
fn test_peel_opaque(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let path = row_path(i);
    out_v[i] = vec4<f32>(path.p_geom, select(0.0, 1.0, path.opaque));
}

// -> (transmittance, refractors met)
@compute @workgroup_size(64)
fn test_peel_transmittance(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let path = row_path(i);
    out_v[i] = vec4<f32>(path.transmittance, f32(path.refractors_met));
}

// -> (the first exit's point P2, 1 where the path has one)
@compute @workgroup_size(64)
fn test_peel_p2(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let path = row_path(i);
    out_v[i] = vec4<f32>(path.p2, select(0.0, 1.0, path.has_exit));
}

// -> (the first exit's direction T2, 0)
@compute @workgroup_size(64)
fn test_peel_t2(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let path = row_path(i);
    out_v[i] = vec4<f32>(path.t2, 0.0);
}
