//! The rough-glass section of `docs/claims.md` (issue 52): on `rough-glass` (four spheres of
//! roughness 0, 0.1, 0.3 and 0.6), each sphere's error against the reference for the engines
//! themselves and for the re-implementations of three.js's, Bevy's, Godot's, HDRP's and
//! Filament's rough models, and what roughness changes in each renderer's image (its frame
//! against its frame of the same spheres at roughness 0), at 256² and at 1024² box-filtered to
//! 256² (B8, B9), and from the camera at twice its distance (B13).

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

/// B13 moves the camera back along its view to this many times its distance from its target.
const DISTANCE: u32 = 2;

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

/// The centre `width / factor × height / factor` of `values` (`width × height`): what a camera
/// `factor` times as far sees of the near camera's frame at its target's depth.
fn centre<T: Copy>(values: &[T], width: u32, height: u32, factor: u32) -> Vec<T> {
    let (w, h) = (width / factor, height / factor);
    let (x0, y0) = ((width - w) / 2, (height - h) / 2);
    (y0..y0 + h)
        .flat_map(|y| (x0..x0 + w).map(move |x| values[(y * width + x) as usize]))
        .collect()
}

/// `mask` (`width × height`) on `factor × factor` blocks: a block is in where all its pixels are.
fn mask_down(mask: &[bool], width: u32, height: u32, factor: u32) -> Vec<bool> {
    (0..height / factor)
        .flat_map(|y| {
            (0..width / factor).map(move |x| {
                (0..factor).all(|dy| {
                    (0..factor)
                        .all(|dx| mask[((y * factor + dy) * width + x * factor + dx) as usize])
                })
            })
        })
        .collect()
}

/// `scene` from its camera moved back along its view to `factor` times its distance from its
/// target, the far plane `factor` times as far.
fn moved_back(scene: &Scene, factor: f32) -> Scene {
    let mut far = scene.clone();
    let camera = &mut far.camera;
    camera.eye = camera.target + (camera.eye - camera.target) * factor;
    camera.far *= factor;
    far
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
    /// An engine rendering the exported scene (B8 and B9 judge these rows; B13 these and the
    /// re-implementations').
    Engine,
}

/// A renderer's frames of the scene (`rough`) and of its smooth twin (every roughness 0), at the
/// section's resolution and at [`FACTOR`] times it.
struct Frames {
    rough: Vec<Vec3>,
    smooth: Vec<Vec3>,
    rough_high: Vec<Vec3>,
    smooth_high: Vec<Vec3>,
    /// From the camera [`DISTANCE`] times as far, at the section's resolution.
    rough_far: Vec<Vec3>,
    smooth_far: Vec<Vec3>,
}

/// Per sphere, the pixels of the section's frame ([`sphere_masks`]), and at
/// `res / DISTANCE` those of the near frame's blocks and of the far frame's centre.
struct Masks {
    frame: Vec<Vec<bool>>,
    near: Vec<Vec<bool>>,
    far: Vec<Vec<bool>>,
}

/// One renderer's numbers, per sphere: FLIP against the reference's rough frame, and the change
/// roughness makes (its rough frame against its smooth twin's) at the low resolution, at the
/// high one box-filtered, and at `res / DISTANCE` from the near camera (box-filtered) and from
/// the far one (its centre).
struct Row {
    label: String,
    kind: Kind,
    flip: Vec<Option<f64>>,
    change: Vec<Option<f64>>,
    change_high: Vec<Option<f64>>,
    change_near: Vec<Option<f64>>,
    change_far: Vec<Option<f64>>,
}

