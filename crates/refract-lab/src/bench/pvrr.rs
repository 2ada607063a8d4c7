//! Kakimoto et al. 2007 §5: `pvrr` on reflection, multiple reflection and the lens.

use std::fmt::Write as _;
use std::sync::Arc;

use refract_scene::{Frame, MethodId, MethodParams};

use super::{BenchArgs, TableOutput, timed};
use crate::backends::{self, GpuPolicy};
use crate::progress::{Note, Progress};
use refract_scene::PvrrParams;

use super::triangles;

/// One row of the pvrr table: label, scene, parameters, the paper's fps range.
type PvrrCase = (
    &'static str,
    &'static str,
    &'static [(&'static str, &'static str)],
    (f64, f64),
);

/// Kakimoto et al. 2007 §5 (GeForce 8800 Ultra, Core 2 Quad 2.66 GHz): the rows of the table,
/// as (label, scene, parameters, paper's fps range).
const PVRR_PAPER: [PvrrCase; 5] = [
    (
        "reflection (Fig. 1, 5)",
        "convex-mirror",
        &[],
        (140.0, 170.0),
    ),
    (
        "multiple reflection (Fig. 11)",
        "mirror-stack",
        &[],
        (70.0, 90.0),
    ),
    ("lens (Fig. 12-14)", "spectacles", &[], (8.0, 10.0)),
    (
        "lens fixed to the eye",
        "spectacles",
        &[("update", "on-change")],
        (70.0, 80.0),
    ),
    (
        "lens fixed, chromatic aberration (Fig. 15)",
        "spectacles",
        &[("update", "on-change"), ("dispersion", "10")],
        (30.0, 35.0),
    ),
];

/// Runs the pvrr table: every row of [`PVRR_PAPER`] at 1024², with maps sized from the
/// footprint (at most 1024 texels) and with fixed 1024-texel maps (`--quick`: 128², at most
/// 128 texels, 3 frames), every backend, colour only.
pub(super) fn run(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<TableOutput> {
    let (res, map, frames) = if args.quick {
        (128, 128, 3)
    } else {
        (1024, 1024, args.frames)
    };
    let backend_ids = backends::parse_backends(&args.backends)?;
    let mut renderers = backends::open(&backend_ids, GpuPolicy::IfAvailable, progress)?;
    let mut records = Vec::new();
    let mut rows = Vec::new();
    let mut frame = Frame::default();
    for (label, name, settings, paper) in PVRR_PAPER {
        let scene = Arc::new(refract_eval::load_scene(name)?.scene);
        let triangles = triangles(&scene);
        let camera = scene.camera(res, res)?;
        for sizing in ["footprint", "fixed"] {
            let mut method = MethodParams::defaults(MethodId::Pvrr);
            method.set("res", &map.to_string(), "bench")?;
            method.set("sizing", sizing, "bench")?;
            for (k, v) in settings {
                method.set(k, v, "bench")?;
            }
            let p = PvrrParams::try_from(method).map_err(|other| {
                crate::LabError::invalid(format_args!("not pvrr: {}", other.id()))
            })?;
            let mut planner = refract_scene::pvrr::PvrrPlanner::default();
            planner.prepare(&scene);
            let plan = planner.plan(&scene, &camera, &p)?;
            let rays = plan.rays();
            let maps = map_sizes(plan);
            for renderer in &mut renderers {
                renderer.prepare(&scene)?;
                let mut record = timed(renderer.as_mut(), &camera, &method, frames, &mut frame)?
                    .record(&scene.name, triangles);
                record.method = format!("pvrr {}", method.describe());
                progress.note(Note::Row(format!(
                    "{label:<44} {sizing:<9} {:<4} {res}² {:>9.2} ms {:>7.1} fps ({rays} rays, maps {maps})",
                    record.backend, record.ms_median, record.fps
                )));
                rows.push((label, sizing, rays, maps.clone(), paper, record.clone()));
                records.push(record);
            }
        }
    }
    let mut md = format!(
        "# Kakimoto et al. 2007, §5\n\n`pvrr` at {res}², maps sized from the reflector's \
         footprint (`sizing=footprint`, the default, at most {map} texels) and at the fixed {map} \
         texels (`sizing=fixed`), colour only, median of {frames} frames after 3 warm-up frames; \
         the per-vertex rays are traced with the CPU BVH on both backends (the GPU row adds that \
         time to its timestamps). Paper: GeForce 8800 Ultra and a 2.66 GHz Core 2 Quad; its \
         scenes had 10,000 polygons (reflection) and a 2,000-triangle lens in 5,000 \
         triangles.\n\n\
         | case | scene | triangles | ray vertices | sizing | maps (texels) | backend | ms | fps | paper fps | ours / paper |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n"
    );
    for (label, sizing, rays, maps, (lo, hi), r) in &rows {
        let _ = writeln!(
            md,
            "| {label} | {} | {} | {rays} | {sizing} | {maps} | {} | {:.1} | {:.1} | {lo}–{hi} | {:.2}× |",
            r.scene,
            r.triangles,
            r.backend,
            r.ms_median,
            r.fps,
            r.fps / lo
        );
    }
    TableOutput::of_frames(md, &records)
}

/// The map sizes of `plan` (views 1..), `w×h` each, comma-separated; `-` without maps.
fn map_sizes(plan: &refract_scene::pvrr::PvrrPlan) -> String {
    let sizes: Vec<String> = plan.views[1..]
        .iter()
        .map(|v| format!("{}×{}", v.camera.width(), v.camera.height()))
        .collect();
    if sizes.is_empty() {
        "-".to_owned()
    } else {
        sizes.join(", ")
    }
}
