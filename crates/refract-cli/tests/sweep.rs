//! `refract sweep` and `refract report` end to end: shards in parallel processes merge to the
//! unsharded result, re-runs skip finished jobs, failures are recorded, and the report works
//! in headless Chromium (when installed; `REFRACT_REQUIRE_BROWSER=1` makes a missing browser a
//! failure, as in CI).

use std::path::Path;
use std::process::{Command, Output};

fn refract(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_refract"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run refract")
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

fn ok(output: &Output) -> String {
    let err = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{err}");
    err
}

const SWEEP: &str = r#"
scenes = ["chart", "sphere"]
methods = ["wyman", "ray-plane", "iterative-seeded"]
res = [24, 32]
ior = [1.2, 1.5]
frames = 1
[params]
seeds = [3, 7]
[[exclude]]
scene = "sphere"
method = "ray-plane"
"#;

/// The results with this machine's timings removed (they differ from run to run).
fn without_timings(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).expect("results.json");
    let mut value: serde_json::Value = serde_json::from_str(&text).expect("json");
    for result in value.as_array_mut().expect("array") {
        if let Some(metrics) = result.get_mut("metrics").and_then(|m| m.as_object_mut()) {
            metrics.insert("ms_per_frame".to_owned(), serde_json::Value::Null);
        }
    }
    value
}

#[test]
fn three_shards_in_parallel_merge_to_the_unsharded_result() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("sweep.toml"), SWEEP).expect("write");
    let exe = env!("CARGO_BIN_EXE_refract");
    let shards: Vec<std::process::Child> = (0..3)
        .map(|i| {
            Command::new(exe)
                .args([
                    "sweep",
                    "sweep.toml",
                    "--shard",
                    &format!("{i}/3"),
                    "--out",
                    &format!("shard{i}"),
                    "--cache",
                    "cache",
                ])
                .current_dir(dir.path())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .expect("spawn a shard")
        })
        .collect();
    for child in shards {
        let output = child.wait_with_output().expect("shard");
        ok(&output);
    }
    ok(&refract(
        &["sweep", "sweep.toml", "--out", "all"],
        dir.path(),
    ));
    ok(&refract(
        &["report", "shard0", "shard1", "shard2", "--out", "merged"],
        dir.path(),
    ));
    ok(&refract(&["report", "all", "--out", "single"], dir.path()));
    let (merged, single) = (
        without_timings(&dir.path().join("merged/results.json")),
        without_timings(&dir.path().join("single/results.json")),
    );
    // chart: 2 res × 2 IORs × (wyman + ray-plane + 2 seeded) = 16; sphere: 2 × 2 × 3 = 12.
    assert_eq!(merged.as_array().map(Vec::len), Some(28));
    assert!(
        merged == single,
        "merged shards differ from the unsharded run"
    );
    assert!(
        merged
            .as_array()
            .expect("array")
            .iter()
            .all(|r| r["status"] == "ok")
    );
    // The shards shared their references through the cache: one per (scene, IOR, resolution).
    let cached = std::fs::read_dir(dir.path().join("cache"))
        .expect("cache")
        .count();
    assert_eq!(cached, 2 * 2 * 2);
    for file in [
        "index.html",
        "report.md",
        "error-vs-ior.svg",
        "error-vs-seeds.svg",
        "time-vs-resolution.svg",
        "error-vs-time.svg",
        "img-comparison-slider.js",
    ] {
        assert!(dir.path().join("merged").join(file).is_file(), "{file}");
    }
    let svg = std::fs::read_to_string(dir.path().join("merged/error-vs-ior.svg")).expect("svg");
    assert!(svg.contains("index of refraction") && svg.contains("mean FLIP"));
    for plot in [
        "error-vs-ior",
        "error-vs-seeds",
        "time-vs-resolution",
        "error-vs-time",
    ] {
        check_print_png(&dir.path().join("merged"), plot);
    }
}

