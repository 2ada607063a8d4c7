//! `refract bench`: Wyman 2005a Table 1 on the models we have — frame rates of `wyman`
//! ("2-sided") and `single` ("1-sided") per backend, the reference render time, and the paper's
//! figures beside ours.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use refract_core::exit::TirPolicy;
use refract_geometry::{LoadOptions, Mesh, builtin, load_mesh};
use refract_scene::atomic_write::write_text_atomically;
use refract_scene::{
    Environment, Frame, FrameOutputs, MethodId, MethodParams, Refractor, Scene, TraceSettings,
};
use serde::Serialize;

use crate::backends::{self, GpuPolicy};
use crate::timing::{FrameTimes, time_frames};

/// Arguments of `refract bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Comma-separated models: sphere (built-in), cow, teapot, bunny, horse (from --data).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "sphere,cow,teapot,bunny,horse"
    )]
    pub scenes: Vec<String>,
    /// Comma-separated methods (Table 1 has wyman = 2-sided and single = 1-sided).
    #[arg(long, value_delimiter = ',', default_value = "wyman,single")]
    pub methods: Vec<MethodId>,
    /// Comma-separated backends: cpu, gpu (gpu is skipped with a notice without an adapter).
    #[arg(long, value_delimiter = ',', default_value = "cpu,gpu")]
    pub backends: Vec<String>,
    /// Square resolution (Table 1: 1024).
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=8192))]
    pub res: u32,
    /// Timed frames per method (median reported; at least 20 for the table).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=10000))]
    pub frames: u32,
    /// Where the meshes are (`meshes/cow.obj`, ...).
    #[arg(long, default_value = "../shared/data")]
    pub data: PathBuf,
    /// Output directory for bench.json and bench.md.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// A small run for smoke tests: 128², 3 frames, sphere and cow only.
    #[arg(long)]
    pub quick: bool,
}

/// One row of `bench.json`.
#[derive(Clone, Debug, Serialize)]
pub struct BenchRecord {
    scene: String,
    triangles: usize,
    method: String,
    backend: String,
    width: u32,
    height: u32,
    ms_median: f64,
    ms_min: f64,
    ms_max: f64,
    frames: u32,
    fps: f64,
}

/// Wyman 2005a Table 1 (GeForce 6800, 3.0 GHz Pentium 4, 1024²): 2-sided fps, 1-sided fps,
/// ray-traced seconds.
const PAPER: [(&str, f64, f64, f64); 3] = [
    ("sphere", 164.3, 323.5, 6.1),
    ("cow", 122.9, 295.7, 31.6),
    ("teapot", 115.7, 306.9, 49.3),
];

/// Model name, file in `meshes/`, IOR (the paper's: 1.5 for the sphere and teapot, 1.2 else).
const MODELS: [(&str, &str, f32); 5] = [
    ("sphere", "builtin:sphere", 1.5),
    ("cow", "cow.obj", 1.2),
    ("teapot", "teapot.obj", 1.5),
    ("bunny", "stanford-bunny.obj", 1.2),
    ("horse", "horse.obj", 1.2),
];

fn load_model(name: &str, data: &std::path::Path) -> anyhow::Result<Option<(Mesh, f32)>> {
    let Some(&(_, file, ior)) = MODELS.iter().find(|m| m.0 == name) else {
        let names: Vec<&str> = MODELS.iter().map(|m| m.0).collect();
        anyhow::bail!(
            "--scenes: unknown model `{name}`; expected one of {}",
            names.join(", ")
        );
    };
    if file.starts_with(builtin::PREFIX) {
        return Ok(Some((builtin::mesh(file)?, ior)));
    }
    let path = data.join("meshes").join(file);
    if !path.is_file() {
        eprintln!("note: {} not found; skipping {name}", path.display());
        return Ok(None);
    }
    Ok(Some((load_mesh(&path, &LoadOptions::default())?.mesh, ior)))
}

