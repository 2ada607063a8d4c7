// The exact reference in WGSL (issue 32): the twin of refract_trace::Tracer over the whole
// scene's BVH (bvh.wgsl, group 1; every refractor and every object in one tree, each triangle
// tagged with its mesh). Snell at every refractor interface with the interpolated shading normal
// between the refractor's medium and the one around it, Beer-Lambert absorption along every
// segment inside an absorbing medium (issue 49),
// conductors reflect with the exact conductor Fresnel reflectance per channel, diffuse objects
// are shaded under the scene light, rays that leave the scene read the environment (WGSL's atan2,
// no polynomial). Rough glass and conductors scatter about one GGX visible microfacet normal
// per interaction (refract_core's sample_rough_interface), its u from the twin of
// refract_trace::sampling::interface_sample at the same path-tree node. Both modes: `transmission` (the refracted path, TIR reflects:
// Tracer::transmission_path) and `full` (deterministic Fresnel splitting at every interface:
// Tracer::full_radiance, its recursion as an explicit stack). One pixel per invocation; the
// samples of refract_trace::sampling::pixel_sample, a range of them per dispatch (the sum is
// carried in the colour buffer between dispatches); the ground truth of the pixel-centre path
// (refract_trace::PathRecord) written per pixel. A dispersive scene renders spectrally, as the
// Tracer does: each sample carries the hero wavelengths of refract_trace::sampling's
// wavelength_sample, a dispersive interface terminates the secondaries and refracts with the
// hero's index, a path's end is the environment's or a diffuse surface's spectrum at its
// wavelengths (the uplift table and the environment's texel spectra in `spectral_data`)
// projected to linear sRGB.

// The per-triangle attributes the hit needs, in the BVH's leaf order.
struct TraceTriangle {
    // Vertex normals; n0.w is the mesh: i < refractor_count refractor i, refractor_count + k
    // object k.
    n0: vec4<f32>,
    n1: vec4<f32>,
    n2: vec4<f32>,
    // Texture coordinates of the three corners (uv0.xy, uv1.xy), (uv2.xy, _).
    uv01: vec4<f32>,
    uv2: vec4<f32>,
}

// refract_trace::TraceSettings and the scene's light (refract_gpu::reference).
struct TraceUniforms {
    light_direction: vec4<f32>,
    light_radiance: vec4<f32>,
    light_ambient: vec4<f32>,
    // The first refractor's index (the frame uniforms').
    ior: f32,
    max_depth: u32,
    // 0: Mitsuba's shading-normal rule, 1: the geometric rule.
    interface_rule: u32,
    // Meshes below it are refractors.
    refractor_count: u32,
    // 1: write the path records (the AOV layers); 0: the colour only (a 4-byte record buffer).
    write_records: u32,
    // 0: transmission, 1: full (TraceMode).
    mode: u32,
    // Samples per pixel (TraceSettings::spp, 1..=4096).
    spp: u32,
    // This dispatch traces samples [sample_first, sample_end) of spp; the first one starts the
    // sum (and writes the records), the last one divides by spp.
    sample_first: u32,
    sample_end: u32,
    // Full mode drops branches whose throughput falls below this.
    throughput_cutoff: f32,
    // 1: some surface is rough (the pixel-centre path is then not the colour).
    rough: u32,
    // 1: the scene is dispersive: render spectrally.
    spectral: u32,
    // The uplift table's resolution per axis (spectral_data's layout).
    uplift_res: u32,
    // Where the lat-long environment's texel spectra start in spectral_data.
    env_spectra: u32,
    _padding: vec2<u32>,
    // The light's ambient and directional terms as emitter spectra (coefficients, scale).
    light_ambient_spectrum: vec4<f32>,
    light_directional_spectrum: vec4<f32>,
}

// What a mesh's surface is, one per mesh in mesh order: a conductor (eta.w = 1; exact Fresnel
// needs eta and k, not the GPU material's F_p) or, for a refractor, the media on its two sides.
struct TraceSurface {
    eta: vec4<f32>,
    k: vec4<f32>,
    // The refractor medium's absorption coefficient per world unit (xyz).
    absorption: vec4<f32>,
    // Index inside, index of the medium around it, the refractor around it (NO_MEDIUM: air).
    ior: f32,
    outside_ior: f32,
    within: u32,
    // GGX α of the surface (0: smooth).
    alpha: f32,
    // Abbe number of a refractor's glass (inf: not dispersive).
    abbe: f32,
    _padding0: f32,
    _padding1: f32,
    _padding2: f32,
}

// The medium of air (no refractor).
const NO_MEDIUM: u32 = 0xffffffffu;

