// Wyman 2005b's lookups in the nearby-geometry (NG) texture (§4): Kay-Greenberg, ray-plane,
// iterative and seeded, the twin of refract_core::nearby_geometry::find_nearby. They read the
// texture through `ng_surface(texel)` (xyz = P, w = 1 where covered), which the module including
// them provides: object_texture.wgsl from the NG texture, nearby_conformance.wgsl analytically;
// and the NG camera from object_surfaces.wgsl's uniforms. LOOKUP is an override constant (one
// pipeline per method).

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

