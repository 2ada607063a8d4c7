// The refraction today's engines ship (Godot, three.js, Bevy, Unity HDRP, Filament), the final
// pass: the twin of refract_core::engine::engine_path and crates/refract-cpu/src/families/engine.rs.
// One pipeline per method (ENGINE_MODEL an override constant). The module also holds
// image_space.wgsl (front faces, environment) and nearby_geometry.wgsl (the opaque objects'
// surface pass from the eye: ng_surface, ng_color), whose bindings it shares; the engine
// writes its flags (off screen, screen weight) in the N2 slot.

struct EngineUniforms {
    world_to_view: mat4x4<f32>,
    amount: f32,
    depth_test: u32,
    filament_lookup: u32,
    // 0: the scene has no opaque objects; the screen texture is neither drawn nor read.
    has_objects: u32,
}

@group(0) @binding(16) var<uniform> engine: EngineUniforms;

// refract_core::engine::ENGINE_* (one pipeline per method).
override ENGINE_MODEL: u32 = ENGINE_SCREEN_OFFSET;

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

// engine.rs: clamp_to_screen. xy = texel, z = 1 when outside the frame.
fn clamp_to_screen(uv_px: vec2<f32>) -> vec3<i32> {
    let w = f32(frame.width);
    let h = f32(frame.height);
    let inside = uv_px.x >= 0.0 && uv_px.y >= 0.0 && uv_px.x < w && uv_px.y < h;
    let x = i32(clamp(uv_px.x, 0.0, w - 1.0));
    let y = i32(clamp(uv_px.y, 0.0, h - 1.0));
    return vec3<i32>(x, y, select(1, 0, inside));
}

// The texel `p` projects to, clamped (z = 1 when outside the frame); `own` behind the eye.
fn projected_texel(p: vec3<f32>, own: vec2<i32>) -> vec3<i32> {
    let q = world_to_pixel(p);
    if q.w > 0.5 {
        return clamp_to_screen(q.xy);
    }
    return vec3<i32>(own, 1);
}

struct EnginePath {
    texel: vec2<i32>,
    screen_weight: f32,
    environment_dir: vec3<f32>,
    p2: vec3<f32>,
    t2: vec3<f32>,
    off_screen: bool,
    has_exit: bool,
}

// engine.rs: engine_path.
fn engine_path(uv_px: vec2<f32>, p1_ws: vec3<f32>, n1_ws: vec3<f32>) -> EnginePath {
    var path: EnginePath;
    path.screen_weight = 1.0;
    path.environment_dir = vec3<f32>(0.0);
    path.has_exit = ENGINE_MODEL != ENGINE_SCREEN_OFFSET;
    let size = vec2<f32>(f32(frame.width), f32(frame.height));
    let incident = normalize_or_zero(p1_ws - frame.eye.xyz);
    let fragment_depth = ng_view_depth(p1_ws);
    let own = clamp_to_screen(uv_px);
    if ENGINE_MODEL == ENGINE_SCREEN_OFFSET {
        let n_view = (engine.world_to_view * vec4<f32>(n1_ws, 0.0)).xyz;
        let offset = uv_px + screen_offset_px(n_view, engine.amount, size);
        let shifted = clamp_to_screen(offset);
        path.texel = shifted.xy;
        path.off_screen = shifted.z == 1;
        if engine.depth_test != 0u {
            let w = smoothstep01(screen_depth(shifted.xy) - fragment_depth);
            path.texel = clamp_to_screen(mix(uv_px, offset, w)).xy;
        }
        return path;
    }
    if ENGINE_MODEL == ENGINE_VOLUME_THICKNESS {
        let e = volume_exit(p1_ws, n1_ws, incident, frame.ior, engine.amount);
        path.p2 = e.p;
        path.t2 = e.dir;
        let c = projected_texel(e.p, own.xy);
        path.texel = c.xy;
        path.off_screen = c.z == 1;
        if engine.depth_test != 0u && screen_depth(path.texel) < fragment_depth {
            path.screen_weight = 0.0;
            path.environment_dir = bevy_fallback_dir(incident, e.dir, engine.amount);
        }
        return path;
    }
    var e: EngineExit;
    if ENGINE_MODEL == ENGINE_PROXY_SPHERE {
        e = proxy_sphere_exit(p1_ws, n1_ws, incident, frame.ior, engine.amount);
    } else if ENGINE_MODEL == ENGINE_PROXY_BOX {
        e = proxy_box_exit(p1_ws, n1_ws, incident, frame.ior, engine.amount);
    } else {
        e = proxy_box_exit(p1_ws, n1_ws, incident, frame.ior, THIN_THICKNESS);
    }
    path.p2 = e.p;
    path.t2 = e.dir;
    if engine.filament_lookup != 0u {
        let c = projected_texel(e.p, own.xy);
        path.texel = c.xy;
        path.off_screen = c.z == 1;
        return path;
    }
    path.environment_dir = e.dir;
    let hit = world_to_pixel(e.p + e.dir * HDRP_SKY_DISTANCE);
    if hit.w < 0.5 {
        path.texel = own.xy;
        path.screen_weight = 0.0;
        path.off_screen = true;
        return path;
    }
    path.screen_weight = hdrp_edge_fade(hit.xy / size);
    let c = clamp_to_screen(hit.xy);
    path.off_screen = c.z == 1;
    if screen_depth(c.xy) > fragment_depth {
        path.texel = c.xy;
    } else {
        path.texel = own.xy;
    }
    return path;
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
    let path = engine_path(px.uv, px.p1, n1);
    var color = vec3<f32>(0.0);
    if path.screen_weight > 0.0 {
        color += path.screen_weight * screen_color(path.texel);
    }
    if path.screen_weight < 1.0 {
        color += (1.0 - path.screen_weight) * environment_radiance(path.environment_dir);
    }
    out_color[i] = vec4<f32>(color, f32(COVERAGE_PATH));
    write_engine_aovs(i, path, true);
}