/// Plot `name`'s PNG beside its SVG is the SVG at 300 dpi (its CSS pixels × 300 / 96) and
/// shows its lines and text: dark pixels on at least 0.2 % of it (an SVG rasterised without
/// a font, or not at all, has no text or nothing).
fn check_print_png(dir: &std::path::Path, name: &str) {
    let svg = std::fs::read_to_string(dir.join(format!("{name}.svg"))).expect("svg");
    let attribute = |key: &str| -> f64 {
        let start = svg.find(&format!("{key}=\"")).expect(key) + key.len() + 2;
        let end = start + svg[start..].find('"').expect("quote");
        svg[start..end].parse().expect("a number")
    };
    let png = image::open(dir.join(format!("{name}.png")))
        .expect("png")
        .to_luma8();
    let scale = 300.0 / 96.0;
    assert_eq!(
        (png.width(), png.height()),
        (
            (attribute("width") * scale).round() as u32,
            (attribute("height") * scale).round() as u32
        ),
        "{name}.png"
    );
    let dark = png.pixels().filter(|p| p.0[0] < 80).count();
    let share = dark as f64 / f64::from(png.width() * png.height());
    assert!(share >= 0.002, "{name}.png: dark pixels on {share}");
}

#[test]
fn reruns_skip_finished_jobs_and_failures_are_recorded() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("sweep.toml"),
        "scenes = [\"sphere\", \"missing.toml\"]\nmethods = [\"single\", \"wyman\"]\nres = [16]\nframes = 1\n",
    )
    .expect("write");
    let first = ok(&refract(
        &["sweep", "sweep.toml", "--out", "out"],
        dir.path(),
    ));
    assert!(first.contains("2 finished, 2 failed"), "{first}");
    let failed: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("out/jobs/missing-16-cpu-wyman.json"))
            .expect("failure recorded"),
    )
    .expect("json");
    assert_eq!(failed["status"], "error");
    assert!(
        failed["error"]
            .as_str()
            .is_some_and(|e| e.contains("missing.toml")),
        "{failed}"
    );
    // Finished jobs are skipped; failed ones run again.
    let second = ok(&refract(
        &["sweep", "sweep.toml", "--out", "out"],
        dir.path(),
    ));
    assert!(second.contains("2 to run"), "{second}");
    std::fs::remove_file(dir.path().join("out/jobs/sphere-16-cpu-single.json")).expect("rm");
    let third = ok(&refract(
        &["sweep", "sweep.toml", "--out", "out"],
        dir.path(),
    ));
    assert!(third.contains("3 to run"), "{third}");
    // The report lists the failures.
    ok(&refract(&["report", "out", "--out", "rep"], dir.path()));
    let md = std::fs::read_to_string(dir.path().join("rep/report.md")).expect("report");
    assert!(md.contains("Failed: `missing-16-cpu-wyman`"), "{md}");
    // Issue 54 #21: a shard where every job fails, with nothing finished before, fails (so
    // that `sweep && report` stops), its failures still recorded.
    std::fs::write(
        dir.path().join("broken.toml"),
        "scenes = [\"missing.toml\"]\nmethods = [\"single\"]\nres = [16]\nframes = 1\n",
    )
    .expect("write");
    let broken = refract(&["sweep", "broken.toml", "--out", "broken"], dir.path());
    assert!(!broken.status.success(), "{}", stderr(&broken));
    assert!(
        stderr(&broken).contains("none of the 1 jobs run finished"),
        "{}",
        stderr(&broken)
    );
    assert!(
        dir.path()
            .join("broken/jobs/missing-16-cpu-single.json")
            .is_file()
    );
    // Bad shard arguments are errors naming them.
    let bad = refract(&["sweep", "sweep.toml", "--shard", "3/3"], dir.path());
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("3/3"));
}

/// The report page and its comparison view in headless Chromium: both render, the viewer
/// opens with the A/B slider, and no console message is logged.
#[test]
fn the_report_works_in_headless_chromium() {
    let Some(chromium) = chromium() else {
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("sweep.toml"),
        "scenes = [\"chart\"]\nmethods = [\"wyman\", \"iterative-seeded\"]\nres = [48]\nframes = 1\n",
    )
    .expect("write");
    ok(&refract(
        &["sweep", "sweep.toml", "--out", "out"],
        dir.path(),
    ));
    ok(&refract(&["report", "out", "--out", "rep"], dir.path()));
    let page = dir.path().join("rep/index.html");
    let url = format!("file://{}", page.display());
    let browse = |extra: &[&str], target: &str| browse(chromium, "1100,800", extra, target);
    let shots = dir.path().join("shots");
    std::fs::create_dir_all(&shots).expect("mkdir");
    for (name, target) in [("page", url.clone()), ("viewer", format!("{url}#view=1"))] {
        let png = shots.join(format!("{name}.png"));
        browse(&[&format!("--screenshot={}", png.display())], &target);
        let size = std::fs::metadata(&png).map(|m| m.len()).unwrap_or(0);
        assert!(size > 10_000, "{name} screenshot {size} bytes");
    }
    let dom = browse(&["--dump-dom"], &format!("{url}#view=1"));
    assert!(
        dom.contains("id=\"viewer\" class=\"open\""),
        "viewer not open"
    );
    assert!(dom.contains("<img-comparison-slider"), "no A/B slider");
    // The colour images are canvases of linear radiance (the exposure control's data).
    assert!(dom.contains("data-kind=\"hdr\""), "no HDR canvas");
    let bright = shots.join("viewer-ev2.png");
    browse(
        &[&format!("--screenshot={}", bright.display())],
        &format!("{url}#view=1&ev=2"),
    );
    let (a, b) = (
        std::fs::read(shots.join("viewer.png")).expect("png"),
        std::fs::read(&bright).expect("png"),
    );
    assert!(a != b, "exposure changes the displayed image");
    assert!(
        dom.contains("<th class=") || dom.contains("<th>"),
        "no table"
    );
}

