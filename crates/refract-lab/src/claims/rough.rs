//! The rough-glass section of `docs/claims.md` (issue 52): on `rough-glass` (four spheres of
//! roughness 0, 0.1, 0.3 and 0.6), each sphere's error against the reference for the engines
//! themselves and for the re-implementations of three.js's, Bevy's, Godot's, HDRP's and
//! Filament's rough models, and what roughness changes in each renderer's image (its frame
//! against its frame of the same spheres at roughness 0), at 256² and at 1024² box-filtered to
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

/// Whose numbers a [`Row`] holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// The reference itself (no FLIP against itself).
    Reference,
    /// A re-implementation on the CPU backend.
    Method,
    /// An engine rendering the exported scene (the rows B8 and B9 judge).
    Engine,
}

/// A renderer's frames of the scene (`rough`) and of its smooth twin (every roughness 0), at the
/// section's resolution and at [`FACTOR`] times it.
struct Frames {
    rough: Vec<Vec3>,
    smooth: Vec<Vec3>,
    rough_high: Vec<Vec3>,
    smooth_high: Vec<Vec3>,
}

/// One renderer's numbers, per sphere: FLIP against the reference's rough frame, and the change
/// roughness makes (its rough frame against its smooth twin's) at the low resolution and at the
/// high one box-filtered.
struct Row {
    label: String,
    kind: Kind,
    flip: Vec<Option<f64>>,
    change: Vec<Option<f64>>,
    change_high: Vec<Option<f64>>,
}

impl Row {
    fn new(
        label: String,
        kind: Kind,
        reference: &[Vec3],
        f: &Frames,
        res: u32,
        masks: &[Vec<bool>],
    ) -> Self {
        let per_sphere = |flip: Vec<f32>| -> Vec<Option<f64>> {
            masks.iter().map(|m| mean_over(&flip, m)).collect()
        };
        let down = |colors: &[Vec3]| box_down(colors, res * FACTOR, res * FACTOR, FACTOR);
        Self {
            label,
            kind,
            flip: per_sphere(flip_map(reference, &f.rough, res, res)),
            change: per_sphere(flip_map(&f.smooth, &f.rough, res, res)),
            change_high: per_sphere(flip_map(
                &down(&f.smooth_high),
                &down(&f.rough_high),
                res,
                res,
            )),
        }
    }

    /// |change at the high resolution − change at the low one| of sphere `k`.
    fn resolution_shift(&self, k: usize) -> Option<f64> {
        Some((self.change_high[k]? - self.change[k]?).abs())
    }
}

/// B8 for one rough sphere: the engine's change within a factor `factor` of the reference's
/// (inconclusive where either is missing or the reference's is 0).
pub(crate) fn b8_verdict(engine: Option<f64>, reference: Option<f64>, factor: f64) -> Verdict {
    match (engine, reference) {
        (Some(e), Some(r)) if r > 0.0 => Verdict::from(e >= r / factor && e <= r * factor),
        _ => Verdict::Inconclusive,
    }
}

