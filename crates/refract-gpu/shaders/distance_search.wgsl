// The WGSL twin of refract_core::distance_map (Umenhoffer et al. 2007, GPU Gems 3 ch. 17):
// cube texel selection, Hit() (linear search uniform in texture space, secant refinement,
// min-max), the scatter at a specular surface and the multiple reflection/refraction loop.
// Function by function the Rust of the same name (dm_ prefix), held to it by the conformance
// tests (crates/refract-gpu/tests/conformance.rs) and by the CPU-vs-GPU agreement tests.
//
// No bindings: the including module defines how the layers are read,
//   dm_layer_count() -> u32, dm_face_size() -> u32,
//   dm_distance(layer: u32, dir: vec3<f32>) -> f32        (negative where empty),
//   dm_range(layer: u32) -> vec3<f32>                     (min, max, 1 when not empty),
//   dm_two_sided(layer: u32) -> bool,
//   dm_surface(layer: u32, dir: vec3<f32>) -> DmSurface,
//   dm_background(dir: vec3<f32>) -> vec3<f32>.

// TexelSurface: outward normal, material rgb and the sign code (< 0 conductor, 0 diffuse,
// > 0 refractor of that index).
struct DmSurface {
    normal: vec3<f32>,
    rgb: vec3<f32>,
    ior: f32,
}

// SearchParams.
struct DmSearch {
    min_steps: u32,
    max_steps: u32,
    secant_steps: u32,
    min_max: bool,
}

// CubeFace::of_direction + cube_texel: (face, x, y, 1), or w = 0 for a zero/non-finite dir.
fn dm_cube_texel(dir: vec3<f32>, size: u32) -> vec4<i32> {
    let a = abs(dir);
    let m = max(a.x, max(a.y, a.z));
    if !(m > 0.0 && m <= F32_MAX) {
        return vec4<i32>(0);
    }
    var face = 0;
    var sc = 0.0;
    var tc = 0.0;
    var ma = 0.0;
    if a.x >= a.y && a.x >= a.z {
        if dir.x >= 0.0 {
            face = 0; sc = -dir.z; tc = -dir.y;
        } else {
            face = 1; sc = dir.z; tc = -dir.y;
        }
        ma = a.x;
    } else if a.y >= a.z {
        if dir.y >= 0.0 {
            face = 2; sc = dir.x; tc = dir.z;
        } else {
            face = 3; sc = dir.x; tc = -dir.z;
        }
        ma = a.y;
    } else {
        if dir.z >= 0.0 {
            face = 4; sc = dir.x; tc = -dir.y;
        } else {
            face = 5; sc = -dir.x; tc = -dir.y;
        }
        ma = a.z;
    }
    let st = vec2<f32>(sc / ma + 1.0, tc / ma + 1.0) * 0.5;
    let hi = f32(size - 1u);
    let xy = clamp(floor(st * f32(size)), vec2<f32>(0.0), vec2<f32>(hi));
    return vec4<i32>(face, i32(xy.x), i32(xy.y), 1);
}

// cube_texel_direction: the (unnormalised) direction through a texel centre.
fn dm_cube_texel_direction(face: i32, texel: vec2<i32>, size: u32) -> vec3<f32> {
    let st = (vec2<f32>(texel) + 0.5) / f32(size) * 2.0 - 1.0;
    let sc = st.x;
    let tc = st.y;
    switch face {
        case 0: { return vec3<f32>(1.0, -tc, -sc); }
        case 1: { return vec3<f32>(-1.0, -tc, sc); }
        case 2: { return vec3<f32>(sc, 1.0, tc); }
        case 3: { return vec3<f32>(sc, -1.0, -tc); }
        case 4: { return vec3<f32>(sc, -tc, 1.0); }
        default: { return vec3<f32>(-sc, -tc, -1.0); }
    }
}

fn dm_ray_parameter(t: f32, a: f32) -> f32 {
    return a * t / (1.0 - t);
}

fn dm_texture_parameter(d: f32, a: f32) -> f32 {
    return d / (a + d);
}

fn dm_linear_steps(s: vec3<f32>, e: vec3<f32>, search: DmSearch) -> u32 {
    let theta = angle_between(s, e);
    let steps = ceil(f32(search.max_steps) * theta / PI);
    let lo = max(search.min_steps, 1u);
    return clamp(u32(steps), lo, max(search.max_steps, lo));
}

// shell_segment: (d_lo, d_hi, 1), or z = 0 when the ray misses the outer sphere.
fn dm_shell_segment(x: vec3<f32>, r: vec3<f32>, r_min: f32, r_max: f32) -> vec3<f32> {
    let b = dot(x, r);
    let xx = dot(x, x);
    let disc_max = b * b - (xx - r_max * r_max);
    if disc_max < 0.0 {
        return vec3<f32>(0.0);
    }
    let root = sqrt(disc_max);
    let d_hi = -b + root;
    if d_hi < 0.0 {
        return vec3<f32>(0.0);
    }
    var d_lo = 0.0;
    if xx > r_max * r_max {
        d_lo = -b - root;
    } else if xx < r_min * r_min {
        d_lo = -b + sqrt(max(b * b - (xx - r_min * r_min), 0.0));
    }
    return vec3<f32>(max(d_lo, 0.0), d_hi, 1.0);
}

