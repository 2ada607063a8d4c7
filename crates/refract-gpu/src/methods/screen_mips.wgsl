// The engines' mip-mapped screen texture (refract_core::screen_mips): its levels' sizes and the
// engines' rough transmission lookups in it (three.js's B-spline, Godot's and HDRP's trilinear
// reads, Bevy's taps: refract_core::engine::bevy_blurred), written against `frame` (its size is
// level 0's), a `mip_texel(level, texel)` and a `screen_depth(texel)` the including module
// provides: the screen pyramid's buffer and the opaque objects' depths in engine.wgsl, analytic
// ones in engine_conformance.wgsl.

// refract_core::screen_mips::level_count for the frame's size.
fn mip_level_count() -> u32 {
    return 32u - countLeadingZeros(max(max(frame.width, frame.height), 1u));
}

// refract_core::screen_mips::level_size.
fn mip_level_size(level: u32) -> vec2<u32> {
    return max(vec2<u32>(frame.width >> level, frame.height >> level), vec2<u32>(1u));
}

// refract_core::screen_mips::bspline_weights.
fn bspline_weights(a: f32) -> vec4<f32> {
    let a2 = a * a;
    let a3 = a2 * a;
    let b = 1.0 - a;
    return vec4<f32>(
        b * b * b / 6.0,
        (3.0 * a3 - 6.0 * a2 + 4.0) / 6.0,
        (-3.0 * a3 + 3.0 * a2 + 3.0 * a + 1.0) / 6.0,
        a3 / 6.0,
    );
}

// refract_core::screen_mips::sample_bspline: the 4 × 4 B-spline sample of `level` at `uv`.
fn sample_bspline(uv: vec2<f32>, level: u32) -> vec3<f32> {
    let size = mip_level_size(level);
    let t = uv * vec2<f32>(size) - vec2<f32>(0.5);
    let base = floor(t);
    let f = t - base;
    let wx = bspline_weights(f.x);
    let wy = bspline_weights(f.y);
    let top = vec2<i32>(size) - vec2<i32>(1);
    var sum = vec3<f32>(0.0);
    for (var j = 0; j < 4; j++) {
        let y = u32(clamp(i32(base.y) - 1 + j, 0, top.y));
        var row = vec3<f32>(0.0);
        for (var i = 0; i < 4; i++) {
            let x = u32(clamp(i32(base.x) - 1 + i, 0, top.x));
            row += wx[i] * mip_texel(level, vec2<u32>(x, y));
        }
        sum += wy[j] * row;
    }
    return sum;
}

// refract_core::screen_mips::hdrp_hit_share.
fn hdrp_hit_share(mip: f32) -> f32 {
    return max(1.0 - 0.08 * mip, 0.0);
}

// refract_core::screen_mips::sample_bilinear.
fn sample_bilinear(uv: vec2<f32>, level: u32) -> vec3<f32> {
    let size = mip_level_size(level);
    let t = uv * vec2<f32>(size) - vec2<f32>(0.5);
    let base = floor(t);
    let f = t - base;
    let top = vec2<i32>(size) - vec2<i32>(1);
    let x0 = u32(clamp(i32(base.x), 0, top.x));
    let x1 = u32(clamp(i32(base.x) + 1, 0, top.x));
    let y0 = u32(clamp(i32(base.y), 0, top.y));
    let y1 = u32(clamp(i32(base.y) + 1, 0, top.y));
    let a = mip_texel(level, vec2<u32>(x0, y0));
    let b = mip_texel(level, vec2<u32>(x1, y0));
    let c = mip_texel(level, vec2<u32>(x0, y1));
    let d = mip_texel(level, vec2<u32>(x1, y1));
    let upper = a + (b - a) * f.x;
    let lower = c + (d - c) * f.x;
    return upper + (lower - upper) * f.y;
}

