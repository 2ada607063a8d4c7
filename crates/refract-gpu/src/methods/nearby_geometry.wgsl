// Wyman 2005b refraction of nearby geometry, the final pass: the two-interface path of
// image_space.wgsl, then the lookup in the nearby-geometry (NG) texture (object_surfaces.wgsl),
// one pipeline per method (LOOKUP an override constant). The twin of
// refract_core::nearby_geometry::find_nearby and crates/refract-cpu/src/families/nearby_geometry.rs.

// refract_core::gpu::LOOKUP_* (one pipeline per method).
override LOOKUP: u32 = LOOKUP_SEEDED;

// nearby_geometry.rs: Plane::intersect over the planes (x = t, y = 1 when hit).
fn nearest_plane_hit(origin: vec3<f32>, dir: vec3<f32>) -> vec2<f32> {
    var best = vec2<f32>(F32_MAX, 0.0);
    for (var k = 0u; k < nearby.plane_count; k++) {
        let t = plane_intersect(nearby.planes[k], origin, dir);
        if t.y > 0.5 && t.x < best.x {
            best = t;
        }
    }
    return best;
}

// nearby_geometry.rs: frustum_segment (x = t0, y = t1, z = 1 when inside).
fn frustum_segment(origin: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    let c0 = nearby.world_to_clip * vec4<f32>(origin, 1.0);
    let c1 = nearby.world_to_clip * vec4<f32>(dir, 0.0);
    var a0 = array<f32, 6>(c0.w + c0.x, c0.w - c0.x, c0.w + c0.y, c0.w - c0.y, c0.z, c0.w - c0.z);
    var a1 = array<f32, 6>(c1.w + c1.x, c1.w - c1.x, c1.w + c1.y, c1.w - c1.y, c1.z, c1.w - c1.z);
    var t0 = 0.0;
    var t1 = F32_MAX;
    for (var k = 0; k < 6; k++) {
        if a1[k] == 0.0 {
            if !(a0[k] >= 0.0) {
                return vec3<f32>(0.0);
            }
        } else {
            let t = -a0[k] / a1[k];
            if a1[k] > 0.0 {
                t0 = max(t0, t);
            } else {
                t1 = min(t1, t);
            }
        }
    }
    return vec3<f32>(t0, t1, select(0.0, 1.0, t0 < t1 && t1 < F32_MAX));
}

// nearby_geometry.rs: seed_parameter.
fn seed_parameter(origin: vec3<f32>, dir: vec3<f32>, segment: vec2<f32>, i: u32, k: u32) -> f32 {
    let s = (f32(i) + 0.5) / f32(k);
    var lambda = s;
    if nearby.spacing == SPACING_SCREEN {
        let w0 = ng_view_depth(origin + segment.x * dir);
        let w1 = ng_view_depth(origin + segment.y * dir);
        lambda = screen_fraction_to_segment(s, w0, w1);
    }
    return segment.x + lambda * (segment.y - segment.x);
}

struct Found {
    hit: bool,
    texel: vec2<i32>,
    p_geom: vec3<f32>,
    iterations: u32,
    converged: bool,
}

fn lookup_at(p: vec3<f32>) -> Found {
    var found: Found;
    found.hit = false;
    let texel = ng_texel_of(p);
    if texel.z == 0 {
        return found;
    }
    let s = ng_surface(texel.xy);
    found.hit = s.w > 0.5;
    found.texel = texel.xy;
    found.p_geom = s.xyz;
    return found;
}

// nearby_geometry.rs: iterate (the distance form of §4.3).
fn iterate(p2: vec3<f32>, t2: vec3<f32>, t_start: f32, iterations: u32) -> Found {
    var hit = lookup_at(p2 + t_start * t2);
    if !hit.hit {
        return hit;
    }
    for (var k = 0u; k < iterations; k++) {
        let t = length(hit.p_geom - p2);
        var next = lookup_at(p2 + t * t2);
        next.iterations = k + 1u;
        if !next.hit {
            return next;
        }
        let repeated = all(next.texel == hit.texel);
        hit = next;
        if repeated {
            hit.converged = true;
            return hit;
        }
    }
    hit.iterations = iterations;
    hit.converged = false;
    return hit;
}

// nearby_geometry.rs: find_nearby.
fn find_nearby(p2: vec3<f32>, t2: vec3<f32>) -> Found {
    var miss: Found;
    miss.hit = false;
    if LOOKUP == LOOKUP_KAY_GREENBERG {
        var found = lookup_at(p2);
        found.converged = found.hit;
        return found;
    }
    if LOOKUP == LOOKUP_RAY_PLANE || LOOKUP == LOOKUP_ITERATIVE {
        let plane = nearest_plane_hit(p2, t2);
        if plane.y < 0.5 {
            return miss;
        }
        if LOOKUP == LOOKUP_RAY_PLANE {
            var found = lookup_at(p2 + plane.x * t2);
            found.converged = found.hit;
            return found;
        }
        return iterate(p2, t2, plane.x, nearby.iterations);
    }
    // LOOKUP_SEEDED from here (shade_nearby paints every other code magenta).
    let segment = frustum_segment(p2, t2);
    if segment.z < 0.5 {
        return miss;
    }
    var best_error = F32_MAX;
    var best_t = 0.0;
    var any_hit = false;
    for (var i = 0u; i < nearby.seeds; i++) {
        let t = seed_parameter(p2, t2, segment.xy, i, nearby.seeds);
        let p = p2 + t * t2;
        let found = lookup_at(p);
        if found.hit {
            let error = abs(ng_view_depth(p) - ng_view_depth(found.p_geom));
            if !any_hit || error < best_error {
                best_error = error;
                best_t = t;
                any_hit = true;
            }
        }
    }
    if !any_hit {
        return miss;
    }
    return iterate(p2, t2, best_t, nearby.iterations);
}

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