impl Row {
    fn new(
        label: String,
        kind: Kind,
        reference: &[Vec3],
        f: &Frames,
        res: u32,
        masks: &Masks,
    ) -> Self {
        let per_sphere = |flip: Vec<f32>, masks: &[Vec<bool>]| -> Vec<Option<f64>> {
            masks.iter().map(|m| mean_over(&flip, m)).collect()
        };
        let down = |colors: &[Vec3]| box_down(colors, res * FACTOR, res * FACTOR, FACTOR);
        let small = res / DISTANCE;
        let near = |colors: &[Vec3]| box_down(colors, res, res, DISTANCE);
        let far = |colors: &[Vec3]| centre(colors, res, res, DISTANCE);
        Self {
            label,
            kind,
            flip: per_sphere(flip_map(reference, &f.rough, res, res), &masks.frame),
            change: per_sphere(flip_map(&f.smooth, &f.rough, res, res), &masks.frame),
            change_high: per_sphere(
                flip_map(&down(&f.smooth_high), &down(&f.rough_high), res, res),
                &masks.frame,
            ),
            change_near: per_sphere(
                flip_map(&near(&f.smooth), &near(&f.rough), small, small),
                &masks.near,
            ),
            change_far: per_sphere(
                flip_map(&far(&f.smooth_far), &far(&f.rough_far), small, small),
                &masks.far,
            ),
        }
    }

    /// |change at the high resolution − change at the low one| of sphere `k`.
    fn resolution_shift(&self, k: usize) -> Option<f64> {
        Some((self.change_high[k]? - self.change[k]?).abs())
    }

