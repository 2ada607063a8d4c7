//! `refract compare` (and the default job): every method against the reference on each scene,
//! with images, error maps, `metrics.json`, `report.md` and `index.html`.

use refract_eval::FrameFiles;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use rayon::prelude::*;

use crate::error::Context;
use refract_core::TirPolicy;
use refract_eval::metrics::{ErrorMaps, MetricsRecord, evaluate_method, reference_record};
use refract_eval::{BUILTIN_SCENES, load_scene};
use refract_scene::{
    Aov, BackendId, Frame, FrameOutputs, MethodId, MethodParams, Renderer, Scene, TraceSettings,
};
use refract_trace::ReferenceRenderer;

use crate::backends::{self, GpuPolicy};
use crate::engines::{ENGINE_BACKEND, EngineRenderers, engine_record};
use crate::jobs::CompareOptions;
use crate::progress::{Note, Progress};
use crate::report::{MethodImages, SceneImages, write_reports};
use crate::timing::time_frames;
use refract_eval::images::{
    P2_SCALE, T2_SCALE_DEG, write_color_described, write_error_map_described, write_hdr_script,
    write_mask_described,
};

/// The parameters of `ids` with the exit TIR policy `tir` and every `(name, value)` of
/// `assignments` applied to the methods that have that parameter (`origin` names where they
/// came from in errors); a parameter none of the methods has is an error.
pub fn method_params(
    ids: &[MethodId],
    tir: TirPolicy,
    assignments: &[(&str, &str)],
    origin: &str,
) -> crate::Result<Vec<MethodParams>> {
    let mut methods: Vec<MethodParams> = ids
        .iter()
        .map(|&id| MethodParams::defaults(id).with_tir_policy(tir))
        .collect();
    for &(name, value) in assignments {
        crate::ensure!(
            methods.iter().any(|method| method.get(name).is_some()),
            "{origin} {name}={value}: none of the selected methods has a parameter `{name}` (see `refract methods`)"
        );
    }
    for method in &mut methods {
        let own: Vec<(&str, &str)> = assignments
            .iter()
            .copied()
            .filter(|&(name, _)| method.get(name).is_some())
            .collect();
        method.set_all(own.iter().copied(), origin)?;
    }
    Ok(methods)
}

/// The default job (`cargo run --release`, `refract` without a command): every method but the
/// reference on both backends (the CPU only without an adapter) and the engines' own renderers
/// of [`refract_engines::Engine::DEFAULT_JOB`] (skipped with a note where Node, Chromium or the
/// npm packages are missing) on
/// every built-in scene at 512², 1 reference sample per pixel (64 on scenes with rough surfaces,
/// [`refract_scene::ROUGH_MIN_SPP`]), 3 timed frames after the AOV frame and no other warm-up
/// (a median for the report's time column, which drops a slow first frame; `refract bench` is
/// the measurement), into `out/`.
pub fn default_options() -> crate::Result<CompareOptions> {
    let ids: Vec<MethodId> = MethodId::approximations().collect();
    Ok(CompareOptions {
        backends: vec![BackendId::Cpu, BackendId::Gpu],
        gpu_policy: GpuPolicy::IfAvailable,
        scenes: BUILTIN_SCENES.iter().map(|s| s.0.into()).collect(),
        methods: method_params(&ids, TirPolicy::ClampToCritical, &[], "default job")?,
        res: 512,
        spp: 1,
        reference_backend: BackendId::Trace,
        warm_up: 0,
        frames: 3,
        engines: refract_engines::Engine::DEFAULT_JOB.to_vec(),
        engine_policy: GpuPolicy::IfAvailable,
        out: PathBuf::from("out"),
    })
}

/// The one stage of a comparison: one step per reference render (one per scene) and one per
/// (scene, method, backend), skipped pairs included, so that a progress bar's ETA covers the
/// whole job.
pub const STAGE_COMPARE: &str = "compare";

