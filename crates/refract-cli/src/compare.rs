//! `refract compare` (and the default job): every method against the reference on each scene,
//! with images, error maps, `metrics.json`, `report.md` and `index.html`.

use refract_eval::FrameFiles;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use refract_eval::load_scene;
use refract_eval::metrics::{MetricsRecord, evaluate_method, reference_record};
use refract_scene::{Aov, BackendId, Frame, FrameOutputs, MethodParams, Renderer, TraceSettings};
use refract_trace::ReferenceRenderer;

use crate::backends::{self, GpuPolicy};
use crate::report::{MethodImages, SceneImages, write_reports};
use crate::timing::time_frames;
use refract_eval::images::{write_color, write_error_map, write_hdr_script, write_mask};

/// What to compare.
pub struct CompareOptions {
    /// Backends.
    pub backends: Vec<BackendId>,
    /// What a missing adapter means.
    pub gpu_policy: GpuPolicy,
    /// Scene names or files.
    pub scenes: Vec<String>,
    /// Methods with their parameters.
    pub methods: Vec<MethodParams>,
    /// Square resolution.
    pub res: u32,
    /// Reference samples per pixel.
    pub spp: u32,
    /// Timed frames per method (after 2 warm-up frames).
    pub frames: u32,
    /// Output directory.
    pub out: PathBuf,
}

pub use refract_eval::images::{P2_SCALE, T2_SCALE_DEG};

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
    crate::memory::check(
        "this comparison",
        options.res,
        options.res,
        crate::memory::COMPARE_BYTES_PER_PIXEL,
        &options.backends,
    )?;
    crate::cleanup::create_dir(&options.out).with_context(|| {
        format!(
            "{}: cannot create the output directory",
            options.out.display()
        )
    })?;
    let mut scenes = Vec::new();
    for spec in &options.scenes {
        let loaded = load_scene(spec)?;
        for warning in &loaded.warnings {
            eprintln!("warning: {warning}");
        }
        scenes.push(Arc::new(loaded.scene));
    }
    let mut renderers = backends::open(&options.backends, options.gpu_policy)?;
    backends::check_supported(&renderers, &options.methods)?;
    let mut reference = ReferenceRenderer::new();
    let settings = MethodParams::Reference(TraceSettings {
        spp: options.spp,
        ..TraceSettings::default()
    });

    let references = bar(scenes.len() as u64, "reference");
    let progress = bar(
        (scenes.len() * options.methods.len() * renderers.len()) as u64,
        "methods",
    );
    let mut records = Vec::new();
    let mut scene_images = Vec::new();
    let (w, h) = (options.res, options.res);
    for scene in &scenes {
        let camera = scene.camera(w, h)?;
        let dir = options.out.join(&scene.name);
        crate::cleanup::create_dir(&dir)
            .with_context(|| format!("{}: cannot create the directory", dir.display()))?;

        reference.prepare(scene)?;
        let mut truth = Frame::default();
        let timing =
            reference.render(&camera, &settings, FrameOutputs::ColorAndAovs, &mut truth)?;
        references.inc(1);
        write_color(&dir.join("reference.png"), w, h, &truth.color)?;
        let key = format!("{}/reference.hdr.js", scene.name);
        write_hdr_script(&dir.join("reference.hdr.js"), &key, w, h, &truth.color)?;
        truth.write_exr(&dir.join("reference.exr"))?;
        write_mask(
            &dir.join("tir-reference.png"),
            w,
            h,
            &tir_mask(&truth),
            &truth.color,
        )?;
        let mut row = reference_record(&truth, timing.ms);
        row.scene.clone_from(&scene.name);
        row.params = settings.describe();
        records.push(row);

        let mut images = Vec::new();
        for renderer in &mut renderers {
            renderer.prepare(scene)?;
        }
        for method in &options.methods {
            if let Err(reason) = refract_scene::scene_support(method.id(), scene) {
                eprintln!("note: {reason}: skipped");
                progress.inc(renderers.len() as u64);
                continue;
            }
            for renderer in &mut renderers {
                let mut frame = Frame::default();
                renderer.render(&camera, method, FrameOutputs::ColorAndAovs, &mut frame)?;
                // Timed frames write the colour only, as a real-time renderer displays it.
                let mut scratch = Frame::default();
                let times = time_frames(2, options.frames, || {
                    Ok(renderer
                        .render(&camera, method, FrameOutputs::Color, &mut scratch)?
                        .ms)
                })?;
                let (mut record, maps) = evaluate_method(&truth, &frame, &camera, scene, method);
                let (id, backend) = (method.id(), renderer.backend());
                let stem = format!("{id}-{backend}");
                // Methods that look up nearby geometry get a map of where they missed it.
                let has_miss = id.info().aovs.contains(&Aov::NgTexel);
                if has_miss {
                    write_mask(
                        &dir.join(format!("miss-{stem}.png")),
                        w,
                        h,
                        &missed_geometry(&truth, &frame),
                        &frame.color,
                    )?;
                }
                record.scene.clone_from(&scene.name);
                record.method = id.name().to_owned();
                record.backend = backend.id().to_owned();
                record.params = method.describe();
                record.ms_per_frame = Some(times.median);
                records.push(record);

                write_color(&dir.join(format!("{stem}.png")), w, h, &frame.color)?;
                let key = format!("{}/{stem}.hdr.js", scene.name);
                write_hdr_script(
                    &dir.join(format!("{stem}.hdr.js")),
                    &key,
                    w,
                    h,
                    &frame.color,
                )?;
                write_error_map(&dir.join(format!("flip-{stem}.png")), w, h, &maps.flip, 1.0)?;
                write_error_map(
                    &dir.join(format!("t2err-{stem}.png")),
                    w,
                    h,
                    &maps.t2_deg,
                    T2_SCALE_DEG,
                )?;
                let has_p2 = id.info().aovs.contains(&Aov::P2);
                if has_p2 {
                    write_error_map(
                        &dir.join(format!("p2err-{stem}.png")),
                        w,
                        h,
                        &maps.p2_rel,
                        P2_SCALE,
                    )?;
                }
                write_mask(
                    &dir.join(format!("tir-{stem}.png")),
                    w,
                    h,
                    &tir_mask(&frame),
                    &frame.color,
                )?;
                images.push(MethodImages {
                    stem,
                    has_p2,
                    has_miss,
                });
                progress.inc(1);
            }
        }
        scene_images.push(SceneImages {
            scene: scene.name.clone(),
            methods: images,
        });
    }
    references.finish_and_clear();
    progress.finish_and_clear();
    write_reports(&options.out, &records, &scene_images, options)?;
    Ok(records)
}

