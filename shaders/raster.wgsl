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

// Front faces: (P1, d_N) and (normalised N1, 1). Empty texels are cleared to 0 (w = 0).
@fragment
fn fs_front(in: VertexOut) -> FrontOut {
    var out: FrontOut;
    out.p1_dn = vec4<f32>(in.p_ws, in.d_n);
    out.n1_covered = vec4<f32>(try_normalize(in.n_ws).xyz, 1.0);
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
    var out: SurfaceOut;
    out.p_scalar = vec4<f32>(in.p_ws, in.d_n);
    out.n_covered = vec4<f32>(try_normalize(in.n_ws).xyz, 1.0);
    out.uv_object = vec4<f32>(in.uv, f32(in.object), 1.0);
    return out;
}