@group(0) @binding(1) var<uniform> trace: TraceUniforms;
@group(0) @binding(2) var<storage, read> trace_materials: array<Material>;
@group(0) @binding(3) var<storage, read> trace_surfaces: array<TraceSurface>;
@group(0) @binding(5) var<storage, read> trace_triangles: array<TraceTriangle>;
@group(0) @binding(6) var<storage, read_write> out_color: array<vec4<f32>>;
// RECORD_WORDS words per pixel: p1, n1, t1, p2, n2, t2, t_out, p_geom (xyz, as f32 bits), then
// a mask (bit k: vector k exists; bit 8 covered, 9 tir, 10 tir_first_exit), then interfaces,
// then the refractors met (bit i: refractor i).
@group(0) @binding(7) var<storage, read_write> out_record: array<u32>;
const RECORD_WORDS: u32 = 27u;
// refract_scene::spectral for a dispersive scene: the uplift table's brightness axis
// (uplift_res values), its coefficients (3 uplift_res³ cells of 3), then from env_spectra on
// four values per lat-long texel (coefficients, scale).
@group(0) @binding(8) var<storage, read> spectral_data: array<f32>;

// refract_trace's OFFSET: secondary rays start ε (1 + max|pᵢ|) off the surface.
const TRACE_OFFSET: f32 = 4e-6;

// A hit with what the path needs (refract_geometry's MeshBvh::hit_details).
struct SceneHit {
    found: bool,
    // The ray parameter of the hit (the distance: directions are unit).
    t: f32,
    p: vec3<f32>,
    mesh: u32,
    geometric: vec3<f32>,
    shading: vec3<f32>,
    uv: vec2<f32>,
}

fn scene_hit(origin: vec3<f32>, dir: vec3<f32>) -> SceneHit {
    var h: SceneHit;
    let closest = bvh_closest_hit(origin, dir, 0.0, BVH_INF);
    h.found = closest.triangle != BVH_MISS;
    if !h.found {
        return h;
    }
    let tri = bvh_triangles[closest.triangle];
    let attributes = trace_triangles[closest.triangle];
    let e1 = tri.v1.xyz - tri.v0.xyz;
    let e2 = tri.v2.xyz - tri.v0.xyz;
    let face = cross(e1, e2);
    let p = origin + dir * closest.t;
    let inv_area2 = 1.0 / dot(face, face);
    let b1 = dot(cross(p - tri.v0.xyz, e2), face) * inv_area2;
    let b2 = dot(cross(e1, p - tri.v0.xyz), face) * inv_area2;
    let b0 = 1.0 - b1 - b2;
    h.t = closest.t;
    h.p = p;
    h.mesh = u32(attributes.n0.w);
    h.geometric = normalize_or_zero(face);
    let shading = b0 * attributes.n0.xyz + b1 * attributes.n1.xyz + b2 * attributes.n2.xyz;
    let length2 = dot(shading, shading);
    if length2 > 0.0 && length2 < BVH_INF {
        h.shading = shading / sqrt(length2);
    } else {
        h.shading = h.geometric;
    }
    h.uv = b0 * attributes.uv01.xy + b1 * attributes.uv01.zw + b2 * attributes.uv2.xy;
    return h;
}

// Tracer::continue_ray: the next ray's origin, pushed off to the side `dir` goes to.
fn continue_origin(h: SceneHit, dir: vec3<f32>) -> vec3<f32> {
    var side = -1.0;
    if dot(dir, h.geometric) >= 0.0 {
        side = 1.0;
    }
    let a = abs(h.p);
    let offset = TRACE_OFFSET * (1.0 + max(max(a.x, a.y), a.z));
    return h.p + side * offset * h.geometric;
}

// Whether mesh `mesh` is a conductor, and its (eta, k).
fn conductor_of(mesh: u32) -> array<vec4<f32>, 3> {
    let c = trace_surfaces[mesh];
    return array<vec4<f32>, 3>(vec4<f32>(c.eta.w), c.eta, c.k);
}

// Tracer's beer_lambert: exp(−σ s) per channel of the medium `medium`'s absorption (1 in air or
// a clear medium; a clear channel keeps everything even over an infinite segment).
fn absorbed(medium: u32, length: f32) -> vec3<f32> {
    if medium == NO_MEDIUM {
        return vec3<f32>(1.0);
    }
    let sigma = trace_surfaces[medium].absorption;
    if sigma.w == 0.0 {
        return vec3<f32>(1.0);
    }
    return select(exp(-sigma.xyz * length), vec3<f32>(1.0), sigma.xyz == vec3<f32>(0.0));
}

