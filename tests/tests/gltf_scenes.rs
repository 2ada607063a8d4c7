//! A glTF file read as a scene (`refract_eval::load_scene("x.glb")`): every transmissive part a
//! refractor with its `KHR_materials_*` glass, the others opaque objects, the file's camera.
//! Held by a round trip: the many-refractor scenes exported by `refract export --format gltf`
//! and read back trace the same refractors, interface by interface, on the same pixels.

use refract_eval::gltf_export::export_gltf;
use refract_eval::load_scene;
use refract_scene::{Aov, Frame, Scene, TraceSettings};

const WIDTH: u32 = 80;
const HEIGHT: u32 = 60;

fn exported_and_read_back(name: &str) -> (Scene, Scene, Vec<String>) {
    let original = load_scene(name).expect("built-in").scene;
    let dir = tempfile::tempdir().expect("temporary directory");
    export_gltf(&original)
        .expect("export")
        .write(dir.path())
        .expect("write");
    let loaded = load_scene(dir.path().join("scene.gltf")).expect("the exported glTF as a scene");
    (original, loaded.scene, loaded.warnings)
}

fn trace(scene: &Scene) -> Frame {
    let camera = scene.camera(WIDTH, HEIGHT).expect("camera");
    refract_trace::render(scene, &camera, &TraceSettings::default())
}

fn counts(frame: &Frame, aov: Aov) -> &[u32] {
    frame
        .count(aov)
        .unwrap_or_else(|| panic!("no {aov:?} layer"))
}

/// Every refractor comes back with its IOR, its nesting, its roughness, its dispersion and its
/// absorption, the chart and the
/// floor as opaque objects; traced from the file's camera, the refractors met and the
/// interfaces crossed agree with the built-in scene's on all but a few silhouette pixels. A
/// lost refractor, a wrong nesting, a camera off by a normalisation or a refractor scaled
/// apart from the others changes hundreds of pixels.
#[test]
fn exported_many_refractor_scenes_read_back_as_the_same_refractors() {
    for name in [
        "glass-behind-glass",
        "vessel",
        "liquid",
        "rough-glass",
        "prism",
    ] {
        let (original, loaded, warnings) = exported_and_read_back(name);
        assert_eq!(
            loaded.refractor_count(),
            original.refractor_count(),
            "{name}: refractors ({warnings:?})"
        );
        assert_eq!(loaded.objects.len(), original.objects.len(), "{name}");
        for (k, (a, b)) in original.refractors().zip(loaded.refractors()).enumerate() {
            assert_eq!(a.ior(), b.ior(), "{name} refractor {k}: IOR");
            assert_eq!(a.within(), b.within(), "{name} refractor {k}: nesting");
            // pbrMetallicRoughness.roughnessFactor (issue 52).
            assert_eq!(
                a.roughness(),
                b.roughness(),
                "{name} refractor {k}: roughness"
            );
            // KHR_materials_dispersion (issue 52): dispersion = 20 / V_d there and back.
            assert!(
                a.abbe() == b.abbe() || ((a.abbe() - b.abbe()) / a.abbe()).abs() < 1e-6,
                "{name} refractor {k}: Abbe number {} vs {}",
                a.abbe(),
                b.abbe()
            );
            assert_eq!(
                a.attenuation().is_some(),
                b.attenuation().is_some(),
                "{name} refractor {k}: absorption"
            );
            assert_eq!(a.mesh().triangles.len(), b.mesh().triangles.len());
        }
        // The whole scene is scaled together: the refractors keep their relative sizes.
        let diameters = |s: &Scene| s.refractors().map(|r| r.diameter()).collect::<Vec<_>>();
        let (da, db) = (diameters(&original), diameters(&loaded));
        for k in 1..da.len() {
            let ratio = (da[k] / da[0]) / (db[k] / db[0]);
            assert!(
                (ratio - 1.0).abs() < 1e-4,
                "{name} refractor {k}: relative size {ratio}"
            );
        }
        let (a, b) = (trace(&original), trace(&loaded));
        for aov in [Aov::RefractorsMet, Aov::Interfaces] {
            let (ca, cb) = (counts(&a, aov), counts(&b, aov));
            let differing = ca.iter().zip(cb).filter(|(x, y)| x != y).count();
            let met = ca.iter().filter(|&&x| x != 0).count();
            println!("{name} {aov:?}: {differing} of {met} pixels differ");
            assert!(met > 400, "{name}: the refractors cover {met} pixels");
            assert!(
                differing * 100 <= met,
                "{name} {aov:?}: {differing} of {met} pixels differ"
            );
        }
    }
}

/// The absorption of `KHR_materials_volume` comes back as the same coefficient, in the scaled
/// scene's units: σ · (the scene's scale) is what the file says.
#[test]
fn attenuation_is_read_in_the_scenes_units() {
    let text = concat!(
        "[[refractor]]\nmesh = \"builtin:sphere\"\nior = 1.5\nscale = 2.0\n",
        "attenuation_color = [0.5, 0.8, 0.9]\nattenuation_distance = 0.7\n",
        "[[refractor]]\nmesh = \"builtin:sphere\"\nior = 1.33\nscale = 1.0\n",
    );
    let original = refract_eval::load_scene_str("absorbing", text, std::path::Path::new("."), "t")
        .expect("scene")
        .scene;
    let dir = tempfile::tempdir().expect("temporary directory");
    export_gltf(&original)
        .expect("export")
        .write(dir.path())
        .expect("write");
    let loaded = load_scene(dir.path().join("scene.gltf"))
        .expect("read back")
        .scene;
    let scale = loaded.refractor.diameter() / original.refractor.diameter();
    let (a, b) = (
        original
            .refractor
            .attenuation()
            .expect("absorbing")
            .coefficient(),
        loaded
            .refractor
            .attenuation()
            .expect("absorbing")
            .coefficient(),
    );
    assert!(
        (a - b * scale).abs().max_element() < 1e-4 * a.max_element(),
        "σ {a} in the scene, {b} read back at scale {scale}"
    );
    assert_eq!(loaded.refractor_at(1).expect("water").within(), Some(0));
}

/// A glTF without any transmissive material is not a scene to refract through: the error says
/// so and names the file.
#[test]
fn a_gltf_without_glass_is_refused_by_name() {
    let original = load_scene("chart").expect("built-in").scene;
    let dir = tempfile::tempdir().expect("temporary directory");
    export_gltf(&original)
        .expect("export")
        .write(dir.path())
        .expect("write");
    let path = dir.path().join("scene.gltf");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("read")).expect("json");
    for material in json["materials"].as_array_mut().expect("materials") {
        if let Some(extensions) = material["extensions"].as_object_mut() {
            extensions.remove("KHR_materials_transmission");
        }
    }
    std::fs::write(&path, json.to_string()).expect("write");
    let message = load_scene(&path).expect_err("no glass").to_string();
    assert!(
        message.contains("scene.gltf") && message.contains("no transmissive material"),
        "{message}"
    );
}
