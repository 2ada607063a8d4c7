// Refraction through any number of interfaces in depth-peeled layers: the line-by-line twin of
// refract_core::depth_peel (same names with a `peel_` prefix, same branches). The includer
// provides the layers and the opaque objects' screen texture:
//   layer_position(texel, layer) -> vec4<f32>  the fragment's P at the texel centre, w = 1
//                                               where the layer is covered (0: empty)
//   layer_normal(texel, layer) -> vec3<f32>    its unit shading normal
//   layer_refractor(texel, layer) -> u32       its refractor's index
//   opaque_position(texel) -> vec4<f32>        the opaque objects' P, w = 1 where one is drawn
//   opaque_normal(texel) -> vec3<f32>          its unit normal
// Where the Rust marks an empty layer with NaN, this twin uses PEEL_EMPTY (WGSL's NaN is not
// reliable).

// refract_core::depth_peel::PeelUniforms.
struct PeelUniforms {
    refractor_bound: vec4<f32>,
    scene_bound: vec4<f32>,
    layers: u32,
    max_interfaces: u32,
    steps: u32,
    thickness: f32,
}

// refract_core::depth_peel::PeelMedium.
struct PeelMedium {
    ior: f32,
    outside_ior: f32,
    within: u32,
    _padding: u32,
    sigma: vec4<f32>,
}

@group(0) @binding(16) var<uniform> peel: PeelUniforms;
@group(0) @binding(17) var<uniform> peel_media: array<PeelMedium, MAX_REFRACTORS>;

const PEEL_EMPTY: f32 = F32_MAX;
// OPAQUE_LAYER: the opaque objects in a crossing; as `exclude`, no layer.
const PEEL_OPAQUE_LAYER: u32 = 0xffffffffu;
const PEEL_SURFACE: u32 = 0u;
const PEEL_OFF_SCREEN: u32 = 1u;
const PEEL_NOTHING: u32 = 2u;

// sphere_exit.
fn peel_sphere_exit(origin: vec3<f32>, dir: vec3<f32>, bound: vec4<f32>) -> f32 {
    let oc = origin - bound.xyz;
    let b = dot(oc, dir);
    let c = dot(oc, oc) - bound.w * bound.w;
    let disc = b * b - c;
    if !(disc > 0.0) {
        return 0.0;
    }
    return max(sqrt(disc) - b, 0.0);
}

// ClipRay (clip(t) = c0 + t c1) with the ray itself: MarchRay.
struct PeelRay {
    c0: vec4<f32>,
    c1: vec4<f32>,
    origin: vec3<f32>,
    dir: vec3<f32>,
}

fn peel_ray(origin: vec3<f32>, dir: vec3<f32>) -> PeelRay {
    return PeelRay(
        frame.world_to_clip * vec4<f32>(origin, 1.0),
        frame.world_to_clip * vec4<f32>(dir, 0.0),
        origin,
        dir,
    );
}

// Sample.
struct PeelSample {
    texel: vec2<i32>,
    q: vec3<f32>,
    inside: bool,
}

// MarchRay::sample: ClipRay::texel (inside the view and its depth range) and the point.
fn peel_sample(ray: PeelRay, t: f32) -> PeelSample {
    let clip = ray.c0 + t * ray.c1;
    var s = PeelSample(vec2<i32>(0), ray.origin + t * ray.dir, false);
    if !(clip.w > 0.0) {
        return s;
    }
    let rcp_w = 1.0 / clip.w;
    let w = f32(frame.width);
    let h = f32(frame.height);
    let u = 0.5 * (clip.x * rcp_w + 1.0) * w;
    let v = 0.5 * (1.0 - clip.y * rcp_w) * h;
    let z = clip.z * rcp_w;
    s.inside = u >= 0.0 && u < w && v >= 0.0 && v < h && z >= 0.0 && z <= 1.0;
    s.texel = vec2<i32>(i32(floor(u)), i32(floor(v)));
    return s;
}

// facing_plane.
fn peel_facing_plane(p: vec3<f32>, n_in: vec3<f32>) -> vec4<f32> {
    let n = select(-n_in, n_in, dot(p - frame.eye.xyz, n_in) > 0.0);
    return vec4<f32>(n, -dot(n, p));
}

// layer_offset: the signed distance from the plane of the layer's (or the opaque objects')
// surface at the texel, negative toward the eye.
fn peel_offset(s: PeelSample, layer: u32) -> f32 {
    var p: vec4<f32>;
    var n: vec3<f32>;
    if layer == PEEL_OPAQUE_LAYER {
        p = opaque_position(s.texel);
        n = opaque_normal(s.texel);
    } else {
        p = layer_position(s.texel, layer);
        n = layer_normal(s.texel, layer);
    }
    if p.w < 0.5 {
        return PEEL_EMPTY;
    }
    let plane = peel_facing_plane(p.xyz, n);
    return dot(plane.xyz, s.q) + plane.w;
}

