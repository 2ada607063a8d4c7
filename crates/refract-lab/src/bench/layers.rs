//! `depth-peel` at 2, 4 and 8 layers beside `wyman` on the scenes with several refractors.

use std::fmt::Write as _;
use std::sync::Arc;

use refract_eval::load_scene;
use refract_scene::{Frame, MethodId, MethodParams};

use super::{BenchArgs, BenchRecord, TableOutput, timed};
use crate::backends::{self, GpuPolicy};
use crate::progress::{Note, Progress};

/// The layer counts timed.
const LAYERS: [u32; 3] = [2, 4, 8];

/// `depth-peel` at 2, 4 and 8 layers beside `wyman` on `glass-behind-glass`, `vessel` and
/// `liquid` at 1024² (`--quick`: 128², 3 frames), each backend, colour only; the time over
/// `wyman`'s on the same scene and backend.
pub(super) fn run(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<TableOutput> {
    let (res, frames) = if args.quick {
        (128, 3)
    } else {
        (1024, args.frames)
    };
    let backend_ids = backends::parse_backends(&args.backends)?;
    let mut renderers = backends::open(&backend_ids, GpuPolicy::IfAvailable, progress)?;
    let mut methods = vec![MethodParams::defaults(MethodId::Wyman)];
    for layers in LAYERS {
        let mut params = MethodParams::defaults(MethodId::DepthPeel);
        params.set("layers", &layers.to_string(), "bench")?;
        methods.push(params);
    }
    let mut records: Vec<BenchRecord> = Vec::new();
    let mut frame = Frame::default();
    for name in ["glass-behind-glass", "vessel", "liquid"] {
        let scene = Arc::new(load_scene(name)?.scene);
        let triangles = scene.refractors().map(|r| r.mesh().triangles.len()).sum();
        let camera = scene.camera(res, res)?;
        for renderer in &mut renderers {
            renderer.prepare(&scene)?;
            for method in &methods {
                let mut record = timed(renderer.as_mut(), &camera, method, frames, &mut frame)?
                    .record(name, triangles);
                if let Some(layers) = method.get("layers") {
                    record.method = format!("{} (layers={layers})", record.method);
                }
                progress.note(Note::Row(format!(
                    "{name:<18} {:<22} {:<4} {:>9.2} ms {:>8.1} fps",
                    record.method, record.backend, record.ms_median, record.fps
                )));
                records.push(record);
            }
        }
    }
    let mut md = format!(
        "# `depth-peel` beside `wyman`\n\n{res}², median of {frames} frames after 3 warm-up \
         frames, colour only, on the scenes with several refractors (their opaque objects \
         included). `depth-peel` peels every refractor's surfaces into that many layers and \
         marches each ray through them (48 steps a segment, 8 interactions at most); `wyman` \
         draws one refractor's front and back faces. Ratio: the method's time over `wyman`'s on \
         the same scene and backend.\n\n\
         | scene | triangles | method | backend | ms | fps | ms / `wyman` ms |\n\
         |---|---|---|---|---|---|---|\n"
    );
    for r in &records {
        let wyman = records
            .iter()
            .find(|w| w.scene == r.scene && w.backend == r.backend && w.method == "wyman")
            .map(|w| w.ms_median);
        let ratio = match wyman {
            Some(w) if r.method != "wyman" => format!("{:.1}×", r.ms_median / w),
            _ => "–".to_owned(),
        };
        let _ = writeln!(
            md,
            "| {} | {} | `{}` | {} | {:.2} | {:.1} | {ratio} |",
            r.scene, r.triangles, r.method, r.backend, r.ms_median, r.fps
        );
    }
    TableOutput::of_frames(md, &records)
}
