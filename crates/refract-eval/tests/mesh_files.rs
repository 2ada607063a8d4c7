//! Loading OBJ and glTF files, good and broken ones (generated here, in a temporary directory).

use std::path::{Path, PathBuf};

use glam::Vec3;
use refract_eval::mesh_files::NormalSource;
use refract_eval::{LoadOptions, load_mesh};
use refract_geometry::GeometryError;

fn write(dir: &Path, name: &str, content: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, content).expect("write test file");
    path
}

fn raw() -> LoadOptions {
    LoadOptions {
        normalize: false,
        ..LoadOptions::default()
    }
}

const CUBE_QUADS: &str = "\
v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1
f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8
";

#[test]
fn obj_quads_are_triangulated_and_normals_computed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let loaded = load_mesh(
        &write(dir.path(), "cube.obj", CUBE_QUADS.as_bytes()),
        &raw(),
    )
    .expect("cube");
    let facts = loaded.mesh.facts();
    assert_eq!((facts.triangles, facts.vertices), (12, 8));
    assert!(facts.watertight);
    assert!((facts.signed_volume - 8.0).abs() < 1e-5);
    assert_eq!(loaded.report.normal_source, NormalSource::Computed);
    // Angle-weighted corner normal of a cube: along the diagonal.
    let corner = loaded.mesh.normals[6];
    assert!((corner - Vec3::ONE.normalize()).length() < 1e-5, "{corner}");
}

#[test]
fn inside_out_mesh_with_inward_non_unit_normals_is_fixed() {
    // The cube wound inward with normals of length 6 pointing inward, like horse.obj.
    let mut obj = String::from(
        "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n",
    );
    for v in [
        [-1, -1, -1],
        [1, -1, -1],
        [1, 1, -1],
        [-1, 1, -1],
        [-1, -1, 1],
        [1, -1, 1],
        [1, 1, 1],
        [-1, 1, 1],
    ] {
        obj += &format!("vn {} {} {}\n", -6 * v[0], -6 * v[1], -6 * v[2]);
    }
    for f in [
        "1 2 3 4", "8 7 6 5", "5 6 2 1", "6 7 3 2", "7 8 4 3", "8 5 1 4",
    ] {
        let face: Vec<String> = f.split(' ').map(|i| format!("{i}//{i}")).collect();
        obj += &format!("f {}\n", face.join(" "));
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let loaded = load_mesh(
        &write(dir.path(), "inside_out.obj", obj.as_bytes()),
        &LoadOptions::default(),
    )
    .expect("loads");
    let report = &loaded.report;
    assert!(
        report.flipped_inside_out && !report.flipped_file_normals,
        "{report:?}"
    );
    assert_eq!(report.non_unit_normals, 8);
    assert_eq!(report.normal_source, NormalSource::File);
    let facts = loaded.mesh.facts();
    assert!(facts.signed_volume > 0.0);
    for (p, n) in loaded.mesh.positions.iter().zip(&loaded.mesh.normals) {
        assert!(p.dot(*n) > 0.0 && (n.length() - 1.0).abs() < 1e-6);
    }
    // Normalised into the unit sphere.
    assert!((facts.bounding_sphere.radius - 1.0).abs() < 1e-5);
}

#[test]
fn broken_obj_files_give_errors_naming_the_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    type IsExpected = fn(&GeometryError) -> bool;
    let cases: [(&str, &str, IsExpected); 6] = [
        ("empty.obj", "", |e| {
            matches!(e, GeometryError::EmptyFile { .. })
        }),
        (
            "out_of_range.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
            |e| matches!(e, GeometryError::Obj { .. }),
        ),
        ("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", |e| {
            matches!(e, GeometryError::NonFinite { vertex: 1, .. })
        }),
        (
            "degenerate.obj",
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n",
            |e| matches!(e, GeometryError::NoTriangles { degenerate: 2, .. }),
        ),
        ("points_only.obj", "v 0 0 0\nv 1 0 0\n", |e| {
            matches!(e, GeometryError::NoTriangles { .. })
        }),
        ("truncated.obj", "v 0 0 0\nv 1 0 0\nv 0 1", |e| {
            matches!(e, GeometryError::Obj { .. })
        }),
    ];
    for (name, content, expected) in cases {
        let path = write(dir.path(), name, content.as_bytes());
        let err = load_mesh(&path, &raw()).expect_err(name);
        assert!(expected(&err), "{name}: unexpected {err:?}");
        assert!(
            err.to_string().contains(name),
            "{name}: message does not name the file: {err}"
        );
    }
    let missing = load_mesh(&dir.path().join("missing.obj"), &raw()).expect_err("missing");
    assert!(
        matches!(missing, GeometryError::Io { .. }) && missing.to_string().contains("missing.obj")
    );
    let unsupported = load_mesh(&write(dir.path(), "mesh.stl", b"solid"), &raw()).expect_err("stl");
    assert!(matches!(
        unsupported,
        GeometryError::UnsupportedFormat { .. }
    ));
}