/// Runs the comparison and writes everything into `options.out`; returns the records (the
/// reference's row, then one per method and backend, per scene). Scene warnings and skipped
/// (method, scene) pairs go to `progress` as notes.
pub fn run(options: &CompareOptions, progress: &dyn Progress) -> crate::Result<Vec<MetricsRecord>> {
    crate::memory::check(
        "this comparison",
        options.res,
        options.res,
        crate::memory::COMPARE_BYTES_PER_PIXEL,
        &options.backends,
    )?;
    for method in &options.methods {
        crate::memory::check_method(
            "this comparison",
            method,
            options.res,
            options.res,
            true,
            &options.backends,
        )?;
    }
    crate::output_dirs::create_dir(&options.out).with_context(|| {
        format!(
            "{}: cannot create the output directory",
            options.out.display()
        )
    })?;
    let mut scenes = Vec::new();
    for spec in &options.scenes {
        let loaded = load_scene(spec)?;
        for warning in &loaded.warnings {
            progress.note(Note::Warning(warning.clone()));
        }
        scenes.push(Arc::new(loaded.scene));
    }
    let mut renderers = backends::open(&options.backends, options.gpu_policy, progress)?;
    backends::check_supported(&renderers, &options.methods)?;
    let engines = EngineRenderers::open(&options.engines, options.engine_policy, progress)?;
    let engine_count = engines.as_ref().map_or(0, EngineRenderers::len);
    let mut reference: Box<dyn Renderer> = match options.reference_backend {
        BackendId::Gpu => Box::new(refract_gpu::GpuRenderer::new()?),
        _ => Box::new(ReferenceRenderer::new()),
    };
    let trace = TraceSettings {
        spp: options.spp,
        ..TraceSettings::default()
    };

    for note in skipped_pairs(&options.methods, &scenes) {
        progress.note(note);
    }
    progress.start(
        STAGE_COMPARE,
        (scenes.len() * (1 + options.methods.len() * renderers.len() + engine_count)) as u64,
    );
    let mut records = Vec::new();
    // What measured the rows (metrics.json's `device`, `version`, `commit`).
    let (cpu, commit) = (
        crate::timing::cpu_description(),
        crate::provenance::checkout_commit(),
    );
    let mut scene_images = Vec::new();
    let (w, h) = (options.res, options.res);
    for scene in &scenes {
        let camera = scene.camera(w, h)?;
        let dir = options.out.join(&scene.name);
        crate::output_dirs::create_dir(&dir)
            .with_context(|| format!("{}: cannot create the directory", dir.display()))?;

        if progress.cancelled() {
            return Err(crate::LabError::Cancelled);
        }
        reference.prepare(scene)?;
        let settings = MethodParams::Reference(trace.for_scene(scene));
        let mut truth = Frame::default();
        let timing =
            reference.render(&camera, &settings, FrameOutputs::ColorAndAovs, &mut truth)?;
        progress.advance(STAGE_COMPARE, 1);
        let description = crate::provenance::frame_description(
            &scene.name,
            &settings,
            reference.backend().id(),
            reference.device().as_deref(),
            (w, h),
        );
        write_color_described(&dir.join("reference.png"), w, h, &truth.color, &description)?;
        let key = format!("{}/reference.hdr.js", scene.name);
        write_hdr_script(&dir.join("reference.hdr.js"), &key, w, h, &truth.color)?;
        truth.write_exr_described(&dir.join("reference.exr"), &description)?;
        let path = dir.join("tir-reference.png");
        write_mask_described(&path, w, h, &tir_mask(&truth), &truth.color, &description)?;
        let mut row = reference_record(&truth, timing.ms);
        row.scene.clone_from(&scene.name);
        // "trace" for the CPU tracer, "gpu" for the GPU's.
        reference.backend().id().clone_into(&mut row.backend);
        row.params = settings.describe();
        row.made_by(reference.device().unwrap_or_else(|| cpu.clone()), &commit);
        records.push(row);

        let mut images = Vec::new();
        for renderer in &mut renderers {
            renderer.prepare(scene)?;
        }
        for method in &options.methods {
            if refract_scene::scene_support(method.id(), scene).is_err() {
                // Said once for all pairs before the run (`skipped_pairs`).
                progress.advance(STAGE_COMPARE, renderers.len() as u64);
                continue;
            }
            for renderer in &mut renderers {
                if progress.cancelled() {
                    return Err(crate::LabError::Cancelled);
                }
                let mut frame = Frame::default();
                renderer.render(&camera, method, FrameOutputs::ColorAndAovs, &mut frame)?;
                // Timed frames write the colour only, as a real-time renderer displays it.
                let mut scratch = Frame::default();
                let times = time_frames(options.warm_up, options.frames, || {
                    Ok(renderer
                        .render(&camera, method, FrameOutputs::Color, &mut scratch)?
                        .ms)
                })?;
                let (id, backend) = (method.id(), renderer.backend());
                let written = MethodImages {
                    stem: format!("{id}-{backend}"),
                    has_p2: id.info().aovs.contains(&Aov::P2),
                    // Methods that look up nearby geometry get a map of where they missed it.
                    has_miss: id.info().aovs.contains(&Aov::NgTexel),
                };
                let description = crate::provenance::frame_description(
                    &scene.name,
                    method,
                    backend.id(),
                    renderer.device().as_deref(),
                    (w, h),
                );
                let (mut record, maps) =
                    evaluate_and_write(&dir, &written, &description, (&truth, &frame), || {
                        evaluate_method(&truth, &frame, &camera, scene, method)
                    })?;
                record.scene.clone_from(&scene.name);
                record.method = id.name().to_owned();
                record.backend = backend.id().to_owned();
                record.params = method.describe();
                record.ms_per_frame = Some(times.median);
                record.made_by(renderer.device().unwrap_or_else(|| cpu.clone()), &commit);
                records.push(record);
                write_error_maps(&dir, &written, &description, (w, h), &maps)?;
                images.push(written);
                progress.advance(STAGE_COMPARE, 1);
            }
        }
        if let Some(engines) = &engines {
            if scene.refractor.is_dielectric() {
                for engine in engines.render(scene, &truth, w, h)? {
                    let written = MethodImages {
                        stem: format!("{}-{ENGINE_BACKEND}", engine.label),
                        has_p2: false,
                        // No miss map where the engine's `P_geom` is not measured
                        // (`Engine::positions_through_glass`): it would show no misses.
                        has_miss: engine.frame.vec3(Aov::PGeom).is_some(),
                    };
                    let description = crate::provenance::file_description(
                        &scene.name,
                        (&engine.label, ""),
                        ENGINE_BACKEND,
                        Some("headless Chromium"),
                        (w, h),
                    );
                    let frames = (&truth, &engine.frame);
                    let (mut record, maps) =
                        evaluate_and_write(&dir, &written, &description, frames, || {
                            engine_record(&truth, &engine.frame, scene, &camera)
                        })?;
                    record.scene.clone_from(&scene.name);
                    record.method.clone_from(&engine.label);
                    record.backend = ENGINE_BACKEND.to_owned();
                    record.made_by(format!("headless Chromium ({ENGINE_BACKEND})"), &commit);
                    records.push(record);
                    write_error_maps(&dir, &written, &description, (w, h), &maps)?;
                    images.push(written);
                }
            }
            progress.advance(STAGE_COMPARE, engines.len() as u64);
        }
        scene_images.push(SceneImages {
            scene: scene.name.clone(),
            methods: images,
        });
    }
    progress.finish(STAGE_COMPARE);
    write_reports(&options.out, &records, &scene_images, options)?;
    Ok(records)
}

