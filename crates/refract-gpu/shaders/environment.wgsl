// Environment lookup with the bindings of the shading pass: the lat-long map's texels in a
// storage buffer (twin of refract_core::environment::sample_latlong_bilinear) and
// refract_trace::Environment::radiance.

@group(0) @binding(4) var<storage, read> env_texels: array<vec4<f32>>;

// environment.rs: sample_latlong_bilinear, texels row-major from the top in env_texels.
// Mitsuba 3's convention: columns x = u W - 1/2 (wrapping), rows on the poles y = v (H - 1).
fn sample_latlong_bilinear(width: u32, height: u32, dir: vec3<f32>) -> vec3<f32> {
    let uv = direction_to_latlong(dir);
    let x = uv.x * f32(width) - 0.5;
    let y = clamp(uv.y * f32(height - 1u), 0.0, f32(height - 1u));
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let w = i32(width);
    let xa = u32(((i32(x0) % w) + w) % w);
    let xb = u32(((i32(x0) + 1) % w + w) % w);
    let ya = u32(y0);
    let yb = min(ya + 1u, height - 1u);
    let a = env_texels[ya * width + xa].xyz;
    let b = env_texels[ya * width + xb].xyz;
    let c = env_texels[yb * width + xa].xyz;
    let d = env_texels[yb * width + xb].xyz;
    let top = a + (b - a) * fx;
    let bottom = c + (d - c) * fx;
    return top + (bottom - top) * fy;
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
