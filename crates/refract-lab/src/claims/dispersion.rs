//! The dispersion section of `docs/claims.md` (issue 52): on `prism` (white slits seen through
//! a glass prism of Abbe number 30), the colour fringe of every dispersing renderer against the
//! reference's: the red channel's centroid minus the blue channel's along x over the prism's
//! pixels, its sign (B10), its size with three wavelengths (B11) and with sixteen (B12).

use std::fmt::Write as _;
use std::sync::Arc;

use glam::Vec3;
use refract_cpu::CpuRenderer;
use refract_eval::load_scene;
use refract_scene::{
    Aov, Frame, FrameOutputs, MethodId, MethodParams, Renderer, TraceMode, TraceSettings,
};

use super::inventory::{Inventory, Ledger, Verdict};
use super::{ClaimsArgs, value};
use crate::engines::EngineRenderers;

/// The scene of the section.
const SCENE: &str = "prism";

/// The frame's size (the prism's spread runs along x).
const SIZE: (u32, u32) = (256, 192);

/// The reference's samples per pixel (four wavelengths each).
const SPP: u32 = 64;

/// The wavelengths of the convergence test (B12) beside the default 3.
const MANY_WAVELENGTHS: u32 = 16;

/// `Δx` per slit image: in each row, each run of lit pixels (largest channel ≥ `lit`) inside
/// `mask` and bounded on both sides by unlit pixels of `mask` (a slit image whole on the prism,
/// not cut by its edge), its red channel's centroid along x minus its blue channel's (each
/// clamped at 0); the mean over the runs weighted by their red plus blue light. `None` without a
/// run (a renderer that shows no slit through the prism).
pub(crate) fn fringe_offset(colors: &[Vec3], width: u32, mask: &[bool], lit: f32) -> Option<f64> {
    let width = width as usize;
    let (mut sum, mut weight) = (0.0, 0.0);
    for (row, row_mask) in colors.chunks(width).zip(mask.chunks(width)) {
        let is_lit = |x: usize| row_mask[x] && row[x].max_element() >= lit;
        let is_dark = |x: usize| row_mask[x] && row[x].max_element() < lit;
        let mut x = 0;
        while x < row.len() {
            if !is_lit(x) {
                x += 1;
                continue;
            }
            let start = x;
            while x < row.len() && is_lit(x) {
                x += 1;
            }
            // Bounded by unlit prism pixels on both sides.
            if start == 0 || x == row.len() || !is_dark(start - 1) || !is_dark(x) {
                continue;
            }
            let (mut red, mut blue) = ((0.0, 0.0), (0.0, 0.0));
            for (i, c) in row[start..x].iter().enumerate() {
                let px = (start + i) as f64 + 0.5;
                let (r, b) = (f64::from(c.x.max(0.0)), f64::from(c.z.max(0.0)));
                red = (red.0 + r * px, red.1 + r);
                blue = (blue.0 + b * px, blue.1 + b);
            }
            if red.1 > 0.0 && blue.1 > 0.0 {
                let light = red.1 + blue.1;
                sum += (red.0 / red.1 - blue.0 / blue.1) * light;
                weight += light;
            }
        }
    }
    (weight > 0.0).then(|| sum / weight)
}

/// B10: the renderer's `Δx` has the reference's sign and is at least `min_px` (inconclusive
/// where either is missing or the reference's own fringe is below `min_px`).
pub(crate) fn b10_verdict(dx: Option<f64>, reference: Option<f64>, min_px: f64) -> Verdict {
    match (dx, reference) {
        (Some(d), Some(r)) if r.abs() >= min_px => {
            Verdict::from(d.signum() == r.signum() && d.abs() >= min_px)
        }
        _ => Verdict::Inconclusive,
    }
}