struct PeelRefined {
    t: f32,
    texel: vec2<i32>,
    ok: bool,
}

// refine.
fn peel_refine(ray: PeelRay, layer: u32, a_in: f32, f_a_in: f32, b_in: f32, f_b_in: f32, texel_b_in: vec2<i32>) -> PeelRefined {
    var a = a_in;
    var f_a = f_a_in;
    var b = b_in;
    var f_b = f_b_in;
    var texel_b = texel_b_in;
    var r = PeelRefined(0.0, vec2<i32>(0), false);
    for (var i = 0u; i < PEEL_REFINE_STEPS; i++) {
        let m = 0.5 * (a + b);
        let s = peel_sample(ray, m);
        if !s.inside {
            return r;
        }
        let f_m = peel_offset(s, layer);
        if f_m == PEEL_EMPTY {
            return r;
        }
        if (f_m < 0.0) == (f_a < 0.0) {
            a = m;
            f_a = f_m;
        } else {
            b = m;
            f_b = f_m;
            texel_b = s.texel;
        }
    }
    r.ok = abs(f_a) <= peel.thickness && abs(f_b) <= peel.thickness;
    r.t = a + (b - a) * clamp(f_a / (f_a - f_b), 0.0, 1.0);
    r.texel = texel_b;
    return r;
}

struct PeelCrossing {
    kind: u32,
    t: f32,
    texel: vec2<i32>,
    layer: u32,
}

// march (the settings from `peel`; `exclude` PEEL_OPAQUE_LAYER for none).
fn peel_march(origin: vec3<f32>, dir: vec3<f32>, t_end: f32, layer_count: u32, opaque: bool, exclude: u32) -> PeelCrossing {
    let ray = peel_ray(origin, dir);
    var c = PeelCrossing(PEEL_OFF_SCREEN, 0.0, vec2<i32>(0), 0u);
    let s0 = peel_sample(ray, 0.0);
    if !s0.inside {
        return c;
    }
    let count = min(layer_count, MAX_PEEL_LAYERS);
    var f_a: array<f32, MAX_PEEL_LAYERS>;
    for (var j = 0u; j < MAX_PEEL_LAYERS; j++) {
        f_a[j] = PEEL_EMPTY;
    }
    for (var j = 0u; j < count; j++) {
        if j != exclude {
            f_a[j] = peel_offset(s0, j);
        }
    }
    var f_opaque_a = PEEL_EMPTY;
    if opaque {
        f_opaque_a = peel_offset(s0, PEEL_OPAQUE_LAYER);
    }
    let steps = max(peel.steps, 1u);
    let dt = t_end / f32(steps);
    var t_a = 0.0;
    for (var i = 1u; i <= steps; i++) {
        let t_b = dt * f32(i);
        let s = peel_sample(ray, t_b);
        if !s.inside {
            return c;
        }
        var found = false;
        var best = PeelCrossing(PEEL_SURFACE, 0.0, vec2<i32>(0), 0u);
        for (var j = 0u; j < count; j++) {
            let f_b = peel_offset(s, j);
            if f_b == PEEL_EMPTY {
                // Layers are peeled in order: none after an empty one is covered here.
                for (var k = j; k < count; k++) {
                    f_a[k] = PEEL_EMPTY;
                }
                break;
            }
            if f_a[j] != PEEL_EMPTY && (f_a[j] < 0.0) != (f_b < 0.0) {
                let hit = peel_refine(ray, j, t_a, f_a[j], t_b, f_b, s.texel);
                if hit.ok && (!found || hit.t < best.t) {
                    found = true;
                    best = PeelCrossing(PEEL_SURFACE, hit.t, hit.texel, j);
                }
            }
            f_a[j] = f_b;
        }
        if opaque {
            let f_b = peel_offset(s, PEEL_OPAQUE_LAYER);
            if f_opaque_a != PEEL_EMPTY && f_b != PEEL_EMPTY && f_opaque_a < 0.0 && f_b >= 0.0 {
                let hit = peel_refine(ray, PEEL_OPAQUE_LAYER, t_a, f_opaque_a, t_b, f_b, s.texel);
                if hit.ok && (!found || hit.t < best.t) {
                    found = true;
                    best = PeelCrossing(PEEL_SURFACE, hit.t, hit.texel, PEEL_OPAQUE_LAYER);
                }
            }
            f_opaque_a = f_b;
        }
        if found {
            return best;
        }
        t_a = t_b;
    }
    c.kind = PEEL_NOTHING;
    return c;
}

struct PeelInteraction {
    dir: vec3<f32>,
    after: u32,
    refracted: bool,
}

