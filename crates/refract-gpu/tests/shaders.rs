//! Every WGSL file is parsed and validated by naga inside `cargo test` (no adapter needed), and
//! the uniform block's layout is compared with the Rust struct's.

use std::mem::offset_of;

use refract_core::gpu::FrameUniforms;
use refract_gpu::shaders::{module_source, modules};

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

#[test]
fn every_wgsl_file_is_in_a_validated_module() {
    let dirs = [
        concat!(env!("CARGO_MANIFEST_DIR"), "/../../shaders"),
        concat!(env!("CARGO_MANIFEST_DIR"), "/../refract-core/wgsl"),
    ];
    let on_disk: Vec<String> = dirs
        .iter()
        .flat_map(|dir| std::fs::read_dir(dir).expect("a shader directory"))
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".wgsl"))
        .collect();
    let modules = modules();
    for file in &on_disk {
        let embedded = modules
            .iter()
            .flat_map(|m| m.files)
            .find(|(name, _)| name == file);
        let Some((_, text)) = embedded else {
            panic!("{file} is in no module")
        };
        // The module embeds the file as it is on disk (not a stale copy under its name).
        let dir = if file.as_str() == "core.wgsl" || file.as_str() == "procedural_sky.wgsl" {
            concat!(env!("CARGO_MANIFEST_DIR"), "/../refract-core/wgsl")
        } else {
            concat!(env!("CARGO_MANIFEST_DIR"), "/../../shaders")
        };
        let on_disk_text = std::fs::read_to_string(format!("{dir}/{file}")).expect("read");
        assert_eq!(*text, on_disk_text, "{file}");
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