    /// |change from the far camera − change from the near one| of sphere `k`.
    fn distance_shift(&self, k: usize) -> Option<f64> {
        Some((self.change_far[k]? - self.change_near[k]?).abs())
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

/// B13 for one rough sphere: the renderer's distance shift ≤ the reference's + `tolerance`
/// (inconclusive where either is missing); the test B9's verdict makes.
pub(crate) fn b13_verdict(
    renderer: Option<f64>,
    reference: Option<f64>,
    tolerance: f64,
) -> Verdict {
    b9_verdict(renderer, reference, tolerance)
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
    let mut b13 = inventory.claim("B13")?;
    let distance_tolerance = b13.threshold("tolerance")?;
    let res = args.res;
    let high = res * FACTOR;
    let high_spp = (SPP / (FACTOR * FACTOR)).max(1);
    let rough = Arc::new(args.view(load_scene(SCENE)?.scene));
    let smooth = Arc::new(smooth_twin(&rough)?);
    let rough_far = Arc::new(moved_back(&rough, DISTANCE as f32));
    let smooth_far = Arc::new(moved_back(&smooth, DISTANCE as f32));
    let (camera, camera_high) = (rough.camera(res, res)?, rough.camera(high, high)?);
    let camera_far = rough_far.camera(res, res)?;
    let mut tracer = args.reference_backend.renderer()?;
    let truth = reference(tracer.as_mut(), &rough, &camera, SPP)?;
    let truth_high = reference(tracer.as_mut(), &rough, &camera_high, high_spp)?;
    let truth_far = reference(tracer.as_mut(), &rough_far, &camera_far, SPP)?;
    let reference_frames = Frames {
        smooth: reference(tracer.as_mut(), &smooth, &camera, SPP)?.color,
        smooth_high: reference(tracer.as_mut(), &smooth, &camera_high, high_spp)?.color,
        smooth_far: reference(tracer.as_mut(), &smooth_far, &camera_far, SPP)?.color,
        rough: truth.color.clone(),
        rough_high: truth_high.color.clone(),
        rough_far: truth_far.color.clone(),
    };
    let frame_masks = sphere_masks(&truth)?;
    let masks = Masks {
        near: frame_masks
            .iter()
            .map(|m| mask_down(m, res, res, DISTANCE))
            .collect(),
        far: sphere_masks(&truth_far)?
            .iter()
            .map(|m| centre(m, res, res, DISTANCE))
            .collect(),
        frame: frame_masks,
    };
    let pixels: Vec<usize> = masks
        .frame
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
            rough_far: cpu_frame(&rough_far, &camera_far)?,
            smooth_far: cpu_frame(&smooth_far, &camera_far)?,
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
            let rough_far = colors(&rough_far, &truth_far, res)?;
            let smooth_far = colors(&smooth_far, &truth_far, res)?;
            for (k, (label, color)) in rough_low.into_iter().enumerate() {
                let frames = Frames {
                    rough: color,
                    smooth: smooth_low[k].1.clone(),
                    rough_high: rough_high[k].1.clone(),
                    smooth_high: smooth_high[k].1.clone(),
                    rough_far: rough_far[k].1.clone(),
                    smooth_far: smooth_far[k].1.clone(),
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
             missing: see the run's notes); B8 and B9 have no rows, B13 the re-implemented \
             rules' only.",
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
    for row in rows.iter().filter(|r| r.kind != Kind::Reference) {
        for (k, roughness) in ROUGHNESS.iter().enumerate().skip(1) {
            b13.push((
                format!("{SCENE}: {}, roughness {roughness}", row.label),
                b13_verdict(
                    row.distance_shift(k),
                    reference_row.distance_shift(k),
                    distance_tolerance,
                ),
                format!(
                    "change from {DISTANCE}× as far {} vs near {}: shift {} (renderer) vs {} \
                     (reference)",
                    value(row.change_far[k], 3),
                    value(row.change_near[k], 3),
                    value(row.distance_shift(k), 3),
                    value(reference_row.distance_shift(k), 3),
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
    let small = res / DISTANCE;
    let _ = writeln!(
        md,
        "\nFrom the camera moved back along its view to {DISTANCE} times its distance from its \
         target (far plane {DISTANCE} times as far), the same resolution: the change roughness \
         makes at {small}², the near frame box-filtered, the far frame's centre {small}² (the \
         same world area at the target's depth; per sphere, the near frame's blocks whose every \
         pixel meets it and the far frame's pixels that do).\n\n\
         | renderer | {} |\n|---|{}",
        ROUGHNESS[1..]
            .iter()
            .map(|r| format!("near, roughness {r} | far, roughness {r}"))
            .collect::<Vec<_>>()
            .join(" | "),
        "---|".repeat(2 * (ROUGHNESS.len() - 1))
    );
    for row in &rows {
        let cells = (1..ROUGHNESS.len())
            .map(|k| {
                format!(
                    "{} | {}",
                    value(row.change_near[k], 3),
                    value(row.change_far[k], 3)
                )
            })
            .collect::<Vec<_>>()
            .join(" | ");
        let _ = writeln!(md, "| {} | {cells} |", row.label);
    }
    md.push_str("\n| claim | scene | measured | verdict |\n|---|---|---|---|\n");
    ledger.rows(&mut md, heading, &[b8, b9, b13]);
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
            change_near: vec![Some(0.0), Some(0.1)],
            change_far: vec![Some(0.0), Some(0.16)],
        };
        assert!((row.resolution_shift(1).expect("shift") - 0.15).abs() < 1e-12);
        assert!((row.distance_shift(1).expect("shift") - 0.06).abs() < 1e-12);
        // B13: the shift across distances against the reference's.
        assert_eq!(
            b13_verdict(row.distance_shift(1), Some(0.05), 0.02),
            Verdict::Confirmed
        );
        assert_eq!(
            b13_verdict(row.distance_shift(1), Some(0.01), 0.02),
            Verdict::NotConfirmed
        );
        assert_eq!(b13_verdict(None, Some(0.01), 0.02), Verdict::Inconclusive);
    }

    /// The far camera's centre and the near frame's blocks.
    #[test]
    fn centre_and_blocks() {
        let values: Vec<u32> = (0..16).collect();
        assert_eq!(centre(&values, 4, 4, 2), vec![5, 6, 9, 10]);
        let mask = [
            true, true, false, true, //
            true, true, true, true, //
            false, false, true, true, //
            false, true, true, true,
        ];
        assert_eq!(mask_down(&mask, 4, 4, 2), vec![true, false, false, true]);
    }

    /// The far camera looks at the same target along the same view, twice as far.
    #[test]
    fn moved_back_doubles_the_distance() {
        let scene = load_scene(SCENE).expect("scene").scene;
        let far = moved_back(&scene, 2.0);
        let (near_cam, far_cam) = (scene.camera, far.camera);
        assert_eq!(far_cam.target, near_cam.target);
        let (a, b) = (near_cam.eye - near_cam.target, far_cam.eye - far_cam.target);
        assert!((b - 2.0 * a).length() < 1e-5);
        assert_eq!(far_cam.far, 2.0 * near_cam.far);
        assert_eq!(far_cam.fov_y, near_cam.fov_y);
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
