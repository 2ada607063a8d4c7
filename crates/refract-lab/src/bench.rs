//! `refract bench`: Wyman 2005a Table 1 on the models we have — frame rates of `wyman`
//! ("2-sided") and `single` ("1-sided") per backend, the reference render time, and the paper's
//! figures beside ours; with `--table nearby`, Wyman 2005b Table 1 (refraction of nearby
//! geometry at 1024² and 512²).

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use crate::error::Context;
use refract_core::Camera;
use refract_core::exit::TirPolicy;
use refract_eval::atomic_write::write_text_atomically;
use refract_eval::{LoadOptions, load_mesh};
use refract_geometry::{Mesh, builtin};
use refract_scene::{
    BackendId, Environment, Frame, FrameOutputs, MethodId, MethodParams, PvrrParams, Refractor,
    Renderer, Scene, TraceMode, TraceSettings,
};
use serde::Serialize;

use crate::backends::{self, GpuPolicy};
use crate::data_scenes;
use crate::progress::{Note, Progress};
use crate::timing::{FrameTimes, time_frames};

/// Arguments of `refract bench`.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct BenchArgs {
    /// Comma-separated models: sphere (built-in), cow, teapot, bunny, horse (from --data).
    #[cfg_attr(
        feature = "clap",
        arg(
            long,
            value_delimiter = ',',
            default_value = "sphere,cow,teapot,bunny,horse"
        )
    )]
    pub scenes: Vec<String>,
    /// Comma-separated methods (Table 1 has wyman = 2-sided and single = 1-sided).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_delimiter = ',', default_value = "wyman,single")
    )]
    pub methods: Vec<MethodId>,
    /// Comma-separated backends: cpu, gpu (gpu is skipped with a notice without an adapter).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_delimiter = ',', default_value = "cpu,gpu")
    )]
    pub backends: Vec<String>,
    /// Square resolution (Table 1: 1024).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=i64::from(refract_scene::MAX_FRAME_SIZE))))]
    pub res: u32,
    /// Timed frames per method (median reported; at least 20 for the table).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=10000)))]
    pub frames: u32,
    /// Where the meshes are (`meshes/cow.obj`, ...).
    #[cfg_attr(feature = "clap", arg(long, default_value = "../shared/data"))]
    pub data: PathBuf,
    /// Output directory for bench.json and bench.md.
    #[cfg_attr(feature = "clap", arg(long, default_value = "out"))]
    pub out: PathBuf,
    /// A small run for smoke tests: 128², 3 frames, sphere and cow only (`--table nearby`:
    /// 64² and 128², the sphere row only).
    #[cfg_attr(feature = "clap", arg(long))]
    pub quick: bool,
    /// Which table: `image-space` (Wyman 2005a Table 1), `nearby` (Wyman 2005b Table 1:
    /// `iterative-seeded` on the paper's four scenes, our models mapped by size, at 1024² and
    /// 512²; `--scenes`, `--methods` and `--res` do not apply), `distance-map` (Umenhoffer et al.
    /// §17.4), `pvrr` (Kakimoto et al. §5), `engine` (the engine methods beside `wyman`) or
    /// `reference` (the exact reference on the CPU tracer and the GPU at 512² and 1024²,
    /// transmission and full, rays per second; `--scenes` applies).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = Table::ImageSpace))]
    pub table: Table,
}

/// The tables `refract bench` reproduces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Table {
    /// Wyman 2005a Table 1.
    ImageSpace,
    /// Wyman 2005b Table 1.
    Nearby,
    /// Umenhoffer et al. 2007 §17.4: the chapter's setting with and without min-max.
    DistanceMap,
    /// Kakimoto et al. 2007 §5: reflection, multiple reflection, the lens (every frame, fixed
    /// to the eye, with chromatic aberration) at 1024².
    Pvrr,
    /// The engine methods beside `wyman` on the sphere and the cow at 1024², both backends.
    Engine,
    /// The exact reference on the CPU tracer and on the GPU: the Table 1 models at 512² and
    /// 1024², transmission and `full`, seconds a frame and rays per second.
    Reference,
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

/// The Table 1 scene of model `name` (the model alone in the procedural environment) and its
/// triangle count; `None` (after a note) when its mesh file is missing.
fn model_scene(
    name: &str,
    data: &std::path::Path,
    progress: &dyn Progress,
) -> crate::Result<Option<(Arc<Scene>, usize)>> {
    let Some((mesh, ior)) = load_model(name, data, progress)? else {
        return Ok(None);
    };
    let triangles = mesh.triangles.len();
    let scene = Scene::new(name, Refractor::new(mesh, ior)?, Environment::Procedural);
    Ok(Some((Arc::new(scene), triangles)))
}