/// Runs the benchmark and writes `bench.json` and `bench.md`.
pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
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
    crate::cleanup::create_dir(&args.out)
        .with_context(|| format!("{}: cannot create the output directory", args.out.display()))?;
    anyhow::ensure!(
        !args.methods.contains(&MethodId::Reference),
        "--methods: the reference is always timed; list the methods to benchmark"
    );
    let methods: Vec<MethodParams> = args
        .methods
        .iter()
        .map(|&id| MethodParams::defaults(id).with_tir_policy(TirPolicy::ClampToCritical))
        .collect();
    let backend_ids = backends::parse_backends(&args.backends)?;
    let mut renderers = backends::open(&backend_ids, GpuPolicy::IfAvailable)?;
    backends::check_supported(&renderers, &methods)?;
    let mut records = Vec::new();
    let mut reference_seconds = Vec::new();
    let mut frame = Frame::default();
    for name in &scenes {
        let Some((mesh, ior)) = load_model(name, &args.data)? else {
            continue;
        };
        let triangles = mesh.triangles.len();
        let scene = Arc::new(Scene::new(
            name.as_str(),
            Refractor::new(mesh, ior)?,
            Environment::Procedural,
        ));
        let camera = scene.camera(res, res)?;
        let start = Instant::now();
        refract_trace::render(&scene, &camera, &TraceSettings::default());
        reference_seconds.push((name.clone(), start.elapsed().as_secs_f64()));
        for renderer in &mut renderers {
            renderer.prepare(&scene)?;
        }
        for method in &methods {
            for renderer in &mut renderers {
                // Colour only, as displayed: the AOVs are for comparisons.
                let times = time_frames(3, frames, || {
                    Ok(renderer
                        .render(&camera, method, FrameOutputs::Color, &mut frame)?
                        .ms)
                })?;
                let FrameTimes { median, min, max } = times;
                let record = BenchRecord {
                    scene: name.clone(),
                    triangles,
                    method: method.id().name().to_owned(),
                    backend: renderer.backend().id().to_owned(),
                    width: res,
                    height: res,
                    ms_median: median,
                    ms_min: min,
                    ms_max: max,
                    frames,
                    fps: 1e3 / median,
                };
                println!(
                    "{:<8} {:>7} tris {:<9} {:<4} {:>9.2} ms  {:>7.1} fps",
                    record.scene, triangles, record.method, record.backend, median, record.fps
                );
                records.push(record);
            }
        }
    }
    let json = serde_json::to_string_pretty(&records).context("serialising bench records")?;
    write(&args.out.join("bench.json"), &json)?;
    let md = table(&records, &reference_seconds, res, frames);
    write(&args.out.join("bench.md"), &md)?;
    println!("\n{md}");
    Ok(())
}

fn write(path: &std::path::Path, text: &str) -> anyhow::Result<()> {
    Ok(write_text_atomically(path, text)?)
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
         paper 2-sided | paper 1-sided | paper ray traced (s) | CPU 2-sided / paper | GPU 2-sided / paper | paper RT / ours |"
    );
    let _ = writeln!(md, "|{}|", ["---"; 13].join("|"));
    for (scene, seconds) in reference {
        let triangles = records
            .iter()
            .find(|r| &r.scene == scene)
            .map_or(0, |r| r.triangles);
        let paper = PAPER.iter().find(|p| p.0 == scene);
        let (p2, p1, prt) = (paper.map(|p| p.1), paper.map(|p| p.2), paper.map(|p| p.3));
        let cpu2 = fps(scene, "wyman", "cpu");
        let gpu2 = fps(scene, "wyman", "gpu");
        let _ = writeln!(
            md,
            "| {scene} | {triangles} | {} | {} | {} | {} | {seconds:.3} | {} | {} | {} | {} | {} | {} |",
            cell(cpu2),
            cell(fps(scene, "single", "cpu")),
            cell(gpu2),
            cell(fps(scene, "single", "gpu")),
            cell(p2),
            cell(p1),
            prt.map_or_else(|| "–".to_owned(), |v| format!("{v:.1}")),
            ratio(cpu2, p2),
            ratio(gpu2, p2),
            prt.map_or_else(|| "–".to_owned(), |p| format!("{:.0}×", p / seconds)),
        );
    }
    md
}
