//! The rough-glass section of `docs/claims.md` (issue 52): on `rough-glass` (four spheres of
//! roughness 0, 0.1, 0.3 and 0.6), each sphere's error against the reference for the engines
//! themselves and for `volume-thickness` (three.js's formula, which reads no roughness), and
//! how much each renderer's image of a sphere changes between 256² and 1024² box-filtered to
//! 256² (B8, B9).

use std::fmt::Write as _;
use std::sync::Arc;

use glam::Vec3;
use refract_core::Camera;
use refract_cpu::CpuRenderer;
use refract_eval::load_scene;
use refract_eval::metrics::flip_map;
use refract_scene::{
    Aov, Frame, FrameOutputs, MethodId, MethodParams, Renderer, Scene, TraceMode, TraceSettings,
};

use super::inventory::{Inventory, Ledger, Verdict};
use super::{ClaimsArgs, value};
use crate::engines::EngineRenderers;

/// The scene of the section.
const SCENE: &str = "rough-glass";

/// The roughness of refractor `k` of [`SCENE`].
const ROUGHNESS: [&str; 4] = ["0", "0.1", "0.3", "0.6"];

/// The reference's samples per pixel at the section's resolution.
const SPP: u32 = 256;

/// The higher resolution is this many times the section's, a side; the reference takes
/// `SPP / FACTOR²` samples there, so that a box-filtered pixel has as many as a low one.
const FACTOR: u32 = 4;

/// `colors` (`width × height`) averaged over `factor × factor` blocks.
fn box_down(colors: &[Vec3], width: u32, height: u32, factor: u32) -> Vec<Vec3> {
    let (w, h) = (width / factor, height / factor);
    let scale = 1.0 / (factor * factor) as f32;
    (0..h)
        .flat_map(|y| {
            (0..w).map(move |x| {
                let mut sum = Vec3::ZERO;
                for dy in 0..factor {
                    for dx in 0..factor {
                        sum += colors[((y * factor + dy) * width + x * factor + dx) as usize];
                    }
                }
                sum * scale
            })
        })
        .collect()
}

