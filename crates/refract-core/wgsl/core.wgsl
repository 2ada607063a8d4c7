// refract-core's twin in WGSL. Every function mirrors the Rust function of the same name in
// crates/refract-core (same formulas, same branches); crates/refract-gpu/tests/conformance.rs
// holds them to it.
// Constants (FACE_FORWARD_EPSILON, NORMAL_INCIDENCE_ANGLE, UNIT_TOLERANCE, policy and mode
// codes) come from the header that crates/refract-gpu generates from Rust.

const PI: f32 = 3.14159265358979;
const TAU: f32 = 6.28318530717959;
const HALF_PI: f32 = 1.5707963267949;
const F32_MAX: f32 = 3.40282347e38;

// vector.rs: robust_normalize. xyz = the unit vector, w = 1 when valid, 0 when v is zero or
// not finite.
fn robust_normalize(v: vec3<f32>) -> vec4<f32> {
    let length_squared = dot(v, v);
    if abs(length_squared - 1.0) <= UNIT_TOLERANCE {
        return vec4<f32>(v, 1.0);
    }
    if length_squared >= 1e-30 && length_squared <= F32_MAX {
        return vec4<f32>(v * (1.0 / sqrt(length_squared)), 1.0);
    }
    let scale = max(max(abs(v.x), abs(v.y)), abs(v.z));
    if !(scale > 0.0 && scale <= F32_MAX) {
        return vec4<f32>(0.0);
    }
    let u = v / scale;
    let len = length(u);
    if !(len > 0.0) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(u / len, 1.0);
}

// glam's try_normalize: xyz = v / |v|, w = 1 when |v| > 0 and finite.
fn try_normalize(v: vec3<f32>) -> vec4<f32> {
    let len = length(v);
    if !(len > 0.0 && len <= F32_MAX) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(v / len, 1.0);
}

// vector.rs: angle_between = atan2(|a x b|, a . b).
fn angle_between(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return atan2(length(cross(a, b)), dot(a, b));
}

// optics.rs: refract, k = (1 - eta^2) + eta^2 (N.I)^2; zero vector on TIR.
fn refract_dir(incident: vec3<f32>, normal: vec3<f32>, eta: f32) -> vec3<f32> {
    let n_dot_i = dot(normal, incident);
    let eta2 = eta * eta;
    let k = (1.0 - eta2) + eta2 * n_dot_i * n_dot_i;
    if k < 0.0 {
        return vec3<f32>(0.0);
    }
    return eta * incident - (eta * n_dot_i + sqrt(k)) * normal;
}

// optics.rs: reflect.
fn reflect_dir(incident: vec3<f32>, normal: vec3<f32>) -> vec3<f32> {
    return incident - 2.0 * dot(normal, incident) * normal;
}

// optics.rs: critical_angle = atan2(1, sqrt((eta - 1)(eta + 1))).
fn critical_angle(eta: f32) -> f32 {
    if eta <= 1.0 {
        return HALF_PI;
    }
    return atan2(1.0, sqrt((eta - 1.0) * (eta + 1.0)));
}

// optics.rs: face_forward_shading_normal.
fn face_forward_shading_normal(normal: vec3<f32>, incident: vec3<f32>) -> vec3<f32> {
    let n_dot_i = dot(normal, incident);
    if n_dot_i < 0.0 {
        return normal;
    }
    let turned = try_normalize(normal - (n_dot_i + FACE_FORWARD_EPSILON) * incident);
    if turned.w > 0.5 {
        return turned.xyz;
    }
    return -incident;
}

