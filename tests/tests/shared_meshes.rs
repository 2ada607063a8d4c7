//! The real meshes of `../shared/data/meshes`: they load with their quirks fixed, and the d_N
//! precompute reports its miss rate (Wyman 2005a §3.1).

use refract_eval::mesh_files::NormalSource;
use refract_eval::{LoadOptions, load_mesh};
use refract_geometry::{MeshBvh, normal_distances};
use refract_tests::shared_data;

struct Expected {
    file: &'static str,
    triangles: usize,
    watertight: bool,
    /// Largest acceptable share of d_N rays that leave through a hole.
    max_miss_rate: f32,
}

const MESHES: [Expected; 7] = [
    Expected {
        file: "cow.obj",
        triangles: 5804,
        watertight: true,
        max_miss_rate: 0.005,
    },
    Expected {
        file: "teapot.obj",
        triangles: 6320,
        watertight: false,
        max_miss_rate: 0.5,
    },
    Expected {
        file: "stanford-bunny.obj",
        triangles: 69451,
        watertight: false,
        max_miss_rate: 0.05,
    },
    Expected {
        file: "horse.obj",
        triangles: 96966,
        watertight: true,
        max_miss_rate: 0.005,
    },
    Expected {
        file: "fandisk.obj",
        triangles: 12946,
        watertight: true,
        max_miss_rate: 0.005,
    },
    // The data README lists spot as open: its uv seams split vertices, but every edge is shared
    // by two triangles once vertices at the same position are identified, which is what counts
    // for refraction.
    Expected {
        file: "spot.obj",
        triangles: 5856,
        watertight: true,
        max_miss_rate: 0.005,
    },
    Expected {
        file: "suzanne.obj",
        triangles: 968,
        watertight: false,
        max_miss_rate: 0.5,
    },
];

#[test]
fn shared_meshes_load_and_precompute_d_n() {
    let Some(data) = shared_data() else { return };
    for expected in &MESHES {
        let path = data.join("meshes").join(expected.file);
        let loaded = load_mesh(&path, &LoadOptions::default()).expect("loads");
        let facts = loaded.mesh.facts();
        let bvh = MeshBvh::build(&loaded.mesh);
        let d_n = normal_distances(&loaded.mesh, &bvh);
        println!(
            "{:20} {:6} tris {:6} verts watertight {:5} boundary edges {:5} miss rate {:.4} \
             (fallback {:.3}) warnings {:?}",
            expected.file,
            facts.triangles,
            facts.vertices,
            facts.watertight,
            facts.boundary_edges,
            d_n.miss_rate(),
            d_n.fallback,
            loaded.report.warnings
        );
        assert!(
            facts.triangles <= expected.triangles && facts.triangles + 10 >= expected.triangles,
            "{}: {} triangles",
            expected.file,
            facts.triangles
        );
        assert_eq!(facts.watertight, expected.watertight, "{}", expected.file);
        assert!(
            (facts.bounding_sphere.radius - 1.0).abs() < 1e-4,
            "normalised"
        );
        assert!(
            d_n.miss_rate() <= expected.max_miss_rate,
            "{}: {}",
            expected.file,
            d_n.miss_rate()
        );
        assert!(d_n.values.iter().all(|d| d.is_finite() && *d >= 0.0));
        if expected.watertight {
            assert!(
                facts.signed_volume > 0.0,
                "{}: outward after loading",
                expected.file
            );
        }
    }
}

/// horse.obj is inside out with inward, non-unit file normals (see the data README).
#[test]
fn horse_quirks_are_detected_and_fixed() {
    let Some(data) = shared_data() else { return };
    let loaded = load_mesh(&data.join("meshes/horse.obj"), &LoadOptions::default()).expect("horse");
    let report = &loaded.report;
    assert_eq!(report.normal_source, NormalSource::File);
    assert!(report.flipped_inside_out, "{report:?}");
    assert!(
        !report.flipped_file_normals,
        "flipping the winding also turned the normals out"
    );
    assert!(
        report.non_unit_normals > 40_000,
        "{}",
        report.non_unit_normals
    );
    // Shading normals now agree with the outward winding almost everywhere.
    let mut from_winding = loaded.mesh.clone();
    from_winding.compute_vertex_normals();
    let agree = loaded
        .mesh
        .normals
        .iter()
        .zip(&from_winding.normals)
        .filter(|(n, w)| n.dot(**w) > 0.5)
        .count();
    assert!(
        agree as f32 > 0.99 * loaded.mesh.normals.len() as f32,
        "{agree}"
    );
}
