//! The real HDR environment maps of `../shared/data/envmaps`, with their quirks.

use glam::Vec3;
use refract_core::environment::latlong_to_direction;
use refract_eval::load_latlong;
use refract_scene::Environment;
use refract_tests::shared_data;

const EXR_MAPS: [&str; 7] = [
    "venice.exr",
    "studio.exr",
    "city.exr",
    "esplanade.exr",
    "forest.exr",
    "sky.exr",
    "apartment.exr",
];

#[test]
fn every_exr_map_loads_with_negatives_clamped_and_counted() {
    let Some(data) = shared_data() else { return };
    for name in EXR_MAPS {
        let (map, report) = load_latlong(&data.join("envmaps").join(name)).expect(name);
        println!("{name}: {}x{}, {report:?}", map.width, map.height);
        assert_eq!((map.width, map.height), (512, 256), "{name}");
        // The data README: every file has some negative texels.
        assert!(report.negative_clamped > 0, "{name}");
        assert!(
            map.texels
                .iter()
                .all(|t| t.cmpge(Vec3::ZERO).all() && t.is_finite())
        );
    }
}

/// city.hdr is city.exr with negatives clamped: both loaders and the lookup must agree.
#[test]
fn hdr_and_exr_loaders_agree_on_city() {
    let Some(data) = shared_data() else { return };
    let (exr, _) = load_latlong(&data.join("envmaps/city.exr")).expect("exr");
    let (hdr, report) = load_latlong(&data.join("envmaps/city.hdr")).expect("hdr");
    assert_eq!(report.negative_clamped, 0);
    assert_eq!((exr.width, exr.height), (hdr.width, hdr.height));
    let exr = Environment::LatLong {
        map: exr,
        intensity: 1.0,
    };
    let hdr = Environment::LatLong {
        map: hdr,
        intensity: 1.0,
    };
    let mut worst = 0.0f32;
    for k in 0..400 {
        let uv = glam::Vec2::new(
            (k % 20) as f32 / 20.0 + 0.013,
            (k / 20) as f32 / 20.0 + 0.02,
        );
        let d = latlong_to_direction(uv);
        let (a, b) = (exr.radiance(d), hdr.radiance(d));
        // RGBE keeps 8 bits of mantissa per channel: relative error below 1 % of the largest.
        worst = worst.max((a - b).abs().max_element() / a.max_element().max(1e-3));
    }
    assert!(worst < 0.02, "worst relative difference {worst}");
}

/// A missing or malformed map is an error naming the file.
#[test]
fn broken_maps_are_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bad = dir.path().join("bad.exr");
    std::fs::write(&bad, b"not an exr").expect("write");
    let err = load_latlong(&bad).expect_err("malformed");
    assert!(err.to_string().contains("bad.exr"), "{err}");
    let err = load_latlong(&dir.path().join("sky.png")).expect_err("unsupported");
    assert!(err.to_string().contains("sky.png"), "{err}");
}
