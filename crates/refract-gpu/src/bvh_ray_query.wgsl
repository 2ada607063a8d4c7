// Closest hits by the adapter's ray queries (wgpu's EXPERIMENTAL_RAY_QUERY, Vulkan's
// VK_KHR_ray_query): the same interface as bvh.wgsl (bvh_closest_hit, bvh_triangles, BVH_MISS,
// BVH_INF), so the reference's path code runs unchanged over either traversal. The acceleration
// structure is one BLAS over the whole scene (the refractor and every object), one TLAS instance
// with the identity transform, built by refract_gpu::reference; the triangles keep the mesh's
// own order, so a hit's primitive index is the triangle's index. The adapter's triangle test is
// its own watertight one (no edge widening), double-sided (no cull flag).

struct BvhTriangle {
    v0: vec4<f32>,
    v1: vec4<f32>,
    v2: vec4<f32>,
}

struct BvhHit {
    t: f32,
    triangle: u32,
}

const BVH_MISS: u32 = 0xffffffffu;
const BVH_INF: f32 = 3.4028235e38;

@group(1) @binding(0) var bvh_scene: acceleration_structure;
@group(1) @binding(1) var<storage, read> bvh_triangles: array<BvhTriangle>;

// The closest hit with t in [t_min, t_max]: every triangle opaque, so one rayQueryProceed
// traverses the whole structure and commits the closest.
fn bvh_closest_hit(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32) -> BvhHit {
    var query: ray_query;
    rayQueryInitialize(&query, bvh_scene, RayDesc(RAY_FLAG_FORCE_OPAQUE, 0xffu, t_min, t_max, origin, dir));
    rayQueryProceed(&query);
    let hit = rayQueryGetCommittedIntersection(&query);
    if hit.kind == RAY_QUERY_INTERSECTION_NONE {
        return BvhHit(BVH_INF, BVH_MISS);
    }
    return BvhHit(hit.t, hit.primitive_index);
}
