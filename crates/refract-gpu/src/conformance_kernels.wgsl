// Whole-kernel conformance: two_interface.wgsl's kernels over an analytic back-face buffer, held
// to refract_core::kernel::{one_interface, two_interface} over the same analytic sampler
// (crates/refract-gpu/tests/conformance.rs). The frame uniforms (binding 0) carry the camera,
// the IOR and the TIR policy; DISTANCE_MODE is the pipeline's override.

@group(0) @binding(1) var<storage, read> in_a: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> in_b: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> out_v: array<vec4<f32>>;

// The radius of the analytic refractor: a sphere at the origin.
const KERNEL_SPHERE_RADIUS: f32 = 1.0;

// The far intersection of the pixel ray through uv_px with the sphere: (outward normal,
// distance from the eye), w < 0 where the ray misses it or uv_px is outside the frame (the
// back-face buffer's empty texels). A texel's position is its pixel centre, as a rasteriser
// samples it.
fn back_face(uv_px: vec2<f32>) -> vec4<f32> {
    let w = f32(frame.width);
    let h = f32(frame.height);
    if !(uv_px.x >= 0.0 && uv_px.y >= 0.0 && uv_px.x < w && uv_px.y < h) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let centre = floor(uv_px) + vec2<f32>(0.5);
    let dir = pixel_ray_dir(centre);
    let o = frame.eye.xyz;
    let b = dot(o, dir);
    let disc = b * b - (dot(o, o) - KERNEL_SPHERE_RADIUS * KERNEL_SPHERE_RADIUS);
    if disc < 0.0 {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let t = -b + sqrt(disc);
    return vec4<f32>((o + t * dir) / KERNEL_SPHERE_RADIUS, t);
}

// A front pixel from a = (p1, d_n), b = (n1, u_px + 4096 v_px): the rasterised surface the
// kernel reads.
fn kernel_pixel(i: u32) -> FrontPixel {
    var px: FrontPixel;
    px.index = i;
    let packed = in_b[i].w;
    let v = floor(packed / 4096.0);
    px.uv = vec2<f32>(packed - 4096.0 * v, v) + vec2<f32>(0.5);
    px.covered = true;
    px.p1 = in_a[i].xyz;
    px.d_n = in_a[i].w;
    px.n1 = in_b[i].xyz;
    return px;
}

// -> (T1, 1 valid + 2 TIR at the entry)
@compute @workgroup_size(64)
fn test_one_interface(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let px = kernel_pixel(i);
    let entry = one_interface(px.p1, px.n1);
    out_v[i] = vec4<f32>(entry.t1, select(0.0, 1.0, entry.valid) + select(0.0, 2.0, entry.tir));
}

// -> (T2, 1 valid + 2 TIR + 4 N2 from the back faces)
@compute @workgroup_size(64)
fn test_two_interface_t2(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    let path = two_interface_path(kernel_pixel(i));
    let flags = select(0.0, 1.0, path.valid) + select(0.0, 2.0, path.tir)
        + select(0.0, 4.0, path.source == EXIT_NORMAL_BACK_FACE);
    out_v[i] = vec4<f32>(path.t2, flags);
}

// -> (P~2, _)
@compute @workgroup_size(64)
fn test_two_interface_p2(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(two_interface_path(kernel_pixel(i)).p2, 0.0);
}

// -> (N2, _)
@compute @workgroup_size(64)
fn test_two_interface_n2(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&out_v) { return; }
    out_v[i] = vec4<f32>(two_interface_path(kernel_pixel(i)).n2, 0.0);
}
