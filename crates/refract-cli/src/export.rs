//! `refract export SCENE --out DIR`: the scene exactly as refract renders it (meshes after
//! loading, normalisation and transforms, with refract's vertex normals), for other renderers.
//! `--format obj` (the default): `refractor.obj` (and `refractor-K.obj` for every further
//! refractor), `object-K.obj`, `environment.exr` (the lat-long map as sampled) and `scene.json`
//! (camera, each refractor's media as Mitsuba's `int_ior`/`ext_ior`, environment); the Mitsuba 3
//! cross-check (`scripts/mitsuba-cross-check.py`) renders from these files. `--format gltf`:
//! glTF 2.0 for the engines' own renderers (`refract_eval::gltf_export`).

use refract_eval::FrameFiles;
use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context;
use refract_eval::atomic_write::write_text_atomically;
use refract_eval::load_scene;
use refract_geometry::Mesh;
use refract_scene::{Environment, Frame};
use serde::Serialize;

/// Arguments of `refract export`.
#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// A built-in scene, a .toml scene file or a .gltf/.glb file.
    pub scene: std::ffi::OsString,
    /// Output directory (created).
    #[arg(long)]
    pub out: PathBuf,
    /// What to write.
    #[arg(long, value_enum, default_value_t = ExportFormat::Obj)]
    pub format: ExportFormat,
}

/// The file formats of `refract export`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ExportFormat {
    /// OBJ meshes, `environment.exr` and `scene.json` (what the Mitsuba 3 cross-check reads).
    Obj,
    /// glTF 2.0 with the Khronos glass extensions, `environment.hdr` and the position-coded
    /// variant for lookup studies (what the engines' own renderers read).
    Gltf,
}

#[derive(Serialize)]
struct CameraJson {
    eye: [f32; 3],
    target: [f32; 3],
    up: [f32; 3],
    fov_y_deg: f32,
}

#[derive(Serialize)]
struct EnvironmentJson {
    /// `latlong`, `constant` or `procedural`.
    kind: &'static str,
    /// `environment.exr` beside scene.json: the map as refract samples it (lat-long only).
    file: Option<PathBuf>,
    /// The file the scene loaded it from.
    source: Option<PathBuf>,
    intensity: f32,
    constant: Option<[f32; 3]>,
}

#[derive(Serialize)]
struct SceneJson {
    name: String,
    camera: CameraJson,
    ior: f32,
    /// The refractor's conductor (`eta`, `k` per RGB channel) when it is one, else `null`.
    conductor: Option<ConductorJson>,
    refractor: String,
    /// Every refractor, the first (`refractor`, `ior`, `conductor` above) first.
    refractors: Vec<RefractorJson>,
    objects: Vec<String>,
    environment: EnvironmentJson,
}

/// One refractor's surface as Mitsuba's `dielectric` describes it.
#[derive(Serialize)]
struct RefractorJson {
    file: String,
    /// The index inside (Mitsuba's `int_ior`).
    int_ior: f32,
    /// The index of the medium around it (`ext_ior`): 1, or that of the refractor it lies in.
    ext_ior: f32,
    /// The refractor it lies within (an index into `refractors`), `null` for air.
    within: Option<usize>,
    conductor: Option<ConductorJson>,
    /// Beer-Lambert absorption of its medium, `null` for clear.
    attenuation: Option<AttenuationJson>,
}

/// `KHR_materials_volume`'s attenuation and the coefficient it means (Mitsuba's
/// `homogeneous` medium with `sigma_t` = `coefficient`, albedo 0).
#[derive(Serialize)]
struct AttenuationJson {
    color: [f32; 3],
    distance: f32,
    coefficient: [f32; 3],
}

#[derive(Serialize)]
struct ConductorJson {
    name: String,
    eta: [f32; 3],
    k: [f32; 3],
}

fn conductor_json(c: refract_scene::Conductor) -> ConductorJson {
    ConductorJson {
        name: refract_scene::conductor_name(&c).to_owned(),
        eta: c.eta.to_array(),
        k: c.k.to_array(),
    }
}

