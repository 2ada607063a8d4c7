// The engine methods' final pass (`screen-offset`, `volume-thickness`, `proxy-sphere`,
// `proxy-box`, `proxy-thin`), the twin of crates/refract-cpu/src/families/engine.rs: per pixel
// engine_path.wgsl's path over the screen texture, the colour read there, the AOVs. The module
// also holds image_space.wgsl (front faces, environment) and object_surfaces.wgsl (the opaque
// objects' surface pass from the eye: ng_surface, ng_color), whose bindings it shares; the
// engine writes its flags (off screen, screen weight) in the N2 slot.
//
// Several refractors: the front-face pass draws them all (the nearest wins; front_n1.w is
// 1 + its index, raster.wgsl), and each pixel refracts with its refractor's IOR and amount
// from `engine_refractors`, over the screen texture of the opaque objects only, as the engines
// draw several transmissive objects.

// Refractor k's (IOR, amount, dispersion half spread, rough LOD or Bevy's roughness): crates/refract-gpu/src/methods/engine.rs.
@group(0) @binding(17) var<uniform> engine_refractors: array<vec4<f32>, MAX_REFRACTORS>;

// The screen texture's colours mip-mapped (refract_core::screen_mips), level after level, for
// rough refractors: written by screen_mip_base and screen_mip_levels before shade_engine.
@group(0) @binding(18) var<storage, read_write> screen_mips: array<vec4<f32>>;

// The screen texel: xyz = P, w = 1 where it holds an object.
fn screen_surface(texel: vec2<i32>) -> vec4<f32> {
    if engine.has_objects == 0u {
        return vec4<f32>(0.0);
    }
    return ng_surface(texel);
}

// The view depth of what screen texel `texel` shows (F32_MAX where the environment).
fn screen_depth(texel: vec2<i32>) -> f32 {
    let s = screen_surface(texel);
    if s.w < 0.5 {
        return F32_MAX;
    }
    return ng_view_depth(s.xyz);
}

// The screen texture's colour at `texel`: the object drawn there or the environment along the
// texel's eye ray.
fn screen_color(texel: vec2<i32>) -> vec3<f32> {
    if screen_surface(texel).w > 0.5 {
        return ng_color(texel);
    }
    return environment_radiance(pixel_ray_dir(vec2<f32>(texel) + vec2<f32>(0.5)));
}

// Where level `level` starts in screen_mips.
fn mip_level_offset(level: u32) -> u32 {
    var offset = 0u;
    for (var j = 0u; j < level; j++) {
        let s = mip_level_size(j);
        offset += s.x * s.y;
    }
    return offset;
}

fn mip_texel(level: u32, texel: vec2<u32>) -> vec3<f32> {
    let s = mip_level_size(level);
    return screen_mips[mip_level_offset(level) + texel.y * s.x + texel.x].xyz;
}

// Level 0: the screen texture's colour per texel.
@compute @workgroup_size(8, 8)
fn screen_mip_base(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.width || id.y >= frame.height {
        return;
    }
    screen_mips[id.y * frame.width + id.x] = vec4<f32>(screen_color(vec2<i32>(id.xy)), 1.0);
}

// Levels 1 and up, one invocation per texel: the mean of its level-0 block
// (refract_core::screen_mips::level_block).
@compute @workgroup_size(64)
fn screen_mip_levels(@builtin(global_invocation_id) id: vec3<u32>) {
    var index = id.x + id.y * 65535u * 64u;
    let levels = mip_level_count();
    let base = frame.width * frame.height;
    var offset = base;
    for (var level = 1u; level < levels; level++) {
        let s = mip_level_size(level);
        let count = s.x * s.y;
        if index < count {
            let texel = vec2<u32>(index % s.x, index / s.x);
            let size = vec2<u32>(frame.width, frame.height);
            let start = texel << vec2<u32>(level);
            let end = max(min((texel + vec2<u32>(1u)) << vec2<u32>(level), size), start + vec2<u32>(1u));
            let stop = min(end, size);
            var sum = vec3<f32>(0.0);
            for (var y = start.y; y < stop.y; y++) {
                for (var x = start.x; x < stop.x; x++) {
                    sum += screen_mips[y * frame.width + x].xyz;
                }
            }
            let n = f32((stop.x - start.x) * (stop.y - start.y));
            screen_mips[offset + index] = vec4<f32>(sum / n, 1.0);
            return;
        }
        index -= count;
        offset += count;
    }
}

