//! `metrics.json`, `report.md`, `index.html` (the interactive page of `refract report`) and
//! `all-images.html` (every image of every method on one page) of a comparison.

use std::fmt::Write as _;
use std::path::Path;

use crate::error::Context;
use refract_eval::atomic_write::write_text_atomically;
use refract_eval::metrics::MetricsRecord;

use refract_eval::images::{P2_SCALE, T2_SCALE_DEG};

use crate::jobs::{CompareOptions, Job, JobImages, JobResult};

/// The images of one method on one backend.
pub struct MethodImages {
    /// `method-backend`.
    pub stem: String,
    /// Whether a `|P~2 − P2|` map was written.
    pub has_p2: bool,
    /// Whether a missed-geometry mask was written (nearby-geometry methods).
    pub has_miss: bool,
}

/// The images written for one scene.
pub struct SceneImages {
    /// Scene name (its subdirectory).
    pub scene: String,
    /// Its methods.
    pub methods: Vec<MethodImages>,
}

fn write_atomically(path: &Path, text: &str) -> crate::Result<()> {
    Ok(write_text_atomically(path, text)?)
}

fn cell(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "–".to_owned(), |v| format!("{v:.digits$}"))
}

fn table_rows(records: &[MetricsRecord]) -> Vec<[String; 14]> {
    records
        .iter()
        .map(|r| {
            [
                r.scene.clone(),
                r.method.clone(),
                r.backend.clone(),
                r.params.clone(),
                cell(r.psnr_ldr_db, 2),
                cell(r.rel_mse, 4),
                cell(r.flip_mean, 4),
                cell(r.t2_angle_deg_mean, 3),
                cell(r.t2_angle_deg_mean_non_tir, 3),
                cell(r.t2_angle_deg_p90_non_tir, 3),
                cell(r.p2_error_rel_mean_non_tir, 4),
                cell(r.p2_error_px_p90_non_tir, 2),
                cell(r.tir_fraction.map(|t| 100.0 * t), 1),
                cell(r.ms_per_frame, 2),
            ]
        })
        .collect()
}

const HEADERS: [&str; 14] = [
    "scene",
    "method",
    "backend",
    "parameters",
    "PSNR LDR (dB)",
    "rel. MSE",
    "mean FLIP",
    "T2 error (°)",
    "T2 error, no TIR (°)",
    "T2 error p90, no TIR (°)",
    "|P~2−P2|/diam, no TIR",
    "|P~2−P2| p90 (px), no TIR",
    "TIR (%)",
    "ms / frame",
];

/// The nearby-geometry table (Wyman 2005b methods only): the hit/miss confusion against the
/// reference, the `P_geom` errors, the lookup alone, iterations and the Fig. 9 guarantee.
fn nearby_table(records: &[MetricsRecord]) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let headers = vec![
        "scene",
        "method",
        "backend",
        "hit both / method only / reference only / neither",
        "misses vs reference (%)",
        "P_geom error (world)",
        "P_geom p50 / p90 (NG px)",
        "lookup error p50 / p90 (NG px)",
        "lookup misses (%)",
        "iterations",
        "features ≥ 3 / ≥ 10 px guaranteed (%)",
    ];
    let pct = |v: Option<f64>| cell(v.map(|v| 100.0 * v), 1);
    let rows = records
        .iter()
        .filter_map(|r| {
            let c = r.nearby_confusion?;
            Some(vec![
                r.scene.clone(),
                r.method.clone(),
                r.backend.clone(),
                format!("{} / {} / {} / {}", c[0], c[1], c[2], c[3]),
                pct(r.nearby_miss_rate),
                cell(r.p_geom_error_world_mean, 4),
                format!(
                    "{} / {}",
                    cell(r.p_geom_error_px_p50, 1),
                    cell(r.p_geom_error_px_p90, 1)
                ),
                format!(
                    "{} / {}",
                    cell(r.lookup_error_px_p50, 2),
                    cell(r.lookup_error_px_p90, 1)
                ),
                pct(r.lookup_miss_rate),
                cell(r.iterations_mean, 2),
                format!(
                    "{} / {}",
                    pct(r.feature_guarantee_3px_share),
                    pct(r.feature_guarantee_10px_share)
                ),
            ])
        })
        .collect();
    (headers, rows)
}

