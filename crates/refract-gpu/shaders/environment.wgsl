// Environment lookup with the bindings of the shading pass: the lat-long map's texels in a
// storage buffer (twin of refract_core::environment::sample_latlong_bilinear) and
// refract_trace::Environment::radiance.

@group(0) @binding(4) var<storage, read> env_texels: array<vec4<f32>>;

// environment.rs: latlong_bilinear_taps: the four texels of the bilinear lookup of unit `dir`
// ((x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1) in row-major order from the top) and
// the fractions (fx, fy). Mitsuba 3's convention: columns x = u W - 1/2 (wrapping), rows on
// the poles y = v (H - 1).
struct LatLongTaps {
    index: vec4<u32>,
    f: vec2<f32>,
}

fn latlong_bilinear_taps(width: u32, height: u32, dir: vec3<f32>) -> LatLongTaps {
    let uv = direction_to_latlong(dir);
    let x = uv.x * f32(width) - 0.5;
    let y = clamp(uv.y * f32(height - 1u), 0.0, f32(height - 1u));
    let x0 = floor(x);
    let y0 = floor(y);
    let w = i32(width);
    let xa = u32(((i32(x0) % w) + w) % w);
    let xb = u32(((i32(x0) + 1) % w + w) % w);
    let ya = u32(y0);
    let yb = min(ya + 1u, height - 1u);
    return LatLongTaps(
        vec4<u32>(ya * width + xa, ya * width + xb, yb * width + xa, yb * width + xb),
        vec2<f32>(x - x0, y - y0),
    );
}

// environment.rs: sample_latlong_bilinear, texels row-major from the top in env_texels.
fn sample_latlong_bilinear(width: u32, height: u32, dir: vec3<f32>) -> vec3<f32> {
    let t = latlong_bilinear_taps(width, height, dir);
    let a = env_texels[t.index.x].xyz;
    let b = env_texels[t.index.y].xyz;
    let c = env_texels[t.index.z].xyz;
    let d = env_texels[t.index.w].xyz;
    let top = a + (b - a) * t.f.x;
    let bottom = c + (d - c) * t.f.x;
    return top + (bottom - top) * t.f.y;
}

// Environment::radiance.
fn environment_radiance(dir: vec3<f32>) -> vec3<f32> {
    if frame.environment_kind == ENVIRONMENT_LATLONG {
        return frame.environment_intensity
            * sample_latlong_bilinear(frame.environment_width, frame.environment_height, dir);
    }
    if frame.environment_kind == ENVIRONMENT_CONSTANT {
        return frame.environment_constant.xyz;
    }
    return procedural_radiance(dir);
}