/// A GLB holding a tetrahedron under a translated and scaled node, with a glass material.
fn tetrahedron_glb(index_override: Option<u16>) -> Vec<u8> {
    tetrahedron_glb_with(index_override, &[], "")
}

/// [`tetrahedron_glb`] with `required` as its `extensionsRequired`.
fn tetrahedron_glb_requiring(index_override: Option<u16>, required: &[&str]) -> Vec<u8> {
    tetrahedron_glb_with(index_override, required, "")
}

/// [`tetrahedron_glb`] with `required` as its `extensionsRequired` and `material` (JSON
/// members ending in a comma) at the start of its material.
fn tetrahedron_glb_with(index_override: Option<u16>, required: &[&str], material: &str) -> Vec<u8> {
    let required = if required.is_empty() {
        String::new()
    } else {
        format!("\"extensionsRequired\":[\"{}\"],", required.join("\",\""))
    };
    let positions: [[f32; 3]; 4] = [
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ];
    let mut indices: [u16; 12] = [0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2];
    if let Some(bad) = index_override {
        indices[5] = bad;
    }
    let mut bin: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},{required}
"extensionsUsed":["KHR_materials_ior","KHR_materials_transmission","KHR_materials_volume"],
"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0,"translation":[2,0,0],"scale":[0.5,0.5,0.5]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
"materials":[{{{material}"extensions":{{"KHR_materials_ior":{{"ior":1.45}},
  "KHR_materials_transmission":{{"transmissionFactor":1.0}},
  "KHR_materials_volume":{{"thicknessFactor":0.2}}}}}}],
"buffers":[{{"byteLength":{len}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,-1,-1],"max":[1,1,1]}},
  {{"bufferView":1,"componentType":5123,"count":12,"type":"SCALAR"}}]}}"#,
        len = bin.len()
    );
    let mut json = json.into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut glb = Vec::new();
    glb.extend(b"glTF");
    glb.extend(2u32.to_le_bytes());
    glb.extend((total as u32).to_le_bytes());
    glb.extend((json.len() as u32).to_le_bytes());
    glb.extend(0x4E4F_534Au32.to_le_bytes());
    glb.extend(&json);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(0x004E_4942u32.to_le_bytes());
    glb.extend(&bin);
    glb
}

#[test]
fn glb_with_node_transform_and_glass_material() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = write(dir.path(), "tetra.glb", &tetrahedron_glb(None));
    let loaded = load_mesh(&path, &raw()).expect("glb loads");
    let material = loaded.material.expect("glass material");
    assert_eq!(material.ior, Some(1.45));
    assert_eq!(material.transmission, Some(1.0));
    // thicknessFactor 0.2 in mesh units under a node scaled by 0.5: 0.1 in the file's world.
    assert_eq!(material.thickness, Some(0.1));
    let facts = loaded.mesh.facts();
    assert_eq!(facts.triangles, 4);
    assert!(facts.watertight);
    // Node transform: x' = 0.5 x + (2, 0, 0).
    assert!((facts.bounding_sphere.center - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6);
    assert!((facts.bounding_sphere.radius - 0.5 * 3f32.sqrt()).abs() < 1e-6);
    // Volume of this regular tetrahedron (edge 2√2 · 0.5): 8/3 · 0.125, outward after any flip.
    assert!(
        (facts.signed_volume - 8.0 / 3.0 * 0.125).abs() < 1e-5,
        "{facts:?}"
    );
}

