// The conformance harness: one compute entry point per core function, each evaluating it on
// `count` input rows (in_a, in_b) and writing one vec4 per row. crates/refract-gpu/tests
// compares the results with the Rust functions on proptest-generated inputs.

@group(0) @binding(0) var<storage, read> in_a: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> in_b: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> out_v: array<vec4<f32>>;

// a = (I, eta), b = (N, _) -> (refract_dir, TIR)
@compute @workgroup_size(64)
fn test_refract(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let t = refract_dir(in_a[i].xyz, in_b[i].xyz, in_a[i].w);
    out_v[i] = vec4<f32>(t, select(0.0, 1.0, all(t == vec3<f32>(0.0))));
}

// a = (I, _), b = (N, _) -> (reflect_dir, _)
@compute @workgroup_size(64)
fn test_reflect(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(reflect_dir(in_a[i].xyz, in_b[i].xyz), 0.0);
}

// a = (N, _), b = (I, _) -> (face_forward_shading_normal, angle_between(a, b))
@compute @workgroup_size(64)
fn test_face_forward(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(face_forward_shading_normal(in_a[i].xyz, in_b[i].xyz), angle_between(in_a[i].xyz, in_b[i].xyz));
}

// a = (cos_i, eta, n, k) -> (fresnel_dielectric, schlick_dielectric, schlick_conductor, critical_angle)
@compute @workgroup_size(64)
fn test_fresnel(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let a = in_a[i];
    out_v[i] = vec4<f32>(
        fresnel_dielectric(a.x, a.y),
        schlick_dielectric(a.x, a.y),
        schlick_conductor(a.x, a.z, a.w),
        critical_angle(a.y),
    );
}

// a = (cos_i, n, k, _) -> (fresnel_conductor, _, _, _)
@compute @workgroup_size(64)
fn test_fresnel_conductor(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let a = in_a[i];
    out_v[i] = vec4<f32>(fresnel_conductor(a.x, a.y, a.z), 0.0, 0.0, 0.0);
}

// a = (theta_i, theta_t, eta, d_v), b = (d_n, mode, _, _) -> (angle_ratio, approximate_distance, _, _)
@compute @workgroup_size(64)
fn test_distance(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let a = in_a[i];
    let b = in_b[i];
    out_v[i] = vec4<f32>(angle_ratio(a.x, a.y, a.z), approximate_distance(u32(b.y), a.x, a.y, a.z, a.w, b.x), 0.0, 0.0);
}

// a = (T1, ior), b = (N2, policy) -> refract_exit
@compute @workgroup_size(64)
fn test_exit(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = refract_exit(in_a[i].xyz, in_b[i].xyz, in_a[i].w, u32(in_b[i].w));
}

// a = (T1, _), b = (L, _) -> exit_normal_outside_silhouette
@compute @workgroup_size(64)
fn test_exit_normal(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(exit_normal_outside_silhouette(in_a[i].xyz, in_b[i].xyz), 0.0);
}

// a = (v, _) -> robust_normalize(v)
@compute @workgroup_size(64)
fn test_normalize(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = robust_normalize(in_a[i].xyz);
}

// a = (dir, _) -> (direction_to_latlong, _, _) ; b unused
@compute @workgroup_size(64)
fn test_latlong(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(direction_to_latlong(in_a[i].xyz), 0.0, 0.0);
}

// a = (dir, _) -> (procedural_radiance, _)
@compute @workgroup_size(64)
fn test_procedural_sky(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(procedural_radiance(in_a[i].xyz), 0.0);
}

// a = plane (n, d), b = (dir, _), origin 0 -> (plane_intersect, _, _)
@compute @workgroup_size(64)
fn test_plane(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(plane_intersect(in_a[i], vec3<f32>(0.0), in_b[i].xyz), 0.0, 0.0);
}

// a = (s, w0, w1, _) -> (screen_fraction_to_segment, _, _, _)
@compute @workgroup_size(64)
fn test_seed_fraction(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(screen_fraction_to_segment(in_a[i].x, in_a[i].y, in_a[i].z), 0.0, 0.0, 0.0);
}

// ---- distance maps: refract_core::distance_map::AnalyticRoom (64² faces) ----

const ANALYTIC_SIZE: u32 = 64u;

fn analytic_centre(dir: vec3<f32>) -> vec3<f32> {
    let t = dm_cube_texel(dir, ANALYTIC_SIZE);
    if t.w == 0 {
        return vec3<f32>(0.0, 0.0, 1.0);
    }
    return normalize(dm_cube_texel_direction(t.x, t.yz, ANALYTIC_SIZE));
}

fn dm_layer_count() -> u32 { return 2u; }
fn dm_face_size() -> u32 { return ANALYTIC_SIZE; }
fn dm_two_sided(layer: u32) -> bool { return layer == 0u; }
fn dm_background(dir: vec3<f32>) -> vec3<f32> { return vec3<f32>(7.0); }

fn dm_distance(layer: u32, dir: vec3<f32>) -> f32 {
    let c = analytic_centre(dir);
    if layer == 0u {
        return select(1.0, -1.0, c.y > 0.8);
    }
    return 3.0 / max(abs(c.x), max(abs(c.y), abs(c.z)));
}

