// The opaque objects over an image-space frame (methods `single`, `wyman`, `wyman-dv`,
// `wyman-dn`): after the kernel, every pixel whose nearest surface is an opaque object — the
// refractor absent there, or behind the object — shows the object's texel of the eye's surface
// pass (the nearby-geometry readers ng_surface, ng_color, ng_view_depth), as an engine draws
// it; the refraction itself still sees the environment only (Wyman 2005a). The twin of
// crates/refract-cpu/src/shade.rs (ShadeContext::object). Run only for scenes with objects.

@compute @workgroup_size(8, 8)
fn draw_objects(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.width || id.y >= frame.height {
        return;
    }
    let texel = vec2<i32>(i32(id.x), i32(id.y));
    let object = ng_surface(texel);
    if object.w < 0.5 {
        return;
    }
    let px = front_pixel(id);
    if px.covered && ng_view_depth(px.p1) < ng_view_depth(object.xyz) {
        return;
    }
    out_color[px.index] = vec4<f32>(ng_color(texel), f32(COVERAGE_BACKGROUND));
    write_aovs(px.index, vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
}
