// Kakimoto et al. 2007, method pvrr: the shading of one view (a map, or the eye's frame) after
// its surface pass. The twin of render_view in crates/refract-cpu/src/pvrr.rs: diffuse surfaces
// shaded by the light, empty pixels the environment, reflector pixels the bilinear lookup of
// their map (one position per channel) times the reflector's tint.

// refract_gpu::methods::pvrr::GpuPvrrDraw: one reflector drawn in one view.
struct PvrrDraw {
    // F0 per channel and the kind in w: 0 mirror (Schlick tint), 1 lens (no tint).
    f0_kind: vec4<f32>,
    map_offset: u32,
    map_width: u32,
    map_height: u32,
    has_map: u32,
}

// refract_gpu::methods::pvrr::PvrrViewUniforms.
struct PvrrView {
    light_direction: vec4<f32>,
    light_radiance: vec4<f32>,
    light_ambient: vec4<f32>,
    // Texel offset of this view's map in `maps`; the eye writes the frame outputs instead.
    out_offset: u32,
    is_eye: u32,
    _padding: vec2<u32>,
}

@group(0) @binding(1) var view_a: texture_2d<f32>;
@group(0) @binding(2) var view_n: texture_2d<f32>;
@group(0) @binding(3) var view_b: texture_2d<f32>;
@group(0) @binding(5) var<storage, read_write> out_color: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> out_flags: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> materials: array<Material>;
@group(0) @binding(8) var<storage, read_write> maps: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> draws: array<PvrrDraw>;
@group(0) @binding(10) var<uniform> view: PvrrView;

override WRITE_AOVS: bool = true;

fn map_texel(d: PvrrDraw, x: u32, y: u32) -> vec3<f32> {
    return maps[d.map_offset + y * d.map_width + x].xyz;
}

// refract_core::pvrr::sample_bilinear.
fn pvrr_sample_bilinear(d: PvrrDraw, st: vec2<f32>) -> vec3<f32> {
    let x = clamp(st.x - 0.5, 0.0, f32(d.map_width - 1u));
    let y = clamp(st.y - 0.5, 0.0, f32(d.map_height - 1u));
    let x0f = floor(x);
    let y0f = floor(y);
    let fx = x - x0f;
    let fy = y - y0f;
    let x0 = u32(x0f);
    let y0 = u32(y0f);
    let x1 = min(x0 + 1u, d.map_width - 1u);
    let y1 = min(y0 + 1u, d.map_height - 1u);
    let top = map_texel(d, x0, y0) * (1.0 - fx) + map_texel(d, x1, y0) * fx;
    let bottom = map_texel(d, x0, y1) * (1.0 - fx) + map_texel(d, x1, y1) * fx;
    return top * (1.0 - fy) + bottom * fy;
}

// refract_core::pvrr::mirror_tint.
fn pvrr_mirror_tint(f0: vec3<f32>, n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let m = 1.0 - min(abs(dot(n, v)), 1.0);
    let m5 = m * m * m * m * m;
    return f0 + (vec3<f32>(1.0) - f0) * m5;
}

struct PvrrShade {
    color: vec3<f32>,
    covered: bool,
    zoom: bool,
}

fn pvrr_shade(px: vec2<i32>, dir: vec3<f32>) -> PvrrShade {
    var out: PvrrShade;
    out.covered = false;
    out.zoom = false;
    let n_covered = textureLoad(view_n, px, 0);
    if n_covered.w < 0.5 {
        out.color = environment_radiance(dir);
        return out;
    }
    let a = textureLoad(view_a, px, 0);
    let b = textureLoad(view_b, px, 0);
    let n = n_covered.xyz;
    if b.z > -0.5 {
        // A diffuse object (refract_cpu::distance_map::surface_material).
        let m = materials[u32(round(b.z)) - 1u];
        var uv = b.xy;
        if m.world_uv != 0u {
            uv = vec2<f32>(a.x, a.z);
        }
        let shading = view.light_ambient.xyz + abs(dot(n, view.light_direction.xyz)) * view.light_radiance.xyz;
        out.color = albedo(m, uv) * shading;
        return out;
    }
    out.covered = true;
    let d = draws[u32(round(-b.z)) - 1u];
    if b.w > 0.0 || d.has_map == 0u {
        out.color = vec3<f32>(0.0);
        out.zoom = true;
        return out;
    }
    var tint = vec3<f32>(1.0);
    if d.f0_kind.w < 0.5 {
        tint = pvrr_mirror_tint(d.f0_kind.xyz, n, dir);
    }
    let r = pvrr_sample_bilinear(d, a.xy);
    let g = pvrr_sample_bilinear(d, b.xy);
    let bl = pvrr_sample_bilinear(d, a.zw);
    out.color = vec3<f32>(r.x, g.y, bl.z) * tint;
    return out;
}

@compute @workgroup_size(8, 8, 1)
fn shade_pvrr(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.width || id.y >= frame.height {
        return;
    }
    let i = id.y * frame.width + id.x;
    let dir = pixel_ray_dir(vec2<f32>(id.xy) + 0.5);
    let s = pvrr_shade(vec2<i32>(id.xy), dir);
    if view.is_eye == 0u {
        maps[view.out_offset + i] = vec4<f32>(s.color, 1.0);
        return;
    }
    out_color[i] = vec4<f32>(s.color, 1.0);
    if WRITE_AOVS {
        out_flags[i] = vec4<f32>(select(0.0, 1.0, s.covered), select(0.0, 1.0, s.zoom), 0.0, 0.0);
    }
}