/// The method × scene matrix of one backend's records as a Markdown table: each cell the mean
/// FLIP over the refractor's pixels and the frame time, the lowest FLIP of each scene in bold,
/// `–` where the method does not run on the scene.
fn matrix_markdown(records: &[MetricsRecord], backend: &str) -> Option<String> {
    let rows: Vec<&MetricsRecord> = records.iter().filter(|r| r.backend == backend).collect();
    if rows.is_empty() {
        return None;
    }
    let mut scenes: Vec<&str> = Vec::new();
    let mut methods: Vec<&str> = Vec::new();
    for r in &rows {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    let find = |method: &str, scene: &str| {
        rows.iter()
            .find(|r| r.method == method && r.scene == scene)
            .copied()
    };
    let best: Vec<Option<f64>> = scenes
        .iter()
        .map(|scene| {
            rows.iter()
                .filter(|r| r.scene == *scene)
                .filter_map(|r| r.flip_mean)
                .min_by(f64::total_cmp)
        })
        .collect();
    let mut md = String::new();
    let _ = writeln!(md, "| method | {} |", scenes.join(" | "));
    let _ = writeln!(md, "|---|{}|", vec!["---"; scenes.len()].join("|"));
    for method in &methods {
        let cells: Vec<String> = scenes
            .iter()
            .zip(&best)
            .map(|(scene, best)| match find(method, scene) {
                Some(r) => {
                    let flip = cell(r.flip_mean, 3);
                    let flip = if r.flip_mean.is_some() && r.flip_mean == *best {
                        format!("**{flip}**")
                    } else {
                        flip
                    };
                    format!("{flip} · {} ms", cell(r.ms_per_frame, 1))
                }
                None => "–".to_owned(),
            })
            .collect();
        let _ = writeln!(md, "| `{method}` | {} |", cells.join(" | "));
    }
    Some(md)
}

/// Writes the three report files.
pub fn write_reports(
    out: &Path,
    records: &[MetricsRecord],
    scenes: &[SceneImages],
    options: &CompareOptions,
) -> crate::Result<()> {
    let json = serde_json::to_string_pretty(records).context("serialising metrics")?;
    write_atomically(&out.join("metrics.json"), &json)?;

    let rows = table_rows(records);
    let mut md = String::new();
    let _ = writeln!(md, "# refract comparison\n");
    let _ = writeln!(
        md,
        "{}², reference: exact tracer, `transmission` mode, {} spp, depth 8. Times: median of {} colour-only frames \
         after 2 warm-up frames (buffers + kernel; GPU: timestamp queries around all passes), this machine.\n",
        options.res, options.spp, options.frames
    );
    for backend in ["cpu", "gpu"] {
        if let Some(matrix) = matrix_markdown(records, backend) {
            let _ = writeln!(
                md,
                "## Methods × scenes, {} backend

Mean FLIP over the refractor's pixels (0:                  identical to the reference; the lowest of each scene in bold) · median frame time.                  `–`: the method does not run on that scene.

{matrix}",
                backend.to_uppercase()
            );
        }
    }
    let _ = writeln!(
        md,
        "## Every job
"
    );
    let _ = writeln!(md, "| {} |", HEADERS.join(" | "));
    let _ = writeln!(md, "|{}|", ["---"; HEADERS.len()].join("|"));
    for row in &rows {
        let _ = writeln!(md, "| {} |", row.join(" | "));
    }
    let (nearby_headers, nearby_rows) = nearby_table(records);
    if !nearby_rows.is_empty() {
        let _ = writeln!(
            md,
            "\n## Nearby geometry (Wyman 2005b)\n\nOver the pixels where both see the refractor; \
             \"lookup\" compares with the exact hit of the method's own ray (`docs/metrics.md`).\n"
        );
        let _ = writeln!(md, "| {} |", nearby_headers.join(" | "));
        let _ = writeln!(md, "|{}|", vec!["---"; nearby_headers.len()].join("|"));
        for row in &nearby_rows {
            let _ = writeln!(md, "| {} |", row.join(" | "));
        }
    }
    for scene in scenes {
        let _ = writeln!(md, "\n## {}\n", scene.scene);
        let _ = writeln!(
            md,
            "| reference | method | FLIP | T2 error (0–{T2_SCALE_DEG}°) |\n|---|---|---|---|"
        );
        for m in &scene.methods {
            let (s, m) = (&scene.scene, &m.stem);
            let _ = writeln!(
                md,
                "| ![]({s}/reference.png) | ![]({s}/{m}.png) `{m}` | ![]({s}/flip-{m}.png) | ![]({s}/t2err-{m}.png) |"
            );
        }
    }
    write_atomically(&out.join("report.md"), &md)?;

    let mut html = String::new();
    let _ = write!(
        html,
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>refract comparison</title><style>\
body{{font-family:system-ui,sans-serif;margin:24px;color:#222;background:#fafafa}}\
table{{border-collapse:collapse;margin:12px 0}}td,th{{padding:4px 10px;border-bottom:1px solid #ddd;text-align:right}}\
td:nth-child(-n+4),th:nth-child(-n+4){{text-align:left}}th{{background:#eee}}\
.row{{display:flex;flex-wrap:wrap;gap:8px;align-items:flex-start;margin:8px 0}}.row figure{{margin:0}}\
img{{width:220px;image-rendering:pixelated;border:1px solid #ccc}}img.map{{width:227px}}\
figcaption{{font-size:12px;color:#555}}h2{{margin-top:32px}}</style></head><body>\
<h1>refract comparison</h1><p>{res}&sup2; pixels. Reference: exact ray tracer, transmission mode, {spp} spp, depth 8. \
Times: median of {frames} colour-only frames after 2 warm-up frames, buffers + kernel (GPU: timestamp queries around all passes, queue waited).</p><table><tr>",
        res = options.res,
        spp = options.spp,
        frames = options.frames
    );
    for h in HEADERS {
        let _ = write!(html, "<th>{h}</th>");
    }
    html.push_str("</tr>");
    for row in &rows {
        html.push_str("<tr>");
        for c in row {
            let _ = write!(html, "<td>{c}</td>");
        }
        html.push_str("</tr>");
    }
    let _ = write!(
        html,
        "</table><p>Error maps use the magma colour map with a colour bar on the right: FLIP 0–1, \
T2 angle error 0–{T2_SCALE_DEG}°, |P~2−P2| 0–{P2_SCALE} of the bounding-sphere diameter; grey where a \
quantity does not exist. TIR masks show TIR pixels in magenta; missed-object masks (nearby-geometry methods) show in magenta the pixels where the reference's path meets an opaque object and the method's lookup found none.</p>"
    );
    if !nearby_rows.is_empty() {
        html.push_str("<h2>Nearby geometry (Wyman 2005b)</h2><table><tr>");
        for h in &nearby_headers {
            let _ = write!(html, "<th>{h}</th>");
        }
        html.push_str("</tr>");
        for row in &nearby_rows {
            html.push_str("<tr>");
            for c in row {
                let _ = write!(html, "<td>{c}</td>");
            }
            html.push_str("</tr>");
        }
        html.push_str("</table>");
    }
    for scene in scenes {
        let s = &scene.scene;
        let _ = write!(html, "<h2>{s}</h2>");
        for images in &scene.methods {
            let m = &images.stem;
            let _ = write!(
                html,
                "<div class=\"row\"><figure><img src=\"{s}/reference.png\"><figcaption>reference</figcaption></figure>\
<figure><img src=\"{s}/{m}.png\"><figcaption>{m}</figcaption></figure>\
<figure><img class=\"map\" src=\"{s}/flip-{m}.png\"><figcaption>FLIP (0–1)</figcaption></figure>\
<figure><img class=\"map\" src=\"{s}/t2err-{m}.png\"><figcaption>T2 error (0–{T2_SCALE_DEG}°)</figcaption></figure>"
            );
            if images.has_p2 {
                let _ = write!(
                    html,
                    "<figure><img class=\"map\" src=\"{s}/p2err-{m}.png\"><figcaption>|P~2−P2| (0–{P2_SCALE} diam)</figcaption></figure>"
                );
            }
            if images.has_miss {
                let _ = write!(
                    html,
                    "<figure><img src=\"{s}/miss-{m}.png\"><figcaption>missed objects ({m})</figcaption></figure>"
                );
            }
            let _ = write!(
                html,
                "<figure><img src=\"{s}/tir-{m}.png\"><figcaption>TIR ({m})</figcaption></figure></div>"
            );
        }
    }
    html.push_str("</body></html>\n");
    write_atomically(&out.join("all-images.html"), &html)?;
    // index.html: the interactive page of `refract report` over the same results.
    let results = job_results(records, scenes, options.res);
    crate::sweep_report::write_html(out, &results)?;
    Ok(())
}

/// The comparison's method rows as the job results the interactive report reads (the
/// reference rows are its "reference" side).
fn job_results(records: &[MetricsRecord], scenes: &[SceneImages], res: u32) -> Vec<JobResult> {
    records
        .iter()
        .filter(|r| r.method != "reference")
        .enumerate()
        .map(|(index, r)| {
            let stem = format!("{}-{}", r.method, r.backend);
            let s = &r.scene;
            let has_miss = scenes
                .iter()
                .find(|i| &i.scene == s)
                .and_then(|i| i.methods.iter().find(|m| m.stem == stem))
                .is_some_and(|m| m.has_miss);
            let images = JobImages {
                color: format!("{s}/{stem}.png"),
                flip: format!("{s}/flip-{stem}.png"),
                t2: format!("{s}/t2err-{stem}.png"),
                reference: format!("{s}/reference.png"),
                miss: has_miss.then(|| format!("{s}/miss-{stem}.png")),
                color_hdr: Some(format!("{s}/{stem}.hdr.js")),
                reference_hdr: Some(format!("{s}/reference.hdr.js")),
            };
            JobResult {
                job: Job {
                    index,
                    id: format!("{s}-{res}-{stem}"),
                    scene: s.clone(),
                    ior: None,
                    res,
                    backend: r.backend.clone(),
                    method: r.method.clone(),
                    params: r
                        .params
                        .split_whitespace()
                        .filter_map(|p| p.split_once('='))
                        .map(|(k, v)| (k.to_owned(), v.to_owned()))
                        .collect(),
                },
                status: "ok".to_owned(),
                error: None,
                metrics: Some(r.clone()),
                images: Some(images),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(scene: &str, method: &str, backend: &str, flip: f64, ms: f64) -> MetricsRecord {
        MetricsRecord {
            scene: scene.to_owned(),
            method: method.to_owned(),
            backend: backend.to_owned(),
            flip_mean: Some(flip),
            ms_per_frame: Some(ms),
            ..MetricsRecord::default()
        }
    }

    /// The matrix has a row per method and a column per scene, the lowest FLIP of each scene in
    /// bold, `–` for a pair that did not run, and one backend's records only.
    #[test]
    fn the_matrix_marks_the_best_method_per_scene() {
        let records = [
            record("sphere", "reference", "trace", 0.0, 300.0),
            record("sphere", "single", "cpu", 0.30, 2.0),
            record("sphere", "wyman", "cpu", 0.10, 4.0),
            record("torus", "single", "cpu", 0.20, 2.0),
            record("sphere", "wyman", "gpu", 0.01, 1.0),
        ];
        let md = matrix_markdown(&records, "cpu").expect("cpu rows");
        let lines: Vec<&str> = md.lines().collect();
        assert_eq!(lines[0], "| method | sphere | torus |");
        assert_eq!(
            lines[2],
            "| `single` | 0.300 · 2.0 ms | **0.200** · 2.0 ms |"
        );
        assert_eq!(lines[3], "| `wyman` | **0.100** · 4.0 ms | – |");
        assert_eq!(lines.len(), 4, "{md}");
        assert!(matrix_markdown(&records, "none").is_none());
    }
}
