//! The engine methods beside `wyman` on the sphere and the cow.

use std::fmt::Write as _;
use std::sync::Arc;

use refract_scene::{Frame, MethodId, MethodParams};

use super::{BenchArgs, TableOutput, timed};
use crate::backends::{self, GpuPolicy};
use crate::progress::{Note, Progress};
use refract_scene::{Environment, Refractor, Scene};

use super::{BenchRecord, load_model};

/// The engine methods (which skip the back-face pass) beside `wyman` on the sphere and the cow
/// at 1024² (`--quick`: 128², 3 frames), each backend, colour only; the ratio to `wyman` on the
/// same backend and scene.
pub(super) fn run(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<TableOutput> {
    let (res, frames) = if args.quick {
        (128, 3)
    } else {
        (1024, args.frames)
    };
    let backend_ids = backends::parse_backends(&args.backends)?;
    let mut renderers = backends::open(&backend_ids, GpuPolicy::IfAvailable, progress)?;
    let methods = [
        MethodId::Wyman,
        MethodId::ScreenOffset,
        MethodId::VolumeThickness,
        MethodId::ProxySphere,
        MethodId::ProxyBox,
        MethodId::ProxyThin,
    ];
    let mut records: Vec<BenchRecord> = Vec::new();
    let mut frame = Frame::default();
    for name in ["sphere", "cow"] {
        let Some((mesh, ior)) = load_model(name, &args.data, progress)? else {
            continue;
        };
        let triangles = mesh.triangles.len();
        let scene = Arc::new(Scene::new(
            name,
            Refractor::new(mesh, ior)?,
            Environment::Procedural,
        ));
        let camera = scene.camera(res, res)?;
        for renderer in &mut renderers {
            renderer.prepare(&scene)?;
            for id in methods {
                let method = MethodParams::defaults(id);
                let record = timed(renderer.as_mut(), &camera, &method, frames, &mut frame)?
                    .record(name, triangles);
                progress.note(Note::Row(format!(
                    "{name:<8} {:<18} {:<4} {:>9.2} ms {:>8.1} fps",
                    record.method, record.backend, record.ms_median, record.fps
                )));
                records.push(record);
            }
        }
    }
    let mut md = format!(
        "# Engine methods beside `wyman`\n\n{res}², median of {frames} frames after 3 warm-up \
         frames, colour only; the engine methods render the opaque objects' screen texture and \
         the front faces, no back faces (these scenes have no opaque objects: the screen pass is \
         empty). Ratio: `wyman`'s time over the method's on the same scene and backend (> 1: \
         faster than `wyman`).\n\n\
         | scene | triangles | method | backend | ms | fps | `wyman` ms / ms | faster than `wyman` |\n\
         |---|---|---|---|---|---|---|---|\n"
    );
    for r in &records {
        let wyman = records
            .iter()
            .find(|w| w.scene == r.scene && w.backend == r.backend && w.method == "wyman")
            .map(|w| w.ms_median);
        let (ratio, faster) = match wyman {
            Some(w) if r.method != "wyman" => (
                format!("{:.2}×", w / r.ms_median),
                if r.ms_median < w { "yes" } else { "no" },
            ),
            _ => ("–".to_owned(), "–"),
        };
        let _ = writeln!(
            md,
            "| {} | {} | `{}` | {} | {:.2} | {:.1} | {ratio} | {faster} |",
            r.scene, r.triangles, r.method, r.backend, r.ms_median, r.fps
        );
    }
    TableOutput::of_frames(md, &records)
}
