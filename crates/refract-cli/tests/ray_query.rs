//! The exact reference over the adapter's hardware ray queries (wgpu's `EXPERIMENTAL_RAY_QUERY`)
//! against the WGSL BVH traversal, pixel by pixel (issue 32), and the `REFRACT_RAY_QUERY` switch.
//!
//! This machine's lavapipe (Mesa 22.3) has no ray queries; Mesa 24.1 and later do.
//! `scripts/newer-lavapipe.sh DEST` unpacks Debian's bookworm-backports Mesa beside the system's
//! and prints its driver manifest; with `REFRACT_RAY_QUERY_ICD` set to that manifest (`.ci/run`
//! does) the comparison runs in `refract` processes started on that driver. Without it the test
//! runs on the default adapter if that has ray queries, and otherwise prints a notice and passes
//! (fails under `REFRACT_REQUIRE_RAY_QUERY=1`).

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use glam::Vec3;
use refract_eval::FrameFiles;
use refract_scene::{Aov, Frame};

/// `refract` with `env` added to its environment.
fn refract(args: &[&str], env: &[(String, OsString)], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_refract"))
        .args(args)
        .envs(env.iter().map(|(k, v)| (k, v)))
        .env("XDG_RUNTIME_DIR", "/tmp")
        .current_dir(dir)
        .output()
        .expect("run refract")
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// The environment in which the GPU has ray queries: the driver of `REFRACT_RAY_QUERY_ICD`
/// (its libraries' directory first on the library path: the unpacked Mesa links a newer libdrm
/// unpacked beside it), or the default one if it has them; `None` after a notice otherwise.
fn ray_query_environment(dir: &Path) -> Option<Vec<(String, OsString)>> {
    let env = match std::env::var_os("REFRACT_RAY_QUERY_ICD") {
        Some(icd) => {
            let text = std::fs::read_to_string(&icd)
                .unwrap_or_else(|err| panic!("REFRACT_RAY_QUERY_ICD={icd:?}: {err}"));
            let manifest: serde_json::Value = serde_json::from_str(&text).expect("an ICD manifest");
            let library = manifest["ICD"]["library_path"]
                .as_str()
                .map(PathBuf::from)
                .expect("ICD.library_path");
            let libraries = library.parent().expect("the driver's directory");
            let mut path = OsString::from(libraries);
            if let Some(existing) = std::env::var_os("LD_LIBRARY_PATH") {
                path.push(":");
                path.push(existing);
            }
            vec![
                ("VK_DRIVER_FILES".to_owned(), icd),
                ("LD_LIBRARY_PATH".to_owned(), path),
            ]
        }
        None => Vec::new(),
    };
    let info = refract(&["info"], &env, dir);
    let text = String::from_utf8_lossy(&info.stdout);
    if text
        .lines()
        .any(|l| l.contains("Vulkan") && l.contains("ray queries: yes"))
    {
        return Some(env);
    }
    assert!(
        !std::env::var("REFRACT_REQUIRE_RAY_QUERY").is_ok_and(|v| v == "1"),
        "REFRACT_REQUIRE_RAY_QUERY=1 but no Vulkan adapter has ray queries:\n{text}{}",
        stderr(&info)
    );
    println!(
        "skipped: no adapter with ray queries (scripts/newer-lavapipe.sh and REFRACT_RAY_QUERY_ICD provide one)"
    );
    None
}

/// Renders the GPU reference of `scene` with `params` at 64² under `REFRACT_RAY_QUERY=policy`.
fn render(
    scene: &str,
    params: &[&str],
    policy: &str,
    env: &[(String, OsString)],
    dir: &Path,
) -> Frame {
    let out = format!("{scene}-{}-{policy}.exr", params.join("-"));
    let mut args = vec![
        "render",
        scene,
        "--method",
        "reference",
        "--backend",
        "gpu",
        "--res",
        "64",
        "--out",
        &out,
    ];
    for p in params {
        args.extend(["--param", p]);
    }
    let mut env = env.to_vec();
    env.push(("REFRACT_RAY_QUERY".to_owned(), policy.into()));
    let output = refract(&args, &env, dir);
    assert!(
        output.status.success(),
        "{args:?} ({policy}): {}",
        stderr(&output)
    );
    Frame::read_exr(&dir.join(&out)).expect("the EXR")
}

/// Where both traversals run, they trace the same reference: the same first hit on 99.9 % of
/// the pixels, the same colour on 99 % (an ulp apart at a checker edge or a shared triangle
/// edge, where the adapter's watertight test and ours may pick different triangles), in both
/// modes, with glass, conductors and lit objects.
#[test]
fn ray_queries_and_the_wgsl_traversal_trace_the_same_reference() {
    let dir = tempfile::tempdir().expect("tempdir");
    let Some(env) = ray_query_environment(dir.path()) else {
        return;
    };
    for (scene, params) in [
        ("sphere", &[][..]),
        ("torus", &["mode=full"][..]),
        ("mirror-stack", &[][..]),
        ("glass-room", &["mode=full", "spp=2"][..]),
    ] {
        let hardware = render(scene, params, "on", &env, dir.path());
        let software = render(scene, params, "off", &env, dir.path());
        let n = hardware.color.len();
        let (p1_h, p1_s) = (
            hardware.vec3(Aov::P1).expect("P1"),
            software.vec3(Aov::P1).expect("P1"),
        );
        let same_point = |a: Vec3, b: Vec3| {
            (a.is_nan() && b.is_nan()) || (a - b).length() <= 1e-4 * (1.0 + a.length())
        };
        let hits = (0..n).filter(|&i| same_point(p1_h[i], p1_s[i])).count() as f64 / n as f64;
        let colors = (0..n)
            .filter(|&i| {
                let (a, b) = (software.color[i], hardware.color[i]);
                (a - b).abs().max_element() <= 1e-3 * (1.0 + a.abs().max_element())
            })
            .count() as f64
            / n as f64;
        println!(
            "{scene} {params:?}: the same first hit on {:.2} %, the same colour on {:.2} %",
            100.0 * hits,
            100.0 * colors
        );
        assert!(
            hits >= 0.999,
            "{scene} {params:?}: the same first hit on {hits}"
        );
        assert!(
            colors >= 0.99,
            "{scene} {params:?}: the same colour on {colors}"
        );
    }
}

/// `REFRACT_RAY_QUERY=on` (or `--ray-query on`) on an adapter without ray queries is an error
/// naming the adapter when the reference renders, not a silent fallback (the other methods
/// trace no rays and render); a value other than auto, on or off is an error
/// naming the variable; `--ray-query` takes precedence over the variable.
#[test]
fn forcing_ray_queries_without_them_is_an_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let args = [
        "render",
        "sphere",
        "--method",
        "reference",
        "--backend",
        "gpu",
        "--res",
        "8",
        "--out",
        "x.png",
    ];
    let env = |policy: &str| vec![("REFRACT_RAY_QUERY".to_owned(), OsString::from(policy))];
    let bogus = refract(&args, &env("maybe"), dir.path());
    assert!(!bogus.status.success());
    assert!(
        stderr(&bogus).contains("REFRACT_RAY_QUERY") && stderr(&bogus).contains("auto, on or off"),
        "{}",
        stderr(&bogus)
    );
    let info = refract(&["info"], &[], dir.path());
    let text = String::from_utf8_lossy(&info.stdout).into_owned();
    if !text.contains("Vulkan") {
        println!("skipped: no Vulkan adapter");
        return;
    }
    let forced = refract(&args, &env("on"), dir.path());
    if text.contains("ray queries: yes") {
        assert!(forced.status.success(), "{}", stderr(&forced));
    } else {
        assert!(!forced.status.success());
        assert!(
            stderr(&forced).contains("has no ray queries"),
            "{}",
            stderr(&forced)
        );
        // Issue 54 #15: only the reference traces rays; a method that does not renders.
        let mut method = args;
        method[3] = "wyman";
        let other = refract(&method, &env("on"), dir.path());
        assert!(other.status.success(), "{}", stderr(&other));
    }
    // And off (the WGSL traversal) runs everywhere; `--ray-query` overrides the variable.
    let off = refract(&args, &env("off"), dir.path());
    assert!(off.status.success(), "{}", stderr(&off));
    let mut flagged = vec!["--ray-query", "off"];
    flagged.extend(args);
    let overridden = refract(&flagged, &env("on"), dir.path());
    assert!(overridden.status.success(), "{}", stderr(&overridden));
}
