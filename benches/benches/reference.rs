//! The reference tracer: 1024² `transmission` renders (1 spp, depth 8) of the sphere and the
//! real meshes, in rays per second.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use refract_core::{Camera, CameraDesc};
use refract_geometry::builtin;
use refract_trace::{Environment, Refractor, Scene, TraceSettings, render};

const RES: u32 = 1024;

fn reference(c: &mut Criterion) {
    let camera = Camera::new(CameraDesc {
        width: RES,
        height: RES,
        ..CameraDesc::default()
    })
    .expect("camera");
    let mut meshes = vec![("sphere", builtin::mesh("sphere").expect("builtin"))];
    for (label, file) in refract_benches::BENCH_MESHES {
        if let Some(mesh) = refract_benches::load_shared_mesh(file) {
            meshes.push((label, mesh));
        }
    }
    let settings = TraceSettings::default();
    for (label, mesh) in meshes {
        let scene = Scene::new(
            Refractor::new(mesh, 1.5).expect("ior"),
            Environment::Procedural,
        );
        // Correctness before timing: the refractor is in view and rays reach the environment.
        let frame = render(&scene, &camera, &settings);
        assert!(
            frame.aov.iter().filter(|a| a.covers_refractor()).count() > (RES * RES / 20) as usize
        );
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