/// B9 for one rough sphere: the engine's resolution shift ≤ the reference's + `tolerance`
/// (inconclusive where either is missing).
pub(crate) fn b9_verdict(engine: Option<f64>, reference: Option<f64>, tolerance: f64) -> Verdict {
    match (engine, reference) {
        (Some(e), Some(r)) => Verdict::from(e <= r + tolerance),
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

/// `scene` with every refractor's roughness 0.
fn smooth_twin(scene: &Scene) -> crate::Result<Scene> {
    let mut smooth = scene.clone();
    smooth.refractor.set_roughness(0.0)?;
    for r in &mut smooth.other_refractors {
        r.set_roughness(0.0)?;
    }
    Ok(smooth)
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
    let factor = b8.threshold("factor")?;
    let mut b9 = inventory.claim("B9")?;
    let tolerance = b9.threshold("tolerance")?;
    let res = args.res;
    let high = res * FACTOR;
    let high_spp = (SPP / (FACTOR * FACTOR)).max(1);
    let rough = Arc::new(load_scene(SCENE)?.scene);
    let smooth = Arc::new(smooth_twin(&rough)?);
    let (camera, camera_high) = (rough.camera(res, res)?, rough.camera(high, high)?);
    let mut tracer = args.reference_backend.renderer()?;
    let truth = reference(tracer.as_mut(), &rough, &camera, SPP)?;
    let truth_high = reference(tracer.as_mut(), &rough, &camera_high, high_spp)?;
    let reference_frames = Frames {
        smooth: reference(tracer.as_mut(), &smooth, &camera, SPP)?.color,
        smooth_high: reference(tracer.as_mut(), &smooth, &camera_high, high_spp)?.color,
        rough: truth.color.clone(),
        rough_high: truth_high.color.clone(),
    };
    let masks = sphere_masks(&truth)?;
    let pixels: Vec<usize> = masks
        .iter()
        .map(|m| m.iter().filter(|&&b| b).count())
        .collect();
    let mut rows = vec![Row::new(
        format!("reference ({SPP} samples a pixel)"),
        Kind::Reference,
        &truth.color,
        &reference_frames,
        res,
        &masks,
    )];
    // The re-implementations of the engines' rough models (`docs/methods.md`, "Rough
    // surfaces"): three.js's, Bevy's, Godot's, HDRP's and Filament's.
    let mut cpu = CpuRenderer::new();
    for (label, id, settings) in [
        (
            "`volume-thickness` (three.js's LOD rule, re-implemented)",
            MethodId::VolumeThickness,
            &[][..],
        ),
        (
            "`volume-thickness`, `depth-test=reject` (Bevy's taps, re-implemented)",
            MethodId::VolumeThickness,
            &[("depth-test", "reject")][..],
        ),
        (
            "`screen-offset` (Godot's LOD rule, re-implemented)",
            MethodId::ScreenOffset,
            &[][..],
        ),
        (
            "`proxy-sphere` (HDRP's mip rule, re-implemented)",
            MethodId::ProxySphere,
            &[("lookup", "hdrp")][..],
        ),
        (
            "`proxy-sphere`, `lookup=filament` (Filament's LOD rule, re-implemented)",
            MethodId::ProxySphere,
            &[("lookup", "filament")][..],
        ),
    ] {
        let mut params = MethodParams::defaults(id);
        for (name, value) in settings {
            params.set(name, value, "claims")?;
        }
        let mut cpu_frame = |scene: &Arc<Scene>, camera: &Camera| -> crate::Result<Vec<Vec3>> {
            cpu.prepare(scene)?;
            let mut frame = Frame::default();
            cpu.render(camera, &params, FrameOutputs::Color, &mut frame)?;
            Ok(frame.color)
        };
        let frames = Frames {
            rough: cpu_frame(&rough, &camera)?,
            smooth: cpu_frame(&smooth, &camera)?,
            rough_high: cpu_frame(&rough, &camera_high)?,
            smooth_high: cpu_frame(&smooth, &camera_high)?,
        };
        rows.push(Row::new(
            label.to_owned(),
            Kind::Method,
            &truth.color,
            &frames,
            res,
            &masks,
        ));
    }
    let mut notes = Vec::new();
    match engines {
        Some(engines) => {
            let colors = |scene: &Scene, truth: &Frame, side: u32| -> crate::Result<Vec<_>> {
                Ok(engines
                    .render(scene, truth, side, side)?
                    .into_iter()
                    .map(|e| (e.label, e.frame.color))
                    .collect())
            };
            let rough_low = colors(&rough, &truth, res)?;
            let smooth_low = colors(&smooth, &truth, res)?;
            let rough_high = colors(&rough, &truth_high, high)?;
            let smooth_high = colors(&smooth, &truth_high, high)?;
            for (k, (label, color)) in rough_low.into_iter().enumerate() {
                let frames = Frames {
                    rough: color,
                    smooth: smooth_low[k].1.clone(),
                    rough_high: rough_high[k].1.clone(),
                    smooth_high: smooth_high[k].1.clone(),
                };
                rows.push(Row::new(
                    format!("`{label}` (the engine itself)"),
                    Kind::Engine,
                    &truth.color,
                    &frames,
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
    for row in rows.iter().filter(|r| r.kind == Kind::Engine) {
        for (k, roughness) in ROUGHNESS.iter().enumerate().skip(1) {
            let scene_label = format!("{SCENE}: {}, roughness {roughness}", row.label);
            b8.push((
                scene_label.clone(),
                b8_verdict(row.change[k], reference_row.change[k], factor),
                format!(
                    "change {} (engine) vs {} (reference)",
                    value(row.change[k], 3),
                    value(reference_row.change[k], 3)
                ),
            ));
            b9.push((
                scene_label,
                b9_verdict(
                    row.resolution_shift(k),
                    reference_row.resolution_shift(k),
                    tolerance,
                ),
                format!(
                    "change at 1024² {} vs 256² {}: shift {} (engine) vs {} (reference)",
                    value(row.change_high[k], 3),
                    value(row.change[k], 3),
                    value(row.resolution_shift(k), 3),
                    value(reference_row.resolution_shift(k), 3),
                ),
            ));
        }
    }
    let heading = "Rough glass (issue 52)";
    let mut md = format!(
        "\n## {heading}\n\n\
         `rough-glass` at {res}²: four glass spheres (IOR 1.5) of roughness {} before the colour \
         chart, the reference in transmission mode at {SPP} samples a pixel (GGX, `α = \
         roughness²`: `docs/reference.md`). Over the pixels whose exact path meets that sphere \
         and no other ({} pixels), mean FLIP: against the reference; and the change roughness \
         makes, the renderer's frame against its own frame of the same spheres at roughness 0, \
         at {res}² and at {high}² box-filtered to {res}² (the reference with {high_spp} samples a \
         pixel there, as many a filtered pixel). The engines render the exported glTF, each with \
         its own rough model (`docs/engines.md`).\n",
        ROUGHNESS.join(", "),
        pixels
            .iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(", "),
    );
    for note in &notes {
        let _ = writeln!(md, "Note: {note}\n");
    }
    let columns = |what: &str, from: usize| {
        ROUGHNESS[from..]
            .iter()
            .map(|r| format!("{what} {r}"))
            .collect::<Vec<_>>()
            .join(" | ")
    };
    let _ = writeln!(
        md,
        "\n| renderer | {} | {} | {} |\n|---|{}",
        columns("FLIP, roughness", 0),
        columns("change at 256², roughness", 1),
        columns(&format!("change at {high}², roughness"), 1),
        "---|".repeat(3 * ROUGHNESS.len() - 2)
    );
    for row in &rows {
        let cells = |values: &[Option<f64>]| {
            values
                .iter()
                .map(|v| value(*v, 3))
                .collect::<Vec<_>>()
                .join(" | ")
        };
        let flip = if row.kind == Kind::Reference {
            vec![None; ROUGHNESS.len()]
        } else {
            row.flip.clone()
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} |",
            row.label,
            cells(&flip),
            cells(&row.change[1..]),
            cells(&row.change_high[1..])
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
        // B8: within a factor 2 of the reference's change, either way.
        assert_eq!(b8_verdict(Some(0.10), Some(0.12), 2.0), Verdict::Confirmed);
        assert_eq!(b8_verdict(Some(0.23), Some(0.12), 2.0), Verdict::Confirmed);
        assert_eq!(
            b8_verdict(Some(0.25), Some(0.12), 2.0),
            Verdict::NotConfirmed
        );
        // A renderer that ignores the roughness changes nothing.
        assert_eq!(
            b8_verdict(Some(0.0), Some(0.12), 2.0),
            Verdict::NotConfirmed
        );
        assert_eq!(b8_verdict(None, Some(0.12), 2.0), Verdict::Inconclusive);
        assert_eq!(b8_verdict(Some(0.1), Some(0.0), 2.0), Verdict::Inconclusive);
        // B9: the shift across resolutions against the reference's.
        assert_eq!(b9_verdict(Some(0.03), Some(0.02), 0.02), Verdict::Confirmed);
        assert_eq!(
            b9_verdict(Some(0.05), Some(0.02), 0.02),
            Verdict::NotConfirmed
        );
        assert_eq!(b9_verdict(None, Some(0.02), 0.02), Verdict::Inconclusive);
        let row = Row {
            label: String::new(),
            kind: Kind::Engine,
            flip: vec![],
            change: vec![Some(0.0), Some(0.2)],
            change_high: vec![Some(0.0), Some(0.05)],
        };
        assert!((row.resolution_shift(1).expect("shift") - 0.15).abs() < 1e-12);
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
