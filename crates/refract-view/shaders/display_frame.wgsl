// The viewer's display of a GPU frame that never left the GPU: one full-screen triangle; each
// pixel reads its vec4 of the method's colour buffer and tonemaps it as
// refract_scene::tonemap::to_srgb8 does for every PNG (Narkowicz's ACES fit, the sRGB transfer
// function, rounded to 8 bits), so the window shows the bytes a readback would have shown. An
// sRGB surface encodes what it is given: the value is decoded first, as the readback path's
// Rgba8UnormSrgb texture decodes it.

struct Display {
    width: u32,
    height: u32,
    srgb_surface: u32,
    _padding: u32,
}

@group(0) @binding(0) var<storage, read> color: array<vec4<f32>>;
@group(0) @binding(1) var<uniform> display: Display;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(xy * 2.0 - 1.0, 0.0, 1.0);
}

// tonemap.rs: aces_filmic.
fn aces_filmic(x: f32) -> f32 {
    let v = max(x, 0.0);
    return clamp(v * (2.51 * v + 0.03) / (v * (2.43 * v + 0.59) + 0.14), 0.0, 1.0);
}

// tonemap.rs: srgb_encode.
fn srgb_encode(linear: f32) -> f32 {
    if linear <= 0.0031308 {
        return 12.92 * linear;
    }
    return 1.055 * pow(linear, 1.0 / 2.4) - 0.055;
}

fn srgb_decode(encoded: f32) -> f32 {
    if encoded <= 0.04045 {
        return encoded / 12.92;
    }
    return pow((encoded + 0.055) / 1.055, 2.4);
}

// tonemap.rs: to_srgb8, as a unorm value (NaN, which max() may not catch, becomes black).
fn to_srgb8(v: f32) -> f32 {
    let x = select(0.0, v, v == v);
    return floor(255.0 * srgb_encode(aces_filmic(x)) + 0.5) / 255.0;
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let xy = min(vec2<u32>(p.xy), vec2<u32>(display.width - 1u, display.height - 1u));
    let c = color[xy.y * display.width + xy.x].rgb;
    var rgb = vec3<f32>(to_srgb8(c.r), to_srgb8(c.g), to_srgb8(c.b));
    if display.srgb_surface != 0u {
        rgb = vec3<f32>(srgb_decode(rgb.r), srgb_decode(rgb.g), srgb_decode(rgb.b));
    }
    return vec4<f32>(rgb, 1.0);
}
