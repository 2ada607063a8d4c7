//! Mutation fuzzing of every loader on stable Rust, through the library APIs: real files
//! (suzanne.obj, a glTF written here, apartment.exr and city.hdr of `../shared/data`, a scene
//! file, a sweep file) with bytes replaced, inserted, deleted and the tail cut, must load or fail with an
//! error, never panic, hang or allocate without bound.
//!
//! `cargo test` runs a small budget (32 cases per loader); a long run:
//! `PROPTEST_CASES=100000 cargo test --release -p refract-tests --test loader_fuzz`.

use refract_eval::FrameFiles;
use std::path::{Path, PathBuf};

use proptest::prelude::*;
use refract_eval::{LoadOptions, load_mesh};

/// One edit of a file: replace, insert or delete a byte at a position (taken modulo the
/// length), or cut the file there.
#[derive(Clone, Debug)]
enum Edit {
    Replace(usize, u8),
    Insert(usize, u8),
    Delete(usize),
    Truncate(usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        4 => (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Edit::Replace(p, b)),
        2 => (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Edit::Insert(p, b)),
        2 => any::<usize>().prop_map(Edit::Delete),
        1 => any::<usize>().prop_map(Edit::Truncate),
    ]
}

fn mutate(seed: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut bytes = seed.to_vec();
    for edit in edits {
        if bytes.is_empty() {
            break;
        }
        let at = |p: usize| p % bytes.len();
        match *edit {
            Edit::Replace(p, b) => {
                let i = at(p);
                bytes[i] = b;
            }
            Edit::Insert(p, b) => {
                let i = at(p);
                bytes.insert(i, b);
            }
            Edit::Delete(p) => {
                let i = at(p);
                bytes.remove(i);
            }
            Edit::Truncate(p) => {
                let i = at(p);
                bytes.truncate(i);
            }
        }
    }
    bytes
}

/// A seed file: from `../shared/data` when present (else a small built-in one, so a fresh
/// clone still fuzzes).
fn seed(shared: &str, fallback: impl FnOnce() -> Vec<u8>) -> Vec<u8> {
    let path = refract_tests::shared_data_dir().join(shared);
    std::fs::read(&path).unwrap_or_else(|_| fallback())
}

fn tetrahedron_obj() -> Vec<u8> {
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n".to_vec()
}

/// A small glTF with an embedded buffer: one triangle, a node transform and a glass material
/// (read as a mesh and as a scene).
fn triangle_gltf() -> Vec<u8> {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let bytes: Vec<u8> = positions.iter().flat_map(|v| v.to_le_bytes()).collect();
    let base64 = base64_encode(&bytes);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0,"translation":[0,0,1],"children":[]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"material":0}}]}}],
"materials":[{{"extensions":{{"KHR_materials_ior":{{"ior":1.4}},"KHR_materials_transmission":{{"transmissionFactor":1}}}}}}],
"extensionsUsed":["KHR_materials_ior","KHR_materials_transmission"],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],
"buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{base64}"}}]}}"#
    )
    .into_bytes()
}