// What a rough refractor's pixel reads (refract_core::engine::RoughRead).
struct RoughRead {
    color: vec3<f32>,
    screen_weight: f32,
    environment_dir: vec3<f32>,
}

// refract_core::engine::EngineModel::read_rough: the blurred screen as the model reads it at a
// rough `lod` (> 0) for `path` of the pixel at `uv_px` whose front surface is `p1`: three.js's
// B-spline at the projected exit point (its texel's centre behind the eye), Bevy's taps around
// it, Godot's trilinear read at the texel's centre, HDRP's at lerp(fragment, texel centre,
// hdrp_hit_share(lod)), Filament's at the projected exit point (its texel's centre behind the
// eye).
fn read_rough(path: EnginePath, uv_px: vec2<f32>, p1: vec3<f32>, lod: f32) -> RoughRead {
    let size = vec2<f32>(f32(frame.width), f32(frame.height));
    let texel_px = vec2<f32>(path.texel) + vec2<f32>(0.5);
    var out = RoughRead(vec3<f32>(0.0), path.screen_weight, path.environment_dir);
    if ENGINE_MODEL == ENGINE_VOLUME_THICKNESS {
        let projected = world_to_pixel(path.p2);
        var read = texel_px;
        if projected.w > 0.5 {
            read = projected.xy;
        }
        if engine.depth_test != 0u {
            let from_eye = p1 - frame.eye.xyz;
            let fragment_depth = eye_view_depth(p1);
            let taps = bevy_blurred(uv_px, read / size, lod, fragment_depth);
            out.color = taps.xyz;
            out.screen_weight = taps.w;
            out.environment_dir = bevy_fallback_dir(normalize(from_eye), path.t2, engine.amount);
            return out;
        }
        out.color = sample_threejs(read / size, lod);
        return out;
    }
    if ENGINE_MODEL >= ENGINE_PROXY_SPHERE {
        if engine.filament_lookup != 0u {
            let projected = world_to_pixel(path.p2);
            var read = texel_px;
            if projected.w > 0.5 {
                read = projected.xy;
            }
            out.color = sample_trilinear(read / size, lod);
            return out;
        }
        let k = hdrp_hit_share(lod);
        out.color = sample_trilinear(mix(uv_px, texel_px, k) / size, lod);
        return out;
    }
    out.color = sample_trilinear(texel_px / size, lod);
    return out;
}

fn write_engine_aovs(i: u32, path: EnginePath, covered: bool) {
    if WRITE_AOVS {
        let exit = covered && path.has_exit;
        out_t2[i] = vec4<f32>(path.t2, select(0.0, 1.0, exit));
        out_p2[i] = vec4<f32>(path.p2, select(0.0, 1.0, exit));
        out_n2[i] = vec4<f32>(select(0.0, 1.0, covered && path.off_screen), path.screen_weight, 0.0, 0.0);
        var object = 0.0;
        var hit = 0.0;
        var p_geom = vec3<f32>(0.0);
        let s = screen_surface(path.texel);
        if covered && path.screen_weight > 0.0 && s.w > 0.5 {
            object = textureLoad(ng_uv_object, path.texel, 0).z;
            hit = 1.0;
            p_geom = s.xyz;
        }
        out_p_geom[i] = vec4<f32>(p_geom, hit);
        out_ng[i] = vec4<f32>(vec2<f32>(path.texel), object, 0.0);
    }
}

