// Umenhoffer et al. 2007 (GPU Gems 3 ch. 17), method distance-map: the per-pixel pass. The
// twin of crates/refract-cpu/src/distance_map.rs.
//
// The layers are surface passes (raster.wgsl fs_surface / fs_surface_peel) of six mirrored 90°
// cube-face cameras around the reference point, stored as 2D array textures of 6·layers array
// layers (layer·6 + face, WebGPU's face order and orientation: a cube texture's memory layout),
// read texel-exactly with dm_cube_texel. The eye's surface pass of every mesh gives the start.

struct DmUniforms {
    center: vec4<f32>,
    refractor: vec4<f32>,
    light_direction: vec4<f32>,
    light_radiance: vec4<f32>,
    light_ambient: vec4<f32>,
    layers: u32,
    size: u32,
    min_steps: u32,
    max_steps: u32,
    secant_steps: u32,
    min_max: u32,
    max_depth: u32,
    fresnel: u32,
}

@group(0) @binding(1) var cam_p: texture_2d<f32>;
@group(0) @binding(2) var cam_n: texture_2d<f32>;
@group(0) @binding(3) var cam_uv_object: texture_2d<f32>;
@group(0) @binding(5) var<storage, read_write> out_color: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> out_counts: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> out_flags: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read> materials: array<Material>;
@group(0) @binding(9) var layer_p: texture_2d_array<f32>;
@group(0) @binding(10) var layer_n: texture_2d_array<f32>;
@group(0) @binding(11) var layer_uv_object: texture_2d_array<f32>;
@group(0) @binding(12) var<storage, read_write> ranges: array<atomic<u32>>;
@group(0) @binding(13) var<uniform> dm: DmUniforms;

override WRITE_AOVS: bool = true;

fn dm_layer_count() -> u32 { return dm.layers; }
fn dm_face_size() -> u32 { return dm.size; }
fn dm_two_sided(layer: u32) -> bool { return layer < 2u; }
fn dm_background(dir: vec3<f32>) -> vec3<f32> { return environment_radiance(dir); }

fn dm_distance(layer: u32, dir: vec3<f32>) -> f32 {
    let t = dm_cube_texel(dir, dm.size);
    if t.w == 0 {
        return -1.0;
    }
    let slice = t.x + 6 * i32(layer);
    if textureLoad(layer_n, t.yz, slice, 0).w < 0.5 {
        return -1.0;
    }
    return length(textureLoad(layer_p, t.yz, slice, 0).xyz - dm.center.xyz);
}

fn dm_range(layer: u32) -> vec3<f32> {
    let lo = bitcast<f32>(atomicLoad(&ranges[2u * layer]));
    let hi = bitcast<f32>(atomicLoad(&ranges[2u * layer + 1u]));
    return vec3<f32>(lo, hi, select(0.0, 1.0, lo <= hi));
}

// surface_material of the CPU backend: object 0 the specular object (uniforms), 1 + k object k.
fn surface_material(p: vec3<f32>, n: vec3<f32>, uv_object: vec4<f32>) -> DmSurface {
    var out: DmSurface;
    out.normal = n;
    let object = u32(round(uv_object.z));
    if object == 0u {
        out.rgb = dm.refractor.xyz;
        out.ior = dm.refractor.w;
        return out;
    }
    let m = materials[object - 1u];
    if m.kind == 4u {
        out.rgb = m.a.xyz;
        out.ior = -1.0;
        return out;
    }
    var uv = uv_object.xy;
    if m.world_uv != 0u {
        uv = vec2<f32>(p.x, p.z);
    }
    let shading = dm.light_ambient.xyz + abs(dot(n, dm.light_direction.xyz)) * dm.light_radiance.xyz;
    out.rgb = albedo(m, uv) * shading;
    out.ior = 0.0;
    return out;
}

fn dm_surface(layer: u32, dir: vec3<f32>) -> DmSurface {
    let t = dm_cube_texel(dir, dm.size);
    let slice = t.x + 6 * i32(layer);
    let p = textureLoad(layer_p, t.yz, slice, 0).xyz;
    let n = textureLoad(layer_n, t.yz, slice, 0).xyz;
    return surface_material(p, n, textureLoad(layer_uv_object, t.yz, slice, 0));
}

// Each layer's smallest and largest distance (min-max acceleration): positive floats order
// like their bits, so atomicMin/atomicMax on the bits (cleared to +inf and 0 each frame). An
// invocation reduces a run of DM_RANGE_RUN texels of a row before its one atomic pair: every
// texel of a layer contends for the same two words. Min and max are exact: the same bits.
const DM_RANGE_RUN: u32 = 32u;

@compute @workgroup_size(8, 8, 1)
fn dm_ranges(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.y >= dm.size || id.z >= 6u * dm.layers {
        return;
    }
    // +inf and 0: no texel (the identity of min and max over the bits).
    var lo = 0x7f800000u;
    var hi = 0u;
    let slice = i32(id.z);
    let start = id.x * DM_RANGE_RUN;
    let stop = min(start + DM_RANGE_RUN, dm.size);
    for (var x = start; x < stop; x++) {
        let texel = vec2<i32>(i32(x), i32(id.y));
        if textureLoad(layer_n, texel, slice, 0).w >= 0.5 {
            let d = bitcast<u32>(length(textureLoad(layer_p, texel, slice, 0).xyz - dm.center.xyz));
            lo = min(lo, d);
            hi = max(hi, d);
        }
    }
    if lo <= hi {
        let layer = id.z / 6u;
        atomicMin(&ranges[2u * layer], lo);
        atomicMax(&ranges[2u * layer + 1u], hi);
    }
}

@compute @workgroup_size(8, 8, 1)
fn shade_distance_map(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.width || id.y >= frame.height {
        return;
    }
    let i = id.y * frame.width + id.x;
    let px = vec2<i32>(id.xy);
    let n_covered = textureLoad(cam_n, px, 0);
    if WRITE_AOVS {
        out_counts[i] = vec4<f32>(0.0);
        out_flags[i] = vec4<f32>(0.0);
    }
    if n_covered.w < 0.5 {
        let dir = pixel_ray_dir(vec2<f32>(id.xy) + 0.5);
        out_color[i] = vec4<f32>(environment_radiance(dir), 1.0);
        return;
    }
    let p = textureLoad(cam_p, px, 0).xyz;
    let n = n_covered.xyz;
    let uv_object = textureLoad(cam_uv_object, px, 0);
    let material = surface_material(p, n, uv_object);
    if material.ior == 0.0 {
        out_color[i] = vec4<f32>(material.rgb, 1.0);
        return;
    }
    let center = dm.center.xyz;
    var start = 2;
    if u32(round(uv_object.z)) == 0u {
        start = select(0, 1, dot(n, p - center) >= 0.0);
    }
    let search = DmSearch(dm.min_steps, dm.max_steps, dm.secant_steps, dm.min_max != 0u);
    let v = normalize(p - frame.eye.xyz);
    let path = dm_trace_path(p - center, v, n, material.rgb, material.ior, start, search, dm.max_depth, dm.fresnel);
    out_color[i] = vec4<f32>(path.radiance, 1.0);
    if WRITE_AOVS {
        out_counts[i] = vec4<f32>(f32(path.last_layer + 1), f32(path.linear_steps), f32(path.secant_steps), f32(path.bounces));
        out_flags[i] = vec4<f32>(1.0, select(0.0, 1.0, path.miss), select(0.0, 1.0, path.tir), select(0.0, 1.0, path.truncated));
    }
}
