//! `refract compare` (and the default job): every method against the reference on each scene,
//! with images, error maps, `metrics.json`, `report.md` and `index.html`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use refract_core::exit::TirPolicy;
use refract_core::{Camera, CameraDesc, Method};
use refract_cpu::{CpuRenderer, MethodParams, PreparedRefractor, render_method};
use refract_trace::{TraceSettings, render};

use crate::images::{write_color, write_error_map, write_mask};
use crate::metrics::{MetricsRecord, evaluate, reference_record};
use crate::report::{SceneImages, write_reports};
use crate::scene_file::load_scene;
use crate::timing::{time_frames, wall_ms};

/// Which backends run the methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// refract-cpu.
    Cpu,
    /// refract-gpu (wgpu).
    Gpu,
}

impl Backend {
    /// Parses a `--backends` list (`cpu`, `gpu`).
    pub fn parse_list(names: &[String]) -> anyhow::Result<Vec<Self>> {
        names
            .iter()
            .map(|name| match name.as_str() {
                "cpu" => Ok(Backend::Cpu),
                "gpu" => Ok(Backend::Gpu),
                other => {
                    anyhow::bail!("--backends: unknown backend `{other}`; expected cpu or gpu")
                }
            })
            .collect()
    }

    /// The id in file names and metrics.
    pub fn id(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::Gpu => "gpu",
        }
    }
}

/// What to do when no GPU adapter exists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GpuPolicy {
    /// The user asked for the GPU: no adapter is an error.
    Required,
    /// The default job: compare on the CPU with a one-line notice.
    IfAvailable,
}

/// What to compare.
pub struct CompareOptions {
    /// Backends.
    pub backends: Vec<Backend>,
    /// What a missing adapter means.
    pub gpu_policy: GpuPolicy,
    /// Scene names or files.
    pub scenes: Vec<String>,
    /// Methods.
    pub methods: Vec<Method>,
    /// Square resolution.
    pub res: u32,
    /// Reference samples per pixel.
    pub spp: u32,
    /// Timed frames per method (after 2 warm-up frames).
    pub frames: u32,
    /// Output directory.
    pub out: PathBuf,
    /// Second-interface TIR policy.
    pub tir_policy: TirPolicy,
}

/// Error-map scales (the top of each colour bar).
pub const T2_SCALE_DEG: f32 = 20.0;
/// |P~2 − P2| scale, fraction of the bounding-sphere diameter.
pub const P2_SCALE: f32 = 0.2;