/// Runs `evaluate` (the metrics against the reference: FLIP and the rest) on this thread while
/// the frame's own images, which need no metric, are written on another
/// ([`write_frame_images`]): nothing is timed while they run.
fn evaluate_and_write<T: Send>(
    dir: &Path,
    written: &MethodImages,
    description: &[(&str, String)],
    frames: (&Frame, &Frame),
    evaluate: impl FnOnce() -> T + Send,
) -> crate::Result<T> {
    let (evaluated, images) = rayon::join(evaluate, || {
        write_frame_images(dir, written, description, frames)
    });
    images?;
    Ok(evaluated)
}

/// Writes a frame's images into `dir`, in parallel: `<stem>.png` and its HDR script, its TIR
/// mask and, for lookups of nearby geometry (`has_miss`), the map of where it missed the
/// objects the reference's path meets; each PNG carries `description`.
fn write_frame_images(
    dir: &Path,
    written: &MethodImages,
    description: &[(&str, String)],
    (truth, frame): (&Frame, &Frame),
) -> crate::Result<()> {
    let (w, h) = (frame.width, frame.height);
    let stem = &written.stem;
    let scene = dir
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    let key = format!("{scene}/{stem}.hdr.js");
    let jobs: [&(dyn Fn() -> Result<(), refract_scene::SceneError> + Sync); 4] = [
        &|| {
            let path = dir.join(format!("{stem}.png"));
            write_color_described(&path, w, h, &frame.color, description)
        },
        &|| {
            write_hdr_script(
                &dir.join(format!("{stem}.hdr.js")),
                &key,
                w,
                h,
                &frame.color,
            )
        },
        &|| {
            let path = dir.join(format!("tir-{stem}.png"));
            write_mask_described(&path, w, h, &tir_mask(frame), &frame.color, description)
        },
        &|| {
            if !written.has_miss {
                return Ok(());
            }
            let missed = refract_eval::metrics::missed_geometry(truth, frame);
            let path = dir.join(format!("miss-{stem}.png"));
            write_mask_described(&path, w, h, &missed, &frame.color, description)
        },
    ];
    jobs.par_iter().try_for_each(|job| job())?;
    Ok(())
}