fn load_model(
    name: &str,
    data: &std::path::Path,
    progress: &dyn Progress,
) -> crate::Result<Option<(Mesh, f32)>> {
    let Some(&(_, file, ior)) = MODELS.iter().find(|m| m.0 == name) else {
        let names: Vec<&str> = MODELS.iter().map(|m| m.0).collect();
        crate::bail!(
            "--scenes: unknown model `{name}`; expected one of {}",
            names.join(", ")
        );
    };
    if file.starts_with(builtin::PREFIX) {
        return Ok(Some((builtin::mesh(file)?, ior)));
    }
    let path = data.join("meshes").join(file);
    if !path.is_file() {
        progress.note(Note::Skipped(format!(
            "{} not found; skipping {name}",
            path.display()
        )));
        return Ok(None);
    }
    Ok(Some((load_mesh(&path, &LoadOptions::default())?.mesh, ior)))
}

/// Wyman 2005b Table 1 (GeForce 6800, "using our iterative approach"): row, our scene, the
/// paper's fps at 1024² and at 512².
const NEARBY_PAPER: [(&str, &str, f64, f64); 4] = [
    ("Sphere w/1 plane", "sphere-plane", 61.0, 212.8),
    ("Sphere & Dragon", "sphere-igea", 16.9, 21.3),
    ("Dragon w/2 planes", "igea-planes", 8.5, 17.8),
    ("Venus & Dragon", "horse-igea", 9.4, 12.6),
];

/// The sphere above one wood plane ("Sphere w/1 plane"); the other rows are `scenes/` files.
const SPHERE_PLANE: &str = "[camera]\neye = [0.0, 0.9, 4.2]\ntarget = [0.0, -0.15, 0.0]\nnear = 0.05\nfar = 12.0\n\n\
     [refractor]\nmesh = \"builtin:sphere\"\nior = 1.5\nscale = 0.8\n\n\
     [[objects]]\nmesh = \"builtin:plane\"\ntexture = \"wood\"\nscale = 6.0\ntranslate = [0.0, -0.8, 0.6]\n";

/// Triangles of every mesh of `scene`.
fn triangles(scene: &refract_scene::Scene) -> usize {
    scene.refractor.mesh().triangles.len()
        + scene
            .objects
            .iter()
            .map(|o| o.mesh().triangles.len())
            .sum::<usize>()
}