// interact.
fn peel_interact(dir: vec3<f32>, n: vec3<f32>, medium: PeelMedium, refractor: u32) -> PeelInteraction {
    let entering = dot(dir, n) < 0.0;
    var n_facing = -n;
    var eta = medium.ior / medium.outside_ior;
    var after = medium.within;
    if entering {
        n_facing = n;
        eta = medium.outside_ior / medium.ior;
        after = refractor + 1u;
    }
    let t = refract_dir(dir, n_facing, eta);
    let refracted = any(t != vec3<f32>(0.0));
    var out_dir = dir;
    if refracted {
        out_dir = normalize(t);
    }
    return PeelInteraction(out_dir, after, refracted);
}

// segment_transmittance.
fn peel_transmittance(current: u32, t: f32) -> vec3<f32> {
    if current == 0u || current > MAX_REFRACTORS {
        return vec3<f32>(1.0);
    }
    let sigma = peel_media[current - 1u].sigma.xyz;
    return exp(-sigma * t);
}

struct PeelPath {
    end: u32,
    origin: vec3<f32>,
    dir: vec3<f32>,
    opaque: bool,
    opaque_texel: vec2<i32>,
    p_geom: vec3<f32>,
    has_exit: bool,
    p2: vec3<f32>,
    t2: vec3<f32>,
    interfaces: u32,
    reflections: u32,
    refractors_met: u32,
    transmittance: vec3<f32>,
}

// peel_path.
fn peel_path(p1: vec3<f32>, n1: vec3<f32>, refractor: u32) -> PeelPath {
    var path: PeelPath;
    path.end = PEEL_END_LEFT;
    path.origin = p1;
    let to_p1 = p1 - frame.eye.xyz;
    path.dir = frame.look_dir.xyz;
    if dot(to_p1, to_p1) > 0.0 {
        path.dir = normalize(to_p1);
    }
    path.opaque = false;
    path.opaque_texel = vec2<i32>(0);
    path.p_geom = vec3<f32>(0.0);
    path.has_exit = false;
    path.p2 = vec3<f32>(0.0);
    path.t2 = vec3<f32>(0.0);
    path.interfaces = 0u;
    path.reflections = 0u;
    path.refractors_met = 0u;
    path.transmittance = vec3<f32>(1.0);
    var current = 0u;
    var n = n1;
    var r = refractor;
    var layer = 0u;
    let has_objects = peel.scene_bound.w > 0.0;
    loop {
        if path.interfaces + path.reflections >= max(peel.max_interfaces, 1u) {
            path.end = PEEL_END_BUDGET;
            break;
        }
        let medium = peel_media[min(r, MAX_REFRACTORS - 1u)];
        let hit = peel_interact(path.dir, n, medium, r);
        if hit.refracted {
            path.dir = hit.dir;
            current = hit.after;
            path.interfaces += 1u;
            if r < 32u {
                path.refractors_met |= 1u << r;
            }
        } else {
            var n_facing = -n;
            if dot(path.dir, n) < 0.0 {
                n_facing = n;
            }
            path.dir = reflect_dir(path.dir, n_facing);
            path.reflections += 1u;
        }
        if path.interfaces + path.reflections == 2u {
            path.has_exit = true;
            path.p2 = path.origin;
            path.t2 = path.dir;
        }
        let t_end = peel_sphere_exit(path.origin, path.dir, peel.refractor_bound);
        let crossing = peel_march(path.origin, path.dir, t_end, peel.layers, has_objects, layer);
        if crossing.kind == PEEL_SURFACE {
            path.transmittance *= peel_transmittance(current, crossing.t);
            if crossing.layer == PEEL_OPAQUE_LAYER {
                path.opaque = true;
                path.opaque_texel = crossing.texel;
                path.p_geom = path.origin + crossing.t * path.dir;
                return path;
            }
            path.origin += crossing.t * path.dir;
            n = layer_normal(crossing.texel, crossing.layer);
            r = layer_refractor(crossing.texel, crossing.layer);
            layer = crossing.layer;
        } else if crossing.kind == PEEL_OFF_SCREEN {
            path.end = PEEL_END_OFF_SCREEN;
            return path;
        } else {
            path.end = select(PEEL_END_LOST, PEEL_END_LEFT, current == 0u);
            break;
        }
    }
    if has_objects {
        let t_end = peel_sphere_exit(path.origin, path.dir, peel.scene_bound);
        let crossing = peel_march(path.origin, path.dir, t_end, 0u, true, PEEL_OPAQUE_LAYER);
        if crossing.kind == PEEL_SURFACE {
            path.opaque = true;
            path.opaque_texel = crossing.texel;
            path.p_geom = path.origin + crossing.t * path.dir;
        }
    }
    return path;
}