/// The mean of `flip` over the pixels `mask` selects (`None` for none).
fn mean_over(flip: &[f32], mask: &[bool]) -> Option<f64> {
    let (sum, n) = flip
        .iter()
        .zip(mask)
        .filter(|(f, m)| **m && f.is_finite())
        .fold((0.0, 0usize), |(s, n), (f, _)| (s + f64::from(*f), n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// Per sphere, the pixels whose exact path meets that sphere and no other.
fn sphere_masks(truth: &Frame) -> crate::Result<Vec<Vec<bool>>> {
    let met = truth
        .count(Aov::RefractorsMet)
        .ok_or_else(|| crate::LabError::invalid("the reference wrote no refractors-met layer"))?;
    Ok((0..ROUGHNESS.len())
        .map(|k| met.iter().map(|&m| m == 1 << k).collect())
        .collect())
}

/// One renderer's numbers, per sphere: FLIP against the reference at the low resolution, and
/// FLIP between its low frame and its high frame box-filtered.
struct Row {
    label: String,
    engine: bool,
    flip: Vec<Option<f64>>,
    resolution: Vec<Option<f64>>,
}

impl Row {
    fn new(
        label: String,
        engine: bool,
        (reference, low, high): (&[Vec3], &[Vec3], &[Vec3]),
        res: u32,
        masks: &[Vec<bool>],
    ) -> Self {
        let against_reference = flip_map(reference, low, res, res);
        let down = box_down(high, res * FACTOR, res * FACTOR, FACTOR);
        let across_resolutions = flip_map(low, &down, res, res);
        Self {
            label,
            engine,
            flip: masks
                .iter()
                .map(|m| mean_over(&against_reference, m))
                .collect(),
            resolution: masks
                .iter()
                .map(|m| mean_over(&across_resolutions, m))
                .collect(),
        }
    }
}

/// B8 for one rough sphere: its FLIP ≤ the smooth sphere's + `tolerance` (inconclusive without
/// pixels on either).
pub(crate) fn b8_verdict(rough: Option<f64>, smooth: Option<f64>, tolerance: f64) -> Verdict {
    match (rough, smooth) {
        (Some(r), Some(s)) => Verdict::from(r <= s + tolerance),
        _ => Verdict::Inconclusive,
    }
}

/// B9 for one rough sphere: the engine's change across resolutions beyond the smooth sphere's
/// ≤ the reference's same difference + `tolerance` (inconclusive where a number is missing).
pub(crate) fn b9_verdict(
    engine: (Option<f64>, Option<f64>),
    reference: (Option<f64>, Option<f64>),
    tolerance: f64,
) -> Verdict {
    match (engine, reference) {
        ((Some(er), Some(es)), (Some(rr), Some(rs))) => {
            Verdict::from(er - es <= rr - rs + tolerance)
        }
        _ => Verdict::Inconclusive,
    }
}

/// The reference of `scene` through `camera` at `spp` samples a pixel, transmission mode.
fn reference(
    renderer: &mut dyn Renderer,
    scene: &Arc<Scene>,
    camera: &Camera,
    spp: u32,
) -> crate::Result<Frame> {
    renderer.prepare(scene)?;
    let mut frame = Frame::default();
    let settings = TraceSettings {
        mode: TraceMode::Transmission,
        spp,
        ..TraceSettings::default()
    };
    renderer.render(
        camera,
        &MethodParams::Reference(settings),
        FrameOutputs::ColorAndAovs,
        &mut frame,
    )?;
    Ok(frame)
}

/// Measures the rough spheres and returns the markdown section; `engines`: the engines' own
/// renderers when they run.
pub fn section(
    args: &ClaimsArgs,
    inventory: &Inventory,
    ledger: &mut Ledger,
    engines: Option<&EngineRenderers>,
) -> crate::Result<String> {
    let mut b8 = inventory.claim("B8")?;
    let b8_tolerance = b8.threshold("tolerance")?;
    let mut b9 = inventory.claim("B9")?;
    let b9_tolerance = b9.threshold("tolerance")?;
    let res = args.res;
    let high = res * FACTOR;
    let scene = Arc::new(load_scene(SCENE)?.scene);
    let (camera, camera_high) = (scene.camera(res, res)?, scene.camera(high, high)?);
    let mut tracer = args.reference_backend.renderer()?;
    let truth = reference(tracer.as_mut(), &scene, &camera, SPP)?;
    let truth_high = reference(
        tracer.as_mut(),
        &scene,
        &camera_high,
        (SPP / (FACTOR * FACTOR)).max(1),
    )?;
    let masks = sphere_masks(&truth)?;
    let pixels: Vec<usize> = masks
        .iter()
        .map(|m| m.iter().filter(|&&b| b).count())
        .collect();
    let mut rows = vec![Row::new(
        format!("reference ({SPP} samples a pixel)"),
        false,
        (&truth.color, &truth.color, &truth_high.color),
        res,
        &masks,
    )];
    // The re-implementation, which reads no roughness.
    let mut cpu = CpuRenderer::new();
    cpu.prepare(&scene)?;
    let params = MethodParams::defaults(MethodId::VolumeThickness);
    let mut frames = Vec::new();
    for camera in [&camera, &camera_high] {
        let mut frame = Frame::default();
        cpu.render(camera, &params, FrameOutputs::Color, &mut frame)?;
        frames.push(frame);
    }
    rows.push(Row::new(
        "`volume-thickness` (reads no roughness)".to_owned(),
        false,
        (&truth.color, &frames[0].color, &frames[1].color),
        res,
        &masks,
    ));
    let mut notes = Vec::new();
    match engines {
        Some(engines) => {
            let low = engines.render(&scene, &truth, res, res)?;
            let high_frames = engines.render(&scene, &truth_high, high, high)?;
            for (a, b) in low.iter().zip(&high_frames) {
                rows.push(Row::new(
                    format!("`{}` (the engine itself)", a.label),
                    true,
                    (&truth.color, &a.frame.color, &b.frame.color),
                    res,
                    &masks,
                ));
            }
        }
        None => notes.push(
            "the engines themselves did not run (Node, Chromium or `npm ci --prefix engines` is \
             missing: see the run's notes); B8 and B9 have no rows.",
        ),
    }
    let reference_row = &rows[0];
    for row in rows.iter().filter(|r| r.engine) {
        for (k, roughness) in ROUGHNESS.iter().enumerate().skip(1) {
            let scene_label = format!("{SCENE}: {}, roughness {roughness}", row.label);
            b8.push((
                scene_label.clone(),
                b8_verdict(row.flip[k], row.flip[0], b8_tolerance),
                format!(
                    "FLIP {} (roughness {roughness}) vs {} (smooth)",
                    value(row.flip[k], 3),
                    value(row.flip[0], 3)
                ),
            ));
            let difference = |r: &Row| match (r.resolution[k], r.resolution[0]) {
                (Some(a), Some(b)) => Some(a - b),
                _ => None,
            };
            b9.push((
                scene_label,
                b9_verdict(
                    (row.resolution[k], row.resolution[0]),
                    (reference_row.resolution[k], reference_row.resolution[0]),
                    b9_tolerance,
                ),
                format!(
                    "256² vs 1024²: {} − {} = {} (engine) vs {} − {} = {} (reference)",
                    value(row.resolution[k], 3),
                    value(row.resolution[0], 3),
                    value(difference(row), 3),
                    value(reference_row.resolution[k], 3),
                    value(reference_row.resolution[0], 3),
                    value(difference(reference_row), 3),
                ),
            ));
        }
    }
    let heading = "Rough glass (issue 52)";
    let mut md = format!(
        "\n## {heading}\n\n\
         `rough-glass` at {res}²: four glass spheres (IOR 1.5) of roughness {} before the colour \
         chart, the reference in transmission mode at {SPP} samples a pixel (GGX, `α = \
         roughness²`: `docs/reference.md`). FLIP: over the pixels whose exact path meets that \
         sphere and no other ({} pixels). Across resolutions: FLIP between the renderer's \
         {res}² frame and its {high}² frame box-filtered to {res}² (the reference with {} samples \
         a pixel there, as many a filtered pixel), over the same pixels: what changes with the \
         resolution alone. The engines render the exported glTF, each with its own rough model \
         (`docs/engines.md`).\n",
        ROUGHNESS.join(", "),
        pixels
            .iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(", "),
        (SPP / (FACTOR * FACTOR)).max(1)
    );
    for note in &notes {
        let _ = writeln!(md, "Note: {note}\n");
    }
    let sphere_columns = |what: &str| {
        ROUGHNESS
            .iter()
            .map(|r| format!("{what} {r}"))
            .collect::<Vec<_>>()
            .join(" | ")
    };
    let _ = writeln!(
        md,
        "| renderer | {} | {} |\n|---|{}",
        sphere_columns("FLIP, roughness"),
        sphere_columns("across resolutions, roughness"),
        "---|".repeat(2 * ROUGHNESS.len())
    );
    for row in &rows {
        let cells = |values: &[Option<f64>]| {
            values
                .iter()
                .map(|v| value(*v, 3))
                .collect::<Vec<_>>()
                .join(" | ")
        };
        let flip = if row.label.starts_with("reference") {
            vec![None; ROUGHNESS.len()]
        } else {
            row.flip.clone()
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} |",
            row.label,
            cells(&flip),
            cells(&row.resolution)
        );
    }
    md.push_str("\n| claim | scene | measured | verdict |\n|---|---|---|---|\n");
    ledger.rows(&mut md, heading, &[b8, b9]);
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The verdicts hold, fail and stay inconclusive on numbers made for each case.
    #[test]
    fn verdicts_follow_their_thresholds() {
        assert_eq!(b8_verdict(Some(0.30), Some(0.26), 0.05), Verdict::Confirmed);
        assert_eq!(
            b8_verdict(Some(0.32), Some(0.26), 0.05),
            Verdict::NotConfirmed
        );
        assert_eq!(b8_verdict(None, Some(0.26), 0.05), Verdict::Inconclusive);
        // The engine changes 0.10 more on the rough sphere, the reference 0.01 more.
        let engine = (Some(0.20), Some(0.10));
        assert_eq!(
            b9_verdict(engine, (Some(0.06), Some(0.05)), 0.02),
            Verdict::NotConfirmed
        );
        assert_eq!(
            b9_verdict(engine, (Some(0.14), Some(0.05)), 0.02),
            Verdict::Confirmed
        );
        assert_eq!(
            b9_verdict((Some(0.2), None), (Some(0.1), Some(0.1)), 0.02),
            Verdict::Inconclusive
        );
    }

    #[test]
    fn box_down_averages_blocks() {
        let colors: Vec<Vec3> = (0..16).map(|i| Vec3::splat(i as f32)).collect();
        let down = box_down(&colors, 4, 4, 2);
        assert_eq!(
            down,
            vec![
                Vec3::splat(2.5),
                Vec3::splat(4.5),
                Vec3::splat(10.5),
                Vec3::splat(12.5)
            ]
        );
    }
}
