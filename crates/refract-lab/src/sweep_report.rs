//! `refract report DIR... --out OUT`: merges the job results of any number of sweep (shard)
//! directories into one report — `results.json`, `report.md`, SVG plots (`plotters`) and an
//! interactive `index.html` (sortable table, per-scene method × backend thumbnails, a comparison
//! view with the vendored `img-comparison-slider`).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::Context;
use refract_eval::atomic_write::write_text_atomically;
use refract_eval::metrics::MetricsRecord;
use refract_scene::MethodId;

use crate::html::escape;
use crate::jobs::{JobImages, JobResult};

/// Arguments of `refract report`.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct ReportArgs {
    /// Sweep output directories (each with `jobs/`), e.g. one per shard.
    #[cfg_attr(feature = "clap", arg(required = true))]
    pub dirs: Vec<PathBuf>,
    /// Where the merged report goes.
    #[cfg_attr(feature = "clap", arg(long, default_value = "report"))]
    pub out: PathBuf,
}

/// The vendored A/B slider (MIT, `crates/refract-cli/assets/`).
const SLIDER_JS: &str = include_str!("../assets/img-comparison-slider.js");
/// The report's own script.
const REPORT_JS: &str = include_str!("../assets/report.js");

/// Every job result under `dirs`, one per job id (a successful result wins over a failed one;
/// among equals the later directory wins), in job order. Image paths are made relative to
/// the merged report by copying the images into `out/images`.
pub fn merge(dirs: &[PathBuf]) -> crate::Result<Vec<(JobResult, PathBuf)>> {
    let mut by_id: BTreeMap<String, (JobResult, PathBuf)> = BTreeMap::new();
    for dir in dirs {
        let jobs = dir.join("jobs");
        let entries = std::fs::read_dir(&jobs)
            .with_context(|| format!("{}: not a sweep directory (no jobs/)", dir.display()))?;
        for entry in entries {
            let path = entry?.path();
            if path.extension().is_none_or(|e| e != "json") {
                continue;
            }
            let text = std::fs::read_to_string(&path)
                .with_context(|| format!("{}: cannot read", path.display()))?;
            let result: JobResult = serde_json::from_str(&text)
                .with_context(|| format!("{}: not a job result", path.display()))?;
            let keep = by_id
                .get(&result.job.id)
                .is_none_or(|(old, _)| old.status != "ok" || result.status == "ok");
            if keep {
                by_id.insert(result.job.id.clone(), (result, dir.clone()));
            }
        }
    }
    let mut results: Vec<(JobResult, PathBuf)> = by_id.into_values().collect();
    results.sort_by_key(|(r, _)| r.job.index);
    Ok(results)
}

/// What `refract report` wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReportSummary {
    /// Job results gathered.
    pub jobs: usize,
    /// Of which failed.
    pub failed: usize,
    /// Plots written.
    pub plots: usize,
    /// The output directory (`index.html`, `report.md`, `results.json`).
    pub out: PathBuf,
    /// Images the results name that none of the directories has (marked on the page).
    pub missing: Vec<String>,
}

