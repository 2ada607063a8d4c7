//! The exact reference on the CPU tracer and on the GPU, seconds a frame and rays per second.

use std::fmt::Write as _;

use refract_scene::{Frame, MethodParams};

use super::{BenchArgs, TableOutput};
use crate::backends::{self, GpuPolicy};
use crate::progress::{Note, Progress};
use std::time::Instant;

use refract_scene::{BackendId, FrameOutputs, Renderer, TraceMode, TraceSettings};

use super::model_scene;

/// One row of the reference table.
struct ReferenceRow {
    scene: String,
    triangles: usize,
    res: u32,
    mode: &'static str,
    backend: String,
    /// Seconds a frame (median), rays a frame.
    measured: (f64, u64),
}

/// Runs the reference table: every model of `--scenes` at 512² and 1024² (`--quick`: sphere and
/// cow at 64² and 128²), `transmission` and `full` (1 sample per pixel, depth 8), on the CPU
/// tracer and, with an adapter, on the GPU; the median of up to 3 frames after one warm-up, colour only, wall clock.
pub(super) fn run(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<TableOutput> {
    let (resolutions, scenes, frames): (&[u32], Vec<String>, u32) = if args.quick {
        (&[64, 128], vec!["sphere".into(), "cow".into()], 1)
    } else {
        (&[512, 1024], args.scenes.clone(), args.frames.min(3))
    };
    let backend_ids = backends::parse_backends(&args.backends)?;
    let mut renderers: Vec<Box<dyn Renderer>> =
        vec![Box::new(refract_trace::ReferenceRenderer::new())];
    if backend_ids.contains(&BackendId::Gpu) {
        for renderer in backends::open(&[BackendId::Gpu], GpuPolicy::IfAvailable, progress)? {
            renderers.push(renderer);
        }
    }
    let mut rows = Vec::new();
    let mut frame = Frame::default();
    for name in &scenes {
        let Some((scene, triangles)) = model_scene(name, &args.data, progress)? else {
            continue;
        };
        for renderer in &mut renderers {
            renderer.prepare(&scene)?;
        }
        for &res in resolutions {
            let camera = scene.camera(res, res)?;
            for (mode, trace_mode) in [
                ("transmission", TraceMode::Transmission),
                ("full", TraceMode::Full),
            ] {
                let method = MethodParams::Reference(TraceSettings {
                    mode: trace_mode,
                    ..TraceSettings::default()
                });
                for renderer in &mut renderers {
                    let backend = renderer.backend().id().to_owned();
                    let mut seconds = Vec::new();
                    for k in 0..=frames {
                        let start = Instant::now();
                        renderer.render(&camera, &method, FrameOutputs::Color, &mut frame)?;
                        if k > 0 {
                            seconds.push(start.elapsed().as_secs_f64());
                        }
                    }
                    seconds.sort_by(f64::total_cmp);
                    let measured = (seconds[seconds.len() / 2], frame.rays);
                    progress.note(Note::Row(format!(
                        "{name:<8} {res:>5}² {mode:<12} {backend:<5} {:>8.3} s {:>8.2} Mrays/s",
                        measured.0,
                        measured.1 as f64 / measured.0 / 1e6
                    )));
                    rows.push(ReferenceRow {
                        scene: name.clone(),
                        triangles,
                        res,
                        mode,
                        backend,
                        measured,
                    });
                }
            }
        }
    }
    let records: Vec<serde_json::Value> = rows
        .iter()
        .map(|r| {
            serde_json::json!({
                "scene": r.scene,
                "triangles": r.triangles,
                "res": r.res,
                "mode": r.mode,
                "backend": r.backend,
                "seconds": r.measured.0,
                "rays": r.measured.1,
            })
        })
        .collect();
    let mut md = format!(
        "# The exact reference on both backends

1 sample per pixel, depth 8, colour only, the median \
         of {frames} frame(s) after one warm-up, wall clock (the GPU's includes the readback of \
         the colour). `trace` is the CPU tracer (rayon over rows); `gpu` is \
         `refract-gpu/src/reference.wgsl`. Rays are closest-hit queries (a camera ray and every \
         continuation), counted on both; the CPU also traces each pixel's centre path for its \
         AOV layers, the GPU only when they are asked for (in `full` mode its count is lower by \
         one path a pixel).\n\n\
         | model | triangles | res | mode | backend | s / frame | Mrays / s |\n|---|---|---|---|---|---|---|\n"
    );
    for r in &rows {
        let (s, rays) = r.measured;
        let (seconds, rate) = (format!("{s:.3}"), format!("{:.2}", rays as f64 / s / 1e6));
        let _ = writeln!(
            md,
            "| {} | {} | {}² | {} | {} | {seconds} | {rate} |",
            r.scene, r.triangles, r.res, r.mode, r.backend
        );
    }
    TableOutput::new(md, &records)
}
