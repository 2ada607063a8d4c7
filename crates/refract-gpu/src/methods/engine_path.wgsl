// The refraction today's engines ship (Godot, three.js, Bevy, Unity HDRP, Filament): where each
// reads the screen for one refractor pixel, the twin of refract_core::engine::engine_path. It
// reads the opaque objects' view depth through `screen_depth(texel)` (F32_MAX where the
// environment), which the module including it provides: engine.wgsl from the screen texture,
// engine_conformance.wgsl analytically. ENGINE_MODEL is an override constant (one pipeline per
// method).

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

// The view depth of `p` from the eye (refract_core::nearby_geometry::view_depth).
fn eye_view_depth(p: vec3<f32>) -> f32 {
    return dot(p - frame.eye.xyz, frame.look_dir.xyz);
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

// engine.rs: engine_path, through a refractor of index `ior` whose model reads `amount` (the
// thickness `d`, or the screen offset's scale).
fn engine_path(uv_px: vec2<f32>, p1_ws: vec3<f32>, n1_ws: vec3<f32>, ior: f32, amount: f32) -> EnginePath {
    var path: EnginePath;
    path.screen_weight = 1.0;
    path.environment_dir = vec3<f32>(0.0);
    path.has_exit = ENGINE_MODEL != ENGINE_SCREEN_OFFSET;
    let size = vec2<f32>(f32(frame.width), f32(frame.height));
    let incident = normalize_or_zero(p1_ws - frame.eye.xyz);
    let fragment_depth = eye_view_depth(p1_ws);
    let own = clamp_to_screen(uv_px);
    if ENGINE_MODEL == ENGINE_SCREEN_OFFSET {
        let n_view = (engine.world_to_view * vec4<f32>(n1_ws, 0.0)).xyz;
        let offset = uv_px + screen_offset_px(n_view, amount, size);
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
        let e = volume_exit(p1_ws, n1_ws, incident, ior, amount);
        path.p2 = e.p;
        path.t2 = e.dir;
        let c = projected_texel(e.p, own.xy);
        path.texel = c.xy;
        path.off_screen = c.z == 1;
        if engine.depth_test != 0u && screen_depth(path.texel) < fragment_depth {
            path.screen_weight = 0.0;
            path.environment_dir = bevy_fallback_dir(incident, e.dir, amount);
        }
        return path;
    }
    var e: EngineExit;
    if ENGINE_MODEL == ENGINE_PROXY_SPHERE {
        e = proxy_sphere_exit(p1_ws, n1_ws, incident, ior, amount);
    } else if ENGINE_MODEL == ENGINE_PROXY_BOX {
        e = proxy_box_exit(p1_ws, n1_ws, incident, ior, amount);
    } else {
        e = proxy_box_exit(p1_ws, n1_ws, incident, ior, THIN_THICKNESS);
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