// Tracer::medium_after: the medium after crossing an interface of refractor `refractor`.
fn medium_after(refractor: u32, entering: bool) -> u32 {
    if entering {
        return refractor;
    }
    return trace_surfaces[refractor].within;
}

// Tracer::shade_object: RGB, or for a spectral path SpectralLighting::diffuse at its
// wavelengths in linear sRGB.
fn shade_object(mesh: u32, h: SceneHit, spectral: bool, wl: Wavelengths) -> vec3<f32> {
    let m = trace_materials[mesh - trace.refractor_count];
    var uv = h.uv;
    if m.world_uv != 0u {
        uv = h.p.xz;
    }
    let a = albedo(m, uv);
    let cos_light = abs(dot(h.shading, trace.light_direction.xyz));
    if spectral {
        let c = uplift_fetch(a);
        var values: vec4<f32>;
        for (var i = 0u; i < 4u; i++) {
            let l = wl.lambda[i];
            values[i] = sigmoid_spectrum(c, l) * (emitter_unlit(trace.light_ambient_spectrum, l)
                + emitter_unlit(trace.light_directional_spectrum, l) * cos_light) * cie_d65(l);
        }
        return wavelengths_to_linear_srgb(wl, values);
    }
    return a * (trace.light_ambient.xyz + cos_light * trace.light_radiance.xyz);
}

// UpliftTable::find_interval: the last k with scale[k] <= z, at most res - 2.
fn uplift_find_interval(z: f32) -> u32 {
    let last = trace.uplift_res - 2u;
    var left = 0u;
    var size = last;
    while size > 0u {
        let half = size >> 1u;
        let middle = left + half + 1u;
        if spectral_data[middle] <= z {
            left = middle;
            size -= half + 1u;
        } else {
            size = half;
        }
    }
    return min(left, last);
}

// UpliftTable::fetch: the sigmoid coefficients of reflectance `rgb_in` (clamped to [0, 1]).
fn uplift_fetch(rgb_in: vec3<f32>) -> vec3<f32> {
    let rgb = clamp(rgb_in, vec3<f32>(0.0), vec3<f32>(1.0));
    if rgb.x == rgb.y && rgb.y == rgb.z {
        let v = rgb.x;
        var c2 = (v - 0.5) / sqrt(v * (1.0 - v));
        if v <= 0.0 {
            c2 = -8192.0;
        } else if v >= 1.0 {
            c2 = 8192.0;
        }
        return vec3<f32>(0.0, 0.0, c2);
    }
    let res = trace.uplift_res;
    let base = res;
    var i = 0u;
    for (var j = 1u; j < 3u; j++) {
        if rgb[j] >= rgb[i] {
            i = j;
        }
    }
    let z = rgb[i];
    if z <= 0.0 {
        return vec3<f32>(spectral_data[base], spectral_data[base + 1u], spectral_data[base + 2u]);
    }
    let scale = f32(res - 1u) / z;
    let x = rgb[(i + 1u) % 3u] * scale;
    let y = rgb[(i + 2u) % 3u] * scale;
    let xi = min(u32(x), res - 2u);
    let yi = min(u32(y), res - 2u);
    let zi = uplift_find_interval(z);
    let offset = base + (((i * res + zi) * res + yi) * res + xi) * 3u;
    let dx = 3u;
    let dy = 3u * res;
    let dz = 3u * res * res;
    let x1 = x - f32(xi);
    let x0 = 1.0 - x1;
    let y1 = y - f32(yi);
    let y0 = 1.0 - y1;
    let z1 = (z - spectral_data[zi]) / (spectral_data[zi + 1u] - spectral_data[zi]);
    let z0 = 1.0 - z1;
    var out: vec3<f32>;
    for (var c = 0u; c < 3u; c++) {
        let o = offset + c;
        out[c] = ((spectral_data[o] * x0 + spectral_data[o + dx] * x1) * y0
                + (spectral_data[o + dy] * x0 + spectral_data[o + dy + dx] * x1) * y1) * z0
            + ((spectral_data[o + dz] * x0 + spectral_data[o + dz + dx] * x1) * y0
                + (spectral_data[o + dz + dy] * x0 + spectral_data[o + dz + dy + dx] * x1) * y1)
                * z1;
    }
    return out;
}

// EmitterSpectrum::at without D65 (f · S_c(λ)) for (c, f) packed in a vec4.
fn emitter_unlit(e: vec4<f32>, lambda: f32) -> f32 {
    return e.w * sigmoid_spectrum(e.xyz, lambda);
}

// uplift::emission_coefficients: (c, f) of linear-sRGB radiance `rgb`.
fn emitter_of(rgb: vec3<f32>) -> vec4<f32> {
    let f = 2.0 * max(max(max(rgb.x, rgb.y), rgb.z), 0.0);
    return vec4<f32>(uplift_fetch(rgb / max(f, 1e-8)), f);
}

