// Rasterising any mesh of the scene from any camera (the frame uniforms' world_to_clip): the
// refractor's back faces (normal + distance from the eye) and front faces (P1 + d_N, N1) of
// Wyman 2005a §4, and any surface with its uv and object id. The twin of
// crates/refract-cpu/src/raster.rs; the hardware interpolates perspective-correctly at pixel
// centres with the top-left rule.

// crates/refract-gpu/src/scene_buffers.rs: Vertex.
struct VertexIn {
    @location(0) p_ws: vec3<f32>,
    @location(1) n_ws: vec3<f32>,
    @location(2) d_n: f32,
    @location(3) uv: vec2<f32>,
    @location(4) object: u32,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) p_ws: vec3<f32>,
    @location(1) n_ws: vec3<f32>,
    @location(2) d_n: f32,
    @location(3) uv: vec2<f32>,
    @location(4) @interpolate(flat) object: u32,
}

@vertex
fn vs_mesh(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.world_to_clip * vec4<f32>(v.p_ws, 1.0);
    out.p_ws = v.p_ws;
    out.n_ws = v.n_ws;
    out.d_n = v.d_n;
    out.uv = v.uv;
    out.object = v.object;
    return out;
}

// Back faces: (normalised normal, distance from the eye). Empty texels are cleared to w = -1.
@fragment
fn fs_back(in: VertexOut) -> @location(0) vec4<f32> {
    let n = try_normalize(in.n_ws);
    return vec4<f32>(n.xyz, length(in.p_ws - frame.eye.xyz));
}

struct FrontOut {
    @location(0) p1_dn: vec4<f32>,
    @location(1) n1_covered: vec4<f32>,
}

// Front faces: (P1, d_N) and (normalised N1, 1 + the refractor's index, the vertices' `object`:
// 1 for the first refractor). Empty texels are cleared to 0 (w = 0).
@fragment
fn fs_front(in: VertexOut) -> FrontOut {
    var out: FrontOut;
    out.p1_dn = vec4<f32>(in.p_ws, in.d_n);
    out.n1_covered = vec4<f32>(try_normalize(in.n_ws).xyz, 1.0 + f32(in.object));
    return out;
}

struct SurfaceOut {
    @location(0) p_scalar: vec4<f32>,
    @location(1) n_covered: vec4<f32>,
    @location(2) uv_object: vec4<f32>,
}

// Any surface: (P, scalar), (normalised N, 1), (uv, object id, 1). Empty texels are cleared to 0.
@fragment
fn fs_surface(in: VertexOut) -> SurfaceOut {
    return surface_out(in);
}

fn surface_out(in: VertexOut) -> SurfaceOut {
    var out: SurfaceOut;
    out.p_scalar = vec4<f32>(in.p_ws, in.d_n);
    out.n_covered = vec4<f32>(try_normalize(in.n_ws).xyz, 1.0);
    out.uv_object = vec4<f32>(in.uv, f32(in.object), 1.0);
    return out;
}

// Depth peeling (the distance-map layers beyond the first of the other geometry): the previous
// layer's face (P, N) and the reference point. A fragment survives when the previous layer has
// a surface at this texel and the fragment is farther from the reference point by more than
// the relative margin (refract_cpu::distance_map::PEEL_MARGIN).
struct PeelUniforms {
    center: vec4<f32>,
    margin: f32,
    _padding0: f32,
    _padding1: f32,
    _padding2: f32,
}

@group(1) @binding(0) var peel_prev_p: texture_2d<f32>;
@group(1) @binding(1) var peel_prev_n: texture_2d<f32>;
@group(1) @binding(2) var<uniform> peel: PeelUniforms;

@fragment
fn fs_surface_peel(in: VertexOut) -> SurfaceOut {
    let texel = vec2<i32>(in.clip.xy);
    if textureLoad(peel_prev_n, texel, 0).w < 0.5 {
        discard;
    }
    let previous = length(textureLoad(peel_prev_p, texel, 0).xyz - peel.center.xyz);
    if length(in.p_ws - peel.center.xyz) <= previous * (1.0 + peel.margin) {
        discard;
    }
    return surface_out(in);
}
