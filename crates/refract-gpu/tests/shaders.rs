//! Every WGSL file is parsed and validated by naga inside `cargo test` (no adapter needed), and
//! the uniform block's layout is compared with the Rust struct's.

use std::mem::offset_of;

use refract_core::gpu::FrameUniforms;
use refract_gpu::{shader_modules as modules, shader_source as module_source};

fn validate(name: &str) -> naga::Module {
    let source = module_source(name).unwrap_or_else(|| panic!("no module {name}"));
    let module = naga::front::wgsl::parse_str(&source)
        .unwrap_or_else(|err| panic!("{name}: {}", err.emit_to_string(&source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|err| panic!("{name}: {}", err.emit_to_string(&source)));
    module
}

#[test]
fn every_module_parses_and_validates() {
    let modules = modules();
    assert!(modules.len() >= 6, "the shared modules and every family's");
    for module in modules {
        validate(module.name);
    }
}

/// The `.wgsl` files under `dir`, recursively, with their paths.
fn wgsl_files(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir)
        .expect("a source directory")
        .flatten()
    {
        let path = entry.path();
        if path.is_dir() {
            files.extend(wgsl_files(&path));
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            files.push(path);
        }
    }
    files
}

/// Every `.wgsl` file of the crate (the shared ones in `shaders/`, each module's own beside it
/// under `src/`) and of refract-core's twin is in a module naga validates, as it is on disk.
#[test]
fn every_wgsl_file_is_in_a_validated_module() {
    let crate_dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let on_disk: Vec<std::path::PathBuf> = ["shaders", "src", "../refract-core/wgsl"]
        .iter()
        .flat_map(|dir| wgsl_files(&crate_dir.join(dir)))
        .collect();
    assert!(on_disk.len() >= 20, "read the WGSL files: {on_disk:?}");
    let modules = modules();
    for path in &on_disk {
        let file = path.file_name().expect("a name").to_string_lossy();
        let embedded: Vec<_> = modules
            .iter()
            .flat_map(|m| m.files)
            .filter(|(name, _)| *name == file)
            .collect();
        assert!(!embedded.is_empty(), "{} is in no module", path.display());
        // Every module embeds the file as it is on disk (not a stale copy under its name).
        let on_disk_text = std::fs::read_to_string(path).expect("read");
        for (_, text) in embedded {
            assert_eq!(*text, on_disk_text, "{}", path.display());
        }
    }
}

#[test]
fn frame_uniforms_layout_matches_rust() {
    let module = validate("image_space");
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some("FrameUniforms"))
        .expect("FrameUniforms in WGSL");
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("not a struct")
    };
    let rust: [(&str, usize); 16] = [
        ("world_to_clip", offset_of!(FrameUniforms, world_to_clip)),
        ("view_to_world", offset_of!(FrameUniforms, view_to_world)),
        ("eye", offset_of!(FrameUniforms, eye)),
        ("look_dir", offset_of!(FrameUniforms, look_dir)),
        (
            "environment_constant",
            offset_of!(FrameUniforms, environment_constant),
        ),
        ("width", offset_of!(FrameUniforms, width)),
        ("height", offset_of!(FrameUniforms, height)),
        ("tan_half_fov_y", offset_of!(FrameUniforms, tan_half_fov_y)),
        ("aspect", offset_of!(FrameUniforms, aspect)),
        ("ior", offset_of!(FrameUniforms, ior)),
        ("tir_policy", offset_of!(FrameUniforms, tir_policy)),
        (
            "environment_kind",
            offset_of!(FrameUniforms, environment_kind),
        ),
        (
            "environment_width",
            offset_of!(FrameUniforms, environment_width),
        ),
        (
            "environment_height",
            offset_of!(FrameUniforms, environment_height),
        ),
        (
            "environment_intensity",
            offset_of!(FrameUniforms, environment_intensity),
        ),
        ("_padding", offset_of!(FrameUniforms, _padding)),
    ];
    assert_eq!(members.len(), rust.len());
    for (member, (name, offset)) in members.iter().zip(rust) {
        assert_eq!(member.name.as_deref(), Some(name));
        assert_eq!(member.offset as usize, offset, "{name}");
    }
    assert_eq!(*span as usize, std::mem::size_of::<FrameUniforms>());
}