fn base64_encode(bytes: &[u8]) -> String {
    const TABLE: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(TABLE[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

fn small_exr() -> Vec<u8> {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("map.exr");
    let mut frame = refract_scene::Frame::new(8, 4);
    frame
        .color
        .iter_mut()
        .enumerate()
        .for_each(|(i, c)| *c = glam::Vec3::splat(i as f32));
    frame.write_exr(&path).expect("write");
    std::fs::read(path).expect("read")
}

fn small_hdr() -> Vec<u8> {
    let mut bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\n".to_vec();
    bytes.extend(std::iter::repeat_n([128u8, 64, 32, 129], 8).flatten());
    bytes
}

fn write_case(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write");
    path
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: std::env::var("PROPTEST_CASES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(32),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn obj_loader_never_panics(edits in prop::collection::vec(edit(), 1..12)) {
        let seed = seed("meshes/suzanne.obj", tetrahedron_obj);
        let dir = tempfile::tempdir().expect("tempdir");
        let path = write_case(dir.path(), "m.obj", &mutate(&seed, &edits));
        let _ = load_mesh(&path, &LoadOptions::default());
    }

    #[test]
    fn gltf_loader_never_panics(edits in prop::collection::vec(edit(), 1..8)) {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = write_case(dir.path(), "m.gltf", &mutate(&triangle_gltf(), &edits));
        let _ = load_mesh(&path, &LoadOptions::default());
        let _ = refract_eval::load_scene(&path);
    }

    #[test]
    fn exr_environment_loader_never_panics(edits in prop::collection::vec(edit(), 1..8)) {
        let seed = seed("envmaps/apartment.exr", small_exr);
        let dir = tempfile::tempdir().expect("tempdir");
        let path = write_case(dir.path(), "e.exr", &mutate(&seed, &edits));
        let _ = refract_eval::load_latlong(&path);
        let _ = refract_scene::Frame::read_exr(&path);
    }

    #[test]
    fn hdr_environment_loader_never_panics(edits in prop::collection::vec(edit(), 1..8)) {
        let seed = seed("envmaps/city.hdr", small_hdr);
        let dir = tempfile::tempdir().expect("tempdir");
        let path = write_case(dir.path(), "e.hdr", &mutate(&seed, &edits));
        let _ = refract_eval::load_latlong(&path);
    }

    #[test]
    fn scene_file_loader_never_panics(edits in prop::collection::vec(edit(), 1..8)) {
        let seed = b"[camera]\neye = [0.0, 0.5, 3.0]\nfov_y_deg = 40.0\n\n[environment]\nintensity = 1.0\n\n\
[refractor]\nmesh = \"builtin:icosphere\"\nior = 1.33\nscale = 0.8\nrotate_deg = [10.0, 0.0, 0.0]\n\n\
[[objects]]\nmesh = \"builtin:plane\"\ntranslate = [0.0, -1.0, 0.0]\nscale = 3.0\ncolor = [0.5, 0.5, 0.5]\n";
        let dir = tempfile::tempdir().expect("tempdir");
        let path = write_case(dir.path(), "s.toml", &mutate(seed, &edits));
        let _ = refract_eval::load_scene(&path);
    }

    /// Sweep files: any edit loads or is an error; digits inserted into the axes can make the
    /// product of the axes enormous, which is refused from the count, never built.
    #[test]
    fn sweep_file_loader_never_panics(edits in prop::collection::vec(edit(), 1..8)) {
        let seed = b"scenes = [\"sphere\", \"chart\"]\nmethods = [\"wyman\", \"iterative-seeded\"]\n\
backends = [\"cpu\"]\nior = [1.2, 1.5]\nres = [32, 64]\nframes = 1\n\n[params]\nseeds = [3, 7]\n\
guard = [0, 20]\n\n[[exclude]]\nscene = \"sphere\"\nmethod = \"iterative-seeded\"\n";
        let dir = tempfile::tempdir().expect("tempdir");
        let path = write_case(dir.path(), "sweep.toml", &mutate(seed, &edits));
        if let Ok(sweep) = refract_lab::sweep::Sweep::load(&path) {
            prop_assert!(sweep.jobs.len() <= refract_lab::sweep::MAX_JOBS);
        }
    }
}

/// The seeds themselves load, so the mutations start from valid files.
#[test]
fn the_seeds_load() {
    let dir = tempfile::tempdir().expect("tempdir");
    let obj = write_case(
        dir.path(),
        "m.obj",
        &seed("meshes/suzanne.obj", tetrahedron_obj),
    );
    load_mesh(&obj, &LoadOptions::default()).expect("obj seed");
    let gltf = write_case(dir.path(), "m.gltf", &triangle_gltf());
    let loaded = load_mesh(&gltf, &LoadOptions::default()).expect("gltf seed");
    assert_eq!(loaded.material.and_then(|m| m.ior), Some(1.4));
    let scene = refract_eval::load_scene(&gltf)
        .expect("gltf seed as a scene")
        .scene;
    assert_eq!(scene.refractor.ior(), 1.4);
    let exr = write_case(
        dir.path(),
        "e.exr",
        &seed("envmaps/apartment.exr", small_exr),
    );
    refract_eval::load_latlong(&exr).expect("exr seed");
    let hdr = write_case(dir.path(), "e.hdr", &seed("envmaps/city.hdr", small_hdr));
    refract_eval::load_latlong(&hdr).expect("hdr seed");
}
