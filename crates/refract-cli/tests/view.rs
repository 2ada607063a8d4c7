//! `refract view` headless: under Xvfb (started here) with lavapipe, a scripted run of a few
//! frames switches the method, reads the presented window back, and its screenshot must be
//! non-blank and match an offline render of the same view within a FLIP threshold. Skipped
//! without `Xvfb` unless `REFRACT_REQUIRE_XVFB=1` (CI installs it).

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// An Xvfb server on a free display, stopped on drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn xvfb() -> Option<Xvfb> {
    let available = Command::new("Xvfb")
        .arg("-help")
        .stderr(Stdio::null())
        .stdout(Stdio::null())
        .status()
        .is_ok();
    if !available {
        assert!(
            !std::env::var("REFRACT_REQUIRE_XVFB").is_ok_and(|v| v == "1"),
            "REFRACT_REQUIRE_XVFB=1 but Xvfb is not installed"
        );
        println!("skipped: Xvfb not found");
        return None;
    }
    // A display number unlikely to be taken: from the process id and a counter (the tests of
    // this file run in parallel threads of one process).
    static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    for _ in 0..20 {
        let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let number = 200 + (std::process::id() % 500) * 8 + n;
        if Path::new(&format!("/tmp/.X11-unix/X{number}")).exists() {
            continue;
        }
        let mut child = Command::new("Xvfb")
            .args([
                format!(":{number}"),
                "-screen".into(),
                "0".into(),
                "640x480x24".into(),
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start Xvfb");
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(10) {
            if child.try_wait().ok().flatten().is_some() {
                break; // it exited: the display was taken, try the next one
            }
            if Path::new(&format!("/tmp/.X11-unix/X{number}")).exists() {
                return Some(Xvfb {
                    child,
                    display: format!(":{number}"),
                });
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = child.kill();
        let _ = child.wait();
    }
    panic!("Xvfb did not start on any of 20 displays");
}

/// The largest difference between two images' bytes and how many bytes differ.
fn byte_difference(a: &[u8], b: &[u8]) -> (u8, usize) {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| x.abs_diff(*y))
        .filter(|d| *d > 0)
        .fold((0, 0), |(worst, n), d| (worst.max(d), n + 1))
}

fn rgb(path: &Path) -> (u32, u32, Vec<u8>) {
    let image = image::open(path).expect("png").to_rgb8();
    (image.width(), image.height(), image.into_raw())
}

/// Runs `refract ARGS` in `dir` on X display `display`; asserts success, returns stderr.
fn refract(dir: &Path, display: &str, args: &[&str]) -> String {
    let output = Command::new(env!("CARGO_BIN_EXE_refract"))
        .args(args)
        .env("DISPLAY", display)
        .env("XDG_RUNTIME_DIR", "/tmp")
        .current_dir(dir)
        .output()
        .expect("run refract");
    let log = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{args:?}: {log}");
    log
}

/// `refract view chart` at `size` with `script`, then the offline GPU render of `method` at the
/// same size: the screenshot's and the render's pixels, and the viewer's log.
fn window_and_offline(
    dir: &Path,
    display: &str,
    size: &str,
    script: &str,
    method: &str,
) -> ((u32, u32, Vec<u8>), Vec<u8>, String) {
    std::fs::write(dir.join("keys.txt"), script).expect("script");
    let log = refract(
        dir,
        display,
        &[
            "view",
            "chart",
            "--method",
            "wyman",
            "--size",
            size,
            "--frames",
            "3",
            "--script",
            "keys.txt",
            "--screenshot",
            "window.png",
        ],
    );
    refract(
        dir,
        display,
        &[
            "render",
            "chart",
            "--method",
            method,
            "--backend",
            "gpu",
            "--res",
            size,
            "--out",
            "offline.png",
        ],
    );
    let window = rgb(&dir.join("window.png"));
    let (w, h, offline) = rgb(&dir.join("offline.png"));
    assert_eq!((window.0, window.1), (w, h));
    (window, offline, log)
}

#[test]
fn a_scripted_window_matches_the_offline_render() {
    let Some(x) = xvfb() else { return };
    let dir = tempfile::tempdir().expect("tempdir");
    // `m` switches wyman to the next method of the registry, wyman-dv.
    let ((w, h, window), reference, log) = window_and_offline(
        dir.path(),
        &x.display,
        "160x120",
        "key h\nkey m\nwait\n",
        "wyman-dv",
    );
    assert!(log.contains("screenshot of the window"), "{log}");
    let metrics: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("window.json")).expect("metrics"),
    )
    .expect("json");
    assert_eq!(metrics["method"], "wyman-dv");
    assert!(metrics["flip_mean"].as_f64().is_some());
    // Not blank: the pixels vary.
    let mean = window.iter().map(|&v| f64::from(v)).sum::<f64>() / window.len() as f64;
    let var = window
        .iter()
        .map(|&v| (f64::from(v) - mean).powi(2))
        .sum::<f64>()
        / window.len() as f64;
    assert!(var.sqrt() > 20.0, "blank window: std dev {}", var.sqrt());
    let flip = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(w, h, &reference),
        nv_flip::FlipImageRgb8::with_data(w, h, &window),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let mean_flip = flip.to_vec().iter().map(|&v| f64::from(v)).sum::<f64>() / f64::from(w * h);
    println!("window vs offline render: mean FLIP {mean_flip:.5}");
    assert!(mean_flip < 0.01, "mean FLIP {mean_flip}");
    // The window drew the GPU's frame on the GPU (no readback), tonemapped in WGSL as every PNG
    // is on the CPU: the same bytes but for an ulp of `pow` here and there.
    assert!(log.contains("no readback"), "{log}");
    // Each of the frame's passes timed on its own (issue 32: per-pass timestamps), where the
    // adapter has timestamp queries (lavapipe does).
    let timestamps = refract_gpu::GpuContext::new().is_ok_and(|c| c.timestamps);
    if !timestamps {
        println!("note: the adapter has no timestamp queries: no pass times to check");
    } else {
        for pass in ["back faces", "front faces", "image-space kernel"] {
            assert!(
                log.lines()
                    .any(|l| l.contains("last frame's GPU passes") && l.contains(pass)),
                "{pass}: {log}"
            );
        }
    }
    let (worst, off) = byte_difference(&window, &reference);
    println!("window vs offline render: {off} bytes differ, by at most {worst}");
    assert!(
        worst <= 1 && off * 200 <= window.len(),
        "{off} bytes differ, by up to {worst}"
    );
    // `--readback` shows the same frame through the CPU (read back, tonemapped, uploaded).
    std::fs::write(dir.path().join("keys.txt"), "key h\nkey m\nwait\n").expect("script");
    let log = refract(
        dir.path(),
        &x.display,
        &[
            "view",
            "chart",
            "--method",
            "wyman",
            "--size",
            "160x120",
            "--frames",
            "3",
            "--script",
            "keys.txt",
            "--readback",
            "--screenshot",
            "through-cpu.png",
        ],
    );
    assert!(log.contains("read back and uploaded"), "{log}");
    let (_, _, through_cpu) = rgb(&dir.path().join("through-cpu.png"));
    let (worst, off) = byte_difference(&window, &through_cpu);
    assert!(
        worst <= 1 && off * 200 <= window.len(),
        "GPU vs CPU tonemap: {off} bytes differ, by up to {worst}"
    );

    // Without `h` the panel is drawn over the image.
    let ((pw, ph, with_panel), plain, _) = window_and_offline(
        dir.path(),
        &x.display,
        "400x300",
        "key m\nwait\nwait\n",
        "wyman-dv",
    );
    let changed = with_panel
        .chunks_exact(3)
        .zip(plain.chunks_exact(3))
        .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > 16))
        .count();
    let share = changed as f64 / f64::from(pw * ph);
    println!("the panel covers {:.1} % of the window", 100.0 * share);
    assert!(share > 0.1, "no panel drawn ({share})");
}