/// The headless browser, or `None` after saying it is skipped (a failure under
/// `REFRACT_REQUIRE_BROWSER=1`).
fn chromium() -> Option<&'static str> {
    let found = ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|b| {
            Command::new(b)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        });
    if found.is_none() {
        assert!(
            !std::env::var("REFRACT_REQUIRE_BROWSER").is_ok_and(|v| v == "1"),
            "REFRACT_REQUIRE_BROWSER=1 but no chromium"
        );
        println!("skipped: chromium not found");
    }
    found
}

/// Headless `chromium` at `window` (`W,H`) on `target` with `extra` flags: its stdout (the DOM
/// with `--dump-dom`); the page must log nothing to the console.
fn browse(chromium: &str, window: &str, extra: &[&str], target: &str) -> String {
    let output = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--enable-logging=stderr",
            "--v=0",
            "--virtual-time-budget=3000",
        ])
        .arg(format!("--window-size={window}"))
        .args(extra)
        .arg(target)
        .output()
        .expect("chromium");
    let log = String::from_utf8_lossy(&output.stderr).into_owned();
    let console: Vec<&str> = log.lines().filter(|l| l.contains(":CONSOLE")).collect();
    assert!(console.is_empty(), "console messages: {console:?}");
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// The first screen of a comparison's `index.html` at 1400 x 900 (issue 31) holds the whole
/// method x scene matrix (every method of the registry: the default job's rows), its cells
/// carry values and colours, and a cell opens the viewer on its job. The screenshots stay in
/// `target/tmp/report-first-screen/` for a person to look at.
#[test]
fn the_first_screen_shows_the_method_scene_matrix() {
    let Some(chromium) = chromium() else {
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    ok(&refract(
        &[
            "compare",
            "sphere",
            "convex-mirror",
            "--res",
            "16",
            "--frames",
            "1",
            "--backends",
            "cpu",
            "--out",
            "out",
        ],
        dir.path(),
    ));
    let url = format!("file://{}", dir.path().join("out/index.html").display());
    let browse = |extra: &[&str], target: &str| browse(chromium, "1400,900", extra, target);
    let shots = Path::new(env!("CARGO_TARGET_TMPDIR")).join("report-first-screen");
    std::fs::create_dir_all(&shots).expect("mkdir");
    for (name, target) in [
        ("first-screen", url.clone()),
        ("cell-opened", format!("{url}#view=0")),
    ] {
        let png = shots.join(format!("{name}.png"));
        browse(&[&format!("--screenshot={}", png.display())], &target);
        assert!(
            png.metadata().map(|m| m.len()).unwrap_or(0) > 10_000,
            "{name}"
        );
        println!("screenshot: {}", png.display());
    }
    let dom = browse(&["--dump-dom"], &url);
    let bottom: u32 = dom
        .split("data-matrix-bottom=\"")
        .nth(1)
        .and_then(|rest| rest.split('"').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("report.js did not lay the matrix out"));
    assert!(
        (100..=900).contains(&bottom),
        "the matrix ends at y = {bottom}, below the first screen"
    );
    let matrix = dom
        .split("id=\"matrix\"")
        .nth(1)
        .and_then(|rest| rest.split("</table>").next())
        .expect("the matrix");
    let rows = matrix.matches("</th><td>").count();
    assert_eq!(
        rows,
        refract_scene::MethodId::approximations().count(),
        "a row per method"
    );
    // report.js wrote each cell's value and colour.
    assert!(
        dom.contains("<span class=\"v\">0."),
        "no values in the cells"
    );
    assert!(
        dom.contains("style=\"background: rgb("),
        "no colours in the cells"
    );
    // The first thumbnail of the page is the matrix's first cell: #view=0 opens it.
    let opened = browse(&["--dump-dom"], &format!("{url}#view=0"));
    assert!(
        opened.contains("id=\"viewer\" class=\"open\""),
        "viewer not open"
    );
    assert!(
        opened.contains("sphere-16-single-cpu"),
        "the viewer shows another job"
    );
}

/// A cache path that is a regular file fails the sweep and leaves no output directory behind
/// (issue 34, item 7).
#[test]
fn a_cache_that_is_a_file_leaves_nothing_behind() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("small.toml"),
        "scenes = [\"sphere\"]\nmethods = [\"single\"]\nres = [16]\nframes = 1\n",
    )
    .expect("write");
    std::fs::write(dir.path().join("cachefile"), "not a directory").expect("write");
    let out = refract(
        &["sweep", "small.toml", "--cache", "cachefile", "--out", "o"],
        dir.path(),
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cachefile"), "{err}");
    assert!(!dir.path().join("o").exists(), "left behind: o/");
}

