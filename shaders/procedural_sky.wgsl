// The procedural default environment of refract-trace in WGSL (no bindings): the twin of
// refract_trace::environment::procedural_radiance.

// environment.rs: procedural_radiance.
fn procedural_radiance(dir: vec3<f32>) -> vec3<f32> {
    let horizon = vec3<f32>(0.85, 0.88, 0.92);
    let zenith = vec3<f32>(0.12, 0.3, 0.75);
    if dir.y >= 0.0 {
        var sky = horizon + (zenith - horizon) * sqrt(dir.y);
        let azimuth = rem_euclid(atan2(dir.x, -dir.z) * (180.0 / PI), 360.0);
        let stripe = azimuth / 30.0;
        let nearest = round_half_away(stripe);
        if abs(stripe - nearest) < 0.06 && dir.y < 0.85 {
            let hue = u32(nearest) % 4u;
            if hue == 0u {
                sky = vec3<f32>(0.9, 0.1, 0.1);
            } else if hue == 1u {
                sky = vec3<f32>(0.95, 0.6, 0.1);
            } else if hue == 2u {
                sky = vec3<f32>(0.2, 0.8, 0.2);
            } else {
                sky = vec3<f32>(0.6, 0.2, 0.8);
            }
        }
        let sun = normalize(vec3<f32>(0.4, 0.6, -0.7));
        if dot(dir, sun) > 0.995 {
            sky = vec3<f32>(8.0, 7.0, 5.0);
        }
        return sky;
    }
    let p = dir / -dir.y;
    let check = rem_euclid(floor(p.x * 2.0) + floor(p.z * 2.0), 2.0);
    let tile = select(vec3<f32>(0.05), vec3<f32>(0.9), check < 1.0);
    let fade = min(-dir.y * 4.0, 1.0);
    return horizon + (tile - horizon) * fade;
}

// Rust's f32::rem_euclid.
fn rem_euclid(x: f32, m: f32) -> f32 {
    let r = x % m;
    return select(r, r + abs(m), r < 0.0);
}

// Rust's f32::round (halves away from zero; WGSL's round() rounds halves to even).
fn round_half_away(x: f32) -> f32 {
    return sign(x) * floor(abs(x) + 0.5);
}