/// B11: `Δx / Δx_ref` in `[1 / (1 + rise), 1 + rise]` (inconclusive where either is missing
/// or the reference's is 0).
pub(crate) fn b11_verdict(dx: Option<f64>, reference: Option<f64>, rise: f64) -> Verdict {
    match (dx, reference) {
        (Some(d), Some(r)) if r != 0.0 => {
            let q = d / r;
            Verdict::from(q >= 1.0 / (1.0 + rise) && q <= 1.0 + rise)
        }
        _ => Verdict::Inconclusive,
    }
}

/// B12: `|Δx_many / Δx_ref − 1| ≤ |Δx_3 / Δx_ref − 1| + tolerance`.
pub(crate) fn b12_verdict(
    many: Option<f64>,
    three: Option<f64>,
    reference: Option<f64>,
    tolerance: f64,
) -> Verdict {
    match (many, three, reference) {
        (Some(m), Some(t), Some(r)) if r != 0.0 => {
            Verdict::from((m / r - 1.0).abs() <= (t / r - 1.0).abs() + tolerance)
        }
        _ => Verdict::Inconclusive,
    }
}

/// One renderer's fringe: at its defaults (3 wavelengths, or its own scheme) and at
/// [`MANY_WAVELENGTHS`] where it has the parameter.
struct Row {
    label: String,
    three: Option<f64>,
    many: Option<f64>,
    /// Whether B12 judges it (a method with the `wavelengths` parameter).
    wavelengths: bool,
}