// The levels ⌊lod⌋ and ⌈lod⌉ (clamped to the pyramid) and fract(lod)
// (refract_core::screen_mips::between_levels).
struct Levels {
    low: u32,
    high: u32,
    fraction: f32,
}

fn levels_of(lod_in: f32) -> Levels {
    let top = mip_level_count() - 1u;
    let lod = max(lod_in, 0.0);
    let low_f = floor(lod);
    let fraction = lod - low_f;
    let low = min(u32(low_f), top);
    let high = min(low + select(0u, 1u, fraction > 0.0), top);
    return Levels(low, high, fraction);
}

// refract_core::screen_mips::sample_trilinear.
fn sample_trilinear(uv: vec2<f32>, lod: f32) -> vec3<f32> {
    let l = levels_of(lod);
    let fine = sample_bilinear(uv, l.low);
    if l.high == l.low {
        return fine;
    }
    return fine + (sample_bilinear(uv, l.high) - fine) * l.fraction;
}

// refract_core::screen_mips::sample_threejs: three.js's textureBicubic at `lod`.
fn sample_threejs(uv: vec2<f32>, lod: f32) -> vec3<f32> {
    let l = levels_of(lod);
    let fine = sample_bspline(uv, l.low);
    if l.high == l.low {
        return fine;
    }
    return fine + (sample_bspline(uv, l.high) - fine) * l.fraction;
}

// refract_core::engine::spiral_offset: Jimenez's spiral offset k.
fn spiral_offset(k: u32) -> vec2<f32> {
    let angle = 0.75 * PI * f32(k + 1u);
    return vec2<f32>(cos(angle), sin(angle)) * (1.0 - f32(k) / 8.0);
}

// refract_core::engine::interleaved_gradient_noise (frame 0).
fn interleaved_gradient_noise(frag_px: vec2<f32>) -> f32 {
    return fract(52.982918 * fract(0.06711056 * frag_px.x + 0.00583715 * frag_px.y));
}

// refract_core::engine::BEVY_TAPS.
const BEVY_TAPS: u32 = 8u;

// refract_core::engine::bevy_blurred: Bevy's taps around `read_uv`; xyz = the accepted taps'
// colours summed over the taps, w = the accepted share.
fn bevy_blurred(frag_px: vec2<f32>, read_uv: vec2<f32>, roughness: f32, fragment_depth: f32) -> vec4<f32> {
    var order = array<u32, 8>(0u, 2u, 4u, 6u, 1u, 3u, 5u, 7u);
    let size = vec2<f32>(f32(frame.width), f32(frame.height));
    let aspect = size.x / size.y;
    let blur = -(roughness * roughness) / fragment_depth;
    let spirals = (BEVY_TAPS + 7u) / 8u;
    let noise = interleaved_gradient_noise(frag_px);
    let checker = f32((i32(frag_px.x) + i32(frag_px.y)) % 2);
    var sum = vec3<f32>(0.0);
    var accepted = 0u;
    for (var i = 0u; i < BEVY_TAPS; i++) {
        let spiral = i >> 3u;
        let angle = (noise + f32(spiral) / f32(spirals)) * TAU;
        let s = sin(angle);
        let c = cos(angle);
        let offset = spiral_offset(order[i & 7u]) * (1.0 - 0.5 * f32(spiral + 1u) / f32(spirals));
        let rotated = vec2<f32>(c * offset.x + s * offset.y, -s * offset.x + c * offset.y);
        let uv = read_uv + rotated * vec2<f32>(1.0, aspect) * blur * (1.0 - checker * 0.1);
        let texel = vec2<i32>(clamp(floor(uv * size), vec2<f32>(0.0), size - vec2<f32>(1.0)));
        if screen_depth(texel) < fragment_depth {
            continue;
        }
        sum += sample_bilinear(uv, 0u);
        accepted += 1u;
    }
    return vec4<f32>(sum / f32(BEVY_TAPS), f32(accepted) / f32(BEVY_TAPS));
}

