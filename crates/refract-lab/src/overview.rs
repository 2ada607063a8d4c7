//! The first screen of a report page: a method × scene matrix, each cell the method's image on
//! that scene and its error against the reference, coloured on one scale per metric, for one
//! backend at a time (`assets/report.js` switches the metric and the backend and recolours; a
//! click on a cell opens the A/B viewer on that job).
//!
//! A sweep may hold several jobs per (method, scene, backend) (parameters, IORs,
//! resolutions): a cell shows the first in job order, and says how many more the table holds.

use std::fmt::Write as _;

use crate::html::escape;
use crate::jobs::JobResult;

/// The metrics a cell can show: `(key, label, unit)`; the key is the cell's `data-` attribute.
pub const METRICS: [(&str, &str, &str); 4] = [
    ("flip", "FLIP", ""),
    ("t2", "T2 error", "°"),
    ("p2", "P2 error", "diam"),
    ("ms", "frame time", "ms"),
];

/// A metric's value of a job, as the cell's data attribute holds it (empty: none).
fn value(result: &JobResult, key: &str) -> String {
    let Some(m) = &result.metrics else {
        return String::new();
    };
    let v = match key {
        "flip" => m.flip_mean,
        "t2" => m.t2_angle_deg_mean_non_tir,
        "p2" => m.p2_error_rel_mean_non_tir,
        "ms" => m.ms_per_frame,
        _ => None,
    };
    v.map_or_else(String::new, |v| format!("{v:.6}"))
}

/// The order of first appearance of `key` over `results`.
fn distinct<'a>(results: &[&'a JobResult], key: impl Fn(&'a JobResult) -> &'a str) -> Vec<&'a str> {
    let mut seen: Vec<&str> = Vec::new();
    for r in results {
        let k = key(r);
        if !seen.contains(&k) {
            seen.push(k);
        }
    }
    seen
}