/// Writes a frame's error maps into `dir`, in parallel: FLIP, T2 and, with `has_p2`, the
/// exit-point error; each PNG carries `description`.
fn write_error_maps(
    dir: &Path,
    written: &MethodImages,
    description: &[(&str, String)],
    (w, h): (u32, u32),
    maps: &ErrorMaps,
) -> crate::Result<()> {
    let stem = &written.stem;
    let map = |name: String, values: &[f32], max: f32| {
        write_error_map_described(&dir.join(name), w, h, values, max, description)
    };
    let jobs: [&(dyn Fn() -> Result<(), refract_scene::SceneError> + Sync); 3] = [
        &|| map(format!("flip-{stem}.png"), &maps.flip, 1.0),
        &|| map(format!("t2err-{stem}.png"), &maps.t2_deg, T2_SCALE_DEG),
        &|| {
            if !written.has_p2 {
                return Ok(());
            }
            map(format!("p2err-{stem}.png"), &maps.p2_rel, P2_SCALE)
        },
    ];
    jobs.par_iter().try_for_each(|job| job())?;
    Ok(())
}

/// The frame's TIR flags (all false when it has no `tir` layer).
fn tir_mask(frame: &Frame) -> Vec<bool> {
    frame
        .flag(Aov::Tir)
        .map_or_else(|| vec![false; frame.pixel_count()], <[bool]>::to_vec)
}

/// The most result rows [`summary`] prints as a table; above it, the best row per scene.
pub const MAX_SUMMARY_ROWS: usize = 24;