// SpectralLighting::environment at the wavelengths `lambda`: a lat-long map's texel spectra
// and scales interpolated apart (Mitsuba 3's spectral envmap), else the emitter of the colour.
fn environment_spectral(dir: vec3<f32>, lambda: vec4<f32>) -> vec4<f32> {
    var out: vec4<f32>;
    if frame.environment_kind == ENVIRONMENT_LATLONG {
        let taps = latlong_bilinear_taps(frame.environment_width, frame.environment_height, dir);
        let fx = taps.f.x;
        let fy = taps.f.y;
        var t: array<vec4<f32>, 4>;
        for (var k = 0u; k < 4u; k++) {
            let o = trace.env_spectra + 4u * taps.index[k];
            t[k] = vec4<f32>(spectral_data[o], spectral_data[o + 1u], spectral_data[o + 2u], spectral_data[o + 3u]);
        }
        let scale_top = t[0].w + (t[1].w - t[0].w) * fx;
        let scale_bottom = t[2].w + (t[3].w - t[2].w) * fx;
        let scale = scale_top + (scale_bottom - scale_top) * fy;
        for (var i = 0u; i < 4u; i++) {
            let l = lambda[i];
            let s0 = sigmoid_spectrum(t[0].xyz, l);
            let s1 = sigmoid_spectrum(t[1].xyz, l);
            let s2 = sigmoid_spectrum(t[2].xyz, l);
            let s3 = sigmoid_spectrum(t[3].xyz, l);
            let top = s0 + (s1 - s0) * fx;
            let bottom = s2 + (s3 - s2) * fx;
            out[i] = (top + (bottom - top) * fy) * scale * frame.environment_intensity * cie_d65(l);
        }
        return out;
    }
    var rgb = frame.environment_constant.xyz;
    if frame.environment_kind != ENVIRONMENT_CONSTANT {
        rgb = procedural_radiance(dir);
    }
    let e = emitter_of(rgb);
    for (var i = 0u; i < 4u; i++) {
        out[i] = emitter_unlit(e, lambda[i]) * cie_d65(lambda[i]);
    }
    return out;
}

// Radiance arriving along `dir` from the environment: RGB, or the linear sRGB of the spectral
// radiance at the path's wavelengths.
fn environment_seen(dir: vec3<f32>, spectral: bool, wl: Wavelengths) -> vec3<f32> {
    if spectral {
        return wavelengths_to_linear_srgb(wl, environment_spectral(dir, wl.lambda));
    }
    return environment_radiance(dir);
}

// refract_trace::sampling::wavelength_sample.
fn wavelength_sample(x: u32, y: u32, index: u32, count: u32) -> f32 {
    let h = sample_hash(path_root(x, y) ^ 0x5BD1E995u);
    let shift = f32(h >> 8u) / 16777216.0;
    let u = (f32(index) + 0.5) / f32(max(count, 1u)) + shift;
    return select(u, u - 1.0, u >= 1.0);
}

// Whether refractor `mesh`'s interface is dispersive (its glass or the glass around it).
fn dispersive_interface(mesh: u32) -> bool {
    let s = trace_surfaces[mesh];
    return s.abbe < 3.0e38 || (s.within != NO_MEDIUM && trace_surfaces[s.within].abbe < 3.0e38);
}

struct PathOut {
    radiance: vec3<f32>,
    p1: vec4<f32>,
    n1: vec4<f32>,
    t1: vec4<f32>,
    p2: vec4<f32>,
    n2: vec4<f32>,
    t2: vec4<f32>,
    t_out: vec4<f32>,
    p_geom: vec4<f32>,
    tir: bool,
    tir_first_exit: bool,
    interfaces: u32,
    refractors_met: u32,
    // Closest-hit queries traced (the frame's ray count).
    rays: u32,
}

// Tracer's Interface::at: the side of the interface the ray is on (by the settings' rule), the
// shading normal facing the ray, n_i / n_t and the radiance factor of a refraction (η² under
// the shading rule, 1 under the geometric one).
struct Interface {
    entering: bool,
    facing: vec3<f32>,
    eta: f32,
    transmitted_radiance: f32,
}