/// Runs Wyman 2005b Table 1.
fn run_nearby(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<String> {
    let (resolutions, frames, rows) = if args.quick {
        (vec![64, 128], 3, &NEARBY_PAPER[..1])
    } else {
        (vec![1024, 512], args.frames, &NEARBY_PAPER[..])
    };
    crate::output_dirs::create_dir(&args.out)
        .with_context(|| format!("{}: cannot create the output directory", args.out.display()))?;
    let method = MethodParams::defaults(MethodId::IterativeSeeded);
    let backend_ids = backends::parse_backends(&args.backends)?;
    let mut renderers = backends::open(&backend_ids, GpuPolicy::IfAvailable, progress)?;
    backends::check_supported(&renderers, std::slice::from_ref(&method))?;
    let mut records = Vec::new();
    let mut frame = Frame::default();
    for &(_, name, _, _) in rows {
        let loaded = if name == "sphere-plane" {
            data_scenes::load_text(name, SPHERE_PLANE, &args.data, progress)?
        } else {
            data_scenes::load(name, &args.data, progress)?
        };
        let Some(scene) = loaded else { continue };
        let scene = Arc::new(scene);
        let triangles = triangles(&scene);
        for renderer in &mut renderers {
            renderer.prepare(&scene)?;
        }
        for &res in &resolutions {
            let camera = scene.camera(res, res)?;
            for renderer in &mut renderers {
                let record = timed(renderer.as_mut(), &camera, &method, frames, &mut frame)?
                    .record(name, triangles);
                progress.note(Note::Row(format!(
                    "{:<13} {:>7} tris {:<4} {:>5}² {:>9.2} ms  {:>7.1} fps",
                    name, triangles, record.backend, res, record.ms_median, record.fps
                )));
                records.push(record);
            }
        }
    }
    let json = serde_json::to_string_pretty(&records).context("serialising bench records")?;
    write(&args.out.join("bench-nearby.json"), &json)?;
    let md = nearby_table(&records, &resolutions, frames, &method);
    write(&args.out.join("bench-nearby.md"), &md)?;
    Ok(md)
}

/// The chapter's figures (§17.4, GeForce 8800 GTX, 800 × 600, 3 layers of 6 × 512² rebuilt
/// every frame, depth 2): fps without and with min-max.
const DISTANCE_MAP_PAPER: [(&str, f64); 2] = [("off", 25.0), ("on", 50.0)];

/// Runs the distance-map row: the chapter's setting (`--quick`: 160 × 120, 64² faces, 3
/// frames) on `teapot-box` (the copper teapot in the room; `mirror-room` without the shared
/// data), min-max off and on, every backend.
fn run_distance_map(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<String> {
    let ((width, height), face, frames) = if args.quick {
        ((160, 120), 64, 3)
    } else {
        ((800, 600), 512, args.frames)
    };
    crate::output_dirs::create_dir(&args.out)
        .with_context(|| format!("{}: cannot create the output directory", args.out.display()))?;
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
    let json = serde_json::to_string_pretty(&records).context("serialising bench records")?;
    write(&args.out.join("bench-distance-map.json"), &json)?;
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
    write(&args.out.join("bench-distance-map.md"), &md)?;
    Ok(md)
}

/// One row of the pvrr table: label, scene, parameters, the paper's fps range.
type PvrrCase = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
    (f64, f64),
);

/// Kakimoto et al. 2007 §5 (GeForce 8800 Ultra, Core 2 Quad 2.66 GHz): the rows of the table,
/// as (label, scene, parameters, paper's fps range).
const PVRR_PAPER: [PvrrCase; 5] = [
    (
        "reflection (Fig. 1, 5)",
        "convex-mirror",
        &[],
        (140.0, 170.0),
    ),
    (
        "multiple reflection (Fig. 11)",
        "mirror-stack",
        &[],
        (70.0, 90.0),
    ),
    ("lens (Fig. 12-14)", "spectacles", &[], (8.0, 10.0)),
    (
        "lens fixed to the eye",
        "spectacles",
        &[("update", "on-change")],
        (70.0, 80.0),
    ),
    (
        "lens fixed, chromatic aberration (Fig. 15)",
        "spectacles",
        &[("update", "on-change"), ("dispersion", "10")],
        (30.0, 35.0),
    ),
];

/// Runs the pvrr table: every row of [`PVRR_PAPER`] at 1024², with maps sized from the
/// footprint (at most 1024 texels) and with fixed 1024-texel maps (`--quick`: 128², at most
/// 128 texels, 3 frames), every backend, colour only.
fn run_pvrr(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<String> {
    let (res, map, frames) = if args.quick {
        (128, 128, 3)
    } else {
        (1024, 1024, args.frames)
    };
    crate::output_dirs::create_dir(&args.out)
        .with_context(|| format!("{}: cannot create the output directory", args.out.display()))?;
    let backend_ids = backends::parse_backends(&args.backends)?;
    let mut renderers = backends::open(&backend_ids, GpuPolicy::IfAvailable, progress)?;
    let mut records = Vec::new();
    let mut rows = Vec::new();
    let mut frame = Frame::default();
    for (label, name, settings, paper) in PVRR_PAPER {
        let scene = Arc::new(refract_eval::load_scene(name)?.scene);
        let triangles = triangles(&scene);
        let camera = scene.camera(res, res)?;
        for sizing in ["footprint", "fixed"] {
            let mut method = MethodParams::defaults(MethodId::Pvrr);
            method.set("res", &map.to_string(), "bench")?;
            method.set("sizing", sizing, "bench")?;
            for (k, v) in settings {
                method.set(k, v, "bench")?;
            }
            let p = PvrrParams::try_from(method).map_err(|other| {
                crate::LabError::invalid(format_args!("not pvrr: {}", other.id()))
            })?;
            let mut planner = refract_scene::pvrr::PvrrPlanner::default();
            planner.prepare(&scene);
            let plan = planner.plan(&scene, &camera, &p)?;
            let rays = plan.rays();
            let maps = map_sizes(plan);
            for renderer in &mut renderers {
                renderer.prepare(&scene)?;
                let mut record = timed(renderer.as_mut(), &camera, &method, frames, &mut frame)?
                    .record(&scene.name, triangles);
                record.method = format!("pvrr {}", method.describe());
                progress.note(Note::Row(format!(
                    "{label:<44} {sizing:<9} {:<4} {res}² {:>9.2} ms {:>7.1} fps ({rays} rays, maps {maps})",
                    record.backend, record.ms_median, record.fps
                )));
                rows.push((label, sizing, rays, maps.clone(), paper, record.clone()));
                records.push(record);
            }
        }
    }
    let json = serde_json::to_string_pretty(&records).context("serialising bench records")?;
    write(&args.out.join("bench-pvrr.json"), &json)?;
    let mut md = format!(
        "# Kakimoto et al. 2007, §5\n\n`pvrr` at {res}², maps sized from the reflector's \
         footprint (`sizing=footprint`, the default, at most {map} texels) and at the fixed {map} \
         texels (`sizing=fixed`), colour only, median of {frames} frames after 3 warm-up frames; \
         the per-vertex rays are traced with the CPU BVH on both backends (the GPU row adds that \
         time to its timestamps). Paper: GeForce 8800 Ultra and a 2.66 GHz Core 2 Quad; its \
         scenes had 10,000 polygons (reflection) and a 2,000-triangle lens in 5,000 \
         triangles.\n\n\
         | case | scene | triangles | ray vertices | sizing | maps (texels) | backend | ms | fps | paper fps | ours / paper |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n"
    );
    for (label, sizing, rays, maps, (lo, hi), r) in &rows {
        let _ = writeln!(
            md,
            "| {label} | {} | {} | {rays} | {sizing} | {maps} | {} | {:.1} | {:.1} | {lo}–{hi} | {:.2}× |",
            r.scene,
            r.triangles,
            r.backend,
            r.ms_median,
            r.fps,
            r.fps / lo
        );
    }
    write(&args.out.join("bench-pvrr.md"), &md)?;
    Ok(md)
}

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
fn run_reference(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<String> {
    let (resolutions, scenes, frames): (&[u32], Vec<String>, u32) = if args.quick {
        (&[64, 128], vec!["sphere".into(), "cow".into()], 1)
    } else {
        (&[512, 1024], args.scenes.clone(), args.frames.min(3))
    };
    crate::output_dirs::create_dir(&args.out)
        .with_context(|| format!("{}: cannot create the output directory", args.out.display()))?;
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
    let json: Vec<serde_json::Value> = rows
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
    let text = serde_json::to_string_pretty(&json).context("serialising bench records")?;
    write(&args.out.join("bench-reference.json"), &text)?;
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
    write(&args.out.join("bench-reference.md"), &md)?;
    Ok(md)
}

/// The map sizes of `plan` (views 1..), `w×h` each, comma-separated; `-` without maps.
fn map_sizes(plan: &refract_scene::pvrr::PvrrPlan) -> String {
    let sizes: Vec<String> = plan.views[1..]
        .iter()
        .map(|v| format!("{}×{}", v.camera.width(), v.camera.height()))
        .collect();
    if sizes.is_empty() {
        "-".to_owned()
    } else {
        sizes.join(", ")
    }
}

/// The engine methods (which skip the back-face pass) beside `wyman` on the sphere and the cow
/// at 1024² (`--quick`: 128², 3 frames), each backend, colour only; the ratio to `wyman` on the
/// same backend and scene.
fn run_engine(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<String> {
    let (res, frames) = if args.quick {
        (128, 3)
    } else {
        (1024, args.frames)
    };
    crate::output_dirs::create_dir(&args.out)
        .with_context(|| format!("{}: cannot create the output directory", args.out.display()))?;
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
    let json = serde_json::to_string_pretty(&records).context("serialising bench records")?;
    write(&args.out.join("bench-engine.json"), &json)?;
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
    write(&args.out.join("bench-engine.md"), &md)?;
    Ok(md)
}

/// Wyman 2005b Table 1's layout with our figures, the paper's and the ratios.
fn nearby_table(
    records: &[BenchRecord],
    resolutions: &[u32],
    frames: u32,
    method: &MethodParams,
) -> String {
    let fps = |scene: &str, backend: &str, res: u32| {
        records
            .iter()
            .find(|r| r.scene == scene && r.backend == backend && r.width == res)
            .map(|r| (r.fps, r.ms_median))
    };
    let cell = |v: Option<(f64, f64)>| {
        v.map_or_else(|| "–".to_owned(), |(f, ms)| format!("{f:.1} ({ms:.1} ms)"))
    };
    let ratio = |v: Option<(f64, f64)>, paper: f64| {
        v.map_or_else(|| "–".to_owned(), |(f, _)| format!("{:.2}×", f / paper))
    };
    let (hi, lo) = (resolutions[0], resolutions[resolutions.len() - 1]);
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Wyman 2005b Table 1, reproduced\n\n`{}` ({}), colour only, median of {frames} frames after 3 warm-up \
         frames; a frame is every per-frame pass (back faces, the NG texture of the opaque objects, front faces, the \
         kernel). Paper: GeForce 6800 + 3.0 GHz Pentium 4 at 1024² and 512²; its Dragon (250k) is our igea \
         (268k triangles), its Venus (100k) our horse (97k).\n",
        method.id(),
        method.describe()
    );
    let _ = writeln!(
        md,
        "| paper row | our scene | triangles | CPU fps {hi}² | CPU fps {lo}² | GPU fps {hi}² | GPU fps {lo}² | \
         paper 1024² | paper 512² | CPU / paper {hi}² | CPU / paper {lo}² |"
    );
    let _ = writeln!(md, "|{}|", ["---"; 11].join("|"));
    for (row, scene, p_hi, p_lo) in NEARBY_PAPER {
        let Some(triangles) = records
            .iter()
            .find(|r| r.scene == scene)
            .map(|r| r.triangles)
        else {
            continue;
        };
        let (c_hi, c_lo) = (fps(scene, "cpu", hi), fps(scene, "cpu", lo));
        let _ = writeln!(
            md,
            "| {row} | {scene} | {triangles} | {} | {} | {} | {} | {p_hi} | {p_lo} | {} | {} |",
            cell(c_hi),
            cell(c_lo),
            cell(fps(scene, "gpu", hi)),
            cell(fps(scene, "gpu", lo)),
            ratio(c_hi, p_hi),
            ratio(c_lo, p_lo),
        );
    }
    if hi != 1024 {
        let _ = writeln!(
            md,
            "\nNote: a quick run ({hi}² and {lo}²); the paper's columns are 1024² and 512²."
        );
    }
    md
}

/// One benchmarked configuration before it is named: method, backend, size and times.
struct Timed {
    method: String,
    backend: String,
    width: u32,
    height: u32,
    frames: u32,
    times: FrameTimes,
}

impl Timed {
    fn record(self, scene: &str, triangles: usize) -> BenchRecord {
        let FrameTimes { median, min, max } = self.times;
        BenchRecord {
            scene: scene.to_owned(),
            triangles,
            method: self.method,
            backend: self.backend,
            width: self.width,
            height: self.height,
            ms_median: median,
            ms_min: min,
            ms_max: max,
            frames: self.frames,
            fps: 1e3 / median,
        }
    }
}

/// `frames` colour-only frames of `method` (as displayed: the AOVs are for comparisons) after 3
/// warm-up frames.
fn timed(
    renderer: &mut dyn Renderer,
    camera: &Camera,
    method: &MethodParams,
    frames: u32,
    frame: &mut Frame,
) -> crate::Result<Timed> {
    let times = time_frames(3, frames, || {
        Ok(renderer
            .render(camera, method, FrameOutputs::Color, frame)?
            .ms)
    })?;
    Ok(Timed {
        method: method.id().name().to_owned(),
        backend: renderer.backend().id().to_owned(),
        width: camera.width(),
        height: camera.height(),
        frames,
        times,
    })
}

/// Runs the benchmark, writes `bench.json` and `bench.md` (`bench-nearby.*` for
/// `--table nearby`, ...) and returns the Markdown table; each row measured goes to `progress`
/// as it is measured.
pub fn run(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<String> {
    if args.table == Table::Nearby {
        return run_nearby(args, progress);
    }
    if args.table == Table::DistanceMap {
        return run_distance_map(args, progress);
    }
    if args.table == Table::Pvrr {
        return run_pvrr(args, progress);
    }
    if args.table == Table::Engine {
        return run_engine(args, progress);
    }
    if args.table == Table::Reference {
        return run_reference(args, progress);
    }
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
    crate::output_dirs::create_dir(&args.out)
        .with_context(|| format!("{}: cannot create the output directory", args.out.display()))?;
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
    let json = serde_json::to_string_pretty(&records).context("serialising bench records")?;
    write(&args.out.join("bench.json"), &json)?;
    let md = table(&records, &reference_seconds, res, frames);
    write(&args.out.join("bench.md"), &md)?;
    Ok(md)
}

fn write(path: &std::path::Path, text: &str) -> crate::Result<()> {
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