/// The console summary of a comparison: up to [`MAX_SUMMARY_ROWS`] results, the table of them;
/// more (the default job has hundreds), the best method of each scene (lowest mean FLIP over
/// the refractor's pixels) and where the full table is. Columns are as wide as their cells.
pub fn summary(records: &[MetricsRecord], out: &Path) -> String {
    let f = |v: Option<f64>, digits: usize| {
        v.map_or_else(|| "-".to_owned(), |v| format!("{v:.digits$}"))
    };
    let mut text = String::new();
    if records.len() <= MAX_SUMMARY_ROWS {
        let header = [
            "scene",
            "method",
            "backend",
            "PSNR dB",
            "FLIP",
            "T2 err deg",
            "P2 err/diam",
            "P2 px p90",
            "TIR",
            "ms/frame",
        ];
        let rows: Vec<Vec<String>> = records
            .iter()
            .map(|r| {
                vec![
                    r.scene.clone(),
                    r.method.clone(),
                    r.backend.clone(),
                    f(r.psnr_ldr_db, 2),
                    f(r.flip_mean, 4),
                    f(r.t2_angle_deg_mean_non_tir, 3),
                    f(r.p2_error_rel_mean_non_tir, 4),
                    f(r.p2_error_px_p90_non_tir, 2),
                    f(r.tir_fraction.map(|t| 100.0 * t), 1) + "%",
                    f(r.ms_per_frame, 1),
                ]
            })
            .collect();
        text += &aligned(&header, &rows, 3);
        text += "\nrefractor pixels only; T2 and P2 at the first exit, without TIR there \
                 (docs/metrics.md)\n";
    } else {
        let scenes = distinct(records.iter().map(|r| r.scene.as_str()));
        let methods = distinct(records.iter().map(|r| r.method.as_str()));
        let backends = distinct(records.iter().map(|r| r.backend.as_str()));
        let _ = writeln!(
            text,
            "{} results: {} scenes, {} methods (the reference included), {} backends; the \
             full table is {}",
            records.len(),
            scenes.len(),
            methods.len(),
            backends.len(),
            out.join("report.md").display()
        );
        let _ = writeln!(
            text,
            "\nbest per scene (lowest mean FLIP over the refractor's pixels; docs/metrics.md):"
        );
        let header = ["scene", "method", "backend", "FLIP", "ms/frame"];
        let rows: Vec<Vec<String>> = scenes
            .iter()
            .filter_map(|scene| {
                records
                    .iter()
                    .filter(|r| r.scene == *scene && r.method != "reference")
                    .filter_map(|r| r.flip_mean.map(|flip| (flip, r)))
                    .min_by(|a, b| a.0.total_cmp(&b.0))
            })
            .map(|(flip, r)| {
                vec![
                    r.scene.clone(),
                    r.method.clone(),
                    r.backend.clone(),
                    format!("{flip:.4}"),
                    f(r.ms_per_frame, 1),
                ]
            })
            .collect();
        text += &aligned(&header, &rows, 3);
    }
    let _ = writeln!(
        text,
        "\nwrote {}/index.html, report.md and metrics.json",
        out.display()
    );
    text
}

/// The distinct values of `values`, in their first order.
fn distinct<'a>(values: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
    let mut seen = Vec::new();
    for value in values {
        if !seen.contains(&value) {
            seen.push(value);
        }
    }
    seen
}

