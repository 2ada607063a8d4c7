// Whole-lookup conformance of the nearby-geometry family: nearby_lookup.wgsl's find_nearby over
// an analytic NG texture, held to refract_core::nearby_geometry::find_nearby over the same
// texture (crates/refract-gpu/tests/nearby_conformance.rs). The NG camera, planes and lookup
// settings are object_surfaces.wgsl's uniforms (binding 15); LOOKUP is the pipeline's override.

@group(0) @binding(1) var<storage, read> in_a: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> in_b: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> out_v: array<vec4<f32>>;

// The analytic NG texture: empty on every seventh column, elsewhere a surface at
// P = (0.05 (x − 32), −0.05 (y − 24), −1 − 0.125 ((x + y) mod 4)), every value exact in f32,
// so that the lookups find, miss and iterate over depth steps.
fn ng_surface(texel: vec2<i32>) -> vec4<f32> {
    if texel.x % 7 == 0 {
        return vec4<f32>(0.0);
    }
    let p = vec3<f32>(
        0.05 * f32(texel.x - 32),
        -0.05 * f32(texel.y - 24),
        -1.0 - 0.125 * f32((texel.x + texel.y) % 4),
    );
    return vec4<f32>(p, 1.0);
}

// a = (P~2, _), b = (T~2, _) -> (texel.x, texel.y, 1 hit + 2 converged, iterations)
@compute @workgroup_size(64)
fn test_find_nearby(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let found = find_nearby(in_a[i].xyz, in_b[i].xyz);
    let flags = select(0.0, 1.0, found.hit) + select(0.0, 2.0, found.converged);
    out_v[i] = vec4<f32>(vec2<f32>(found.texel), flags, f32(found.iterations));
}

// -> (P_geom, _)
@compute @workgroup_size(64)
fn test_find_nearby_p_geom(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(find_nearby(in_a[i].xyz, in_b[i].xyz).p_geom, 0.0);
}
