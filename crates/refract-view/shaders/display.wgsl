// The viewer's display pass: one full-screen triangle; each pixel shows its texel of the
// frame (already tonemapped to sRGB by the CPU), clamped to the texture.
@group(0) @binding(0) var image: texture_2d<f32>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(xy * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let size = textureDimensions(image);
    let texel = min(vec2<u32>(p.xy), size - 1u);
    return vec4<f32>(textureLoad(image, texel, 0).rgb, 1.0);
}
