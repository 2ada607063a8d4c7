//! `refract info MESH`: what the geometry precompute sees in a mesh.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use refract_eval::{LoadOptions, load_mesh};
use refract_geometry::{MeshBvh, builtin, normal_distances};

/// Arguments of `refract info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// A mesh file (.obj, .gltf, .glb) or a built-in shape (builtin:sphere, builtin:lens, ...);
    /// without one, only the GPU adapters are listed.
    pub mesh: Option<std::ffi::OsString>,
    /// Keep the file's coordinates instead of centring and scaling into the unit sphere.
    #[arg(long)]
    pub no_normalize: bool,
    /// Merge vertices closer than this fraction of the bounding radius before computing normals
    /// (a finite number from 0 to 0.1).
    #[arg(long, value_name = "EPSILON", value_parser = parse_weld)]
    pub weld: Option<f32>,
}

fn parse_weld(text: &str) -> Result<f32, String> {
    text.parse::<f32>()
        .ok()
        .filter(|v| v.is_finite() && (0.0..=0.1).contains(v))
        .ok_or_else(|| format!("`{text}`: expected a finite number from 0 to 0.1"))
}

/// Lists the GPU adapters; with a mesh, loads it, builds the BVH and d_N, and prints facts and
/// timings.
pub fn run(args: &InfoArgs) -> anyhow::Result<()> {
    let adapters = refract_gpu::list_adapters();
    if adapters.is_empty() {
        println!("GPU adapters     none (the GPU backend needs one; Debian: mesa-vulkan-drivers)");
    }
    for adapter in &adapters {
        let info = &adapter.info;
        let driver = if info.driver_info.is_empty() {
            String::new()
        } else {
            format!(", {}", info.driver_info)
        };
        println!(
            "GPU adapter      {} ({:?}, {:?}{driver}); ray queries: {}",
            info.name,
            info.backend,
            info.device_type,
            if adapter.ray_queries { "yes" } else { "no" }
        );
    }
    let Some(mesh_spec) = &args.mesh else {
        return Ok(());
    };
    println!();
    let start = Instant::now();
    let builtin_name = mesh_spec
        .to_str()
        .filter(|spec| spec.starts_with(builtin::PREFIX));
    let (mesh, report, material) = if let Some(spec) = builtin_name {
        (builtin::mesh(spec)?, None, None)
    } else {
        let options = LoadOptions {
            normalize: !args.no_normalize,
            weld_relative_epsilon: args.weld,
        };
        let path = PathBuf::from(mesh_spec);
        let loaded = load_mesh(&path, &options)?;
        (loaded.mesh, Some(loaded.report), loaded.material)
    };
    let load_ms = start.elapsed().as_secs_f64() * 1e3;
    let start = Instant::now();
    let bvh = MeshBvh::try_build(&mesh)?;
    let bvh_ms = start.elapsed().as_secs_f64() * 1e3;
    let start = Instant::now();
    let d_n = normal_distances(&mesh, &bvh);
    let d_n_ms = start.elapsed().as_secs_f64() * 1e3;

    let facts = mesh.facts();
    println!("mesh             {}", mesh.name);
    println!("triangles        {}", facts.triangles);
    println!("vertices         {}", facts.vertices);
    println!(
        "watertight       {} ({} boundary edges, {} non-manifold edges)",
        if facts.watertight { "yes" } else { "no" },
        facts.boundary_edges,
        facts.non_manifold_edges
    );
    println!("signed volume    {:.5}", facts.signed_volume);
    let sphere = facts.bounding_sphere;
    println!(
        "bounding sphere  centre ({:.4}, {:.4}, {:.4}) radius {:.4}",
        sphere.center.x, sphere.center.y, sphere.center.z, sphere.radius
    );
    if let Some(report) = &report {
        println!(
            "loaded           {} vertices, {} triangles as read; {} degenerate removed, {} welded; normals {:?}",
            report.source_vertices,
            report.source_triangles,
            report.degenerate_removed,
            report.welded,
            report.normal_source
        );
        for warning in &report.warnings {
            println!("warning          {warning}");
        }
    }
    if let Some(material) = material {
        println!(
            "glass material   ior {:?}, transmission {:?}, thickness {:?}",
            material.ior, material.transmission, material.thickness
        );
    }
    let (min, max) = d_n
        .values
        .iter()
        .fold((f32::INFINITY, 0.0f32), |(lo, hi), &d| {
            (lo.min(d), hi.max(d))
        });
    let mean =
        d_n.values.iter().map(|&d| f64::from(d)).sum::<f64>() / d_n.values.len().max(1) as f64;
    println!(
        "d_N              min {min:.4} mean {mean:.4} max {max:.4}; {} misses ({:.2}%) and {} rays over the budget of {} triangles used fallback {:.4}",
        d_n.misses,
        100.0 * d_n.miss_rate(),
        d_n.over_budget,
        refract_geometry::distance_along_normal::RAY_BUDGET,
        d_n.fallback
    );
    println!("time             load {load_ms:.1} ms, BVH build {bvh_ms:.1} ms, d_N {d_n_ms:.1} ms");
    Ok(())
}