/// A sweep directory whose images were deleted: `refract report` says how many are missing and
/// the page marks them (issue 34, item 8: it exited 0 without a word, linking missing images).
#[test]
fn the_report_names_missing_images() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("small.toml"),
        "scenes = [\"sphere\"]\nmethods = [\"single\", \"wyman\"]\nres = [16]\nframes = 1\n",
    )
    .expect("write");
    ok(&refract(&["sweep", "small.toml", "--out", "s"], dir.path()));
    std::fs::remove_dir_all(dir.path().join("s/images")).expect("delete the images");
    let out = refract(&["report", "s", "--out", "r"], dir.path());
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("images the results name are missing"), "{err}");
    let page = std::fs::read_to_string(dir.path().join("r/index.html")).expect("page");
    assert!(page.contains("id=\"missing\""), "no missing-images banner");
    // Two jobs, each marked in the overview matrix and in its scene's grid.
    assert_eq!(
        page.matches("missing: images/").count(),
        4,
        "two thumbnails marked twice"
    );
}

/// A cached reference of the wrong size (here another resolution's, copied over it) is not
/// used: the job warns, traces the reference again and replaces the entry (issue 54 #6: it
/// panicked inside the job, and the bad entry stayed).
#[test]
fn a_cached_reference_of_the_wrong_size_is_replaced() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cached = |dir: &Path| -> Vec<std::path::PathBuf> {
        let mut files: Vec<_> = std::fs::read_dir(dir.join("cache"))
            .expect("cache")
            .map(|e| e.expect("entry").path())
            .collect();
        files.sort();
        files
    };
    for res in [16, 24] {
        std::fs::write(
            dir.path().join(format!("r{res}.toml")),
            format!("scenes = [\"sphere\"]\nmethods = [\"single\"]\nres = [{res}]\nframes = 1\nimages = false\n"),
        )
        .expect("write");
    }
    let run = |file: &str, out: &str| {
        refract(
            &["sweep", file, "--cache", "cache", "--out", out],
            dir.path(),
        )
    };
    ok(&run("r16.toml", "a"));
    let small = cached(dir.path()).remove(0);
    ok(&run("r24.toml", "b"));
    let large = cached(dir.path())
        .into_iter()
        .find(|p| *p != small)
        .expect("the 24x24 reference");
    let size = std::fs::metadata(&large).expect("size").len();
    std::fs::copy(&small, &large).expect("copy over");
    let out = run("r24.toml", "c");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("the cached reference is unusable (16x16 pixels, expected 24x24)"),
        "{err}"
    );
    assert_eq!(
        std::fs::metadata(&large).expect("size").len(),
        size,
        "the entry is replaced by a 24x24 reference"
    );
}

/// A report that fails on a write leaves no `images/` behind in its output directory
/// (issue 54 #14): here `results.json` is a directory, so its write fails after the images are
/// copied.
#[test]
fn a_failed_report_leaves_no_images_behind() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("small.toml"),
        "scenes = [\"sphere\"]\nmethods = [\"single\"]\nres = [16]\nframes = 1\n",
    )
    .expect("write");
    ok(&refract(&["sweep", "small.toml", "--out", "s"], dir.path()));
    std::fs::create_dir_all(dir.path().join("r/results.json")).expect("a directory in the way");
    let out = refract(&["report", "s", "--out", "r"], dir.path());
    assert!(!out.status.success(), "the report wrote over a directory");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("results.json"), "{err}");
    assert!(
        !dir.path().join("r/images").exists(),
        "left behind: r/images/"
    );
}

