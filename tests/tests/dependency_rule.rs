//! The dependency rule of `docs/architecture.md`, checked over `cargo metadata`: refract-core
//! depends on no workspace crate; geometry on core only; the API crate (refract-scene) on core
//! and geometry, so on no renderer and no file format; refract-eval (files, metrics) on the API;
//! the reference and the two backends on the API crate and never on one another, on refract-eval
//! or on anything above them (only the reference's tests write files through refract-eval); and
//! the reference uses exact math only, never an approximation a backend uses.

use std::collections::BTreeSet;
use std::process::Command;

/// Every workspace package with the workspace crates it depends on (any kind: normal, dev,
/// build) and those it links outside its tests (normal and build).
fn workspace_dependencies() -> Vec<(String, BTreeSet<String>, BTreeSet<String>)> {
    let metadata = cargo_metadata();
    let packages = metadata["packages"].as_array().expect("packages");
    let names: BTreeSet<String> = packages
        .iter()
        .filter_map(|p| p["name"].as_str().map(str::to_owned))
        .collect();
    packages
        .iter()
        .map(|p| {
            let workspace = |dev: bool| {
                p["dependencies"]
                    .as_array()
                    .expect("dependencies")
                    .iter()
                    .filter(|d| dev || d["kind"].as_str() != Some("dev"))
                    .filter_map(|d| d["name"].as_str())
                    .filter(|d| names.contains(*d))
                    .map(str::to_owned)
                    .collect()
            };
            (
                p["name"].as_str().expect("name").to_owned(),
                workspace(true),
                workspace(false),
            )
        })
        .collect()
}

/// `cargo metadata` of the workspace's own packages.
fn cargo_metadata() -> serde_json::Value {
    let output = Command::new(env!("CARGO"))
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(refract_tests::workspace_root())
        .output()
        .expect("cargo metadata");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).expect("json")
}

fn set(names: &[&str]) -> BTreeSet<String> {
    names.iter().map(|s| (*s).to_owned()).collect()
}

#[test]
fn crates_depend_only_downward() {
    let packages = workspace_dependencies();
    let find = |name: &str| {
        packages
            .iter()
            .find(|(n, _, _)| n == name)
            .unwrap_or_else(|| panic!("no package {name}"))
    };
    let deps = |name: &str| -> BTreeSet<String> { find(name).1.clone() };
    let links = |name: &str| -> BTreeSet<String> { find(name).2.clone() };
    assert_eq!(
        deps("refract-core"),
        set(&[]),
        "core depends on no workspace crate"
    );
    assert_eq!(deps("refract-geometry"), set(&["refract-core"]));
    assert_eq!(
        deps("refract-scene"),
        set(&["refract-core", "refract-geometry"]),
        "the API crate depends on no renderer and nothing above it"
    );
    assert_eq!(
        deps("refract-eval"),
        set(&["refract-core", "refract-geometry", "refract-scene"]),
        "refract-eval sits on the API crate and on no renderer"
    );
    let renderers = ["refract-trace", "refract-cpu", "refract-gpu"];
    for renderer in renderers {
        let d = deps(renderer);
        assert!(
            d.contains("refract-scene"),
            "{renderer} renders refract-scene's Scene"
        );
        for other in renderers.iter().filter(|o| **o != renderer) {
            assert!(!d.contains(*other), "{renderer} must not depend on {other}");
        }
        assert!(
            !d.contains("refract-cli") && !d.contains("refract-tests"),
            "{renderer}: {d:?}"
        );
        assert!(
            links(renderer).is_subset(&set(&["refract-core", "refract-geometry", "refract-scene"])),
            "{renderer} links only the API crate and below (no files, metrics, experiments, \
             viewer): {:?}",
            links(renderer)
        );
    }
    // The engines' own renderers export scenes through refract-eval and run outside the
    // process: no backend, no experiments.
    assert_eq!(
        links("refract-engines"),
        set(&["refract-core", "refract-scene", "refract-eval"]),
        "refract-engines sits on the files and links no renderer (its tests compare with one)"
    );
    // The experiments sit on the renderers and the files; nothing below them knows them.
    let lab = deps("refract-lab");
    for below in [
        "refract-eval",
        "refract-trace",
        "refract-cpu",
        "refract-gpu",
    ] {
        assert!(lab.contains(below), "refract-lab runs {below}");
    }
    assert!(
        !lab.contains("refract-view") && !lab.contains("refract-cli"),
        "refract-lab: {lab:?}"
    );
    assert!(
        !deps("refract-view").contains("refract-cli")
            && !deps("refract-view").contains("refract-lab"),
        "the viewer depends on the renderers and the files only"
    );
    // The Python package is an edge like the CLI: it calls the experiments library, never the
    // CLI or the viewer, and nothing depends on it.
    let python = deps("refract-python");
    assert!(python.contains("refract-lab"), "refract-python: {python:?}");
    assert!(
        !python.contains("refract-cli") && !python.contains("refract-view"),
        "refract-python: {python:?}"
    );
    for (name, d, _) in &packages {
        assert!(
            !d.contains("refract-python"),
            "{name} must not depend on the Python package"
        );
    }
    for name in [
        "refract-core",
        "refract-geometry",
        "refract-scene",
        "refract-eval",
        "refract-trace",
        "refract-cpu",
        "refract-gpu",
        "refract-engines",
    ] {
        let d = deps(name);
        assert!(
            !d.contains("refract-lab") && !d.contains("refract-view"),
            "{name} must not depend on the experiments or the viewer: {d:?}"
        );
    }
    println!("{packages:#?}");
}

