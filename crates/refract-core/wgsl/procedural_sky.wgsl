// The procedural default environment in WGSL (no bindings): the twin of
// refract_core::procedural_sky::procedural_radiance (with the GPU's built-in atan2).

// procedural_sky.rs: procedural_radiance.
fn procedural_radiance(dir: vec3<f32>) -> vec3<f32> {
    let horizon = vec3<f32>(0.85, 0.88, 0.92);
    let zenith = vec3<f32>(0.12, 0.3, 0.75);
    if dir.y >= 0.0 {
        var sky = horizon + (zenith - horizon) * sqrt(dir.y);
        let signed = atan2(dir.x, -dir.z) * (180.0 / PI);
        let azimuth = select(signed, signed + 360.0, signed < 0.0);
        let stripe = azimuth / 30.0;
        let nearest = floor(stripe + 0.5);
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
    let cells = floor(p.x * 2.0) + floor(p.z * 2.0);
    let check = cells - 2.0 * floor(cells * 0.5);
    let tile = select(vec3<f32>(0.05), vec3<f32>(0.9), check < 1.0);
    let fade = min(-dir.y * 4.0, 1.0);
    return horizon + (tile - horizon) * fade;
}