fn bar(len: u64, message: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    if let Ok(style) = ProgressStyle::with_template("{msg:>12} [{bar:30}] {pos}/{len} {elapsed}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(message.to_owned());
    bar
}

/// Runs the comparison and writes everything into `options.out`; returns the records.
pub fn run(options: &CompareOptions) -> anyhow::Result<Vec<MetricsRecord>> {
    std::fs::create_dir_all(&options.out).with_context(|| {
        format!(
            "{}: cannot create the output directory",
            options.out.display()
        )
    })?;
    let mut scenes = Vec::new();
    for spec in &options.scenes {
        let scene = load_scene(spec)?;
        for warning in &scene.warnings {
            eprintln!("warning: {warning}");
        }
        scenes.push(scene);
    }
    let gpu = if options.backends.contains(&Backend::Gpu) {
        match refract_gpu::GpuContext::new() {
            Ok(context) => {
                let renderer = refract_gpu::GpuRenderer::new(&context)?;
                eprintln!("GPU: {} ({:?})", context.info.name, context.info.backend);
                Some((context, renderer))
            }
            Err(err) if options.gpu_policy == GpuPolicy::IfAvailable => {
                eprintln!("note: {err}; comparing on the CPU only");
                None
            }
            Err(err) => return Err(err.into()),
        }
    } else {
        None
    };
    let backends: Vec<Backend> = options
        .backends
        .iter()
        .copied()
        .filter(|b| *b == Backend::Cpu || gpu.is_some())
        .collect();

    let references = bar(scenes.len() as u64, "reference");
    let methods = bar(
        (scenes.len() * options.methods.len() * backends.len()) as u64,
        "methods",
    );
    let mut records = Vec::new();
    let mut scene_images = Vec::new();
    for loaded in &scenes {
        let camera = Camera::new(CameraDesc {
            width: options.res,
            height: options.res,
            ..loaded.camera
        })
        .with_context(|| format!("scene {}: camera", loaded.name))?;
        let dir = options.out.join(&loaded.name);
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("{}: cannot create the directory", dir.display()))?;

        let settings = TraceSettings {
            spp: options.spp,
            ..TraceSettings::default()
        };
        let start = Instant::now();
        let reference = render(&loaded.scene, &camera, &settings);
        let reference_ms = start.elapsed().as_secs_f64() * 1e3;
        references.inc(1);
        write_color(
            &dir.join("reference.png"),
            options.res,
            options.res,
            &reference.radiance,
        )?;
        reference.write_exr(&dir.join("reference.exr"))?;
        let tir: Vec<bool> = reference.aov.iter().map(|a| a.tir).collect();
        write_mask(
            &dir.join("tir-reference.png"),
            options.res,
            options.res,
            &tir,
            &reference.radiance,
        )?;
        let mut row = reference_record(&reference, reference_ms);
        row.scene.clone_from(&loaded.name);
        records.push(row);

        let diameter = 2.0 * loaded.scene.refractor.mesh.bounding_sphere().radius;
        let prepared = PreparedRefractor {
            mesh: &loaded.scene.refractor.mesh,
            d_n: &loaded.d_n,
        };
        let mut method_ids = Vec::new();
        let gpu_scene = gpu.as_ref().map(|(context, _)| {
            refract_gpu::GpuScene::new(
                context,
                &loaded.scene.refractor.mesh,
                &loaded.d_n,
                &loaded.scene.environment,
            )
        });
        for &method in &options.methods {
            let params = MethodParams {
                method,
                ior: loaded.scene.refractor.ior(),
                tir_policy: options.tir_policy,
            };
            let environment = &loaded.scene.environment;
            for &backend in &backends {
                let (frame, ms) = match (backend, &gpu, &gpu_scene) {
                    (Backend::Gpu, Some((context, renderer)), Some(gpu_scene)) => {
                        let run = refract_gpu::GpuFrame::new(
                            context, renderer, gpu_scene, &camera, &params,
                        )?;
                        run.execute(context, renderer, gpu_scene, true)?;
                        let frame = run.read(context)?;
                        let times = time_frames(2, options.frames, || {
                            Ok(run.execute(context, renderer, gpu_scene, false)?.ms)
                        })?;
                        (frame, times.median)
                    }
                    _ => {
                        let frame = render_method(&prepared, environment, &camera, &params)?;
                        let mut renderer = CpuRenderer::default();
                        let times = time_frames(2, options.frames, || {
                            wall_ms(|| {
                                renderer.render(&prepared, environment, &camera, &params)?;
                                Ok(())
                            })
                        })?;
                        (frame, times.median)
                    }
                };
                let (mut record, maps) = evaluate(&reference, &frame, diameter);
                record.scene.clone_from(&loaded.name);
                record.method = method.id().to_owned();
                record.backend = backend.id().to_owned();
                record.ms_per_frame = Some(ms);
                records.push(record);

                let stem = format!("{}-{}", method.id(), backend.id());
                let (w, h) = (options.res, options.res);
                write_color(&dir.join(format!("{stem}.png")), w, h, &frame.color)?;
                write_error_map(&dir.join(format!("flip-{stem}.png")), w, h, &maps.flip, 1.0)?;
                write_error_map(
                    &dir.join(format!("t2err-{stem}.png")),
                    w,
                    h,
                    &maps.t2_deg,
                    T2_SCALE_DEG,
                )?;
                if method != Method::Single {
                    write_error_map(
                        &dir.join(format!("p2err-{stem}.png")),
                        w,
                        h,
                        &maps.p2_rel,
                        P2_SCALE,
                    )?;
                }
                let tir: Vec<bool> = frame.aov.iter().map(|a| a.tir).collect();
                write_mask(
                    &dir.join(format!("tir-{stem}.png")),
                    w,
                    h,
                    &tir,
                    &frame.color,
                )?;
                method_ids.push(stem);
                methods.inc(1);
            }
        }
        scene_images.push(SceneImages {
            scene: loaded.name.clone(),
            methods: method_ids,
        });
    }
    references.finish_and_clear();
    methods.finish_and_clear();
    write_reports(&options.out, &records, &scene_images, options)?;
    Ok(records)
}

/// The summary table printed at the end.
pub fn print_summary(records: &[MetricsRecord], out: &Path) {
    let f = |v: Option<f64>, digits: usize| {
        v.map_or_else(|| "-".to_owned(), |v| format!("{v:.digits$}"))
    };
    println!(
        "{:<10} {:<10} {:<7} {:>8} {:>8} {:>12} {:>12} {:>7} {:>10}",
        "scene",
        "method",
        "backend",
        "PSNR dB",
        "FLIP",
        "T2 err deg",
        "P2 err/diam",
        "TIR",
        "ms/frame"
    );
    for r in records {
        println!(
            "{:<10} {:<10} {:<7} {:>8} {:>8} {:>12} {:>12} {:>7} {:>10}",
            r.scene,
            r.method,
            r.backend,
            f(r.psnr_db, 2),
            f(r.flip_mean, 4),
            f(r.t2_angle_deg_mean_non_tir, 3),
            f(r.p2_error_rel_mean_non_tir, 4),
            f(r.tir_fraction.map(|t| 100.0 * t), 1) + "%",
            f(r.ms_per_frame, 1)
        );
    }
    println!(
        "\nwrote {}/index.html, report.md and metrics.json",
        out.display()
    );
}