/// The `.rs` files under `dir`, recursively.
fn rust_files(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir)
        .expect("a source directory")
        .flatten()
    {
        let path = entry.path();
        if path.is_dir() {
            files.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
    files
}

/// The modules of the crate at `src` (a directory) and the modules each imports by a
/// `crate::` path, as edges `(from, to)`. A module is a source file's path under `src` without
/// its extension (`mod.rs` is its directory), cut to its first two components, so that a
/// family's own submodules (`families/distance_map/eye_pass.rs`) are the family; test modules
/// (from the first `#[cfg(test)]`) and comments are left out.
fn module_imports(src: &std::path::Path) -> Vec<(String, String)> {
    let module_of = |rel: &std::path::Path| {
        let mut parts: Vec<String> = rel
            .with_extension("")
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        if parts.last().is_some_and(|p| p == "mod") {
            parts.pop();
        }
        parts.truncate(2);
        parts.join("/")
    };
    // Modules the crate root re-exports under a shorter path (`pub use families::{pvrr, ..}`
    // makes `crate::pvrr` the module `families/pvrr`).
    let root = std::fs::read_to_string(src.join("lib.rs")).unwrap_or_default();
    let mut aliases = std::collections::BTreeMap::new();
    for line in root.lines() {
        let Some(rest) = line.trim().strip_prefix("pub use ") else {
            continue;
        };
        let Some((dir, names)) = rest.split_once("::") else {
            continue;
        };
        let names = names
            .trim_end_matches(';')
            .trim_matches(|c| c == '{' || c == '}');
        for name in names.split(',').map(str::trim) {
            if src.join(dir).join(format!("{name}.rs")).is_file() {
                aliases.insert(name.to_owned(), format!("{dir}/{name}"));
            }
        }
    }
    let mut edges = Vec::new();
    for path in rust_files(src) {
        let rel = path.strip_prefix(src).expect("under src").to_owned();
        let from = module_of(&rel);
        let text = std::fs::read_to_string(&path).expect("read");
        // The code outside tests and comments (a doc link is no import).
        let code: String = text
            .split("#[cfg(test)]")
            .next()
            .unwrap_or_default()
            .lines()
            .filter(|line| !line.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        for (i, _) in code.match_indices("crate::") {
            // The longest run of path segments after `crate::` that names a module file.
            let mut segments: Vec<String> = code[i + "crate::".len()..]
                .split("::")
                .map(|s| {
                    s.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                        .next()
                })
                .map(|s| s.unwrap_or_default().to_owned())
                .take_while(|s| !s.is_empty())
                .collect();
            if let Some(alias) = segments.first().and_then(|first| aliases.get(first)) {
                segments[0] = alias.clone();
            }
            let target = (1..=segments.len()).rev().find_map(|n| {
                let dir = segments[..n].join("/");
                [format!("{dir}.rs"), format!("{dir}/mod.rs")]
                    .into_iter()
                    .map(std::path::PathBuf::from)
                    .find(|candidate| src.join(candidate).is_file())
            });
            if let Some(target) = target {
                let to = module_of(&target);
                if to != from {
                    edges.push((from.clone(), to));
                }
            }
        }
    }
    edges
}

/// A module of `edges` that reaches itself through the imports of others, with its path.
fn import_cycle(edges: &[(String, String)]) -> Option<Vec<String>> {
    for (start, _) in edges {
        // Depth-first from `start`, remembering how each module was reached.
        let mut parent = std::collections::BTreeMap::new();
        let mut stack = vec![start.clone()];
        while let Some(m) = stack.pop() {
            for (a, b) in edges.iter().filter(|(a, _)| *a == m) {
                if b == start {
                    let mut path = vec![b.clone(), a.clone()];
                    while let Some(p) = parent.get(path.last().expect("non-empty")) {
                        path.push(String::clone(p));
                    }
                    path.reverse();
                    return Some(path);
                }
                if !parent.contains_key(b) {
                    parent.insert(b.clone(), a.clone());
                    stack.push(b.clone());
                }
            }
        }
    }
    None
}

/// The cycle finder finds a cycle where there is one and none in a layered graph: the negative
/// control of the tests below.
#[test]
fn the_import_cycle_finder_finds_cycles() {
    let edge = |a: &str, b: &str| (a.to_owned(), b.to_owned());
    let layered = [edge("a", "b"), edge("b", "c"), edge("a", "c")];
    assert_eq!(import_cycle(&layered), None);
    let cycle = [
        edge("a", "b"),
        edge("b", "c"),
        edge("c", "a"),
        edge("c", "d"),
    ];
    let found = import_cycle(&cycle).expect("a cycle");
    assert_eq!(found.first(), found.last());
    assert_eq!(found.len(), 4, "{found:?}");
}

/// The experiments library never prints (progress and notes go through its `Progress`
/// callback), and its modules import each other without a circle.
#[test]
fn the_experiments_library_is_quiet_and_layered() {
    let src = refract_tests::workspace_root().join("crates/refract-lab/src");
    let files = rust_files(&src);
    assert!(files.len() >= 10, "read refract-lab's sources");
    for path in &files {
        let text = std::fs::read_to_string(path).expect("read");
        for needle in ["println!", "eprintln!", "print!(", "eprint!(", "dbg!"] {
            assert!(
                !text.contains(needle),
                "{} prints ({needle}); report through Progress instead",
                path.display()
            );
        }
    }
    let edges = module_imports(&src);
    assert!(edges.len() >= 20, "read refract-lab's imports: {edges:?}");
    if let Some(cycle) = import_cycle(&edges) {
        panic!("refract-lab's modules import each other in a circle: {cycle:?}");
    }
}

/// The backends' modules import each other without a circle: the plumbing several families
/// share lives outside the family modules (`refract-gpu/src/passes/`, refract-cpu's
/// `object_surfaces`, `shade`, `buffers`), and no family module imports another family's.
#[test]
fn the_backends_are_layered() {
    for (krate, families) in [("refract-gpu", "methods/"), ("refract-cpu", "families/")] {
        let src = refract_tests::workspace_root()
            .join("crates")
            .join(krate)
            .join("src");
        let edges = module_imports(&src);
        assert!(edges.len() >= 20, "read {krate}'s imports: {edges:?}");
        if let Some(cycle) = import_cycle(&edges) {
            panic!("{krate}'s modules import each other in a circle: {cycle:?}");
        }
        for (from, to) in &edges {
            assert!(
                !(from.starts_with(families) && to.starts_with(families)),
                "{krate}: the family module {from} imports the family module {to}; move what \
                 they share out of the family"
            );
        }
    }
}

/// The reference's sources name nothing of the backends' approximations: the polynomial
/// `atan2`, the eight-lane kernels and lookups, or the environment lookup built on them.
#[test]
fn the_reference_uses_exact_math_only() {
    let src = refract_tests::workspace_root().join("crates/refract-trace/src");
    let forbidden = [
        "arctangent",
        "Polynomial",
        "lanes",
        "kernel_x8",
        "_x8",
        ".radiance(",
        "radiance_with",
    ];
    let mut checked = 0;
    for entry in std::fs::read_dir(&src).expect("refract-trace/src") {
        let path = entry.expect("entry").path();
        let text = std::fs::read_to_string(&path).expect("source");
        for word in forbidden {
            assert!(
                !text.contains(word),
                "{} uses `{word}`: the reference must use exact math (radiance_exact, libm)",
                path.display()
            );
        }
        checked += 1;
    }
    assert!(checked >= 3, "read the reference's sources");
    let tracer = std::fs::read_to_string(src.join("tracer.rs")).expect("tracer.rs");
    assert!(
        tracer.contains("radiance_exact"),
        "the tracer looks the environment up exactly"
    );
}

/// refract-core builds without std (`--no-default-features --features libm`): the crate is
/// `#![no_std]` then, so any `std::` that creeps back fails this build. When the
/// `thumbv7em-none-eabihf` target is installed (`rustup target add thumbv7em-none-eabihf`) it
/// is also built for that target, which has no std at all.
#[test]
fn the_core_builds_without_std() {
    let root = refract_tests::workspace_root();
    let target_dir = root.join("target/no-std-check");
    let build = |target: Option<&str>| {
        let mut command = Command::new(env!("CARGO"));
        command
            .args([
                "build",
                "--offline",
                "-p",
                "refract-core",
                "--no-default-features",
                "--features",
                "libm",
            ])
            .arg("--target-dir")
            .arg(&target_dir)
            .current_dir(&root);
        if let Some(target) = target {
            command.args(["--target", target]);
        }
        let output = command.output().expect("cargo build");
        assert!(
            output.status.success(),
            "refract-core without std ({target:?}):\n{}",
            String::from_utf8_lossy(&output.stderr)
        );
    };
    build(None);
    // Installed when the target's sysroot has its `libcore`.
    let installed = Command::new("rustc")
        .args([
            "--print",
            "target-libdir",
            "--target",
            "thumbv7em-none-eabihf",
        ])
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .and_then(|dir| std::fs::read_dir(dir.trim()).ok())
        .is_some_and(|entries| {
            entries
                .flatten()
                .any(|e| e.file_name().to_string_lossy().starts_with("libcore"))
        });
    if installed {
        build(Some("thumbv7em-none-eabihf"));
    } else {
        println!("note: thumbv7em-none-eabihf is not installed; built for the host without std");
    }
}

/// The library crates meant for crates.io embed nothing from outside their own directory
/// (`include_str!`/`include_bytes!` paths resolve inside the crate), so `cargo package` ships
/// what they compile: refract-core's WGSL in `crates/refract-core/wgsl/`, the GPU backend's in
/// `crates/refract-gpu/shaders/`.
#[test]
fn packaged_crates_embed_only_their_own_files() {
    let root = refract_tests::workspace_root();
    let mut embedded = 0;
    for krate in ["refract-core", "refract-scene", "refract-gpu"] {
        let dir = root.join("crates").join(krate);
        let dir = dir.canonicalize().expect("crate directory");
        for file in rust_files(&dir.join("src")) {
            let text = std::fs::read_to_string(&file).expect("source");
            for macro_name in ["include_str!(\"", "include_bytes!(\""] {
                for (at, _) in text.match_indices(macro_name) {
                    let rest = &text[at + macro_name.len()..];
                    let relative = &rest[..rest.find('"').expect("closing quote")];
                    let path = file.parent().expect("parent").join(relative);
                    let path = path
                        .canonicalize()
                        .unwrap_or_else(|e| panic!("{}: {relative}: {e}", file.display()));
                    assert!(
                        path.starts_with(&dir),
                        "{} embeds {relative}, outside {krate}: `cargo package -p {krate}` would not ship it",
                        file.display()
                    );
                    embedded += 1;
                }
            }
        }
    }
    assert!(
        embedded >= 20,
        "found the WGSL files the crates embed ({embedded})"
    );
}

/// Every declared dependency of every workspace package is used: its crate name (`-` as `_`,
/// or its `rename`) appears as a path, a `use`, a macro or an attribute in the package's
/// sources (`src/`, `tests/`, `benches/`, `examples/`, `build.rs`), for normal and dev
/// dependencies alike (a text check, as `cargo-machete` makes: it found 10 unused ones when it
/// was written).
#[test]
fn declared_dependencies_are_used() {
    let metadata = cargo_metadata();
    let mut unused = Vec::new();
    let mut checked = 0;
    for package in metadata["packages"].as_array().expect("packages") {
        let name = package["name"].as_str().expect("name");
        let manifest = std::path::PathBuf::from(package["manifest_path"].as_str().expect("path"));
        let dir = manifest.parent().expect("package directory");
        let mut text = String::new();
        for sub in ["src", "tests", "benches", "examples"] {
            let sub = dir.join(sub);
            if sub.is_dir() {
                for file in rust_files(&sub) {
                    text.push_str(&std::fs::read_to_string(file).expect("source"));
                }
            }
        }
        if let Ok(build) = std::fs::read_to_string(dir.join("build.rs")) {
            text.push_str(&build);
        }
        for dep in package["dependencies"].as_array().expect("dependencies") {
            let dep_name = dep["rename"]
                .as_str()
                .or(dep["name"].as_str())
                .expect("dependency name");
            let ident = dep_name.replace('-', "_");
            let used = [
                format!("{ident}::"),
                format!("use {ident}"),
                format!("extern crate {ident}"),
                format!("{ident}!"),
                format!("#[{ident}"),
            ]
            .iter()
            .any(|pattern| text.contains(pattern.as_str()));
            if !used {
                unused.push(format!("{name}: {dep_name}"));
            }
            checked += 1;
        }
    }
    assert!(checked > 50, "read the dependencies ({checked})");
    assert!(unused.is_empty(), "declared but never used: {unused:#?}");
}