struct DmBracket {
    d_near: f32,
    ratio_near: f32,
    d_far: f32,
    ratio_far: f32,
    found: bool,
    taken: u32,
}

// With `stop`, ends without a bracket after the first sample at or beyond `d_stop` (the best
// hit so far).
fn dm_linear_search(layer: u32, x: vec3<f32>, r: vec3<f32>, a: f32, t_lo: f32, t_hi: f32, steps: u32, skip_cos: f32, stop: bool, d_stop: f32) -> DmBracket {
    var out: DmBracket;
    out.found = false;
    out.taken = steps + 1u;
    let dt = (t_hi - t_lo) / f32(steps);
    let two_sided = dm_two_sided(layer);
    let x_len = length(x);
    var has_previous = false;
    var d_prev = 0.0;
    var ratio_prev = 0.0;
    for (var i = 0u; i <= steps; i++) {
        let t = min(t_lo + dt * f32(i), t_hi);
        let d = dm_ray_parameter(t, a);
        let p = x + r * d;
        let stored = dm_distance(layer, p);
        let p_len = length(p);
        if stored <= 0.0 || dot(p, x) > skip_cos * p_len * x_len {
            has_previous = false;
        } else {
            let ratio = p_len / stored;
            if has_previous && ((ratio_prev < 1.0) != (ratio < 1.0)) && (two_sided || ratio_prev < 1.0) {
                out.d_near = d_prev;
                out.ratio_near = ratio_prev;
                out.d_far = d;
                out.ratio_far = ratio;
                out.found = true;
                out.taken = i + 1u;
                return out;
            }
            has_previous = true;
            d_prev = d;
            ratio_prev = ratio;
        }
        if stop && d >= d_stop {
            out.taken = i + 1u;
            return out;
        }
    }
    return out;
}

// (d, steps taken).
fn dm_secant(layer: u32, x: vec3<f32>, r: vec3<f32>, bracket: DmBracket, steps: u32) -> vec2<f32> {
    var da = bracket.d_near;
    var ra = bracket.ratio_near;
    var db = bracket.d_far;
    var rb = bracket.ratio_far;
    var d = select(db, da, ra >= 1.0);
    for (var i = 0u; i < steps; i++) {
        let denom = rb - ra;
        if denom == 0.0 {
            return vec2<f32>(d, f32(i));
        }
        let d_new = da + (db - da) * (1.0 - ra) / denom;
        let p = x + r * d_new;
        let stored = dm_distance(layer, p);
        if stored <= 0.0 {
            return vec2<f32>(d, f32(i + 1u));
        }
        d = d_new;
        let ratio = length(p) / stored;
        if abs(ratio - 1.0) < DM_SECANT_TOLERANCE {
            return vec2<f32>(d, f32(i + 1u));
        }
        if (ratio < 1.0) == (ra < 1.0) {
            da = d_new;
            ra = ratio;
        } else {
            db = d_new;
            rb = ratio;
        }
    }
    return vec2<f32>(d, f32(steps));
}

struct DmHit {
    d: f32,
    layer: u32,
    found: bool,
    linear_steps: u32,
    secant_steps: u32,
}

// Hit(): `start` is the layer the ray starts on, -1 for none.
fn dm_hit(x: vec3<f32>, r: vec3<f32>, start: i32, search: DmSearch) -> DmHit {
    var out: DmHit;
    out.found = false;
    out.d = 0.0;
    out.layer = 0u;
    out.linear_steps = 0u;
    out.secant_steps = 0u;
    let a = max(length(x), 1e-6);
    let skip_cos_start = cos(DM_START_SKIP_TEXELS * 2.0 / f32(max(dm_face_size(), 1u)));
    let count = min(dm_layer_count(), DM_MAX_LAYERS);
    for (var layer = 0u; layer < count; layer++) {
        var t_lo = DM_T_START;
        var t_hi = DM_T_END;
        if search.min_max {
            let range = dm_range(layer);
            if range.z == 0.0 {
                continue;
            }
            let shell = dm_shell_segment(x, r, range.x * (1.0 - DM_MIN_MAX_MARGIN), range.y * (1.0 + DM_MIN_MAX_MARGIN));
            if shell.z == 0.0 {
                continue;
            }
            t_lo = max(dm_texture_parameter(shell.x, a), DM_T_START);
            t_hi = min(dm_texture_parameter(shell.y, a), DM_T_END);
            if t_hi <= t_lo {
                continue;
            }
        }
        // A layer whose first sample lies behind the best hit so far cannot beat it.
        let d_first = dm_ray_parameter(t_lo, a);
        if out.found && d_first >= out.d {
            continue;
        }
        let s = x + r * d_first;
        let e = x + r * dm_ray_parameter(t_hi, a);
        let steps = dm_linear_steps(s, e, search);
        var skip_cos = 2.0;
        if start == i32(layer) {
            skip_cos = skip_cos_start;
        }
        // A bracket behind the best hit so far cannot win: the search stops there.
        let bracket = dm_linear_search(layer, x, r, a, t_lo, t_hi, steps, skip_cos, out.found, out.d);
        out.linear_steps += bracket.taken;
        if !bracket.found {
            continue;
        }
        let refined = dm_secant(layer, x, r, bracket, search.secant_steps);
        out.secant_steps += u32(refined.y);
        if !out.found || refined.x < out.d {
            out.found = true;
            out.d = refined.x;
            out.layer = layer;
        }
    }
    return out;
}

