//! Umenhoffer et al. 2007 on the CPU backend at the chapter's setting (800 × 600, 3 layers of
//! 6 × 512², depth 2): the layered distance map rebuilt alone, and whole colour-only frames
//! (the map, the eye pass and the searches) with and without min-max, on `mirror-room`
//! (built-in) and `teapot-box` (the Utah teapot from `../shared/data`, skipped without it).

use std::path::Path;
use std::sync::Arc;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use refract_cpu::CpuRenderer;
use refract_cpu::distance_map::DistanceMap;
use refract_eval::load_scene;
use refract_scene::{Frame, FrameOutputs, MethodId, MethodParams, Renderer};

const SIZE: (u32, u32) = (800, 600);
const FACE: u32 = 512;
const LAYERS: u32 = 3;

fn distance_map(c: &mut Criterion) {
    let mut group = c.benchmark_group("cpu/distance-map");
    group.sample_size(10);
    group.throughput(Throughput::Elements(u64::from(SIZE.0 * SIZE.1)));
    let teapot_box = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/teapot-box.toml");
    for spec in ["mirror-room", &teapot_box.display().to_string()] {
        let scene = match load_scene(spec) {
            Ok(loaded) => Arc::new(loaded.scene),
            Err(err) => {
                eprintln!("skipped {spec}: {err}");
                continue;
            }
        };
        let label = scene.name.clone();
        let camera = scene.camera(SIZE.0, SIZE.1).expect("camera");
        let mut map = DistanceMap::default();
        map.prepare(&scene);
        group.bench_function(format!("{label}/map"), |b| {
            b.iter(|| map.render(&scene, LAYERS as usize, FACE).expect("map"))
        });
        let mut renderer = CpuRenderer::new();
        renderer.prepare(&scene).expect("prepare");
        let mut frame = Frame::default();
        for minmax in ["on", "off"] {
            let mut params = MethodParams::defaults(MethodId::DistanceMap);
            for (name, value) in [
                ("minmax", minmax),
                ("res", &FACE.to_string()),
                ("layers", &LAYERS.to_string()),
                ("depth", "2"),
            ] {
                params.set(name, value, "bench").expect(name);
            }
            // Correctness before timing: every pixel of the frame is finite.
            renderer
                .render(&camera, &params, FrameOutputs::Color, &mut frame)
                .expect("frame");
            assert!(frame.color.iter().all(|c| c.is_finite()), "{label}");
            group.bench_function(format!("{label}/minmax={minmax}/frame-colour-only"), |b| {
                b.iter(|| {
                    renderer
                        .render(&camera, &params, FrameOutputs::Color, &mut frame)
                        .expect("frame")
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, distance_map);
criterion_main!(benches);