fn dm_range(layer: u32) -> vec3<f32> {
    if layer == 0u {
        return vec3<f32>(1.0, 1.0, 1.0);
    }
    return vec3<f32>(3.0, 3.0 * sqrt(3.0), 1.0);
}

fn dm_surface(layer: u32, dir: vec3<f32>) -> DmSurface {
    let c = analytic_centre(dir);
    var out: DmSurface;
    if layer == 0u {
        out.normal = c;
        out.rgb = vec3<f32>(1.0);
        out.ior = -1.0;
        return out;
    }
    let a = abs(c);
    if a.x >= a.y && a.x >= a.z {
        out.normal = vec3<f32>(-sign(c.x), 0.0, 0.0);
    } else if a.y >= a.z {
        out.normal = vec3<f32>(0.0, -sign(c.y), 0.0);
    } else {
        out.normal = vec3<f32>(0.0, 0.0, -sign(c.z));
    }
    out.rgb = vec3<f32>(0.5, 0.25, 0.125);
    out.ior = 0.0;
    return out;
}

// a = (dir, size) -> (face, x, y, valid) of dm_cube_texel
@compute @workgroup_size(64)
fn test_dm_texel(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(dm_cube_texel(in_a[i].xyz, u32(in_a[i].w)));
}

// a = (x, start layer or -1), b = (R, min_max) -> (d or -1, layer, linear steps, secant steps)
// with the default search (15..80 linear steps, 5 secant steps)
@compute @workgroup_size(64)
fn test_dm_hit(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let search = DmSearch(15u, 80u, 5u, in_b[i].w > 0.5);
    let h = dm_hit(in_a[i].xyz, in_b[i].xyz, i32(in_a[i].w), search);
    out_v[i] = vec4<f32>(select(-1.0, h.d, h.found), f32(h.layer), f32(h.linear_steps), f32(h.secant_steps));
}

// a = (x on the mirror sphere, max depth), b = (V, _) -> (radiance, bounces) of dm_trace_path
// from a mirror (F_p 0.9) with outward normal normalize(x), start layer 0
@compute @workgroup_size(64)
fn test_dm_path(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let x = in_a[i].xyz;
    let search = DmSearch(15u, 80u, 5u, true);
    let path = dm_trace_path(x, in_b[i].xyz, normalize(x), vec3<f32>(0.9), -1.0, 0, search, u32(in_a[i].w), DM_FRESNEL_IGNORE);
    out_v[i] = vec4<f32>(path.radiance, f32(path.bounces));
}

// ---- microfacet.rs ----

// a = (v_local, alpha), b = (m_local, _) -> (ggx_d(m), smith_g1(v, m), visible_normal_pdf(v, m), _)
@compute @workgroup_size(64)
fn test_ggx(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let a = in_a[i];
    let m = in_b[i].xyz;
    out_v[i] = vec4<f32>(ggx_d(m, a.w), smith_g1(a.xyz, m, a.w), visible_normal_pdf(a.xyz, m, a.w), 0.0);
}

// The sample point of row k: fract((k + ½) (0.7548777, 0.5698403)) (refract-gpu's test).
fn row_sample(k: u32) -> vec2<f32> {
    return fract((f32(k) + 0.5) * vec2<f32>(0.7548777, 0.5698403));
}

// a = (dir, eta), b = (facing, alpha) -> (m, fresnel) of sample_rough_interface at row_sample
@compute @workgroup_size(64)
fn test_rough_normal(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let s = sample_rough_interface(in_a[i].xyz, in_b[i].xyz, in_a[i].w, in_b[i].w, row_sample(i));
    out_v[i] = vec4<f32>(s.m, s.fresnel);
}

// as test_rough_normal -> (reflected, reflected_masking)
@compute @workgroup_size(64)
fn test_rough_reflected(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let s = sample_rough_interface(in_a[i].xyz, in_b[i].xyz, in_a[i].w, in_b[i].w, row_sample(i));
    out_v[i] = vec4<f32>(s.reflected, s.reflected_masking);
}

// as test_rough_normal -> (refracted, refracted_masking)
@compute @workgroup_size(64)
fn test_rough_refracted(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let s = sample_rough_interface(in_a[i].xyz, in_b[i].xyz, in_a[i].w, in_b[i].w, row_sample(i));
    out_v[i] = vec4<f32>(s.refracted, s.refracted_masking);
}

// a = (λ, _, _, _) -> (cie_1931_xyz(λ), cie_d65(λ))
@compute @workgroup_size(64)
fn test_spectral_tables(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let lambda = in_a[i].x;
    out_v[i] = vec4<f32>(cie_1931_xyz(lambda), cie_d65(lambda));
}

// a = (u, λ, ior, abbe), b = (c0, c1, c2, terminate) -> (λ₀ of wavelengths_sample(u), its
// weight, sigmoid_spectrum(c, λ), dispersive_ior(ior, abbe, λ)); with b.w > 0.5 the weight is
// the hero's after wavelengths_terminated.
@compute @workgroup_size(64)
fn test_spectral_sample(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let a = in_a[i];
    let b = in_b[i];
    var w = wavelengths_sample(a.x);
    if b.w > 0.5 {
        w = wavelengths_terminated(w);
    }
    out_v[i] = vec4<f32>(w.lambda.x, w.weight.x, sigmoid_spectrum(b.xyz, a.y), dispersive_ior(a.z, a.w, a.y));
}
