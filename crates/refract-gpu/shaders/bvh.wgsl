// Closest hits against a mesh's BVH on the GPU: the traversal the exact reference will run in
// WGSL (issue 32). The BVH is refract_geometry::FlatBvh: an obvhs BVH2 as 32-byte nodes and its
// triangles in leaf order. The triangle test is the twin of refract-geometry's `intersect`:
// double-sided Möller–Trumbore with the edges widened by EDGE_TOLERANCE, so that rays through
// shared edges and vertices hit (watertight as the CPU's). Exact formulas, no approximation.

struct BvhNode {
    min: vec3<f32>,
    prim_count: u32,
    max: vec3<f32>,
    first_index: u32,
}

struct BvhTriangle {
    v0: vec4<f32>,
    v1: vec4<f32>,
    v2: vec4<f32>,
}

// A ray and its parameter range: origin.w = t_min, dir.w = t_max.
struct BvhRay {
    origin: vec4<f32>,
    dir: vec4<f32>,
}

// The closest hit: t (+inf for a miss) and the triangle's index in leaf order (BVH_MISS).
struct BvhHit {
    t: f32,
    triangle: u32,
}

const BVH_MISS: u32 = 0xffffffffu;
// refract_geometry::FLAT_BVH_MAX_DEPTH.
const BVH_STACK: u32 = 64u;
// refract_geometry::bvh::EDGE_TOLERANCE.
const EDGE_TOLERANCE: f32 = 1e-5;
const BVH_INF: f32 = 3.4028235e38;

// Group 1: a module's own bindings are in group 0.
@group(1) @binding(0) var<storage, read> bvh_nodes: array<BvhNode>;
@group(1) @binding(1) var<storage, read> bvh_triangles: array<BvhTriangle>;

// refract-geometry's `intersect`: the ray parameter of the hit in [t_min, t_max], or BVH_INF.
fn intersect_triangle(tri: BvhTriangle, origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32) -> f32 {
    let e1 = tri.v1.xyz - tri.v0.xyz;
    let e2 = tri.v2.xyz - tri.v0.xyz;
    let p = cross(dir, e2);
    let det = dot(e1, p);
    if det == 0.0 {
        return BVH_INF;
    }
    let inv_det = 1.0 / det;
    let s = origin - tri.v0.xyz;
    let u = dot(s, p) * inv_det;
    if !(u >= -EDGE_TOLERANCE && u <= 1.0 + EDGE_TOLERANCE) {
        return BVH_INF;
    }
    let q = cross(s, e1);
    let v = dot(dir, q) * inv_det;
    if v < -EDGE_TOLERANCE || u + v > 1.0 + EDGE_TOLERANCE {
        return BVH_INF;
    }
    let t = dot(e2, q) * inv_det;
    if t >= t_min && t <= t_max {
        return t;
    }
    return BVH_INF;
}

// The entry parameter of the ray into a node's box within [t_min, t_max], BVH_INF when it misses
// (slabs; a zero direction component divides to ±inf, which the min/max order handles).
fn enter_box(node: BvhNode, origin: vec3<f32>, inv_dir: vec3<f32>, t_min: f32, t_max: f32) -> f32 {
    let t0 = (node.min - origin) * inv_dir;
    let t1 = (node.max - origin) * inv_dir;
    let near = max(max(min(t0.x, t1.x), min(t0.y, t1.y)), max(min(t0.z, t1.z), t_min));
    let far = min(min(max(t0.x, t1.x), max(t0.y, t1.y)), min(max(t0.z, t1.z), t_max));
    if near <= far {
        return near;
    }
    return BVH_INF;
}

// The closest hit of the ray with t in [t_min, t_max]: depth-first, the nearer child first, the
// ray shortened by every hit; ties keep the first triangle found.
fn bvh_closest_hit(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32) -> BvhHit {
    var hit = BvhHit(BVH_INF, BVH_MISS);
    if arrayLength(&bvh_triangles) == 0u {
        return hit;
    }
    let inv_dir = 1.0 / dir;
    var far = t_max;
    var stack: array<u32, BVH_STACK>;
    var top = 0u;
    var node_index = 0u;
    if enter_box(bvh_nodes[0], origin, inv_dir, t_min, far) == BVH_INF {
        return hit;
    }
    loop {
        let node = bvh_nodes[node_index];
        if node.prim_count > 0u {
            for (var k = 0u; k < node.prim_count; k++) {
                let i = node.first_index + k;
                let t = intersect_triangle(bvh_triangles[i], origin, dir, t_min, far);
                if t < hit.t {
                    hit = BvhHit(t, i);
                    far = t;
                }
            }
        } else {
            let a = node.first_index;
            let ta = enter_box(bvh_nodes[a], origin, inv_dir, t_min, far);
            let tb = enter_box(bvh_nodes[a + 1u], origin, inv_dir, t_min, far);
            if ta != BVH_INF || tb != BVH_INF {
                var near_child = a;
                var far_child = a + 1u;
                var far_t = tb;
                if tb < ta {
                    near_child = a + 1u;
                    far_child = a;
                    far_t = ta;
                }
                if far_t != BVH_INF && top < BVH_STACK {
                    stack[top] = far_child;
                    top += 1u;
                }
                node_index = near_child;
                continue;
            }
        }
        // Pop the next node that still lies before the closest hit.
        var next = BVH_MISS;
        loop {
            if top == 0u {
                break;
            }
            top -= 1u;
            let candidate = stack[top];
            if enter_box(bvh_nodes[candidate], origin, inv_dir, t_min, far) != BVH_INF {
                next = candidate;
                break;
            }
        }
        if next == BVH_MISS {
            break;
        }
        node_index = next;
    }
    return hit;
}