/// Pixels where the reference's path meets an opaque object and the method's lookup found none
/// (Wyman 2005b Fig. 6, 8: "rays completely miss the dragon").
pub(crate) fn missed_geometry(truth: &Frame, frame: &Frame) -> Vec<bool> {
    let (Some(t), Some(o)) = (truth.vec3(Aov::PGeom), frame.vec3(Aov::PGeom)) else {
        return vec![false; frame.pixel_count()];
    };
    let covered = frame.flag(Aov::Covered);
    (0..frame.pixel_count())
        .map(|i| covered.is_some_and(|c| c[i]) && !t[i].is_nan() && o[i].is_nan())
        .collect()
}

/// The frame's TIR flags (all false when it has no `tir` layer).
fn tir_mask(frame: &Frame) -> Vec<bool> {
    frame
        .flag(Aov::Tir)
        .map_or_else(|| vec![false; frame.pixel_count()], <[bool]>::to_vec)
}

/// The summary table printed at the end.
pub fn print_summary(records: &[MetricsRecord], out: &Path) {
    let f = |v: Option<f64>, digits: usize| {
        v.map_or_else(|| "-".to_owned(), |v| format!("{v:.digits$}"))
    };
    println!(
        "{:<10} {:<10} {:<7} {:>8} {:>8} {:>11} {:>11} {:>11} {:>7} {:>9}",
        "scene",
        "method",
        "backend",
        "PSNR dB",
        "FLIP",
        "T2 err deg",
        "P2 err/diam",
        "P2 px p90",
        "TIR",
        "ms/frame"
    );
    for r in records {
        println!(
            "{:<10} {:<10} {:<7} {:>8} {:>8} {:>11} {:>11} {:>11} {:>7} {:>9}",
            r.scene,
            r.method,
            r.backend,
            f(r.psnr_ldr_db, 2),
            f(r.flip_mean, 4),
            f(r.t2_angle_deg_mean_non_tir, 3),
            f(r.p2_error_rel_mean_non_tir, 4),
            f(r.p2_error_px_p90_non_tir, 2),
            f(r.tir_fraction.map(|t| 100.0 * t), 1) + "%",
            f(r.ms_per_frame, 1)
        );
    }
    println!(
        "\nrefractor pixels only; T2 and P2 at the first exit, without TIR there (docs/metrics.md)"
    );
    println!(
        "\nwrote {}/index.html, report.md and metrics.json",
        out.display()
    );
}