/// Gathers the job results under `args.dirs` (shards) into `args.out`: their images,
/// `results.json`, the plots, `report.md` and the interactive `index.html`.
pub fn run(args: &ReportArgs) -> crate::Result<ReportSummary> {
    let results = merge(&args.dirs)?;
    crate::ensure!(
        !results.is_empty(),
        "no job results under {}",
        args.dirs
            .iter()
            .map(|d| d.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    let images_dir = args.out.join("images");
    // Remembered, so that a report that fails later removes it (issue 54 #14).
    crate::output_dirs::create_dir(&images_dir)
        .with_context(|| format!("{}: cannot create the directory", images_dir.display()))?;
    for (result, dir) in &results {
        let files = result
            .images
            .as_ref()
            .map(|i| i.files())
            .unwrap_or_default();
        for image in files {
            let (from, to) = (dir.join(image), args.out.join(image));
            if from.is_file() && !to.is_file() {
                std::fs::copy(&from, &to)
                    .with_context(|| format!("copying {} to {}", from.display(), to.display()))?;
            }
        }
    }
    let results: Vec<JobResult> = results.into_iter().map(|(r, _)| r).collect();
    write_text_atomically(
        &args.out.join("results.json"),
        &serde_json::to_string_pretty(&results).context("serialising results")?,
    )?;
    let Page { plots, missing } = write_html(&args.out, &results)?;
    write_text_atomically(&args.out.join("report.md"), &markdown(&results, &plots))?;
    Ok(ReportSummary {
        jobs: results.len(),
        failed: results.iter().filter(|r| r.status != "ok").count(),
        plots: plots.len(),
        out: args.out.clone(),
        missing,
    })
}

/// Writes the plots, the scripts and the interactive `index.html` of `results` into `out`
/// (whose `images/` or scene directories hold the images the results name); returns the plots
/// and the images that are missing.
pub fn write_html(out: &Path, results: &[JobResult]) -> crate::Result<Page> {
    let plots = crate::plots::write_plots(out, results)?;
    write_text_atomically(&out.join("img-comparison-slider.js"), SLIDER_JS)?;
    write_text_atomically(&out.join("report.js"), REPORT_JS)?;
    let all_images = out.join("all-images.html").is_file();
    let missing = missing_images(out, results);
    write_text_atomically(
        &out.join("index.html"),
        &html(results, &plots, all_images, &missing)?,
    )?;
    Ok(Page { plots, missing })
}

/// What `write_html` wrote: the plots as `(file, title)`, and the images the results name that
/// are not under the output directory (the page says so and marks their thumbnails).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Page {
    /// The plots, `(file, title)`.
    pub plots: Vec<(String, String)>,
    /// The images named by the results but missing, relative to the output directory.
    pub missing: Vec<String>,
}

/// The images `results` name that are not files under `out`, in the results' order.
fn missing_images(out: &Path, results: &[JobResult]) -> Vec<String> {
    results
        .iter()
        .filter_map(|r| r.images.as_ref())
        .flat_map(|i| i.files())
        .filter(|file| !out.join(file).is_file())
        .map(str::to_owned)
        .collect()
}

fn cell(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "–".to_owned(), |v| format!("{v:.digits$}"))
}

