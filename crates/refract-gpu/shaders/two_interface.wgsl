// The one- and two-interface kernels (refract_core::kernel::{one_interface, two_interface}),
// over a `back_face(uv_px) -> vec4<f32>` (xyz = normal, w = distance, w < 0 where empty) and the
// frame uniforms that the including module provides: image_space.wgsl's reads the back-face
// texture, conformance_kernels.wgsl's an analytic sphere (the whole-kernel conformance test).

// How d~ is approximated (refract_core::gpu::distance_mode_code): fixed per pipeline, one
// pipeline per method.
override DISTANCE_MODE: u32 = DISTANCE_INTERPOLATED;

// One pixel of the front-face buffer.
struct FrontPixel {
    index: u32,
    uv: vec2<f32>,
    covered: bool,
    p1: vec3<f32>,
    n1: vec3<f32>,
    d_n: f32,
}

fn is_finite3(v: vec3<f32>) -> bool {
    let a = abs(v);
    return a.x <= F32_MAX && a.y <= F32_MAX && a.z <= F32_MAX;
}

// The entry refraction at P1.
struct Entry {
    valid: bool,
    view: vec3<f32>,
    n1: vec3<f32>,
    t1: vec3<f32>,
    tir: bool,
}

// kernel.rs: entry_frame + one_interface.
fn one_interface(p1: vec3<f32>, n1_raw: vec3<f32>) -> Entry {
    var entry: Entry;
    entry.valid = false;
    let view4 = robust_normalize(p1 - frame.eye.xyz);
    let n4 = robust_normalize(n1_raw);
    if view4.w < 0.5 || n4.w < 0.5 {
        return entry;
    }
    entry.view = view4.xyz;
    entry.n1 = face_forward_shading_normal(n4.xyz, entry.view);
    let refracted = refract_dir(entry.view, entry.n1, 1.0 / frame.ior);
    entry.tir = all(refracted == vec3<f32>(0.0));
    let t1_4 = robust_normalize(select(refracted, reflect_dir(entry.view, entry.n1), entry.tir));
    entry.t1 = t1_4.xyz;
    entry.valid = t1_4.w >= 0.5;
    return entry;
}

// The two-interface path of a covered pixel (kernel.rs: two_interface), shared by the
// `wyman` family and the nearby-geometry methods. `t2` is zero when the TIR policy absorbed the
// ray; a TIR at the entry gives P~2 = P1, N2 = N1 and the reflected T1.
struct TwoPath {
    valid: bool,
    p2: vec3<f32>,
    t2: vec3<f32>,
    n2: vec3<f32>,
    source: u32,
    tir: bool,
}

fn two_interface_path(px: FrontPixel) -> TwoPath {
    var path: TwoPath;
    path.valid = false;
    let entry = one_interface(px.p1, px.n1);
    if !entry.valid || !(px.d_n >= 0.0 && px.d_n <= F32_MAX) {
        return path;
    }
    let p1 = px.p1;
    let t1 = entry.t1;
    if entry.tir {
        path.valid = true;
        path.p2 = p1;
        path.t2 = t1;
        path.n2 = entry.n1;
        path.source = EXIT_NORMAL_FALLBACK;
        path.tir = true;
        return path;
    }
    let back = back_face(px.uv);
    let d_v = back.w - length(p1 - frame.eye.xyz);
    let has_d_v = back.w >= 0.0 && d_v >= 0.0 && d_v <= F32_MAX;
    let eta_in = 1.0 / frame.ior;
    let theta_i = angle_between(-entry.view, entry.n1);
    let theta_t = angle_between(t1, -entry.n1);
    let d_tilde = approximate_distance(DISTANCE_MODE, theta_i, theta_t, eta_in, select(px.d_n, d_v, has_d_v), px.d_n);
    let p2 = p1 + d_tilde * t1;

    var n2 = exit_normal_outside_silhouette(t1, frame.look_dir.xyz);
    var source = EXIT_NORMAL_FALLBACK;
    let pixel = world_to_pixel(p2);
    if pixel.w > 0.5 {
        let sampled = back_face(pixel.xy);
        if sampled.w >= 0.0 {
            let unit = robust_normalize(sampled.xyz);
            if unit.w > 0.5 {
                n2 = unit.xyz;
                source = EXIT_NORMAL_BACK_FACE;
            }
        }
    }
    let exit = refract_exit(t1, n2, frame.ior, frame.tir_policy);
    if !(is_finite3(p2) && abs(d_tilde) <= F32_MAX && is_finite3(exit.xyz)) {
        return path;
    }
    path.valid = true;
    path.p2 = p2;
    path.t2 = exit.xyz;
    path.n2 = n2;
    path.source = source;
    path.tir = exit.w > 0.5;
    return path;
}
