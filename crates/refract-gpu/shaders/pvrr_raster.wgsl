// Kakimoto et al. 2007, method pvrr: a reflector drawn with its vertices' map positions
// (refract_core::pvrr::PvrrVertex, the second vertex buffer), interpolated perspective-
// correctly by the hardware (§3.1 step 4). The draw's index is the instance index. The twin of
// the reflector pixels of crates/refract-cpu/src/pvrr.rs.

struct PvrrVertexIn {
    @location(0) p_ws: vec3<f32>,
    @location(1) n_ws: vec3<f32>,
    // PvrrVertex: the R and G map positions; the B map position, the state, padding.
    @location(5) st_rg: vec4<f32>,
    @location(6) st_b_state: vec4<f32>,
}

struct PvrrVertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) n_ws: vec3<f32>,
    @location(1) st_rg: vec4<f32>,
    @location(2) st_b_state: vec4<f32>,
    @location(3) @interpolate(flat) draw: u32,
}

@vertex
fn vs_pvrr(v: PvrrVertexIn, @builtin(instance_index) draw: u32) -> PvrrVertexOut {
    var out: PvrrVertexOut;
    out.clip = frame.world_to_clip * vec4<f32>(v.p_ws, 1.0);
    out.n_ws = v.n_ws;
    out.st_rg = v.st_rg;
    out.st_b_state = v.st_b_state;
    out.draw = draw;
    return out;
}

// The surface targets of a reflector pixel: (R st, B st), (N, 1), (G st, −(draw + 1), state).
// Diffuse pixels (fs_surface) hold (P, scalar), (N, 1), (uv, object ≥ 1, 1).
@fragment
fn fs_pvrr(in: PvrrVertexOut) -> SurfaceOut {
    var out: SurfaceOut;
    out.p_scalar = vec4<f32>(in.st_rg.xy, in.st_b_state.xy);
    out.n_covered = vec4<f32>(try_normalize(in.n_ws).xyz, 1.0);
    out.uv_object = vec4<f32>(in.st_rg.zw, -(f32(in.draw) + 1.0), in.st_b_state.z);
    return out;
}
