//! Wyman 2005a Table 1: `wyman` ("2-sided") and `single` ("1-sided") per backend, the
//! reference render time, and the paper's figures beside ours.

use std::fmt::Write as _;

use refract_scene::{Frame, MethodId, MethodParams};

use super::{BenchArgs, TableOutput, timed};
use crate::backends::{self, GpuPolicy};
use crate::progress::{Note, Progress};
use std::time::Instant;

use refract_core::exit::TirPolicy;
use refract_scene::TraceSettings;

use super::{BenchRecord, model_scene};

/// Wyman 2005a Table 1 (GeForce 6800, 3.0 GHz Pentium 4, 1024²): 2-sided fps, 1-sided fps,
/// ray-traced seconds.
const PAPER: [(&str, f64, f64, f64); 3] = [
    ("sphere", 164.3, 323.5, 6.1),
    ("cow", 122.9, 295.7, 31.6),
    ("teapot", 115.7, 306.9, 49.3),
];

/// Runs Wyman 2005a Table 1: every model of `--scenes` (`--quick`: sphere and cow at 128², 3
/// frames) with every method of `--methods` on every backend, and the reference's time.
pub(super) fn run(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<TableOutput> {
    let (res, frames) = if args.quick {
        (128, 3)
    } else {
        (args.res, args.frames)
    };
    let scenes: Vec<String> = if args.quick {
        vec!["sphere".into(), "cow".into()]
    } else {
        args.scenes.clone()
    };
    crate::ensure!(
        !args.methods.contains(&MethodId::Reference),
        "--methods: the reference is always timed; list the methods to benchmark"
    );
    let methods: Vec<MethodParams> = args
        .methods
        .iter()
        .map(|&id| MethodParams::defaults(id).with_tir_policy(TirPolicy::ClampToCritical))
        .collect();
    let backend_ids = backends::parse_backends(&args.backends)?;
    let mut renderers = backends::open(&backend_ids, GpuPolicy::IfAvailable, progress)?;
    backends::check_supported(&renderers, &methods)?;
    let mut records = Vec::new();
    let mut reference_seconds = Vec::new();
    let mut frame = Frame::default();
    for name in &scenes {
        let Some((scene, triangles)) = model_scene(name, &args.data, progress)? else {
            continue;
        };
        let camera = scene.camera(res, res)?;
        let start = Instant::now();
        refract_trace::render(&scene, &camera, &TraceSettings::default());
        reference_seconds.push((name.clone(), start.elapsed().as_secs_f64()));
        for renderer in &mut renderers {
            renderer.prepare(&scene)?;
        }
        for method in &methods {
            for renderer in &mut renderers {
                let record = timed(renderer.as_mut(), &camera, method, frames, &mut frame)?
                    .record(name, triangles);
                progress.note(Note::Row(format!(
                    "{:<8} {:>7} tris {:<9} {:<4} {:>9.2} ms  {:>7.1} fps",
                    record.scene,
                    triangles,
                    record.method,
                    record.backend,
                    record.ms_median,
                    record.fps
                )));
                records.push(record);
            }
        }
    }
    let md = table(&records, &reference_seconds, res, frames);
    TableOutput::of_frames(md, &records)
}

/// The Table 1 layout: per model, 2-sided and 1-sided fps per backend, the reference time, and
/// the paper's numbers with our/paper ratios.
fn table(records: &[BenchRecord], reference: &[(String, f64)], res: u32, frames: u32) -> String {
    let fps = |scene: &str, method: &str, backend: &str| {
        records
            .iter()
            .find(|r| r.scene == scene && r.method == method && r.backend == backend)
            .map(|r| r.fps)
    };
    let cell = |v: Option<f64>| v.map_or_else(|| "–".to_owned(), |v| format!("{v:.1}"));
    let ratio = |ours: Option<f64>, paper: Option<f64>| match (ours, paper) {
        (Some(o), Some(p)) => format!("{:.2}×", o / p),
        _ => "–".to_owned(),
    };
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Wyman 2005a Table 1, reproduced\n\n{res}², median of {frames} frames after 3 warm-up frames; a frame is every \
         per-frame pass writing the colour only, as displayed (buffers + kernel; GPU: timestamp queries, queue waited). Reference: exact tracer, \
         transmission, 1 spp, depth 8. Paper: GeForce 6800 + 3.0 GHz Pentium 4.\n"
    );
    if res != 1024 {
        let _ = writeln!(
            md,
            "Note: the paper measured 1024²; the ratios below compare different resolutions.\n"
        );
    }
    let _ = writeln!(
        md,
        "| model | triangles | 2-sided CPU fps | 1-sided CPU fps | 2-sided GPU fps | 1-sided GPU fps | ray traced (s) | \
         paper 2-sided | paper 1-sided | paper ray traced (s) | CPU 2-sided / paper | CPU 1-sided / paper | \
         GPU 2-sided / paper | GPU 1-sided / paper | paper RT / ours |"
    );
    let _ = writeln!(md, "|{}|", ["---"; 15].join("|"));
    for (scene, seconds) in reference {
        let triangles = records
            .iter()
            .find(|r| &r.scene == scene)
            .map_or(0, |r| r.triangles);
        let paper = PAPER.iter().find(|p| p.0 == scene);
        let (p2, p1, prt) = (paper.map(|p| p.1), paper.map(|p| p.2), paper.map(|p| p.3));
        let (cpu2, cpu1) = (fps(scene, "wyman", "cpu"), fps(scene, "single", "cpu"));
        let (gpu2, gpu1) = (fps(scene, "wyman", "gpu"), fps(scene, "single", "gpu"));
        let _ = writeln!(
            md,
            "| {scene} | {triangles} | {} | {} | {} | {} | {seconds:.3} | {} | {} | {} | {} | {} | {} | {} | {} |",
            cell(cpu2),
            cell(cpu1),
            cell(gpu2),
            cell(gpu1),
            cell(p2),
            cell(p1),
            prt.map_or_else(|| "–".to_owned(), |v| format!("{v:.1}")),
            ratio(cpu2, p2),
            ratio(cpu1, p1),
            ratio(gpu2, p2),
            ratio(gpu1, p1),
            prt.map_or_else(|| "–".to_owned(), |p| format!("{:.0}×", p / seconds)),
        );
    }
    md
}