/// Without a display the viewer stops with one message asking for one (no panic).
#[test]
fn without_a_display_the_viewer_says_so() {
    let output = Command::new(env!("CARGO_BIN_EXE_refract"))
        .args(["view", "sphere", "--frames", "1"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("run refract view");
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(err.contains("display"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

/// `v` splits the window: the method on the left, the exact reference (refined in the
/// background until complete) on the right, each matching its offline render. The method runs
/// on the GPU, so the reference is traced there too (issue 32), and its half matches the CPU
/// tracer's render; with `--backend cpu` the CPU tracer traces it.
#[test]
fn the_split_view_shows_the_reference_on_the_right() {
    let Some(x) = xvfb() else { return };
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("keys.txt"), "key h\nkey v\nwait\n").expect("script");
    let run = |args: &[&str]| refract(dir.path(), &x.display, args);
    let log = run(&[
        "view",
        "chart",
        "--method",
        "ray-plane",
        "--size",
        "160x120",
        "--frames",
        "2",
        "--script",
        "keys.txt",
        "--screenshot",
        "split.png",
    ]);
    run(&[
        "render",
        "chart",
        "--method",
        "reference",
        "--res",
        "160x120",
        "--out",
        "ref.png",
    ]);
    run(&[
        "render",
        "chart",
        "--method",
        "ray-plane",
        "--backend",
        "gpu",
        "--res",
        "160x120",
        "--out",
        "method.png",
    ]);
    assert!(
        log.contains("split-view reference traced on the GPU"),
        "{log}"
    );
    let cpu_log = run(&[
        "view",
        "chart",
        "--method",
        "ray-plane",
        "--backend",
        "cpu",
        "--size",
        "96x64",
        "--frames",
        "2",
        "--script",
        "keys.txt",
        "--screenshot",
        "split-cpu.png",
    ]);
    assert!(
        cpu_log.contains("split-view reference traced on the CPU tracer"),
        "{cpu_log}"
    );
    let (w, h, split) = rgb(&dir.path().join("split.png"));
    let (_, _, reference) = rgb(&dir.path().join("ref.png"));
    let (_, _, method) = rgb(&dir.path().join("method.png"));
    // Mean absolute difference per half (the divider columns excluded).
    let half = |image: &[u8], right: bool| -> f64 {
        let mut sum = 0.0;
        let mut n = 0.0;
        for y in 0..h {
            for xx in 0..w {
                let on_right = xx >= w / 2 + 2;
                let on_left = xx < w / 2;
                if (right && on_right) || (!right && on_left) {
                    for k in 0..3 {
                        let i = (3 * (y * w + xx) + k) as usize;
                        sum += (f64::from(split[i]) - f64::from(image[i])).abs();
                        n += 1.0;
                    }
                }
            }
        }
        sum / n
    };
    let (left, right) = (half(&method, false), half(&reference, true));
    println!(
        "split view: left vs method {left:.3}, right vs reference {right:.3} (mean |Δ| of 8-bit)"
    );
    assert!(left < 1.0 && right < 1.0, "left {left}, right {right}");
    // And the halves differ from the other image (the reference is not the method).
    assert!(half(&reference, false) > 2.0 * left.max(0.1));
}
