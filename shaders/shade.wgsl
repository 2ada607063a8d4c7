// Pass 3: the per-pixel kernels over the buffers, as a compute pass. The twin of
// refract_cpu::render::shade with refract_core::kernel::{one_interface, two_interface}.
//
// A compute pass (not the paper's fragment program) because every AOV (colour, T2, P~2, N2 and
// flags: 64 bytes per pixel) goes to storage buffers; fragment outputs would exceed the
// 32-byte-per-sample colour attachment limit of WebGPU, and the kernel stays one entry point
// that reads like the CPU backend.

@group(0) @binding(1) var front_p1_dn: texture_2d<f32>;
@group(0) @binding(2) var front_n1: texture_2d<f32>;
@group(0) @binding(3) var back_faces: texture_2d<f32>;
@group(0) @binding(5) var<storage, read_write> out_color: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> out_t2: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> out_p2: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> out_n2: array<vec4<f32>>;

// buffers.rs: BackFaces::back_face. xyz = normal, w = distance; w < 0 where empty.
fn back_face(uv_px: vec2<f32>) -> vec4<f32> {
    let w = f32(frame.width);
    let h = f32(frame.height);
    if !(uv_px.x >= 0.0 && uv_px.y >= 0.0 && uv_px.x < w && uv_px.y < h) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    return textureLoad(back_faces, vec2<i32>(i32(uv_px.x), i32(uv_px.y)), 0);
}

fn is_finite3(v: vec3<f32>) -> bool {
    let a = abs(v);
    return a.x <= F32_MAX && a.y <= F32_MAX && a.z <= F32_MAX;
}

// Whether the AOVs (T2, P~2, N2) are stored: false for colour-only frames (a pipeline
// constant; the CPU backend's FrameOutputs::Color).
override WRITE_AOVS: bool = true;

fn write_aovs(i: u32, t2: vec4<f32>, p2: vec4<f32>, n2: vec4<f32>) {
    if WRITE_AOVS {
        out_t2[i] = t2;
        out_p2[i] = p2;
        out_n2[i] = n2;
    }
}

fn write_degenerate(i: u32) {
    // A covered pixel whose kernel reported a degenerate input: black, no path.
    out_color[i] = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    write_aovs(i, vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
}

@compute @workgroup_size(8, 8)
fn shade(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.width || id.y >= frame.height {
        return;
    }
    let i = id.y * frame.width + id.x;
    let uv = vec2<f32>(f32(id.x) + 0.5, f32(id.y) + 0.5);
    let coords = vec2<i32>(i32(id.x), i32(id.y));
    let n1_covered = textureLoad(front_n1, coords, 0);
    if n1_covered.w < 0.5 {
        out_color[i] = vec4<f32>(environment_radiance(pixel_ray_dir(uv)), 0.0);
        write_aovs(i, vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
        return;
    }
    let p1_dn = textureLoad(front_p1_dn, coords, 0);
    let p1 = p1_dn.xyz;
    let d_n = p1_dn.w;

    // kernel.rs: entry_frame + one_interface.
    let view4 = robust_normalize(p1 - frame.eye.xyz);
    let n4 = robust_normalize(n1_covered.xyz);
    if view4.w < 0.5 || n4.w < 0.5 {
        write_degenerate(i);
        return;
    }
    let view = view4.xyz;
    let n1 = face_forward_shading_normal(n4.xyz, view);
    let eta_in = 1.0 / frame.ior;
    let refracted = refract_dir(view, n1, eta_in);
    let tir_entry = all(refracted == vec3<f32>(0.0));
    let t1_4 = robust_normalize(select(refracted, reflect_dir(view, n1), tir_entry));
    if t1_4.w < 0.5 {
        write_degenerate(i);
        return;
    }
    let t1 = t1_4.xyz;
    if frame.method_kind == METHOD_SINGLE {
        out_color[i] = vec4<f32>(environment_radiance(t1), 1.0);
        write_aovs(i, vec4<f32>(t1, select(0.0, 1.0, tir_entry)), vec4<f32>(0.0), vec4<f32>(0.0));
        return;
    }

    // kernel.rs: two_interface.
    if !(d_n >= 0.0 && d_n <= F32_MAX) {
        write_degenerate(i);
        return;
    }
    let back = back_face(uv);
    let d_v = back.w - length(p1 - frame.eye.xyz);
    let has_d_v = back.w >= 0.0 && d_v >= 0.0 && d_v <= F32_MAX;
    if tir_entry {
        out_color[i] = vec4<f32>(environment_radiance(t1), 1.0);
        write_aovs(i, vec4<f32>(t1, 1.0), vec4<f32>(p1, f32(EXIT_NORMAL_FALLBACK)), vec4<f32>(n1, 1.0));
        return;
    }
    let theta_i = angle_between(-view, n1);
    let theta_t = angle_between(t1, -n1);
    let d_tilde = approximate_distance(frame.distance_mode, theta_i, theta_t, eta_in, select(d_n, d_v, has_d_v), d_n);
    let p2 = p1 + d_tilde * t1;

    var n2 = exit_normal_outside_silhouette(t1, frame.look_dir.xyz);
    var source = EXIT_NORMAL_FALLBACK;
    let px = world_to_pixel(p2);
    if px.w > 0.5 {
        let sampled = back_face(px.xy);
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
        write_degenerate(i);
        return;
    }
    var color = vec3<f32>(0.0);
    if any(exit.xyz != vec3<f32>(0.0)) {
        color = environment_radiance(exit.xyz);
    }
    out_color[i] = vec4<f32>(color, 1.0);
    write_aovs(i, vec4<f32>(exit.xyz, select(0.0, 1.0, exit.w > 0.5 || tir_entry)), vec4<f32>(p2, f32(source)), vec4<f32>(n2, 1.0));
}