// `hero` is the wavelength (nm) whose indices a dispersive interface has, or negative for the
// indices at the d line (Tracer::interface).
fn interface_at(dir: vec3<f32>, h: SceneHit, hero: f32) -> Interface {
    let surface = trace_surfaces[h.mesh];
    var ior = surface.ior;
    var outside_ior = surface.outside_ior;
    if hero > 0.0 {
        ior = dispersive_ior(surface.ior, surface.abbe, hero);
        outside_ior = 1.0;
        if surface.within != NO_MEDIUM {
            let o = trace_surfaces[surface.within];
            outside_ior = dispersive_ior(o.ior, o.abbe, hero);
        }
    }
    var i: Interface;
    if trace.interface_rule == 0u {
        i.entering = -dot(dir, h.shading) >= 0.0;
        i.facing = select(-h.shading, h.shading, i.entering);
    } else {
        i.entering = dot(dir, h.geometric) < 0.0;
        i.facing = face_forward_shading_normal(select(-h.shading, h.shading, i.entering), dir);
    }
    i.eta = select(ior / outside_ior, outside_ior / ior, i.entering);
    i.transmitted_radiance = 1.0;
    if trace.interface_rule == 0u {
        i.transmitted_radiance = i.eta * i.eta;
    }
    return i;
}

// Tracer::conductor_bounce: the reflected direction and weight per channel at a conductor hit,
// about the shading normal turned toward the ray or, on a rough one when sampled, about a
// visible microfacet normal (weight times its masking G1).
struct Bounce {
    dir: vec3<f32>,
    weight: vec3<f32>,
    rough: bool,
}

fn conductor_bounce(dir: vec3<f32>, h: SceneHit, sampled: bool, depth: u32, index: u32, key: u32) -> Bounce {
    let c = trace_surfaces[h.mesh];
    var oriented = -h.shading;
    if dot(dir, h.geometric) < 0.0 {
        oriented = h.shading;
    }
    let facing = face_forward_shading_normal(oriented, dir);
    var b: Bounce;
    var normal = facing;
    var masking = 1.0;
    b.rough = sampled && c.alpha > 0.0;
    if b.rough {
        let m = sample_rough_interface(dir, facing, 1.0, c.alpha, interface_sample(key, depth, index));
        b.dir = m.reflected;
        normal = m.m;
        masking = m.reflected_masking;
    } else {
        b.dir = normalize(reflect_dir(dir, facing));
    }
    let cos_i = -dot(dir, normal);
    b.weight = vec3<f32>(
        fresnel_conductor(cos_i, c.eta.x, c.k.x),
        fresnel_conductor(cos_i, c.eta.y, c.k.y),
        fresnel_conductor(cos_i, c.eta.z, c.k.z),
    ) * masking;
    return b;
}

// refract_trace::sampling: the path tree's keys and the rough interfaces' samples.
const REFLECTED: u32 = 0u;
const TRANSMITTED: u32 = 1u;
const STRATIFIED_DEPTHS: u32 = 4u;

fn path_root(x: u32, y: u32) -> u32 {
    return sample_hash(sample_hash(x ^ 0xA511E9B3u) + y);
}

fn path_child(key: u32, branch: u32) -> u32 {
    return sample_hash(key ^ ((branch + 1u) * 0x9E3779B9u));
}

fn radical_inverse(base: u32, index: u32) -> f32 {
    var i = index;
    var reversed = 0u;
    var denominator = 1u;
    while i > 0u {
        reversed = reversed * base + i % base;
        denominator *= base;
        i /= base;
    }
    return f32(reversed) / f32(denominator);
}

fn interface_sample(key: u32, depth: u32, index: u32) -> vec2<f32> {
    if depth < STRATIFIED_DEPTHS {
        let bases = array<vec2<u32>, 4>(vec2<u32>(3u, 5u), vec2<u32>(7u, 11u), vec2<u32>(13u, 17u), vec2<u32>(19u, 23u));
        let b = bases[depth];
        let h = sample_hash(key);
        let shift = vec2<f32>(f32(h & 0xFFFFu) / 65536.0, f32(h >> 16u) / 65536.0);
        return fract(vec2<f32>(radical_inverse(b.x, index), radical_inverse(b.y, index)) + shift);
    }
    let h1 = sample_hash(key ^ sample_hash(index));
    let h2 = sample_hash(h1 ^ 0x85EBCA6Bu);
    return vec2<f32>(f32(h1 >> 8u) / 16777216.0, f32(h2 >> 8u) / 16777216.0);
}