/// A table column: its header and how a result shows in it.
type Column = (&'static str, fn(&JobResult) -> String);

/// A job's parameters that differ from its method's defaults, `name=value` (`–` for none): a
/// compare job lists every parameter, which wrapped into four lines of the table.
fn non_default_params(r: &JobResult) -> String {
    let defaults = r
        .job
        .method
        .parse::<MethodId>()
        .ok()
        .map(refract_scene::MethodParams::defaults);
    let changed: Vec<String> = r
        .job
        .params
        .iter()
        .filter(|(k, v)| defaults.as_ref().and_then(|d| d.get(k)).as_ref() != Some(*v))
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    if changed.is_empty() {
        "–".to_owned()
    } else {
        changed.join(" ")
    }
}

/// The table columns.
fn columns() -> Vec<Column> {
    fn m(r: &JobResult) -> Option<&MetricsRecord> {
        r.metrics.as_ref()
    }
    vec![
        ("job", |r| r.job.id.clone()),
        ("scene", |r| r.job.scene.clone()),
        ("IOR", |r| {
            r.job
                .ior
                .map_or_else(|| "scene".to_owned(), |i| i.to_string())
        }),
        ("res", |r| r.job.res.to_string()),
        ("backend", |r| r.job.backend.clone()),
        ("method", |r| r.job.method.clone()),
        ("params (not default)", non_default_params),
        ("status", |r| r.status.clone()),
        ("PSNR (dB)", |r| cell(m(r).and_then(|m| m.psnr_ldr_db), 2)),
        ("mean FLIP", |r| cell(m(r).and_then(|m| m.flip_mean), 4)),
        ("T2 error, no TIR (°)", |r| {
            cell(m(r).and_then(|m| m.t2_angle_deg_mean_non_tir), 3)
        }),
        ("T2 p90, no TIR (°)", |r| {
            cell(m(r).and_then(|m| m.t2_angle_deg_p90_non_tir), 3)
        }),
        ("|P~2−P2|/diam, no TIR", |r| {
            cell(m(r).and_then(|m| m.p2_error_rel_mean_non_tir), 4)
        }),
        ("TIR (%)", |r| {
            cell(m(r).and_then(|m| m.tir_fraction).map(|v| 100.0 * v), 1)
        }),
        ("misses vs reference (%)", |r| {
            cell(m(r).and_then(|m| m.nearby_miss_rate).map(|v| 100.0 * v), 1)
        }),
        ("ms / frame", |r| cell(m(r).and_then(|m| m.ms_per_frame), 2)),
    ]
}

fn markdown(results: &[JobResult], plots: &[(String, String)]) -> String {
    let mut md = String::from("# refract sweep report\n\n");
    let _ = writeln!(
        md,
        "{} jobs. Errors against the exact reference over refractor pixels (`docs/metrics.md`); \
         times: median colour-only frame on the machine that ran the job.\n",
        results.len()
    );
    let cols = columns();
    let _ = writeln!(
        md,
        "| {} |\n|{}|",
        cols.iter().map(|c| c.0).collect::<Vec<_>>().join(" | "),
        vec!["---"; cols.len()].join("|")
    );
    for r in results {
        let row: Vec<String> = cols.iter().map(|c| c.1(r)).collect();
        let _ = writeln!(md, "| {} |", row.join(" | "));
    }
    for r in results.iter().filter(|r| r.status != "ok") {
        let _ = writeln!(
            md,
            "\nFailed: `{}`: {}",
            r.job.id,
            r.error.as_deref().unwrap_or("")
        );
    }
    for (file, title) in plots {
        let png = crate::plots::print_png(file);
        let _ = writeln!(
            md,
            "\n## {title}\n\n![{title}]({file})\n\nFor print: [{png}]({png}) ({} dpi).",
            crate::plots::PRINT_DPI
        );
    }
    md
}

/// The link to plot `file`'s print PNG, as a caption under it.
fn print_link(file: &str) -> String {
    let png = crate::plots::print_png(file);
    format!(
        "<figcaption class=\"print\"><a href=\"{png}\">PNG, {} dpi, for print</a></figcaption>",
        crate::plots::PRINT_DPI
    )
}

/// A job's clickable thumbnail: a `figure.thumb` with what the A/B viewer (`report.js`) needs
/// as data attributes (`class` adds classes; the figure of a missing image is marked, not
/// clickable).
fn thumb_figure(r: &JobResult, imgs: &JobImages, missing: &[String], class: &str) -> String {
    let miss = imgs.miss.as_deref().unwrap_or("");
    let (hdr, reference_hdr) = (
        imgs.color_hdr.as_deref().unwrap_or(""),
        imgs.reference_hdr.as_deref().unwrap_or(""),
    );
    let params: Vec<String> = r
        .job
        .params
        .iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    let caption = format!("{} {} {}", r.job.method, r.job.backend, params.join(" "));
    if missing.contains(&imgs.color) {
        return format!(
            "<figure class=\"failed\"><figcaption>missing: {}<br>{}</figcaption></figure>",
            escape(&imgs.color),
            escape(&caption)
        );
    }
    format!(
        "<figure class=\"{class}\" data-image=\"{}\" data-flip=\"{}\" data-t2=\"{}\" data-reference=\"{}\" data-miss=\"{miss}\" \
data-hdr=\"{hdr}\" data-reference-hdr=\"{reference_hdr}\" data-title=\"{}\"><img src=\"{}\" loading=\"lazy\"><figcaption>{}</figcaption></figure>",
        imgs.color,
        imgs.flip,
        imgs.t2,
        imgs.reference,
        escape(&format!("{} — {caption}", r.job.id)),
        imgs.color,
        escape(&caption)
    )
}

fn html(
    results: &[JobResult],
    plots: &[(String, String)],
    all_images: bool,
    missing: &[String],
) -> crate::Result<String> {
    let cols = columns();
    let mut h = String::new();
    let _ = write!(
        h,
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>refract sweep report</title>\
<script src=\"img-comparison-slider.js\" defer></script><script src=\"report.js\" defer></script><style>\
body{{font-family:system-ui,sans-serif;margin:24px;color:#222;background:#fafafa}}\
table{{border-collapse:collapse;margin:12px 0}}td,th{{padding:3px 8px;border-bottom:1px solid #ddd;text-align:right;white-space:nowrap}}\
th{{background:#eee;cursor:pointer;user-select:none}}th.asc::after{{content:' ▲'}}th.desc::after{{content:' ▼'}}\
td:nth-child(-n+8),th:nth-child(-n+8){{text-align:left}}td:nth-child(7){{font-size:12px}}.grid{{display:grid;gap:6px;margin:8px 0}}.grid figure{{margin:0;cursor:pointer}}\
.grid img{{width:160px;image-rendering:pixelated;border:1px solid #ccc}}figcaption{{font-size:11px;color:#555;max-width:160px}}\
#viewer{{display:none;position:fixed;inset:0;background:#181818;color:#eee;z-index:10}}\
#viewer.open{{display:flex;flex-direction:column}}#bar{{padding:8px 12px;font-size:14px}}#bar kbd{{background:#444;border-radius:3px;padding:0 4px}}\
#stage{{flex:1;overflow:hidden;display:flex;align-items:center;justify-content:center}}\
#stage img,#stage canvas{{image-rendering:pixelated;transform-origin:0 0}}img-comparison-slider{{--divider-width:2px;--divider-color:#ff0}}\
.plots img{{max-width:100%;background:#fff;border:1px solid #ccc;margin:6px 0}}.failed,.failed figcaption{{color:#b00}}\
.grid figure.failed{{width:160px;min-height:160px;border:1px dashed #b00;box-sizing:border-box;padding:4px;cursor:default}}\
h1{{margin:0 0 4px;font-size:22px}}body>p:first-of-type{{margin:0 0 6px;font-size:13px}}\
#controls{{display:flex;gap:14px;align-items:center;font-size:13px;margin:4px 0}}#controls .hint{{color:#777}}\
#scale{{display:inline-flex;align-items:center;gap:4px;font-size:12px}}#scale i{{display:inline-block;width:120px;height:10px}}\
#matrix{{margin:4px 0}}#matrix th,#matrix td{{padding:1px 3px;border:0;font-size:12px}}#matrix thead th{{background:none;cursor:default;text-align:center}}\
#matrix tbody th{{background:none;text-align:right;white-space:nowrap;cursor:default}}\
#matrix .cell{{display:none;align-items:center;gap:3px;border-radius:3px;padding:1px 3px 1px 1px}}\
#matrix[data-backend=cpu] .cell[data-backend=cpu],#matrix[data-backend=gpu] .cell[data-backend=gpu],#matrix .cell.only{{display:flex}}\
#matrix figure{{margin:0;cursor:pointer}}#matrix figure img{{width:36px;height:36px;display:block;border:0}}#matrix figcaption{{display:none}}\
#matrix .v{{font-variant-numeric:tabular-nums;min-width:42px;text-align:right}}\
#filters{{display:flex;gap:14px;font-size:13px}}</style></head><body>\
<h1>refract report</h1><p>{} jobs{}. Click a column to sort; click a thumbnail to compare it with the reference \
(keys in the viewer). Errors against the exact reference over refractor pixels (<code>docs/metrics.md</code>).</p>",
        results.len(),
        if all_images {
            " (<a href=\"all-images.html\">every image on one page</a>)"
        } else {
            ""
        }
    );
    if !missing.is_empty() {
        let shown: Vec<String> = missing.iter().take(8).map(|f| escape(f)).collect();
        let _ = write!(
            h,
            "<p class=\"failed\" id=\"missing\">{} images the results name are missing from this \
             directory: {}{}. Their thumbnails are marked <em>missing</em>.</p>",
            missing.len(),
            shown.join(", "),
            if missing.len() > shown.len() {
                ", …"
            } else {
                ""
            }
        );
    }
    h.push_str(&crate::overview::matrix_html(results, |r, class| {
        r.images.as_ref().map_or_else(String::new, |imgs| {
            thumb_figure(r, imgs, missing, &format!("thumb {class}"))
        })
    }));
    // Under the matrix: error against frame time per scene, with the Pareto fronts.
    let (trade_off, other_plots): (Vec<_>, Vec<_>) = plots
        .iter()
        .partition(|(file, _)| file == "error-vs-time.svg");
    for (file, title) in &trade_off {
        let _ = write!(
            h,
            "<div class=\"plots\"><img id=\"trade-off\" src=\"{file}\" alt=\"{}\">{}</div>",
            escape(title),
            print_link(file)
        );
    }
    h.push_str("<h2>Every job</h2><table id=\"metrics\"><thead><tr>");
    for (name, _) in &cols {
        let _ = write!(h, "<th>{}</th>", escape(name));
    }
    h.push_str("</tr></thead><tbody>");
    for r in results {
        let class = if r.status == "ok" {
            ""
        } else {
            " class=\"failed\""
        };
        let _ = write!(h, "<tr{class}>");
        for (_, value) in &cols {
            let _ = write!(h, "<td>{}</td>", escape(&value(r)));
        }
        h.push_str("</tr>");
    }
    h.push_str("</tbody></table>");
    for r in results.iter().filter(|r| r.status != "ok") {
        let _ = write!(
            h,
            "<p class=\"failed\">Failed: <code>{}</code>: {}</p>",
            escape(&r.job.id),
            escape(r.error.as_deref().unwrap_or(""))
        );
    }
    if !other_plots.is_empty() {
        h.push_str("<h2>Plots</h2><div class=\"plots\">");
        for (file, title) in other_plots {
            let _ = write!(
                h,
                "<figure><img src=\"{file}\" alt=\"{}\">{}</figure>",
                escape(title),
                print_link(file)
            );
        }
        h.push_str("</div>");
    }
    // Per scene group (scene, IOR, resolution): a method × backend grid of thumbnails.
    let mut groups: BTreeMap<(String, String, u32), Vec<&JobResult>> = BTreeMap::new();
    for r in results.iter().filter(|r| r.images.is_some()) {
        let ior = r
            .job
            .ior
            .map_or_else(|| "scene".to_owned(), |i| i.to_string());
        groups
            .entry((r.job.scene.clone(), ior, r.job.res))
            .or_default()
            .push(r);
    }
    for ((scene, ior, res), jobs) in &groups {
        let backends: Vec<&str> = {
            let mut b: Vec<&str> = jobs.iter().map(|r| r.job.backend.as_str()).collect();
            b.sort_unstable();
            b.dedup();
            b
        };
        let _ = write!(
            h,
            "<h2>{} — IOR {}, {res}²</h2><div class=\"grid\" style=\"grid-template-columns:repeat({},max-content)\">",
            escape(scene),
            escape(ior),
            backends.len()
        );
        let mut ordered = jobs.clone();
        ordered.sort_by_key(|r| {
            let method = r
                .job
                .method
                .parse::<MethodId>()
                .map_or(usize::MAX, |m| m as usize);
            (method, r.job.params.clone(), r.job.backend.clone())
        });
        for r in ordered {
            let Some(imgs) = &r.images else { continue };
            h.push_str(&thumb_figure(r, imgs, missing, "thumb"));
        }
        h.push_str("</div>");
    }
    h.push_str(
        "<div id=\"viewer\"><div id=\"bar\"></div><div id=\"stage\"></div></div></body></html>\n",
    );
    Ok(h)
}
