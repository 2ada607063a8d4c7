//! The reference tracer: 1024² `transmission` renders (1 spp, depth 8) of the sphere and the
//! real meshes, in rays per second.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use refract_geometry::builtin;
use refract_scene::{Aov, TraceSettings};
use refract_trace::render;

const RES: u32 = 1024;

fn reference(c: &mut Criterion) {
    let camera = refract_benches::bench_camera(RES);
    let mut meshes = vec![("sphere", builtin::mesh("sphere").expect("builtin"))];
    for (label, file) in refract_benches::BENCH_MESHES {
        if let Some(mesh) = refract_benches::load_shared_mesh(file) {
            meshes.push((label, mesh));
        }
    }
    let settings = TraceSettings::default();
    for (label, mesh) in meshes {
        let scene = refract_benches::bench_scene(label, mesh, 1.5);
        // Correctness before timing: the refractor is in view and rays reach the environment.
        let frame = render(&scene, &camera, &settings);
        let covered = frame.flag(Aov::Covered).expect("covered");
        assert!(covered.iter().filter(|c| **c).count() > (RES * RES / 20) as usize);
        let mut group = c.benchmark_group(format!("reference/{label}"));
        group.sample_size(10);
        group.throughput(Throughput::Elements(frame.rays));
        group.bench_function("transmission_1024_1spp", |b| {
            b.iter(|| render(&scene, &camera, &settings))
        });
        group.finish();
    }
}

criterion_group!(benches, reference);
criterion_main!(benches);