// fresnel.rs: fresnel_dielectric.
fn fresnel_dielectric(cos_i_in: f32, eta: f32) -> f32 {
    let cos_i = clamp(cos_i_in, 0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = sqrt(1.0 - sin2_t);
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return clamp(0.5 * (r_s * r_s + r_p * r_p), 0.0, 1.0);
}

// fresnel.rs: f0_dielectric.
fn f0_dielectric(eta: f32) -> f32 {
    let r = (1.0 - eta) / (1.0 + eta);
    return r * r;
}

// fresnel.rs: f0_conductor.
fn f0_conductor(n: f32, k: f32) -> f32 {
    return ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
}

// fresnel.rs: schlick.
fn schlick(cos_theta: f32, f0: f32) -> f32 {
    let m = 1.0 - clamp(cos_theta, 0.0, 1.0);
    let m2 = m * m;
    return f0 + (1.0 - f0) * m2 * m2 * m;
}

// fresnel.rs: schlick_dielectric.
fn schlick_dielectric(cos_i_in: f32, eta: f32) -> f32 {
    let cos_i = clamp(cos_i_in, 0.0, 1.0);
    let f0 = f0_dielectric(eta);
    if eta <= 1.0 {
        return schlick(cos_i, f0);
    }
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    return schlick(sqrt(1.0 - sin2_t), f0);
}

// fresnel.rs: fresnel_conductor (exact, per channel; the reference's conductors).
fn fresnel_conductor(cos_i: f32, n: f32, k: f32) -> f32 {
    let c = clamp(cos_i, 0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let n2 = n * n;
    let k2 = k * k;
    let t0 = n2 - k2 - s2;
    let a2b2 = sqrt(max(t0 * t0 + 4.0 * n2 * k2, 0.0));
    let a = sqrt(max(0.5 * (a2b2 + t0), 0.0));
    let t1 = a2b2 + c2;
    let t2 = 2.0 * c * a;
    var r_s = 1.0;
    if t1 + t2 > 0.0 {
        r_s = (t1 - t2) / (t1 + t2);
    }
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    var r_p = r_s;
    if t3 + t4 > 0.0 {
        r_p = r_s * (t3 - t4) / (t3 + t4);
    }
    return clamp(0.5 * (r_s + r_p), 0.0, 1.0);
}

// fresnel.rs: schlick_conductor.
fn schlick_conductor(cos_i: f32, n: f32, k: f32) -> f32 {
    return schlick(cos_i, f0_conductor(n, k));
}

// interpolated_distance.rs: angle_ratio.
fn angle_ratio(theta_i: f32, theta_t: f32, eta: f32) -> f32 {
    var ratio = eta;
    if theta_i > NORMAL_INCIDENCE_ANGLE {
        ratio = theta_t / theta_i;
    }
    return clamp(ratio, 0.0, 1.0);
}

// interpolated_distance.rs: interpolated_distance.
fn interpolated_distance(theta_i: f32, theta_t: f32, eta: f32, d_v: f32, d_n: f32) -> f32 {
    let w = angle_ratio(theta_i, theta_t, eta);
    return w * d_v + (1.0 - w) * d_n;
}

// interpolated_distance.rs: approximate_distance.
// A code that is none of the three is NaN, never another mode's distance.
fn approximate_distance(mode: u32, theta_i: f32, theta_t: f32, eta: f32, d_v: f32, d_n: f32) -> f32 {
    if mode == DISTANCE_INTERPOLATED {
        return interpolated_distance(theta_i, theta_t, eta, d_v, d_n);
    }
    if mode == DISTANCE_VIEW_ONLY {
        return d_v;
    }
    if mode == DISTANCE_NORMAL_ONLY {
        return d_n;
    }
    return bitcast<f32>(0x7fc00000u);
}

// exit.rs: exit_normal_outside_silhouette.
fn exit_normal_outside_silhouette(t1: vec3<f32>, look_dir: vec3<f32>) -> vec3<f32> {
    let n = try_normalize(t1 - dot(look_dir, t1) * look_dir);
    if n.w > 0.5 {
        return n.xyz;
    }
    return t1;
}

// exit.rs: refract_exit. xyz = T2, w = 1 when the exit was a TIR.
fn refract_exit(t1: vec3<f32>, n2: vec3<f32>, ior: f32, policy: u32) -> vec4<f32> {
    let inward = face_forward_shading_normal(-n2, t1);
    let t2 = refract_dir(t1, inward, ior);
    if any(t2 != vec3<f32>(0.0)) {
        let unit = robust_normalize(t2);
        return vec4<f32>(select(t1, unit.xyz, unit.w > 0.5), 0.0);
    }
    if policy == TIR_CLAMP_TO_CRITICAL {
        let tangent = try_normalize(t1 - dot(t1, inward) * inward);
        return vec4<f32>(select(t1, tangent.xyz, tangent.w > 0.5), 1.0);
    }
    if policy == TIR_REFLECT_ONCE {
        return vec4<f32>(reflect_dir(t1, inward), 1.0);
    }
    return vec4<f32>(0.0, 0.0, 0.0, 1.0);
}

// environment.rs: direction_to_latlong.
fn direction_to_latlong(dir: vec3<f32>) -> vec2<f32> {
    var u = atan2(dir.x, -dir.z) / TAU;
    if u < 0.0 {
        u = u + 1.0;
    }
    if u >= 1.0 {
        u = 0.0;
    }
    let theta = atan2(sqrt(dir.x * dir.x + dir.z * dir.z), dir.y);
    return vec2<f32>(u, theta / PI);
}

// nearby_geometry.rs: Plane::intersect. plane = (n, d); x = t, y = 1 when hit (t > 0, finite).
fn plane_intersect(plane: vec4<f32>, origin: vec3<f32>, dir: vec3<f32>) -> vec2<f32> {
    let denom = dot(plane.xyz, dir);
    let t = (plane.w - dot(plane.xyz, origin)) / denom;
    let hit = denom != 0.0 && t > 0.0 && abs(t) <= F32_MAX;
    return vec2<f32>(select(0.0, t, hit), select(0.0, 1.0, hit));
}

// nearby_geometry.rs: screen_fraction_to_segment.
fn screen_fraction_to_segment(s: f32, w0: f32, w1: f32) -> f32 {
    let denom = (1.0 - s) * w1 + s * w0;
    return select(s, s * w0 / denom, denom > 0.0);
}

// engine.rs: the exit models of today's engines (Godot, three.js, Bevy, Unity HDRP, Filament).
struct EngineExit {
    p: vec3<f32>,
    dir: vec3<f32>,
}

// glam's normalize_or_zero.
fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let n = try_normalize(v);
    return select(vec3<f32>(0.0), n.xyz, n.w > 0.5);
}

// engine.rs: proxy_sphere_exit (HDRP RefractionModelSphere, Filament refractionSolidSphere).
fn proxy_sphere_exit(p: vec3<f32>, n: vec3<f32>, incident: vec3<f32>, ior: f32, d: f32) -> EngineExit {
    let t = refract_dir(incident, n, 1.0 / ior);
    let cos_t = -dot(n, t);
    let p1 = p + t * (d * cos_t);
    let center = p - n * (0.5 * d);
    let n1 = normalize_or_zero(center - p1);
    let r2 = refract_dir(t, n1, ior);
    return EngineExit(p1, select(r2, t, all(r2 == vec3<f32>(0.0))));
}

// engine.rs: proxy_box_exit (HDRP RefractionModelBox; thin with d = THIN_THICKNESS).
fn proxy_box_exit(p: vec3<f32>, n: vec3<f32>, incident: vec3<f32>, ior: f32, d: f32) -> EngineExit {
    let t = refract_dir(incident, n, 1.0 / ior);
    let cos_t = -dot(n, t);
    return EngineExit(p + t * (d / max(cos_t, HDRP_MIN_COS)), incident);
}

// engine.rs: volume_exit (three.js, Bevy): X = P + T d.
fn volume_exit(p: vec3<f32>, n: vec3<f32>, incident: vec3<f32>, ior: f32, d: f32) -> EngineExit {
    let t = refract_dir(incident, n, 1.0 / ior);
    return EngineExit(p + t * d, t);
}

// engine.rs: bevy_fallback_dir.
fn bevy_fallback_dir(incident: vec3<f32>, t: vec3<f32>, d: f32) -> vec3<f32> {
    return normalize_or_zero(incident + t * d);
}

// engine.rs: screen_offset_px (Godot: -n_view.xy * scale of SCREEN_UV, in y-down pixels).
fn screen_offset_px(n_view: vec3<f32>, scale: f32, size: vec2<f32>) -> vec2<f32> {
    return -vec2<f32>(n_view.x, n_view.y) * scale * size;
}

// engine.rs: smoothstep01.
fn smoothstep01(x_in: f32) -> f32 {
    let x = clamp(x_in, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

// engine.rs: hdrp_edge_fade.
fn hdrp_edge_fade(uv: vec2<f32>) -> f32 {
    let fx = smoothstep01(clamp((1.0 - abs(2.0 * uv.x - 1.0)) / HDRP_EDGE_FADE, 0.0, 1.0));
    let fy = smoothstep01(clamp((1.0 - abs(2.0 * uv.y - 1.0)) / HDRP_EDGE_FADE, 0.0, 1.0));
    return fx * fy;
}

// microfacet.rs: orthonormal_basis (Duff et al. 2017): (t, b) with (t, b, n) right-handed.
fn orthonormal_basis(n: vec3<f32>) -> array<vec3<f32>, 2> {
    var sign = -1.0;
    if n.z >= 0.0 {
        sign = 1.0;
    }
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return array<vec3<f32>, 2>(
        vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        vec3<f32>(b, sign + n.y * n.y * a, -n.y),
    );
}

// microfacet.rs: ggx_d, D(m) = 1 / (π α² ((m_x² + m_y²)/α² + m_z²)²), 0 below the surface.
fn ggx_d(m: vec3<f32>, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let s = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
    let d = 1.0 / (PI * a2 * s * s);
    if d * m.z > 1e-20 {
        return d;
    }
    return 0.0;
}

// microfacet.rs: smith_g1, G1(v, m) = 2 / (1 + √(1 + α² tan²θv)), 0 on the back of m.
fn smith_g1(v: vec3<f32>, m: vec3<f32>, alpha: f32) -> f32 {
    if dot(v, m) * v.z <= 0.0 {
        return 0.0;
    }
    let xy = alpha * alpha * (v.x * v.x + v.y * v.y);
    if xy == 0.0 {
        return 1.0;
    }
    return 2.0 / (1.0 + sqrt(1.0 + xy / (v.z * v.z)));
}

// microfacet.rs: sample_visible_normal (Heitz 2018, listing 1).
fn sample_visible_normal(wi: vec3<f32>, alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let vh = normalize(vec3<f32>(alpha * wi.x, alpha * wi.y, wi.z));
    let lensq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if lensq > 0.0 {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) * (1.0 / sqrt(lensq));
    }
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let phi = TAU * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(1.0 - p1 * p1) + s * (r * sin(phi));
    let nh = t1 * p1 + t2 * p2 + vh * sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0));
    return normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
}