/// `conformance::ENTRY_POINTS` and `KERNEL_ENTRY_POINTS` list every entry point of their
/// modules, no more and no fewer (the lists are what a reader of the harness trusts).
#[test]
fn conformance_entry_point_lists_are_complete() {
    for (module, listed) in [
        ("conformance", &refract_gpu::conformance::ENTRY_POINTS[..]),
        (
            "conformance-kernels",
            &refract_gpu::conformance::KERNEL_ENTRY_POINTS[..],
        ),
    ] {
        let parsed = validate(module);
        let mut found: Vec<&str> = parsed
            .entry_points
            .iter()
            .map(|e| e.name.as_str())
            .collect();
        let mut listed = listed.to_vec();
        found.sort_unstable();
        listed.sort_unstable();
        assert_eq!(found, listed, "{module}");
    }
}

/// The names of every function reachable from `entry` in `module` (calls followed through
/// blocks, branches, loops and switches).
fn reachable_functions(module: &naga::Module, entry: &str) -> std::collections::BTreeSet<String> {
    fn walk(
        module: &naga::Module,
        block: &naga::Block,
        seen: &mut std::collections::BTreeSet<String>,
    ) {
        for statement in block.iter() {
            match statement {
                naga::Statement::Block(inner) => walk(module, inner, seen),
                naga::Statement::If { accept, reject, .. } => {
                    walk(module, accept, seen);
                    walk(module, reject, seen);
                }
                naga::Statement::Loop {
                    body, continuing, ..
                } => {
                    walk(module, body, seen);
                    walk(module, continuing, seen);
                }
                naga::Statement::Switch { cases, .. } => {
                    for case in cases {
                        walk(module, &case.body, seen);
                    }
                }
                naga::Statement::Call { function, .. } => {
                    let callee = &module.functions[*function];
                    let name = callee.name.clone().unwrap_or_default();
                    if seen.insert(name) {
                        walk(module, &callee.body, seen);
                    }
                }
                _ => {}
            }
        }
    }
    let point = module
        .entry_points
        .iter()
        .find(|e| e.name == entry)
        .unwrap_or_else(|| panic!("no entry point {entry}"));
    let mut seen = std::collections::BTreeSet::new();
    walk(module, &point.function.body, &mut seen);
    seen
}

/// The GPU reference, like the CPU one (`tests/tests/dependency_rule.rs`), uses exact math only:
/// nothing reachable from its entry points is one of the backends' approximations (Schlick's
/// Fresnel, Wyman's `d~` and exit normal, the TIR policies, the distance-map search, the
/// engines' proxies and screen lookups). The check follows the call graph that naga parses, so
/// an approximation reached through a helper is found too; the negative control below shows it
/// finds one that is reached.
#[test]
fn the_gpu_reference_uses_exact_math_only() {
    let forbidden = |name: &str| {
        [
            "schlick",
            "angle_ratio",
            "interpolated_distance",
            "approximate_distance",
            "exit_normal_outside_silhouette",
            "refract_exit",
            "two_interface_path",
            "one_interface",
            "proxy_sphere_exit",
            "proxy_box_exit",
            "volume_exit",
            "bevy_fallback_dir",
            "screen_offset_px",
            "hdrp_edge_fade",
            "screen_fraction_to_segment",
        ]
        .iter()
        .any(|f| name.starts_with(f))
            || name.starts_with("dm_")
    };
    for module_name in ["reference", "reference-ray-query"] {
        let Some(source) = module_source(module_name) else {
            panic!("no module {module_name}")
        };
        let module = naga::front::wgsl::parse_str(&source).expect("parses");
        let mut reached = 0;
        for entry in &module.entry_points {
            let functions = reachable_functions(&module, &entry.name);
            reached += functions.len();
            let bad: Vec<_> = functions.iter().filter(|f| forbidden(f)).collect();
            assert!(
                bad.is_empty(),
                "{module_name}::{} reaches {bad:?}",
                entry.name
            );
        }
        assert!(
            reached > 5,
            "{module_name}: the call graph was walked ({reached})"
        );
    }
    // Negative control: the image-space module's kernel reaches the approximations.
    let image_space = naga::front::wgsl::parse_str(&module_source("image_space").expect("module"))
        .expect("parses");
    let functions = reachable_functions(&image_space, "shade_two_interface");
    assert!(functions.iter().any(|f| forbidden(f)), "{functions:?}");
}