#[test]
fn broken_gltf_files_give_errors_naming_the_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let good = tetrahedron_glb(None);
    let cases: [(&str, Vec<u8>); 4] = [
        ("truncated.glb", good[..good.len() / 2].to_vec()),
        ("bad_index.glb", tetrahedron_glb(Some(40))),
        (
            "malformed.gltf",
            b"{ \"asset\": { \"version\": \"2.0\" }, \"meshes\": [ { ".to_vec(),
        ),
        (
            "missing_buffer.gltf",
            br#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":48,"uri":"nowhere.bin"}]}"#
                .to_vec(),
        ),
    ];
    for (name, bytes) in cases {
        let err = load_mesh(&write(dir.path(), name, &bytes), &raw()).expect_err(name);
        assert!(matches!(err, GeometryError::Gltf { .. }), "{name}: {err:?}");
        assert!(err.to_string().contains(name), "{name}: {err}");
    }
    // glTF 1.0 is another format: refused by name (issue 34, item 9).
    let old = write(
        dir.path(),
        "old.gltf",
        br#"{"asset":{"version":"1.0"},"meshes":[]}"#,
    );
    let err = load_mesh(&old, &raw()).expect_err("glTF 1.0");
    assert!(matches!(err, GeometryError::Gltf { .. }), "{err:?}");
    assert!(
        err.to_string().contains("old.gltf") && err.to_string().contains("glTF 1.0"),
        "{err}"
    );
    let no_mesh = write(
        dir.path(),
        "no_mesh.gltf",
        br#"{"asset":{"version":"2.0"}}"#,
    );
    assert!(matches!(
        load_mesh(&no_mesh, &raw()),
        Err(GeometryError::NoTriangles { .. })
    ));
}