// Methods `screen-offset`, `volume-thickness`, `proxy-sphere`, `proxy-box`, `proxy-thin`.
@compute @workgroup_size(8, 8)
fn shade_engine(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.width || id.y >= frame.height {
        return;
    }
    let px = front_pixel(id);
    let i = px.index;
    var none: EnginePath;
    none.screen_weight = 0.0;
    if ENGINE_MODEL > ENGINE_PROXY_THIN {
        out_color[i] = vec4<f32>(UNKNOWN_CODE_COLOR, f32(COVERAGE_BACKGROUND));
        write_engine_aovs(i, none, false);
        return;
    }
    let texel = vec2<i32>(i32(id.x), i32(id.y));
    let object = screen_surface(texel);
    let in_front = !px.covered || (object.w > 0.5 && ng_view_depth(object.xyz) < ng_view_depth(px.p1));
    if in_front {
        out_color[i] = vec4<f32>(screen_color(texel), f32(COVERAGE_BACKGROUND));
        write_engine_aovs(i, none, false);
        return;
    }
    let n4 = robust_normalize(px.n1);
    let n1 = select(px.n1, n4.xyz, n4.w > 0.5);
    let k = min(u32(round(textureLoad(front_n1, texel, 0).w)) - 1u, MAX_REFRACTORS - 1u);
    let refractor = engine_refractors[k];
    // The model's dispersion (refract_core::engine_dispersion::EngineDispersion): three.js's
    // one path per channel at ior − s, ior, ior + s, channel c read from path c; Filament's
    // (the sphere with its lookup) four paths at ior + f o_j + jitter, each read in full and
    // mixed by K_j, the sum clamped at 0. The AOVs from the lookup at the base index. Without
    // it one path for all three channels.
    let spread = refractor.z;
    let filament = ENGINE_MODEL == ENGINE_PROXY_SPHERE && engine.filament_lookup != 0u;
    var passes = 1u;
    var aov_lookup = 0u;
    var jitter = 0.0;
    if spread > 0.0 {
        if filament {
            passes = 4u;
            aov_lookup = 2u;
            jitter = (interleaved_gradient_noise(px.uv) - 0.5) * FILAMENT_JITTER * spread;
        } else {
            passes = 3u;
            aov_lookup = 1u;
        }
    }
    var color = vec3<f32>(0.0);
    var middle: EnginePath;
    for (var lookup = 0u; lookup < passes; lookup++) {
        var ior = refractor.x;
        var channels = vec3<f32>(1.0);
        if passes == 3u {
            ior = refractor.x + (f32(lookup) - 1.0) * spread;
            channels = vec3<f32>(0.0);
            channels[lookup] = 1.0;
        } else if passes == 4u {
            ior = refractor.x + spread * FILAMENT_OFFSETS[lookup] + jitter;
        }
        let path = engine_path(px.uv, px.p1, n1, ior, refractor.y);
        var weight = path.screen_weight;
        var environment_dir = path.environment_dir;
        var read = vec3<f32>(0.0);
        if refractor.w > 0.0 {
            let rough = read_rough(path, px.uv, px.p1, refractor.w);
            weight = rough.screen_weight;
            environment_dir = rough.environment_dir;
            if weight > 0.0 {
                read += (weight * channels) * rough.color;
            }
        } else if weight > 0.0 {
            read += (weight * channels) * screen_color(path.texel);
        }
        if weight < 1.0 {
            read += ((1.0 - weight) * channels) * environment_radiance(environment_dir);
        }
        if passes == 4u {
            color += FILAMENT_MATRICES[lookup] * read;
        } else {
            color += read;
        }
        if lookup == aov_lookup {
            middle = path;
        }
    }
    if passes == 4u {
        color = max(color, vec3<f32>(0.0));
    }
    let path = middle;
    out_color[i] = vec4<f32>(color, f32(COVERAGE_PATH));
    write_engine_aovs(i, path, true);
}
