//! The experiments from Rust, without the CLI: a comparison with typed options returns its
//! records and writes its files, reports through a `Progress` (nothing printed), and a skipped
//! (method, scene) pair is a note, not a line on stderr.

use refract_core::TirPolicy;
use refract_lab::backends::GpuPolicy;
use refract_lab::compare::{self, method_params};
use refract_lab::jobs::CompareOptions;
use refract_lab::progress::{Note, Notes};
use refract_scene::{BackendId, MethodId};

#[test]
fn a_comparison_runs_as_a_library_call() {
    let dir = tempfile::tempdir().expect("tempdir");
    let methods = method_params(
        &[MethodId::Single, MethodId::Wyman],
        TirPolicy::ClampToCritical,
        &[("back", "second")],
        "test",
    )
    .expect("methods");
    assert_eq!(methods[1].get("back").as_deref(), Some("second"));
    let options = CompareOptions {
        backends: vec![BackendId::Cpu],
        gpu_policy: GpuPolicy::IfAvailable,
        scenes: vec!["sphere".into(), "mirror-room".into()],
        methods,
        res: 16,
        spp: 1,
        reference_backend: BackendId::Trace,
        warm_up: 1,
        frames: 1,
        engines: vec![],
        engine_policy: GpuPolicy::IfAvailable,
        out: dir.path().join("out"),
    };
    let notes = Notes::default();
    let records = compare::run(&options, &notes).expect("compare");
    // Per scene the reference's row, then the methods that render it: the image-space methods
    // refract through glass only, so the mirror room has the reference's row alone.
    let rows: Vec<(&str, &str)> = records
        .iter()
        .map(|r| (r.scene.as_str(), r.method.as_str()))
        .collect();
    assert_eq!(
        rows,
        [
            ("sphere", "reference"),
            ("sphere", "single"),
            ("sphere", "wyman"),
            ("mirror-room", "reference"),
        ]
    );
    let notes = notes.0.into_inner().expect("notes");
    // One line for both skipped pairs, naming the methods and the scene.
    let skipped: Vec<&Note> = notes
        .iter()
        .filter(|n| matches!(n, Note::Skipped(_)))
        .collect();
    assert_eq!(
        skipped,
        [&Note::Skipped(
            "2 methods that refract through glass only skipped on 1 scene whose specular object is a conductor: single, wyman on mirror-room".into()
        )],
        "{notes:?}"
    );
    for file in [
        "metrics.json",
        "index.html",
        "report.md",
        "sphere/reference.png",
    ] {
        assert!(options.out.join(file).is_file(), "{file}");
    }
    // A parameter none of the methods has is an error naming it.
    let err = method_params(
        &[MethodId::Single],
        TirPolicy::ClampToCritical,
        &[("seeds", "3")],
        "--param",
    )
    .expect_err("single has no seeds");
    assert!(err.to_string().contains("seeds"), "{err}");
}

/// An engine's own renderer is a row like a method's: three.js on the chart beside
/// `volume-thickness`, with FLIP and the nearby-geometry metrics from its position-coded frame,
/// and its images. Without Node, Chromium or the npm packages: skipped with a line, except
/// under `REFRACT_REQUIRE_ENGINES=1`.
#[test]
fn a_comparison_runs_the_engines_own_renderers() {
    let required = std::env::var("REFRACT_REQUIRE_ENGINES").is_ok_and(|v| v == "1");
    if let Err(why) = refract_engines::EngineDriver::locate() {
        assert!(!required, "REFRACT_REQUIRE_ENGINES=1: {why}");
        println!("skipped: {why}");
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let options = CompareOptions {
        backends: vec![BackendId::Cpu],
        gpu_policy: GpuPolicy::IfAvailable,
        scenes: vec!["chart".into()],
        methods: method_params(
            &[MethodId::VolumeThickness],
            TirPolicy::ClampToCritical,
            &[],
            "test",
        )
        .expect("methods"),
        res: 48,
        spp: 1,
        reference_backend: BackendId::Trace,
        warm_up: 1,
        frames: 1,
        engines: vec![refract_engines::Engine::Threejs],
        engine_policy: GpuPolicy::Required,
        out: dir.path().join("out"),
    };
    let records = compare::run(&options, &refract_lab::progress::Quiet).expect("compare");
    let engine = records
        .iter()
        .find(|r| r.method.starts_with("threejs@"))
        .expect("a three.js row");
    assert_eq!(engine.backend, "webgl");
    assert!(
        engine.flip_mean.is_some_and(|f| f > 0.0 && f < 1.0),
        "{engine:?}"
    );
    let [both, ..] = engine.nearby_confusion.expect("P_geom metrics");
    assert!(both > 50, "{engine:?}");
    let stem = format!("{}-webgl", engine.method);
    for file in [
        format!("chart/{stem}.png"),
        format!("chart/flip-{stem}.png"),
    ] {
        assert!(options.out.join(&file).is_file(), "{file}");
    }
}