// Tracer::refracted_path: Tracer::transmission_path (`sampled` false: every surface as if
// smooth) or Tracer::transmission_sample (rough surfaces sampled at sample `index`, from the
// path-tree node `key_in`).
fn transmission_path(origin_in: vec3<f32>, dir_in: vec3<f32>, sampled: bool, index: u32, key_in: u32, spectral: bool, wl_in: Wavelengths) -> PathOut {
    var out: PathOut;
    var wl = wl_in;
    var key = key_in;
    var origin = origin_in;
    var dir = dir_in;
    var depth = 0u;
    var scale = vec3<f32>(1.0);
    var medium = NO_MEDIUM;
    loop {
        let h = scene_hit(origin, dir);
        out.rays += 1u;
        scale *= absorbed(medium, select(BVH_INF, h.t, h.found));
        if !h.found {
            if out.p1.w != 0.0 {
                out.t_out = vec4<f32>(dir, 1.0);
            }
            out.radiance = scale * environment_seen(dir, spectral, wl);
            return out;
        }
        let conductor = conductor_of(h.mesh);
        if conductor[0].x != 0.0 {
            if depth == trace.max_depth {
                out.radiance = vec3<f32>(0.0);
                return out;
            }
            let bounce = conductor_bounce(dir, h, sampled, depth, index, key);
            depth += 1u;
            let next = bounce.dir;
            scale *= bounce.weight;
            key = path_child(key, REFLECTED);
            if h.mesh < trace.refractor_count {
                out.refractors_met |= 1u << h.mesh;
                if out.p1.w == 0.0 {
                    out.p1 = vec4<f32>(h.p, 1.0);
                    out.n1 = vec4<f32>(h.shading, 1.0);
                    out.t1 = vec4<f32>(next, 1.0);
                }
            }
            if bounce.rough && all(scale == vec3<f32>(0.0)) {
                out.radiance = vec3<f32>(0.0);
                return out;
            }
            origin = continue_origin(h, next);
            dir = next;
            continue;
        }
        if h.mesh >= trace.refractor_count {
            if out.p1.w != 0.0 {
                out.t_out = vec4<f32>(dir, 1.0);
                out.p_geom = vec4<f32>(h.p, 1.0);
            }
            out.radiance = scale * shade_object(h.mesh, h, spectral, wl);
            return out;
        }
        if depth == trace.max_depth {
            out.radiance = vec3<f32>(0.0);
            return out;
        }
        var hero = -1.0;
        if spectral && dispersive_interface(h.mesh) {
            wl = wavelengths_terminated(wl);
            hero = wl.lambda.x;
        }
        let side = interface_at(dir, h, hero);
        let entering = side.entering;
        let facing = side.facing;
        let eta = side.eta;
        let transmitted = side.transmitted_radiance;
        let alpha = trace_surfaces[h.mesh].alpha;
        var next: vec3<f32>;
        var tir: bool;
        if sampled && alpha > 0.0 {
            let m = sample_rough_interface(dir, facing, eta, alpha, interface_sample(key, depth, index));
            tir = all(m.refracted == vec3<f32>(0.0));
            var weight = m.refracted_masking;
            next = m.refracted;
            if tir {
                weight = m.reflected_masking;
                next = m.reflected;
            }
            if weight == 0.0 {
                out.radiance = vec3<f32>(0.0);
                return out;
            }
            scale *= weight;
            key = path_child(key, select(TRANSMITTED, REFLECTED, tir));
        } else {
            let refracted = refract_dir(dir, facing, eta);
            tir = all(refracted == vec3<f32>(0.0));
            if tir {
                next = normalize(reflect_dir(dir, facing));
            } else {
                next = normalize(refracted);
            }
        }
        depth += 1u;
        if !tir {
            scale *= transmitted;
            medium = medium_after(h.mesh, entering);
        }
        if out.p1.w == 0.0 {
            out.p1 = vec4<f32>(h.p, 1.0);
            out.n1 = vec4<f32>(h.shading, 1.0);
            out.t1 = vec4<f32>(next, 1.0);
        } else if out.p2.w == 0.0 && !entering {
            out.p2 = vec4<f32>(h.p, 1.0);
            out.n2 = vec4<f32>(h.shading, 1.0);
            out.t2 = vec4<f32>(next, 1.0);
            out.tir_first_exit = tir;
        }
        out.refractors_met |= 1u << h.mesh;
        out.tir = out.tir || tir;
        out.interfaces += select(1u, 0u, tir);
        origin = continue_origin(h, next);
        dir = next;
    }
    return out;
}

