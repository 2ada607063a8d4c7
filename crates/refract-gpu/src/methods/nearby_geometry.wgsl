// Wyman 2005b refraction of nearby geometry, the final pass: the two-interface path of
// image_space.wgsl, then nearby_lookup.wgsl's lookup in the nearby-geometry (NG) texture
// (object_texture.wgsl), one pipeline per method. The twin of
// crates/refract-cpu/src/families/nearby_geometry.rs.

fn write_nearby_aovs(i: u32, found: Found) {
    if WRITE_AOVS {
        let flags = select(0.0, 1.0, found.hit) + select(0.0, 2.0, found.converged);
        out_p_geom[i] = vec4<f32>(found.p_geom, flags);
        var object = 0.0;
        if found.hit {
            object = textureLoad(ng_uv_object, found.texel, 0).z;
        }
        out_ng[i] = vec4<f32>(vec2<f32>(found.texel), object, f32(found.iterations));
    }
}

// Methods `kay-greenberg`, `ray-plane`, `iterative`, `iterative-seeded`.
@compute @workgroup_size(8, 8)
fn shade_nearby(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= frame.width || id.y >= frame.height {
        return;
    }
    let px = front_pixel(id);
    let i = px.index;
    if LOOKUP != LOOKUP_KAY_GREENBERG && LOOKUP != LOOKUP_RAY_PLANE && LOOKUP != LOOKUP_ITERATIVE && LOOKUP != LOOKUP_SEEDED {
        out_color[i] = vec4<f32>(UNKNOWN_CODE_COLOR, f32(COVERAGE_BACKGROUND));
        return;
    }
    var none: Found;
    none.hit = false;
    let object_texel = vec2<i32>(i32(id.x + nearby.pad_x), i32(id.y + nearby.pad_y));
    let object = ng_surface(object_texel);
    let in_front = !px.covered || (object.w > 0.5 && ng_view_depth(object.xyz) < ng_view_depth(px.p1));
    if in_front {
        if object.w > 0.5 {
            out_color[i] = vec4<f32>(ng_color(object_texel), f32(COVERAGE_BACKGROUND));
            write_aovs(i, vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
        } else {
            write_background(px);
        }
        write_nearby_aovs(i, none);
        return;
    }
    let path = two_interface_path(px);
    if !path.valid {
        write_degenerate(i);
        write_nearby_aovs(i, none);
        return;
    }
    write_path_aovs(i, path);
    if all(path.t2 == vec3<f32>(0.0)) {
        out_color[i] = vec4<f32>(0.0, 0.0, 0.0, f32(COVERAGE_PATH));
        write_nearby_aovs(i, none);
        return;
    }
    let found = find_nearby(path.p2, path.t2);
    var color: vec3<f32>;
    if found.hit {
        color = ng_color(found.texel);
    } else {
        color = environment_radiance(path.t2);
    }
    out_color[i] = vec4<f32>(color, f32(COVERAGE_PATH));
    write_nearby_aovs(i, found);
}
