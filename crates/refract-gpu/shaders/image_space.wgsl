// Wyman 2005a image-space refraction, pass 3: the per-pixel kernels over the buffers, as a
// compute pass, one entry point per family member: `shade_single` (method single) and
// `shade_two_interface` (wyman, wyman-dv, wyman-dn: one pipeline each, DISTANCE_MODE an
// override constant). The twin of crates/refract-cpu/src/shade.rs; the kernels themselves are
// two_interface.wgsl's, over this file's `back_face`.
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

// Whether the AOVs (T2, P~2, N2) are stored: false for colour-only frames (a pipeline
// constant; FrameOutputs::Color).
override WRITE_AOVS: bool = true;
fn write_aovs(i: u32, t2: vec4<f32>, p2: vec4<f32>, n2: vec4<f32>) {
    if WRITE_AOVS {
        out_t2[i] = t2;
        out_p2[i] = p2;
        out_n2[i] = n2;
    }
}

fn write_degenerate(i: u32) {
    // A covered pixel whose kernel reported a degenerate input: black, no path (read back as
    // NaN AOVs, like the CPU backend's).
    out_color[i] = vec4<f32>(0.0, 0.0, 0.0, f32(COVERAGE_DEGENERATE));
    write_aovs(i, vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
}

fn front_pixel(id: vec3<u32>) -> FrontPixel {
    var px: FrontPixel;
    px.index = id.y * frame.width + id.x;
    px.uv = vec2<f32>(f32(id.x) + 0.5, f32(id.y) + 0.5);
    let coords = vec2<i32>(i32(id.x), i32(id.y));
    let n1_covered = textureLoad(front_n1, coords, 0);
    px.covered = n1_covered.w >= 0.5;
    px.n1 = n1_covered.xyz;
    let p1_dn = textureLoad(front_p1_dn, coords, 0);
    px.p1 = p1_dn.xyz;
    px.d_n = p1_dn.w;
    return px;
}

// A pixel that sees the environment directly.
fn write_background(px: FrontPixel) {
    out_color[px.index] = vec4<f32>(environment_radiance(pixel_ray_dir(px.uv)), f32(COVERAGE_BACKGROUND));
    write_aovs(px.index, vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
}

// Method `single`: the environment along T1.
@compute @workgroup_size(8, 8)
fn shade_single(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.width || id.y >= frame.height {
        return;
    }
    let px = front_pixel(id);
    if !px.covered {
        write_background(px);
        return;
    }
    let entry = one_interface(px.p1, px.n1);
    if !entry.valid {
        write_degenerate(px.index);
        return;
    }
    out_color[px.index] = vec4<f32>(environment_radiance(entry.t1), f32(COVERAGE_PATH));
    write_aovs(px.index, vec4<f32>(entry.t1, select(0.0, 1.0, entry.tir)), vec4<f32>(0.0), vec4<f32>(0.0));
}

// The AOVs of a two-interface path: T2 (w: TIR), P~2 (w: exit-normal code), N2 (w: valid).
fn write_path_aovs(i: u32, path: TwoPath) {
    write_aovs(i, vec4<f32>(path.t2, select(0.0, 1.0, path.tir)), vec4<f32>(path.p2, f32(path.source)), vec4<f32>(path.n2, 1.0));
}

// Methods `wyman`, `wyman-dv`, `wyman-dn` (kernel.rs: two_interface): the environment along T2.
@compute @workgroup_size(8, 8)
fn shade_two_interface(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.width || id.y >= frame.height {
        return;
    }
    let px = front_pixel(id);
    let i = px.index;
    if DISTANCE_MODE != DISTANCE_INTERPOLATED && DISTANCE_MODE != DISTANCE_VIEW_ONLY && DISTANCE_MODE != DISTANCE_NORMAL_ONLY {
        out_color[i] = vec4<f32>(UNKNOWN_CODE_COLOR, f32(COVERAGE_BACKGROUND));
        return;
    }
    if !px.covered {
        write_background(px);
        return;
    }
    let path = two_interface_path(px);
    if !path.valid {
        write_degenerate(i);
        return;
    }
    var color = vec3<f32>(0.0);
    if any(path.t2 != vec3<f32>(0.0)) {
        color = environment_radiance(path.t2);
    }
    out_color[i] = vec4<f32>(color, f32(COVERAGE_PATH));
    write_path_aovs(i, path);
}