/// Measures the prism and returns the markdown section; `engines`: the engines' own renderers
/// when they run.
pub fn section(
    args: &ClaimsArgs,
    inventory: &Inventory,
    ledger: &mut Ledger,
    engines: Option<&EngineRenderers>,
) -> crate::Result<String> {
    let mut b10 = inventory.claim("B10")?;
    let min_px = b10.threshold("min_px")?;
    let lit = b10.threshold("lit")? as f32;
    let mut b11 = inventory.claim("B11")?;
    let rise = b11.threshold("rise")?;
    let mut b12 = inventory.claim("B12")?;
    let tolerance = b12.threshold("tolerance")?;
    let (width, height) = SIZE;
    let scene = Arc::new(args.view(load_scene(SCENE)?.scene));
    let camera = scene.camera(width, height)?;
    let mut tracer = args.reference_backend.renderer()?;
    tracer.prepare(&scene)?;
    let mut truth = Frame::default();
    let settings = TraceSettings {
        mode: TraceMode::Transmission,
        spp: SPP,
        ..TraceSettings::default()
    };
    tracer.render(
        &camera,
        &MethodParams::Reference(settings),
        FrameOutputs::ColorAndAovs,
        &mut truth,
    )?;
    let mask = truth
        .flag(Aov::Covered)
        .ok_or_else(|| crate::LabError::invalid("the reference wrote no covered layer"))?
        .to_vec();
    let pixels = mask.iter().filter(|&&m| m).count();
    let reference = fringe_offset(&truth.color, width, &mask, lit);

    let mut cpu = CpuRenderer::new();
    cpu.prepare(&scene)?;
    let mut frame = Frame::default();
    let mut offset = |params: &MethodParams| -> crate::Result<Option<f64>> {
        cpu.render(&camera, params, FrameOutputs::Color, &mut frame)?;
        Ok(fringe_offset(&frame.color, width, &mask, lit))
    };
    let mut rows = Vec::new();
    for id in MethodId::approximations() {
        let mut params = MethodParams::defaults(id);
        if params.wavelengths().is_some() {
            let three = offset(&params)?;
            params.set("wavelengths", &MANY_WAVELENGTHS.to_string(), "claims")?;
            rows.push(Row {
                label: format!("`{}`", id.info().name),
                three,
                many: offset(&params)?,
                wavelengths: true,
            });
        } else if id == MethodId::VolumeThickness {
            rows.push(Row {
                label: "`volume-thickness` (three.js's three indices)".to_owned(),
                three: offset(&params)?,
                many: None,
                wavelengths: false,
            });
        } else if id == MethodId::ProxySphere {
            params.set("lookup", "filament", "claims")?;
            rows.push(Row {
                label: "`proxy-sphere`, `lookup=filament` (Filament's four wavelengths)".to_owned(),
                three: offset(&params)?,
                many: None,
                wavelengths: false,
            });
        }
    }
    let mut notes = Vec::new();
    match engines {
        Some(engines) => {
            for e in engines.render(&scene, &truth, width, height)? {
                rows.push(Row {
                    label: format!("`{}` (the engine itself)", e.label),
                    three: fringe_offset(&e.frame.color, width, &mask, lit),
                    many: None,
                    wavelengths: false,
                });
            }
        }
        None => notes.push(
            "the engines themselves did not run (Node, Chromium or `npm ci --prefix engines` is \
             missing: see the run's notes); they have no rows.",
        ),
    }
    for row in &rows {
        let scene_label = format!("{SCENE}: {}", row.label);
        let measured = format!(
            "Δx {} px vs {} px (reference)",
            value(row.three, 2),
            value(reference, 2)
        );
        b10.push((
            scene_label.clone(),
            b10_verdict(row.three, reference, min_px),
            measured.clone(),
        ));
        b11.push((
            scene_label.clone(),
            b11_verdict(row.three, reference, rise),
            format!(
                "{measured}: ratio {}",
                value(row.three.zip(reference).map(|(d, r)| d / r), 2)
            ),
        ));
        if row.wavelengths {
            let ratio = |d: Option<f64>| value(d.zip(reference).map(|(d, r)| d / r), 3);
            b12.push((
                scene_label,
                b12_verdict(row.many, row.three, reference, tolerance),
                format!(
                    "ratio to the reference {} at {MANY_WAVELENGTHS} wavelengths, {} at 3",
                    ratio(row.many),
                    ratio(row.three)
                ),
            ));
        }
    }
    let heading = "Dispersion (issue 52)";
    let mut md = format!(
        "\n## {heading}\n\n\
         `prism` at {width} × {height}: a glass prism (n_d 1.5, Abbe number 30: `n(λ)` from 1.529 \
         at 400 nm to 1.493 at 700 nm) before fifteen white slits on a black wall, the reference \
         in transmission mode at {SPP} samples a pixel, four wavelengths each (`docs/reference.md`). \
         The fringe is Δx per slit image: on the {pixels} pixels whose pixel-centre path the \
         reference finds on the prism, in each row each run of lit pixels (largest channel ≥ \
         {lit}) with unlit prism pixels on both sides (a slit's image not cut by the prism's \
         edge), the red channel's centroid minus the blue channel's along x (each clamped at 0), \
         in pixels, averaged over the runs weighted by their red plus blue light: reference {} px \
         (– where a renderer shows no whole slit image on the prism). The methods run on the CPU backend, those with the \
         `wavelengths` parameter at 3 (their default) and {MANY_WAVELENGTHS} wavelengths \
         (`docs/methods.md`, \"Dispersion\"); the engines render the exported glTF with its \
         `KHR_materials_dispersion`.\n",
        value(reference, 2),
    );
    for note in &notes {
        let _ = writeln!(md, "Note: {note}\n");
    }
    let _ = writeln!(
        md,
        "\n| renderer | Δx (px), 3 wavelengths or its own scheme | ratio to the reference | Δx (px), {MANY_WAVELENGTHS} wavelengths | ratio |\n|---|---|---|---|---|"
    );
    let ratio = |d: Option<f64>| value(d.zip(reference).map(|(d, r)| d / r), 2);
    for row in &rows {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} |",
            row.label,
            value(row.three, 2),
            ratio(row.three),
            value(row.many, 2),
            ratio(row.many)
        );
    }
    md.push_str("\n| claim | scene | measured | verdict |\n|---|---|---|---|\n");
    ledger.rows(&mut md, heading, &[b10, b11, b12]);
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fringe of rows made for it: a slit image with red two pixels right of blue, one
    /// cut by the mask's edge (ignored) and one touching the frame's edge (ignored).
    #[test]
    fn fringe_offset_is_red_minus_blue_per_whole_slit_image() {
        let width = 10;
        let dark = Vec3::ZERO;
        let mut colors = vec![dark; 30];
        // Row 0: a whole image at x 3..6: blue at 3, green at 4, red at 5.
        colors[3] = Vec3::new(0.0, 0.0, 1.0);
        colors[4] = Vec3::new(0.0, 1.0, -0.5); // negative blue is clamped away
        colors[5] = Vec3::new(1.0, 0.0, 0.0);
        // Row 1: an image cut by the mask (mask starts at x 2, image at 2..4).
        colors[10 + 2] = Vec3::new(0.0, 0.0, 1.0);
        colors[10 + 3] = Vec3::new(1.0, 0.0, 0.0);
        // Row 2: an image running off the frame's right edge.
        colors[20 + 8] = Vec3::new(0.0, 0.0, 1.0);
        colors[20 + 9] = Vec3::new(3.0, 0.0, 0.0);
        let mut mask = vec![true; 30];
        mask[10] = false;
        mask[11] = false;
        let dx = fringe_offset(&colors, width, &mask, 0.01).expect("a whole image");
        assert!((dx - 2.0).abs() < 1e-12, "{dx}");
        // Without row 0's image, no whole image is left.
        colors[3] = dark;
        colors[4] = dark;
        colors[5] = dark;
        assert_eq!(fringe_offset(&colors, width, &mask, 0.01), None);
    }

    /// The verdicts hold, fail and stay inconclusive on numbers made for each case.
    #[test]
    fn verdicts_follow_their_thresholds() {
        assert_eq!(b10_verdict(Some(3.0), Some(4.0), 0.25), Verdict::Confirmed);
        // The wrong order, and no fringe at all.
        assert_eq!(
            b10_verdict(Some(-3.0), Some(4.0), 0.25),
            Verdict::NotConfirmed
        );
        assert_eq!(
            b10_verdict(Some(0.1), Some(4.0), 0.25),
            Verdict::NotConfirmed
        );
        assert_eq!(
            b10_verdict(Some(3.0), Some(0.1), 0.25),
            Verdict::Inconclusive
        );
        assert_eq!(b10_verdict(None, Some(4.0), 0.25), Verdict::Inconclusive);
        // B11: within 20 % either way.
        assert_eq!(b11_verdict(Some(4.7), Some(4.0), 0.2), Verdict::Confirmed);
        assert_eq!(b11_verdict(Some(3.4), Some(4.0), 0.2), Verdict::Confirmed);
        assert_eq!(
            b11_verdict(Some(4.9), Some(4.0), 0.2),
            Verdict::NotConfirmed
        );
        assert_eq!(
            b11_verdict(Some(3.2), Some(4.0), 0.2),
            Verdict::NotConfirmed
        );
        assert_eq!(
            b11_verdict(Some(-4.0), Some(4.0), 0.2),
            Verdict::NotConfirmed
        );
        assert_eq!(
            b11_verdict(Some(4.0), Some(0.0), 0.2),
            Verdict::Inconclusive
        );
        // B12: closer (or no further than the tolerance) with more wavelengths.
        assert_eq!(
            b12_verdict(Some(4.1), Some(5.0), Some(4.0), 0.02),
            Verdict::Confirmed
        );
        assert_eq!(
            b12_verdict(Some(3.0), Some(3.6), Some(4.0), 0.02),
            Verdict::NotConfirmed
        );
        assert_eq!(
            b12_verdict(None, Some(3.6), Some(4.0), 0.02),
            Verdict::Inconclusive
        );
    }
}