/// The overview section's HTML (empty when no job has images). `thumb` writes a cell's
/// clickable figure the way the page's other thumbnails are written (the viewer's data).
pub fn matrix_html(results: &[JobResult], thumb: impl Fn(&JobResult, &str) -> String) -> String {
    let with_images: Vec<&JobResult> = results.iter().filter(|r| r.images.is_some()).collect();
    if with_images.is_empty() {
        return String::new();
    }
    let scenes = distinct(&with_images, |r| r.job.scene.as_str());
    let mut methods = distinct(&with_images, |r| r.job.method.as_str());
    methods.sort_by_key(|m| {
        m.parse::<refract_scene::MethodId>()
            .map_or(usize::MAX, |id| id as usize)
    });
    let mut backends = distinct(&with_images, |r| r.job.backend.as_str());
    backends.sort_unstable();
    // A row rendered by one backend only (an engine's own renderer: `webgl`) shows whichever
    // backend is selected; the switch lists the backends the other rows share.
    let backends_of = |method: &str| {
        distinct(&with_images, |r| r.job.backend.as_str())
            .into_iter()
            .filter(|b| {
                with_images
                    .iter()
                    .any(|r| r.job.method == method && r.job.backend == *b)
            })
            .count()
    };
    let switched: Vec<&str> = backends
        .iter()
        .copied()
        .filter(|b| {
            with_images
                .iter()
                .any(|r| r.job.backend == *b && backends_of(&r.job.method) > 1)
        })
        .collect();
    let switched = if switched.is_empty() {
        backends.clone()
    } else {
        switched
    };

    let mut h = String::new();
    h.push_str("<section id=\"overview\"><div id=\"controls\"><label>error <select id=\"metric\">");
    for (key, label, unit) in METRICS {
        let unit = if unit.is_empty() {
            String::new()
        } else {
            format!(" ({unit})")
        };
        let _ = write!(h, "<option value=\"{key}\">{label}{unit}</option>");
    }
    h.push_str("</select></label>");
    for (i, backend) in switched.iter().enumerate() {
        let checked = if i == 0 { " checked" } else { "" };
        let _ = write!(
            h,
            "<label><input type=\"radio\" name=\"backend\" value=\"{b}\"{checked}> {B}</label>",
            b = escape(backend),
            B = escape(&backend.to_uppercase())
        );
    }
    h.push_str(
        "<span id=\"scale\"></span><span class=\"hint\">lower is better in every metric; \
         click a cell to compare it with the reference</span></div>",
    );
    let _ = write!(
        h,
        "<table id=\"matrix\" data-backend=\"{}\"><thead><tr><th></th>",
        escape(switched.first().copied().unwrap_or("cpu"))
    );
    for scene in &scenes {
        let _ = write!(h, "<th>{}</th>", escape(scene));
    }
    h.push_str("</tr></thead><tbody>");
    for method in &methods {
        let only = if backends_of(method) == 1 {
            " only"
        } else {
            ""
        };
        let _ = write!(h, "<tr><th>{}</th>", escape(method));
        for scene in &scenes {
            h.push_str("<td>");
            for backend in &backends {
                let jobs: Vec<&&JobResult> = with_images
                    .iter()
                    .filter(|r| {
                        r.job.method == *method
                            && r.job.scene == *scene
                            && r.job.backend == *backend
                    })
                    .collect();
                let Some(first) = jobs.first() else { continue };
                let _ = write!(
                    h,
                    "<div class=\"cell{only}\" data-backend=\"{}\"",
                    escape(backend)
                );
                for (key, _, _) in METRICS {
                    let _ = write!(h, " data-{key}=\"{}\"", value(first, key));
                }
                if jobs.len() > 1 {
                    let _ = write!(h, " title=\"{} more jobs in the table\"", jobs.len() - 1);
                }
                h.push('>');
                h.push_str(&thumb(first, "cell-thumb"));
                h.push_str("<span class=\"v\"></span></div>");
            }
            h.push_str("</td>");
        }
        h.push_str("</tr>");
    }
    h.push_str("</tbody></table></section>");
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::jobs::{Job, JobImages};
    use refract_eval::metrics::MetricsRecord;

    fn result(scene: &str, method: &str, backend: &str, flip: f64) -> JobResult {
        JobResult {
            job: Job {
                index: 0,
                id: format!("{scene}-{method}-{backend}"),
                scene: scene.to_owned(),
                ior: None,
                res: 64,
                backend: backend.to_owned(),
                method: method.to_owned(),
                params: Default::default(),
            },
            status: "ok".to_owned(),
            error: None,
            metrics: Some(MetricsRecord {
                flip_mean: Some(flip),
                ..MetricsRecord::default()
            }),
            images: Some(JobImages::default()),
        }
    }

    /// Methods in registry order as rows, scenes in job order as columns, one cell per backend
    /// with its values; a pair that did not run has an empty cell.
    #[test]
    fn the_matrix_has_a_row_per_method_and_a_cell_per_backend() {
        let results = [
            result("torus", "wyman", "gpu", 0.2),
            result("torus", "single", "cpu", 0.5),
            result("sphere", "wyman", "cpu", 0.1),
            result("torus", "threejs@0.187.0", "webgl", 0.4),
        ];
        let h = matrix_html(&results, |r, class| format!("<fig {class} {}>", r.job.id));
        let header = h
            .find("<th>torus</th><th>sphere</th>")
            .expect("scenes in job order");
        let single = h.find("<tr><th>single</th>").expect("single row");
        let wyman = h.find("<tr><th>wyman</th>").expect("wyman row");
        assert!(header < single && single < wyman, "registry order: {h}");
        assert!(
            h.contains("data-backend=\"gpu\" data-flip=\"0.200000\""),
            "{h}"
        );
        assert!(h.contains("<fig cell-thumb sphere-wyman-cpu>"), "{h}");
        // single ran on the CPU only: its cells show whichever backend is selected; on
        // sphere it did not run: an empty cell.
        assert!(h.contains("<tr><th>single</th><td><div class=\"cell only\" data-backend=\"cpu\" data-flip=\"0.500000\""), "{h}");
        assert!(h.contains("</td><td></td></tr>"), "{h}");
        assert!(
            h.contains("<div class=\"cell\" data-backend=\"gpu\""),
            "{h}"
        );
        // The engine's row shows under either switch position, which lists cpu and gpu only.
        assert!(
            h.contains(
                "<tr><th>threejs@0.187.0</th><td><div class=\"cell only\" data-backend=\"webgl\""
            ),
            "{h}"
        );
        assert!(
            h.contains("value=\"cpu\" checked") && h.contains("value=\"gpu\">"),
            "{h}"
        );
        assert!(!h.contains("value=\"webgl\""), "{h}");
        assert_eq!(matrix_html(&[], |_, _| String::new()), "");
    }
}