struct DmScatter {
    dir: vec3<f32>,
    weight: vec3<f32>,
    tir: bool,
}

fn dm_scatter(v: vec3<f32>, n_in: vec3<f32>, rgb: vec3<f32>, ior: f32, fresnel: u32) -> DmScatter {
    var out: DmScatter;
    out.tir = false;
    let c = abs(dot(v, n_in));
    if ior < 0.0 {
        out.dir = reflect_dir(v, n_in);
        out.weight = vec3<f32>(schlick(c, rgb.x), schlick(c, rgb.y), schlick(c, rgb.z));
        return out;
    }
    var n = n_in;
    var eta = 1.0 / ior;
    if dot(v, n_in) > 0.0 {
        n = -n_in;
        eta = ior;
    }
    let t = refract_dir(v, n, eta);
    if all(t == vec3<f32>(0.0)) {
        out.dir = reflect_dir(v, n);
        out.weight = vec3<f32>(1.0);
        out.tir = true;
        return out;
    }
    out.weight = vec3<f32>(1.0);
    if fresnel != DM_FRESNEL_IGNORE {
        out.weight = vec3<f32>(1.0 - schlick(c, rgb.x));
    }
    out.dir = normalize(t);
    return out;
}

struct DmPath {
    radiance: vec3<f32>,
    bounces: u32,
    last_layer: i32,
    miss: bool,
    tir: bool,
    truncated: bool,
    linear_steps: u32,
    secant_steps: u32,
}

fn dm_continue_path(x0: vec3<f32>, first: vec3<f32>, first_weight: vec3<f32>, start: i32, search: DmSearch, max_depth: u32, fresnel: u32) -> DmPath {
    var out: DmPath;
    out.radiance = vec3<f32>(0.0);
    out.bounces = 0u;
    out.last_layer = -1;
    out.miss = false;
    out.tir = false;
    out.truncated = false;
    out.linear_steps = 0u;
    out.secant_steps = 0u;
    var x = x0;
    var r = first;
    var layer = start;
    var throughput = first_weight;
    var depth = 1u;
    loop {
        let h = dm_hit(x, r, layer, search);
        out.bounces += 1u;
        out.linear_steps += h.linear_steps;
        out.secant_steps += h.secant_steps;
        if !h.found {
            out.miss = true;
            out.last_layer = -1;
            out.radiance = throughput * dm_background(r);
            return out;
        }
        out.last_layer = i32(h.layer);
        let l = x + r * h.d;
        let surface = dm_surface(h.layer, l);
        if surface.ior == 0.0 {
            out.radiance = throughput * surface.rgb;
            return out;
        }
        if depth >= max_depth {
            out.truncated = true;
            return out;
        }
        depth += 1u;
        let next = dm_scatter(r, surface.normal, surface.rgb, surface.ior, fresnel);
        out.tir = out.tir || next.tir;
        throughput *= next.weight;
        x = l;
        r = next.dir;
        layer = i32(h.layer);
    }
    return out; // not reached: every iteration returns or goes on (naga wants a return)
}

// trace_path: from the surface the eye sees (x in cube-map space, v toward it, outward n).
fn dm_trace_path(x: vec3<f32>, v: vec3<f32>, n: vec3<f32>, rgb: vec3<f32>, ior: f32, start: i32, search: DmSearch, max_depth: u32, fresnel: u32) -> DmPath {
    let first = dm_scatter(v, n, rgb, ior, fresnel);
    var out = dm_continue_path(x, first.dir, first.weight, start, search, max_depth, fresnel);
    out.tir = out.tir || first.tir;
    if fresnel == DM_FRESNEL_SPLIT && ior > 0.0 && !first.tir {
        let f = schlick(abs(dot(v, n)), rgb.x);
        let other = dm_continue_path(x, reflect_dir(v, n), vec3<f32>(f), start, search, max_depth, fresnel);
        out.radiance += other.radiance;
        out.bounces += other.bounces;
        out.miss = out.miss || other.miss;
        out.tir = out.tir || other.tir;
        out.truncated = out.truncated || other.truncated;
        out.linear_steps += other.linear_steps;
        out.secant_steps += other.secant_steps;
    }
    return out;
}
