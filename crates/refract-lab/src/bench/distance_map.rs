//! Umenhoffer et al. 2007 §17.4: `distance-map` in the chapter's setting, min-max off and on.

use std::fmt::Write as _;
use std::sync::Arc;

use refract_scene::{Frame, MethodId, MethodParams};

use super::triangles;
use super::{BenchArgs, TableOutput, timed};
use crate::backends::{self, GpuPolicy};
use crate::data_scenes;
use crate::progress::{Note, Progress};

/// The chapter's figures (§17.4, GeForce 8800 GTX, 800 × 600, 3 layers of 6 × 512² rebuilt
/// every frame, depth 2): fps without and with min-max.
const DISTANCE_MAP_PAPER: [(&str, f64); 2] = [("off", 25.0), ("on", 50.0)];

/// Runs the distance-map row: the chapter's setting (`--quick`: 160 × 120, 64² faces, 3
/// frames) on `teapot-box` (the copper teapot in the room; `mirror-room` without the shared
/// data), min-max off and on, every backend.
pub(super) fn run(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<TableOutput> {
    let ((width, height), face, frames) = if args.quick {
        ((160, 120), 64, 3)
    } else {
        ((800, 600), 512, args.frames)
    };
    let scene = match data_scenes::load("teapot-box", &args.data, progress)? {
        Some(scene) => scene,
        None => refract_eval::load_scene("mirror-room")?.scene,
    };
    let scene = Arc::new(scene);
    let triangles = triangles(&scene);
    let backend_ids = backends::parse_backends(&args.backends)?;
    let mut renderers = backends::open(&backend_ids, GpuPolicy::IfAvailable, progress)?;
    let camera = scene.camera(width, height)?;
    let mut records = Vec::new();
    let mut frame = Frame::default();
    for renderer in &mut renderers {
        renderer.prepare(&scene)?;
        for (minmax, _) in DISTANCE_MAP_PAPER {
            let mut method = MethodParams::defaults(MethodId::DistanceMap);
            for (name, value) in [
                ("minmax", minmax),
                ("res", &face.to_string()),
                ("layers", "3"),
                ("depth", "2"),
            ] {
                method.set(name, value, "bench")?;
            }
            let mut record = timed(renderer.as_mut(), &camera, &method, frames, &mut frame)?
                .record(&scene.name, triangles);
            record.method = format!("distance-map minmax={minmax}");
            progress.note(Note::Row(format!(
                "{:<12} {:<4} {width}x{height} faces {face}² minmax={minmax:<3} {:>9.2} ms {:>7.1} fps",
                scene.name, record.backend, record.ms_median, record.fps
            )));
            records.push(record);
        }
    }
    let mut md = format!(
        "# Umenhoffer et al. 2007, the chapter's setting\n\n`distance-map` on `{}` ({triangles} \
         triangles), {width} × {height}, 3 layers of 6 × {face}² rebuilt every frame, depth 2, \
         colour only, median of {frames} frames after 3 warm-up frames. Paper: GeForce 8800 GTX, \
         a reflective teapot in a complex environment.\n\n\
         | backend | min-max | ms | fps | paper fps | ours / paper |\n|---|---|---|---|---|---|\n",
        scene.name
    );
    for r in &records {
        let on = r.method.ends_with("on");
        let paper = DISTANCE_MAP_PAPER[usize::from(on)].1;
        let _ = writeln!(
            md,
            "| {} | {} | {:.1} | {:.1} | {paper} | {:.2}× |",
            r.backend,
            if on { "on" } else { "off" },
            r.ms_median,
            r.fps,
            r.fps / paper
        );
    }
    TableOutput::of_frames(md, &records)
}