/// `header` and `rows` as a text table, each column as wide as its widest cell, the first
/// `text_columns` left-aligned and the rest (numbers) right-aligned.
fn aligned(header: &[&str], rows: &[Vec<String>], text_columns: usize) -> String {
    let widths: Vec<usize> = (0..header.len())
        .map(|c| {
            rows.iter()
                .map(|row| row[c].chars().count())
                .chain([header[c].chars().count()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut text = String::new();
    let cells = header.iter().map(|h| (*h).to_owned());
    for row in std::iter::once(cells.collect::<Vec<_>>()).chain(rows.iter().cloned()) {
        let line: Vec<String> = row
            .iter()
            .zip(&widths)
            .enumerate()
            .map(|(c, (cell, &width))| {
                if c < text_columns {
                    format!("{cell:<width$}")
                } else {
                    format!("{cell:>width$}")
                }
            })
            .collect();
        let _ = writeln!(text, "{}", line.join("  ").trim_end());
    }
    text
}

/// The (method, scene) pairs `compare` leaves out, one note per reason: how many methods on
/// how many scenes, then their names (`refract_scene::scene_support` says why each pair is
/// left out; the pairs of one reason share it but for the names).
fn skipped_pairs(methods: &[MethodParams], scenes: &[Arc<Scene>]) -> Vec<Note> {
    // The reasons, in the order `scene_support` checks them.
    let reasons = [
        (
            "refract through glass only",
            "whose specular object is a conductor",
            (|s: &Scene| s.refractor.conductor().is_some()) as fn(&Scene) -> bool,
        ),
        (
            "shade opaque objects as diffuse only",
            "with a conductor among their objects",
            |s: &Scene| s.objects.iter().any(|o| o.conductor().is_some()),
        ),
    ];
    let mut notes = Vec::new();
    let mut said: Vec<(MethodId, &str)> = Vec::new();
    for (what, which, applies) in reasons {
        let mut method_names: Vec<&str> = Vec::new();
        let mut scene_names: Vec<&str> = Vec::new();
        for scene in scenes.iter().filter(|s| applies(s)) {
            for method in methods {
                let id = method.id();
                let pair = (id, scene.name.as_str());
                if said.contains(&pair) || refract_scene::scene_support(id, scene).is_ok() {
                    continue;
                }
                said.push(pair);
                if !method_names.contains(&id.name()) {
                    method_names.push(id.name());
                }
                if !scene_names.contains(&scene.name.as_str()) {
                    scene_names.push(&scene.name);
                }
            }
        }
        if !method_names.is_empty() {
            let count = |n: usize, noun: &str| match n {
                1 => format!("1 {noun}"),
                n => format!("{n} {noun}s"),
            };
            notes.push(Note::Skipped(format!(
                "{} that {what} skipped on {} {which}: {} on {}",
                count(method_names.len(), "method"),
                count(scene_names.len(), "scene"),
                method_names.join(", "),
                scene_names.join(", ")
            )));
        }
    }
    // Any other reason `scene_support` may give: one line per pair, as it says it.
    for scene in scenes {
        for method in methods {
            let id = method.id();
            if said.contains(&(id, scene.name.as_str())) {
                continue;
            }
            if let Err(reason) = refract_scene::scene_support(id, scene) {
                notes.push(Note::Skipped(format!("{reason}: skipped")));
            }
        }
    }
    notes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(scene: &str, method: &str, flip: f64) -> MetricsRecord {
        MetricsRecord {
            scene: scene.to_owned(),
            method: method.to_owned(),
            backend: "cpu".to_owned(),
            flip_mean: Some(flip),
            ms_per_frame: Some(1.5),
            ..MetricsRecord::default()
        }
    }

    /// A few results: their table, columns as wide as the widest cell (before: method names
    /// wider than the column shifted the rest of their row).
    #[test]
    fn a_few_results_are_an_aligned_table() {
        let records = [
            record("sphere", "reference", 0.0),
            record("sphere", "iterative-seeded", 0.05),
            record("engine-failures", "wyman", 0.1),
        ];
        let text = summary(&records, Path::new("out"));
        let lines: Vec<&str> = text.lines().take(4).collect();
        let column = |line: &str| line.find("cpu").or_else(|| line.find("backend"));
        let at = column(lines[0]).expect("the header");
        assert!(lines.iter().all(|l| column(l) == Some(at)), "{text}");
        assert!(text.contains("iterative-seeded"));
    }

    /// Many results (the default job's hundreds): the best method of each scene, not every row.
    #[test]
    fn many_results_are_the_best_per_scene() {
        let mut records = Vec::new();
        for scene in ["sphere", "torus"] {
            records.push(record(scene, "reference", 0.0));
            for i in 0..20 {
                let flip = if scene == "torus" {
                    0.2 - 0.01 * i as f64
                } else {
                    0.1 + 0.01 * i as f64
                };
                records.push(record(scene, &format!("m{i}"), flip));
            }
        }
        let text = summary(&records, Path::new("out"));
        assert!(text.contains("42 results: 2 scenes, 21 methods"), "{text}");
        assert!(text.contains("out/report.md"), "{text}");
        let best: Vec<&str> = text
            .lines()
            .filter(|l| l.starts_with("sphere") || l.starts_with("torus"))
            .collect();
        assert_eq!(best.len(), 2, "{text}");
        assert!(
            best[0].contains(" m0 ") && best[1].contains(" m19 "),
            "{text}"
        );
    }
}
