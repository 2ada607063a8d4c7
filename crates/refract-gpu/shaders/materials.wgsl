// The opaque objects' materials as the GPU reads them (crates/refract-gpu/src/scene_buffers.rs
// GpuMaterial): no bindings, shared by the nearby-geometry and distance-map modules.

// refract_scene::Albedo as the GPU reads it: kind 0 constant (a), 1 checker (a, b, squares),
// 2 colour chart, 3 wood (light a, dark b, rings = squares), 4 conductor (a = F_p per channel); world_uv: the mesh has no uvs and
// uses world (x, z).
struct Material {
    a: vec4<f32>,
    b: vec4<f32>,
    kind: u32,
    world_uv: u32,
    squares: f32,
    _padding: u32,
}

fn fract_euclid(x: f32) -> f32 {
    return x - floor(x);
}

// refract_scene::Albedo::at.
fn albedo(m: Material, uv: vec2<f32>) -> vec3<f32> {
    switch m.kind {
        case 1u: {
            let cell = floor(uv * m.squares);
            return select(m.b.xyz, m.a.xyz, fract_euclid(0.5 * (cell.x + cell.y)) < 0.25);
        }
        case 2u: {
            if !(uv.x >= 0.0 && uv.x < 1.0 && uv.y >= 0.0 && uv.y < 1.0) {
                return vec3<f32>(0.18);
            }
            let index = u32(uv.y * 4.0) * 6u + u32(uv.x * 6.0);
            var chart = COLOR_CHART;
            return chart[index];
        }
        case 3u: {
            let r = length(vec2<f32>(uv.x - 0.5, (uv.y - 0.5) * 0.25));
            let f = fract_euclid(m.squares * r + 0.15 * sin(40.0 * uv.x));
            return m.a.xyz + (m.b.xyz - m.a.xyz) * (f * f);
        }
        default: {
            return m.a.xyz;
        }
    }
}