// refract_trace::sampling::hash: lowbias32 (Chris Wellons).
fn sample_hash(x_in: u32) -> u32 {
    var x = x_in;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

// refract_trace::sampling::pixel_sample: the offset in [0, 1)² of sample `index` of `count` in
// pixel (x, y): the centre for one sample, else a Hammersley set ((i + ½)/N, φ₂(i)) under a
// hashed per-pixel Cranley–Patterson rotation.
fn pixel_sample(x: u32, y: u32, index: u32, count: u32) -> vec2<f32> {
    if count <= 1u {
        return vec2<f32>(0.5);
    }
    let h = sample_hash((x * 0x9E3779B9u) ^ sample_hash(y));
    let shift = vec2<f32>(f32(h & 0xFFFFu) / 65536.0, f32(h >> 16u) / 65536.0);
    // φ₂(i) = reverseBits(i) / 2³² (the scale is a power of two: exact).
    let p = vec2<f32>((f32(index) + 0.5) / f32(count), f32(reverseBits(index)) * 2.3283064365386963e-10);
    return fract(p + shift);
}

// A pending branch of the full mode's splitting tree: where it starts, its depth (specular
// interactions so far), the scalar throughput the cutoff tests and the colour weight it carries
// to the pixel (the product of the reflectances, transmittances and η² factors above it).
struct Branch {
    origin: vec3<f32>,
    depth: u32,
    dir: vec3<f32>,
    throughput: f32,
    weight: vec3<f32>,
    // The medium it travels in (NO_MEDIUM: air).
    medium: u32,
    // Its node in the path tree (refract_trace's PathSampler::key).
    key: u32,
    // The weights of the sample's wavelengths on this branch (Wavelengths::weight).
    wl_weight: vec4<f32>,
}

// Pending branches never outnumber the depth limit (their depths strictly increase from the
// bottom of the stack, each at most max_depth), so the parameter's maximum bounds the stack.
const FULL_STACK: u32 = 64u;

// Tracer::full_radiance: radiance along the ray with Fresnel splitting at every refractor
// interface (the reflected branch pushed, the transmitted one followed), conductors reflecting
// with their exact reflectance, branches under the throughput cutoff or past the depth limit
// dropped; rough surfaces split about one visible microfacet normal drawn at the branch's node
// for sample `index`. Returns the radiance and (w) the closest-hit queries traced.
fn full_radiance(origin: vec3<f32>, dir: vec3<f32>, index: u32, key: u32, spectral: bool, wl_in: Wavelengths) -> vec4<f32> {
    var stack: array<Branch, FULL_STACK>;
    var top = 0u;
    var radiance = vec3<f32>(0.0);
    var rays = 0u;
    var b = Branch(origin, 0u, dir, 1.0, vec3<f32>(1.0), NO_MEDIUM, key, wl_in.weight);
    let cutoff = trace.throughput_cutoff;
    loop {
        let h = scene_hit(b.origin, b.dir);
        rays += 1u;
        b.weight *= absorbed(b.medium, select(BVH_INF, h.t, h.found));
        // Whether the branch ended here (its contribution, if any, added).
        var ended = true;
        let wl = Wavelengths(wl_in.lambda, b.wl_weight);
        if !h.found {
            radiance += b.weight * environment_seen(b.dir, spectral, wl);
        } else {
            let conductor = conductor_of(h.mesh);
            if conductor[0].x != 0.0 {
                if b.depth < trace.max_depth {
                    let bounce = conductor_bounce(b.dir, h, true, b.depth, index, b.key);
                    let next = bounce.dir;
                    let reflectance = bounce.weight;
                    let throughput = b.throughput * max(max(reflectance.x, reflectance.y), reflectance.z);
                    if throughput > cutoff {
                        b = Branch(continue_origin(h, next), b.depth + 1u, next, throughput, b.weight * reflectance, b.medium, path_child(b.key, REFLECTED), b.wl_weight);
                        ended = false;
                    }
                }
            } else if h.mesh >= trace.refractor_count {
                radiance += b.weight * shade_object(h.mesh, h, spectral, wl);
            } else if b.depth < trace.max_depth {
                var hero = -1.0;
                if spectral && dispersive_interface(h.mesh) {
                    b.wl_weight = wavelengths_terminated(wl).weight;
                    hero = wl.lambda.x;
                }
                let i = interface_at(b.dir, h, hero);
                let alpha = trace_surfaces[h.mesh].alpha;
                // The two lobes: direction and weight of each.
                var reflected_dir: vec3<f32>;
                var refracted: vec3<f32>;
                var reflectance: f32;
                var transmittance: f32;
                if alpha > 0.0 {
                    let m = sample_rough_interface(b.dir, i.facing, i.eta, alpha, interface_sample(b.key, b.depth, index));
                    reflected_dir = m.reflected;
                    refracted = m.refracted;
                    reflectance = m.fresnel * m.reflected_masking;
                    transmittance = (1.0 - m.fresnel) * m.refracted_masking;
                } else {
                    refracted = refract_dir(b.dir, i.facing, i.eta);
                    reflectance = fresnel_dielectric(-dot(b.dir, i.facing), i.eta);
                    if all(refracted == vec3<f32>(0.0)) {
                        reflectance = 1.0;
                    }
                    transmittance = 1.0 - reflectance;
                    reflected_dir = normalize(reflect_dir(b.dir, i.facing));
                }
                let reflected = reflectance * b.throughput > cutoff;
                let transmitted = transmittance * b.throughput > cutoff;
                let depth = b.depth + 1u;
                if reflected {
                    let next = reflected_dir;
                    let branch = Branch(continue_origin(h, next), depth, next, b.throughput * reflectance, b.weight * reflectance, b.medium, path_child(b.key, REFLECTED), b.wl_weight);
                    // (The stack cannot be full: see FULL_STACK.)
                    if transmitted && top < FULL_STACK {
                        stack[top] = branch;
                        top += 1u;
                    } else {
                        b = branch;
                        ended = false;
                    }
                }
                if transmitted {
                    let next = normalize(refracted);
                    b = Branch(
                        continue_origin(h, next),
                        depth,
                        next,
                        b.throughput * transmittance,
                        b.weight * (transmittance * i.transmitted_radiance),
                        medium_after(h.mesh, i.entering),
                        path_child(b.key, TRANSMITTED),
                        b.wl_weight,
                    );
                    ended = false;
                }
            }
        }
        if ended {
            if top == 0u {
                break;
            }
            top -= 1u;
            b = stack[top];
        }
    }
    return vec4<f32>(radiance, f32(rays));
}

@compute @workgroup_size(8, 8)
fn trace_reference(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.width || id.y >= frame.height {
        return;
    }
    let i = id.y * frame.width + id.x;
    // Tracer::pixel: the sum of the samples so far (xyz) and the rays traced (w: exact in f32
    // up to 2^24 a pixel).
    var sum = vec4<f32>(0.0);
    if trace.sample_first > 0u {
        sum = out_color[i];
    } else {
        let centre_is_colour = trace.mode == 0u && trace.spp == 1u && trace.rough == 0u && trace.spectral == 0u;
        if centre_is_colour || trace.write_records != 0u {
            let path = transmission_path(frame.eye.xyz, pixel_ray_dir(vec2<f32>(f32(id.x) + 0.5, f32(id.y) + 0.5)), false, 0u, 0u, false, Wavelengths(vec4<f32>(0.0), vec4<f32>(0.0)));
            write_record(i, path);
            if centre_is_colour {
                out_color[i] = vec4<f32>(path.radiance, f32(path.rays));
                return;
            }
            sum.w = f32(path.rays);
        }
    }
    for (var s = trace.sample_first; s < trace.sample_end; s++) {
        let offset = pixel_sample(id.x, id.y, s, trace.spp);
        let dir = pixel_ray_dir(vec2<f32>(f32(id.x), f32(id.y)) + offset);
        let key = path_root(id.x, id.y);
        let spectral = trace.spectral != 0u;
        var wl = Wavelengths(vec4<f32>(0.0), vec4<f32>(0.0));
        if spectral {
            wl = wavelengths_sample(wavelength_sample(id.x, id.y, s, trace.spp));
        }
        if trace.mode == 0u {
            let path = transmission_path(frame.eye.xyz, dir, true, s, key, spectral, wl);
            sum += vec4<f32>(path.radiance, f32(path.rays));
        } else {
            sum += full_radiance(frame.eye.xyz, dir, s, key, spectral, wl);
        }
    }
    if trace.sample_end == trace.spp {
        sum = vec4<f32>(sum.xyz / f32(trace.spp), sum.w);
    }
    out_color[i] = sum;
}

// The pixel's path record (RECORD_WORDS words), when the records are asked for.
fn write_record(i: u32, path: PathOut) {
    if trace.write_records == 0u {
        return;
    }
    let vectors = array<vec4<f32>, 8>(
        path.p1, path.n1, path.t1, path.p2, path.n2, path.t2, path.t_out, path.p_geom,
    );
    let r = RECORD_WORDS * i;
    var mask = 0u;
    for (var k = 0u; k < 8u; k++) {
        let v = vectors[k];
        out_record[r + 3u * k] = bitcast<u32>(v.x);
        out_record[r + 3u * k + 1u] = bitcast<u32>(v.y);
        out_record[r + 3u * k + 2u] = bitcast<u32>(v.z);
        mask |= select(0u, 1u << k, v.w != 0.0);
    }
    mask |= select(0u, 1u << 8u, path.p1.w != 0.0);
    mask |= select(0u, 1u << 9u, path.tir);
    mask |= select(0u, 1u << 10u, path.tir_first_exit);
    out_record[r + 24u] = mask;
    out_record[r + 25u] = path.interfaces;
    out_record[r + 26u] = path.refractors_met;
}