/// glTF node hierarchies that are not trees, primitives naming missing accessors, and very deep
/// (valid) hierarchies: clear errors, never a panic or a stack overflow (before: exit 134 and a
/// panic inside gltf-json).
#[test]
fn malformed_gltf_hierarchies_and_accessors_are_errors_not_crashes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let asset = r#""asset":{"version":"2.0"}"#;
    let missing = write(
        dir.path(),
        "missing.gltf",
        format!(r#"{{{asset},"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}]}}"#)
            .as_bytes(),
    );
    let err = load_mesh(&missing, &raw()).expect_err("missing accessor");
    assert!(
        err.to_string().contains("missing.gltf") && err.to_string().contains("accessor 0"),
        "{err}"
    );
    let cycle = write(
        dir.path(),
        "cycle.gltf",
        format!(r#"{{{asset},"scenes":[{{"nodes":[0]}}],"nodes":[{{"children":[0]}}]}}"#)
            .as_bytes(),
    );
    let err = load_mesh(&cycle, &raw()).expect_err("cycle");
    assert!(err.to_string().contains("reached twice"), "{err}");
    // An acyclic chain 50,000 nodes deep: walked without recursion; it has no mesh.
    let n = 50_000;
    let nodes: Vec<String> = (0..n)
        .map(|i| {
            if i + 1 < n {
                format!(r#"{{"children":[{}]}}"#, i + 1)
            } else {
                "{}".to_owned()
            }
        })
        .collect();
    let deep = write(
        dir.path(),
        "deep.gltf",
        format!(
            r#"{{{asset},"scenes":[{{"nodes":[0]}}],"nodes":[{}]}}"#,
            nodes.join(",")
        )
        .as_bytes(),
    );
    let err = load_mesh(&deep, &raw()).expect_err("no triangles");
    assert!(err.to_string().contains("deep.gltf"), "{err}");
}

/// Coincident duplicated triangles (as real scans have) are removed on load with a warning, so
/// that 80,000 copies of a tetrahedron's faces load as the tetrahedron (before: quadratic BVH
/// and `d_N` work, minutes for 64k duplicates).
#[test]
fn coincident_duplicate_triangles_are_removed_with_a_warning() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut obj = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n");
    for _ in 0..20_000 {
        obj.push_str("f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    }
    let path = write(dir.path(), "dup.obj", obj.as_bytes());
    let loaded = load_mesh(&path, &raw()).expect("loads");
    assert_eq!(loaded.mesh.triangles.len(), 4);
    assert_eq!(loaded.report.duplicates_removed, 79_996);
    assert!(
        loaded
            .report
            .warnings
            .iter()
            .any(|w| w.contains("79996 coincident duplicate")),
        "{:?}",
        loaded.report.warnings
    );
}

/// A well-shaped tetrahedron is not degenerate at any scale `f32` can hold (before: called
/// degenerate at 1e38, where squared lengths overflow, and at 1e-30, where they underflow).
#[test]
fn tiny_and_huge_meshes_are_not_degenerate() {
    let dir = tempfile::tempdir().expect("tempdir");
    for scale in [1e38f32, 1e-30] {
        let obj = format!(
            "v 0 0 0\nv {s:e} 0 0\nv 0 {s:e} 0\nv 0 0 {s:e}\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
            s = scale
        );
        let path = write(dir.path(), "tet.obj", obj.as_bytes());
        let loaded = load_mesh(&path, &LoadOptions::default()).expect("loads");
        assert_eq!(loaded.report.degenerate_removed, 0, "scale {scale}");
        assert_eq!(loaded.mesh.triangles.len(), 4);
        let sphere = loaded.mesh.bounding_sphere();
        assert!(
            (sphere.radius - 1.0).abs() < 1e-4,
            "normalised: {}",
            sphere.radius
        );
    }
}

/// OBJ errors say what and where (before: just `read error`), and comments may hold any bytes.
#[test]
fn obj_errors_say_what_and_where_and_comments_may_be_any_bytes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let folder = dir.path().join("folder.obj");
    std::fs::create_dir(&folder).expect("mkdir");
    let err = load_mesh(&folder, &raw()).expect_err("directory");
    assert!(format!("{err}: {:?}", std::error::Error::source(&err)).contains("folder.obj"));
    let bytes: Vec<u8> = (0..2000u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
        .collect();
    let random = write(dir.path(), "random.obj", &bytes);
    let err = load_mesh(&random, &raw())
        .expect_err("random bytes")
        .to_string();
    assert!(err.contains("random.obj") && err.contains("line"), "{err}");
    let malformed = write(
        dir.path(),
        "bad.obj",
        b"v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n",
    );
    let err = load_mesh(&malformed, &raw())
        .expect_err("malformed")
        .to_string();
    assert!(err.contains("line 2") && err.contains("v 1 x 0"), "{err}");
    let latin1 = write(
        dir.path(),
        "latin1.obj",
        b"# caf\xe9 cr\xe8me\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let loaded = load_mesh(&latin1, &raw()).expect("a non-UTF-8 comment is fine");
    assert_eq!(loaded.mesh.triangles.len(), 1);
}

/// An accessor that reads past its buffer view is reported as such (before: "a primitive
/// without POSITION").
#[test]
fn gltf_accessor_overruns_name_the_accessor_and_view() {
    let dir = tempfile::tempdir().expect("tempdir");
    let glb = tetrahedron_glb(None);
    let (from, to) = (br#""count":4,"type":"VEC3""#, br#""count":9,"type":"VEC3""#);
    let at = glb
        .windows(from.len())
        .position(|w| w == from)
        .expect("the position accessor");
    let mut short = glb.clone();
    short[at..at + from.len()].copy_from_slice(to);
    let path = write(dir.path(), "short.glb", &short);
    let err = load_mesh(&path, &raw()).expect_err("overrun").to_string();
    assert!(
        err.contains("short.glb")
            && err.contains("accessor 0 needs 108 bytes of buffer view 0, which has 48"),
        "{err}"
    );
}

/// `KHR_materials_volume`'s thickness becomes the refractor's default engine thickness, scaled
/// by the node (0.5), the normalisation into the unit sphere (1/(0.5·√3)) and the scene's
/// `scale` (2), as the engines scale it with the object; the engine methods use it.
#[test]
fn gltf_volume_thickness_follows_the_object_into_the_scene() {
    let dir = tempfile::tempdir().expect("tempdir");
    write(dir.path(), "tetra.glb", &tetrahedron_glb(None));
    let scene_path = write(
        dir.path(),
        "scene.toml",
        b"[refractor]\nmesh = \"tetra.glb\"\nior = 1.45\nscale = 2.0\n",
    );
    let scene = refract_eval::load_scene(scene_path.to_str().expect("utf-8"))
        .expect("scene")
        .scene;
    let expected = 0.2 * 0.5 / (0.5 * 3f32.sqrt()) * 2.0;
    let thickness = scene
        .refractor
        .volume_thickness()
        .expect("a volume thickness");
    assert!(
        (thickness - expected).abs() < 1e-5,
        "{thickness} vs {expected}"
    );
    let params =
        refract_scene::registry::EngineParams::try_from((refract_scene::MethodId::VolumeThickness
            .info()
            .defaults)());
    let params = params.expect("engine parameters");
    assert_eq!(params.thickness_for(&scene.refractor), thickness);
    // Without a glTF thickness the default is the mean d_N.
    let sphere = refract_eval::load_scene("sphere").expect("sphere").scene;
    assert_eq!(sphere.refractor.volume_thickness(), None);
    assert_eq!(
        params.thickness_for(&sphere.refractor),
        sphere.refractor.mean_d_n()
    );
}

/// A file that requires `KHR_materials_volume` loads with its thickness (issue 54 #8: gltf's
/// validation refused it as unsupported although the loader reads it); one that requires an
/// extension refract cannot read is refused, naming the extension.
#[test]
fn gltf_required_extensions_that_are_read_are_accepted() {
    let dir = tempfile::tempdir().expect("tempdir");
    let required = ["KHR_materials_volume", "KHR_materials_ior"];
    let path = write(
        dir.path(),
        "required.glb",
        &tetrahedron_glb_requiring(None, &required),
    );
    let loaded = load_mesh(&path, &raw()).expect("KHR_materials_volume is read");
    let glass = loaded.material.expect("a glass material");
    assert!(glass.thickness.is_some(), "{glass:?}");
    let draco = write(
        dir.path(),
        "draco.glb",
        &tetrahedron_glb_requiring(None, &["KHR_draco_mesh_compression"]),
    );
    let err = load_mesh(&draco, &raw()).expect_err("draco").to_string();
    assert!(
        err.contains("draco.glb")
            && err.contains("extensionsRequired lists KHR_draco_mesh_compression")
            && err.contains("KHR_materials_volume"),
        "{err}"
    );
}

/// A glass material's roughness is read, glTF's default 1 when it gives none (issue 52), and
/// no longer warned about as unmodelled; `"roughnessFactor": 0` is smooth glass.
#[test]
fn gltf_glass_roughness_is_read_with_gltfs_default() {
    let dir = tempfile::tempdir().expect("tempdir");
    let load = |name: &str, material: &str| {
        let path = write(dir.path(), name, &tetrahedron_glb_with(None, &[], material));
        load_mesh(&path, &raw()).expect("load")
    };
    let rough = load("rough.glb", "");
    assert_eq!(rough.material.map(|m| m.roughness), Some(1.0));
    assert!(
        rough.report.warnings.iter().all(|w| !w.contains("rough")),
        "{:?}",
        rough.report.warnings
    );
    let smooth = load(
        "smooth.glb",
        r#""pbrMetallicRoughness":{"roughnessFactor":0},"#,
    );
    assert_eq!(smooth.material.map(|m| m.roughness), Some(0.0));
    let half = load(
        "half.glb",
        r#""pbrMetallicRoughness":{"roughnessFactor":0.5},"#,
    );
    assert_eq!(half.material.map(|m| m.roughness), Some(0.5));
    assert!(smooth.report.warnings.iter().all(|w| !w.contains("glass")));
}