/// `reference_backend = "gpu"` in a sweep file: the references are traced on the GPU, cached
/// apart from the CPU tracer's, and give the same metrics within the two references' f32
/// differences (at 2 samples per pixel: the GPU supersamples too); bad values are refused
/// naming the key.
#[test]
fn sweeps_trace_their_references_on_the_gpu_when_asked() {
    let dir = tempfile::tempdir().expect("tempdir");
    let sweep = |backend: &str, spp: u32| {
        format!(
            "scenes = [\"sphere\"]\nmethods = [\"wyman\", \"single\"]\nres = [32]\nframes = 1\nimages = false\nspp = {spp}\nreference_backend = \"{backend}\"\n"
        )
    };
    std::fs::write(dir.path().join("bad.toml"), sweep("tpu", 1)).expect("write");
    let out = refract(&["sweep", "bad.toml", "--out", "bad"], dir.path());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("reference_backend"),
        "{err}"
    );
    if std::env::var("REFRACT_REQUIRE_GPU").is_err() && refract_gpu::GpuContext::new().is_err() {
        println!("skipped: no GPU adapter");
        return;
    }
    let flips = |backend: &str| -> Vec<f64> {
        let file = format!("{backend}.toml");
        std::fs::write(dir.path().join(&file), sweep(backend, 2)).expect("write");
        ok(&refract(
            &["sweep", &file, "--cache", "cache", "--out", backend],
            dir.path(),
        ));
        let mut jobs: Vec<_> = std::fs::read_dir(dir.path().join(backend).join("jobs"))
            .expect("jobs")
            .map(|e| e.expect("entry").path())
            .collect();
        jobs.sort();
        jobs.iter()
            .map(|path| {
                let text = std::fs::read_to_string(path).expect("job");
                let job: serde_json::Value = serde_json::from_str(&text).expect("json");
                job["metrics"]["flip_mean"].as_f64().expect("flip")
            })
            .collect()
    };
    let (cpu, gpu) = (flips("cpu"), flips("gpu"));
    assert_eq!(cpu.len(), 2);
    for (c, g) in cpu.iter().zip(&gpu) {
        assert!(
            (c - g).abs() <= 1e-3 * (1.0 + c),
            "FLIP {c} (CPU) vs {g} (GPU)"
        );
    }
    let cached = std::fs::read_dir(dir.path().join("cache"))
        .expect("cache")
        .filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "exr"))
        })
        .count();
    assert_eq!(cached, 2, "one reference per backend in the cache");
}

/// `engines = [...]` in a sweep file: each engine renders each scene itself (backend `webgl`,
/// labelled with its version) beside the methods, with the methods' metrics and images
/// (issue 50, item 3). Without Node, Chromium or `npm ci --prefix engines` the engine job fails
/// naming what is missing; this test then prints `skipped:` unless REFRACT_REQUIRE_ENGINES=1.
#[test]
fn sweeps_run_the_engines_themselves() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("engines.toml"),
        "scenes = [\"chart\"]\nmethods = [\"volume-thickness\"]\nengines = [\"threejs\"]\nres = [32]\nframes = 1\n",
    )
    .expect("write");
    let out = refract(&["sweep", "engines.toml", "--out", "s"], dir.path());
    let job = std::fs::read_to_string(dir.path().join("s/jobs/chart-32-webgl-threejs.json"))
        .expect("the engine's job");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let result: serde_json::Value = serde_json::from_str(&job).expect("json");
    let required = std::env::var("REFRACT_REQUIRE_ENGINES").is_ok_and(|v| v == "1");
    if result["status"] == "error" && !required {
        println!("skipped: {}", result["error"]);
        return;
    }
    assert_eq!(result["status"], "ok", "{job}");
    assert!(
        result["metrics"]["method"]
            .as_str()
            .is_some_and(|m| m.starts_with("threejs@")),
        "{job}"
    );
    assert_eq!(result["metrics"]["backend"], "webgl");
    assert!(result["metrics"]["flip_mean"].as_f64().is_some(), "{job}");
    assert!(
        dir.path()
            .join("s/images/chart-32-webgl-threejs.png")
            .is_file()
    );
}