// microfacet.rs: visible_normal_pdf, D_wi(m) = G1(wi, m) max(0, wi·m) D(m) / cos θi.
fn visible_normal_pdf(wi: vec3<f32>, m: vec3<f32>, alpha: f32) -> f32 {
    if wi.z <= 0.0 {
        return 0.0;
    }
    return smith_g1(wi, m, alpha) * max(dot(wi, m), 0.0) * ggx_d(m, alpha) / wi.z;
}

// microfacet.rs: MicrofacetSample.
struct MicrofacetSample {
    m: vec3<f32>,
    fresnel: f32,
    reflected: vec3<f32>,
    reflected_masking: f32,
    refracted: vec3<f32>,
    refracted_masking: f32,
}

// microfacet.rs: sample_rough_interface: one visible microfacet normal of the interface seen
// along `dir` with macro normal `facing` (toward the ray), both lobes about it.
fn sample_rough_interface(dir: vec3<f32>, facing: vec3<f32>, eta: f32, alpha: f32, u: vec2<f32>) -> MicrofacetSample {
    let basis = orthonormal_basis(facing);
    let t = basis[0];
    let b = basis[1];
    let wi = vec3<f32>(dot(-dir, t), dot(-dir, b), dot(-dir, facing));
    var s: MicrofacetSample;
    if wi.z <= 0.0 {
        s.m = facing;
        s.fresnel = 1.0;
        s.reflected = reflect_dir(dir, facing);
        return s;
    }
    let m_local = sample_visible_normal(wi, alpha, u);
    let m = normalize(t * m_local.x + b * m_local.y + facing * m_local.z);
    s.m = m;
    s.reflected = normalize(reflect_dir(dir, m));
    let refracted = refract_dir(dir, m, eta);
    let tir = all(refracted == vec3<f32>(0.0));
    s.fresnel = 1.0;
    if !tir {
        s.refracted = normalize(refracted);
        s.fresnel = fresnel_dielectric(-dot(dir, m), eta);
    }
    let ml = vec3<f32>(dot(m, t), dot(m, b), dot(m, facing));
    let rl = vec3<f32>(dot(s.reflected, t), dot(s.reflected, b), dot(s.reflected, facing));
    if rl.z > 0.0 {
        s.reflected_masking = smith_g1(rl, ml, alpha);
    }
    let tl = vec3<f32>(dot(s.refracted, t), dot(s.refracted, b), dot(s.refracted, facing));
    if !tir && tl.z < 0.0 {
        s.refracted_masking = smith_g1(tl, ml, alpha);
    }
    return s;
}
