//! Renders the reference of a mesh to PNG + EXR and prints the ray throughput:
//! `cargo run --release -p refract-trace --example render_reference -- MESH IOR RES OUT_PREFIX [ENVMAP]`
//! (MESH is a file or builtin:NAME).

use refract_eval::FrameFiles;
use std::path::PathBuf;
use std::time::Instant;

use refract_core::{Camera, CameraDesc};
use refract_eval::load_latlong;
use refract_eval::{LoadOptions, load_mesh};
use refract_geometry::builtin;
use refract_scene::{Environment, Refractor, Scene, TraceSettings};
use refract_trace::render;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [mesh, ior, res, out, rest @ ..] = args.as_slice() else {
        return Err("usage: render_reference MESH IOR RES OUT_PREFIX [ENVMAP]".into());
    };
    let mesh = if mesh.starts_with(builtin::PREFIX) {
        builtin::mesh(mesh)?
    } else {
        load_mesh(&PathBuf::from(mesh), &LoadOptions::default())?.mesh
    };
    let environment = match rest.first() {
        Some(path) => {
            let (map, report) = load_latlong(&PathBuf::from(path))?;
            eprintln!("environment: {report:?}");
            Environment::LatLong {
                map,
                intensity: 1.0,
            }
        }
        None => Environment::Procedural,
    };
    let scene = Scene::new("example", Refractor::new(mesh, ior.parse()?)?, environment);
    let res: u32 = res.parse()?;
    let camera = Camera::new(CameraDesc {
        width: res,
        height: res,
        ..CameraDesc::default()
    })?;
    let start = Instant::now();
    let frame = render(&scene, &camera, &TraceSettings::default());
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "{res}x{res}: {seconds:.3} s, {} rays, {:.2} Mrays/s",
        frame.rays,
        frame.rays as f64 / seconds / 1e6
    );
    frame.write_png(&PathBuf::from(format!("{out}.png")))?;
    frame.write_exr(&PathBuf::from(format!("{out}.exr")))?;
    Ok(())
}
