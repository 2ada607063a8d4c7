//! Wyman 2005b Table 1: `iterative-seeded` on the paper's four scenes at 1024² and 512².

use std::fmt::Write as _;
use std::sync::Arc;

use refract_scene::{Frame, MethodId, MethodParams};

use super::{BenchArgs, TableOutput, timed};
use super::{BenchRecord, triangles};
use crate::backends::{self, GpuPolicy};
use crate::data_scenes;
use crate::progress::{Note, Progress};

/// Wyman 2005b Table 1 (GeForce 6800, "using our iterative approach"): row, our scene, the
/// paper's fps at 1024² and at 512².
pub(crate) const NEARBY_PAPER: [(&str, &str, f64, f64); 4] = [
    ("Sphere w/1 plane", "sphere-plane", 61.0, 212.8),
    ("Sphere & Dragon", "sphere-igea", 16.9, 21.3),
    ("Dragon w/2 planes", "igea-planes", 8.5, 17.8),
    ("Venus & Dragon", "horse-igea", 9.4, 12.6),
];

/// The sphere above one wood plane ("Sphere w/1 plane"); the other rows are `scenes/` files.
const SPHERE_PLANE: &str = "[camera]\neye = [0.0, 0.9, 4.2]\ntarget = [0.0, -0.15, 0.0]\nnear = 0.05\nfar = 12.0\n\n\
     [refractor]\nmesh = \"builtin:sphere\"\nior = 1.5\nscale = 0.8\n\n\
     [[objects]]\nmesh = \"builtin:plane\"\ntexture = \"wood\"\nscale = 6.0\ntranslate = [0.0, -0.8, 0.6]\n";

/// The scene of a row of [`NEARBY_PAPER`] (`None`, noted, where its meshes are missing).
pub(crate) fn load_row(
    name: &str,
    data: &std::path::Path,
    progress: &dyn Progress,
) -> crate::Result<Option<refract_scene::Scene>> {
    if name == "sphere-plane" {
        data_scenes::load_text(name, SPHERE_PLANE, data, progress)
    } else {
        data_scenes::load(name, data, progress)
    }
}

/// Runs Wyman 2005b Table 1.
pub(super) fn run(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<TableOutput> {
    let (resolutions, frames, rows) = if args.quick {
        (vec![64, 128], 3, &NEARBY_PAPER[..1])
    } else {
        (vec![1024, 512], args.frames, &NEARBY_PAPER[..])
    };
    let method = MethodParams::defaults(MethodId::IterativeSeeded);
    let backend_ids = backends::parse_backends(&args.backends)?;
    let mut renderers = backends::open(&backend_ids, GpuPolicy::IfAvailable, progress)?;
    backends::check_supported(&renderers, std::slice::from_ref(&method))?;
    let mut records = Vec::new();
    let mut frame = Frame::default();
    for &(_, name, _, _) in rows {
        let Some(scene) = load_row(name, &args.data, progress)? else {
            continue;
        };
        let scene = Arc::new(scene);
        let triangles = triangles(&scene);
        for renderer in &mut renderers {
            renderer.prepare(&scene)?;
        }
        for &res in &resolutions {
            let camera = scene.camera(res, res)?;
            for renderer in &mut renderers {
                let record = timed(renderer.as_mut(), &camera, &method, frames, &mut frame)?
                    .record(name, triangles);
                progress.note(Note::Row(format!(
                    "{:<13} {:>7} tris {:<4} {:>5}² {:>9.2} ms  {:>7.1} fps",
                    name, triangles, record.backend, res, record.ms_median, record.fps
                )));
                records.push(record);
            }
        }
    }
    let md = nearby_table(&records, &resolutions, frames, &method);
    TableOutput::of_frames(md, &records)
}

/// Wyman 2005b Table 1's layout with our figures, the paper's and the ratios.
fn nearby_table(
    records: &[BenchRecord],
    resolutions: &[u32],
    frames: u32,
    method: &MethodParams,
) -> String {
    let fps = |scene: &str, backend: &str, res: u32| {
        records
            .iter()
            .find(|r| r.scene == scene && r.backend == backend && r.width == res)
            .map(|r| (r.fps, r.ms_median))
    };
    let cell = |v: Option<(f64, f64)>| {
        v.map_or_else(|| "–".to_owned(), |(f, ms)| format!("{f:.1} ({ms:.1} ms)"))
    };
    let ratio = |v: Option<(f64, f64)>, paper: f64| {
        v.map_or_else(|| "–".to_owned(), |(f, _)| format!("{:.2}×", f / paper))
    };
    let (hi, lo) = (resolutions[0], resolutions[resolutions.len() - 1]);
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Wyman 2005b Table 1, reproduced\n\n`{}` ({}), colour only, median of {frames} frames after 3 warm-up \
         frames; a frame is every per-frame pass (back faces, the NG texture of the opaque objects, front faces, the \
         kernel). Paper: GeForce 6800 + 3.0 GHz Pentium 4 at 1024² and 512²; its Dragon (250k) is our igea \
         (268k triangles), its Venus (100k) our horse (97k).\n",
        method.id(),
        method.describe()
    );
    let _ = writeln!(
        md,
        "| paper row | our scene | triangles | CPU fps {hi}² | CPU fps {lo}² | GPU fps {hi}² | GPU fps {lo}² | \
         paper 1024² | paper 512² | CPU / paper {hi}² | CPU / paper {lo}² |"
    );
    let _ = writeln!(md, "|{}|", ["---"; 11].join("|"));
    for (row, scene, p_hi, p_lo) in NEARBY_PAPER {
        let Some(triangles) = records
            .iter()
            .find(|r| r.scene == scene)
            .map(|r| r.triangles)
        else {
            continue;
        };
        let (c_hi, c_lo) = (fps(scene, "cpu", hi), fps(scene, "cpu", lo));
        let _ = writeln!(
            md,
            "| {row} | {scene} | {triangles} | {} | {} | {} | {} | {p_hi} | {p_lo} | {} | {} |",
            cell(c_hi),
            cell(c_lo),
            cell(fps(scene, "gpu", hi)),
            cell(fps(scene, "gpu", lo)),
            ratio(c_hi, p_hi),
            ratio(c_lo, p_lo),
        );
    }
    if hi != 1024 {
        let _ = writeln!(
            md,
            "\nNote: a quick run ({hi}² and {lo}²); the paper's columns are 1024² and 512²."
        );
    }
    md
}