/// A mesh as OBJ with per-vertex normals (`f a//a b//b c//c`, 1-based).
fn obj(mesh: &Mesh) -> String {
    let mut text = format!("# {} exported by refract\n", mesh.name);
    for p in &mesh.positions {
        let _ = writeln!(text, "v {:e} {:e} {:e}", p.x, p.y, p.z);
    }
    for n in &mesh.normals {
        let _ = writeln!(text, "vn {:e} {:e} {:e}", n.x, n.y, n.z);
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        let _ = writeln!(text, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    text
}

/// Runs `refract export`.
pub fn run(args: &ExportArgs) -> anyhow::Result<()> {
    let loaded = load_scene(&args.scene)?;
    let scene = loaded.scene;
    refract_lab::output_dirs::create_dir(&args.out)
        .with_context(|| format!("{}: cannot create the directory", args.out.display()))?;
    if args.format == ExportFormat::Gltf {
        let written = refract_eval::gltf_export::export_gltf(&scene)?.write(&args.out)?;
        println!(
            "{}: {} files -> {}",
            scene.name,
            written.len(),
            args.out.join("scene.gltf").display()
        );
        return Ok(());
    }
    let mut refractors = Vec::new();
    for (k, refractor) in scene.refractors().enumerate() {
        let file = format!("{}.obj", refract_eval::gltf_export::refractor_name(k));
        write_text_atomically(&args.out.join(&file), &obj(refractor.mesh()))?;
        refractors.push(RefractorJson {
            file,
            int_ior: refractor.ior(),
            ext_ior: scene.outside_ior(k),
            within: refractor.within(),
            conductor: refractor.conductor().map(conductor_json),
            attenuation: refractor.attenuation().map(|a| AttenuationJson {
                color: a.color.to_array(),
                distance: a.distance,
                coefficient: a.coefficient().to_array(),
            }),
        });
    }
    let mut objects = Vec::new();
    for (k, object) in scene.objects.iter().enumerate() {
        let name = format!("object-{k}.obj");
        write_text_atomically(&args.out.join(&name), &obj(object.mesh()))?;
        objects.push(name);
    }
    let environment = match &scene.environment {
        Environment::LatLong { map, intensity } => {
            // The map as refract samples it (negative and non-finite texels already clamped to
            // 0), so that the other renderer sees the same radiance.
            let path = args.out.join("environment.exr");
            let mut texels = Frame::new(map.width, map.height);
            texels.color.clone_from(&map.texels);
            texels.write_exr(&path)?;
            EnvironmentJson {
                kind: "latlong",
                file: Some(path.canonicalize().unwrap_or(path)),
                source: scene.environment_file.clone(),
                intensity: *intensity,
                constant: None,
            }
        }
        Environment::Constant(c) => EnvironmentJson {
            kind: "constant",
            file: None,
            source: None,
            intensity: 1.0,
            constant: Some(c.to_array()),
        },
        Environment::Procedural => EnvironmentJson {
            kind: "procedural",
            file: None,
            source: None,
            intensity: 1.0,
            constant: None,
        },
    };
    let c = &scene.camera;
    let json = SceneJson {
        name: scene.name.clone(),
        camera: CameraJson {
            eye: c.eye.to_array(),
            target: c.target.to_array(),
            up: c.up.to_array(),
            fov_y_deg: c.fov_y.to_degrees(),
        },
        ior: scene.refractor.ior(),
        conductor: scene.refractor.conductor().map(conductor_json),
        refractor: "refractor.obj".into(),
        refractors,
        objects,
        environment,
    };
    let text = serde_json::to_string_pretty(&json).context("serialising scene.json")?;
    write_text_atomically(&args.out.join("scene.json"), &text)?;
    println!(
        "{}: {} triangles -> {}",
        scene.name,
        scene.refractor.mesh().triangles.len(),
        args.out.display()
    );
    Ok(())
}
