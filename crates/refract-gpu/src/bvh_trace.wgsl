// Closest hits of a batch of rays (refract_gpu::bvh::GpuBvh::closest_hits): the BVH's
// conformance kernel (bvh.wgsl's bindings in group 1).

// The conformance kernel: one closest hit per ray of `bvh_rays`, written as (t, triangle bits).
@group(0) @binding(0) var<storage, read> bvh_rays: array<BvhRay>;
@group(0) @binding(1) var<storage, read_write> bvh_hits: array<vec2<u32>>;

@compute @workgroup_size(64)
fn trace_closest(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&bvh_rays) {
        return;
    }
    let ray = bvh_rays[i];
    let hit = bvh_closest_hit(ray.origin.xyz, ray.dir.xyz, ray.origin.w, ray.dir.w);
    bvh_hits[i] = vec2<u32>(bitcast<u32>(hit.t), hit.triangle);
}
