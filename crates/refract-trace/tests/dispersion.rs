//! Dispersion in the reference (issue 52): the spectral render against the RGB one where
//! dispersion vanishes, dispersion 0 as no dispersion, and what a prism does to light.

use glam::Vec3;
use refract_eval::load_scene;
use refract_scene::{Environment, Frame, LatLongMap, Scene, TraceMode, TraceSettings};
use refract_trace::render;

fn settings(spp: u32, mode: TraceMode) -> TraceSettings {
    TraceSettings {
        spp,
        mode,
        ..TraceSettings::default()
    }
}

fn frame(scene: &Scene, res: (u32, u32), settings: &TraceSettings) -> Frame {
    let camera = scene.camera(res.0, res.1).expect("camera");
    render(scene, &camera, settings)
}

fn mean(frame: &Frame) -> Vec3 {
    frame.color.iter().copied().sum::<Vec3>() / frame.color.len() as f32
}

/// Dispersion 0 is no dispersion: an infinite Abbe number leaves the render bit for bit the
/// RGB one (the reference renders spectrally only where some glass disperses).
#[test]
fn infinite_abbe_number_is_the_rgb_render() {
    let mut scene = load_scene("chart").expect("chart").scene;
    let settings = settings(4, TraceMode::Full);
    let rgb = frame(&scene, (40, 30), &settings);
    scene.refractor.set_abbe(f32::INFINITY).expect("abbe");
    assert!(!scene.has_dispersion());
    let again = frame(&scene, (40, 30), &settings);
    assert_eq!(rgb.color, again.color);
}

/// A lat-long map of 64 × 32 texels whose colour changes with the direction in all three
/// channels (saturated hues, an HDR hot spot of 40).
fn colourful_map() -> Environment {
    let (width, height) = (64u32, 32u32);
    let texels = (0..width * height)
        .map(|i| {
            let (x, y) = (
                (i % width) as f32 / width as f32,
                (i / width) as f32 / height as f32,
            );
            let hue = Vec3::new(
                (std::f32::consts::TAU * x).sin() * 0.5 + 0.5,
                (std::f32::consts::TAU * (x + y)).cos() * 0.5 + 0.5,
                y,
            );
            if (x - 0.3).abs() < 0.04 && (y - 0.4).abs() < 0.06 {
                hue * 40.0
            } else {
                hue
            }
        })
        .collect();
    Environment::LatLong {
        map: LatLongMap {
            width,
            height,
            texels,
        },
        intensity: 1.5,
    }
}

/// The whole spectral pipeline where the index no longer depends on the wavelength (Abbe
/// number 10³⁰: `n(λ) = n_d` in `f32`, but the render is spectral): RGB uplifted to spectra,
/// wavelengths sampled, spectra back to linear sRGB. On `chart` (the procedural sky, the
/// colour chart and the wood floor lit by the directional light, through a glass sphere) and
/// on the same sphere in a colourful lat-long map (Mitsuba's per-texel spectra), in both
/// modes, the spectral frame's mean agrees with the RGB frame's to 1 % per channel and its
/// pixels to 0.1 RMS at 256 samples (measured on `chart`: 0.4 % and 0.041-0.049, the
/// one-wavelength noise). A missing D65, a missing `1/p(λ)` or the hero's factor 4, a wrong
/// normalisation or colour matrix, or texel spectra from the wrong texels move the mean by
/// 5 % or more.
#[test]
fn spectral_render_converges_to_the_rgb_one_without_dispersion() {
    let chart = load_scene("chart").expect("chart").scene;
    let mut in_map = chart.clone();
    in_map.objects.clear();
    in_map.environment = colourful_map();
    for (rgb_scene, mode) in [
        (&chart, TraceMode::Transmission),
        (&chart, TraceMode::Full),
        (&in_map, TraceMode::Transmission),
    ] {
        let mut spectral_scene = rgb_scene.clone();
        spectral_scene.refractor.set_abbe(1e30).expect("abbe");
        assert!(spectral_scene.has_dispersion());
        let settings = settings(256, mode);
        let rgb = frame(rgb_scene, (32, 24), &settings);
        let spectral = frame(&spectral_scene, (32, 24), &settings);
        let (m_rgb, m_spectral) = (mean(&rgb), mean(&spectral));
        let relative = ((m_spectral - m_rgb) / m_rgb).abs().max_element();
        assert!(
            relative < 0.01,
            "{mode:?}: mean {m_spectral} vs RGB {m_rgb}"
        );
        let rms = (rgb
            .color
            .iter()
            .zip(&spectral.color)
            .map(|(a, b)| (*a - *b).length_squared())
            .sum::<f32>()
            / rgb.color.len() as f32)
            .sqrt();
        assert!(rms < 0.1, "{mode:?}: per-pixel RMS {rms}");
    }
}

/// What the prism does: it bends each wavelength by its own angle, so it spreads the white
/// slits into spectra without making or losing light. On `prism`, the dispersive render's
/// mean equals the non-dispersive one's to 5 % (the light is only redistributed; each
/// wavelength sees the slits shifted by its own amount, measured 2.4 % off in blue), while
/// inside the prism's image its pixels are coloured: the mean chroma (max − min channel over
/// the brightest channel) of the lit pixels seen through the glass is above 0.5 with
/// dispersion and below 0.05 without (white slits stay white).
#[test]
fn a_prism_spreads_white_into_spectra_and_keeps_the_light() {
    let dispersive = load_scene("prism").expect("prism").scene;
    assert!(dispersive.has_dispersion());
    let mut clear = dispersive.clone();
    clear.refractor.set_abbe(f32::INFINITY).expect("abbe");
    let settings = settings(64, TraceMode::Transmission);
    let res = (96, 72);
    let coloured = frame(&dispersive, res, &settings);
    let white = frame(&clear, res, &settings);
    let (a, b) = (mean(&coloured), mean(&white));
    assert!(((a - b) / b).abs().max_element() < 0.05, "mean {a} vs {b}");
    let covered = coloured
        .flag(refract_scene::Aov::Covered)
        .expect("covered layer");
    let chroma = |frame: &Frame| {
        let lit: Vec<f32> = frame
            .color
            .iter()
            .zip(covered)
            .filter(|(c, covered)| **covered && c.max_element() > 0.2)
            .map(|(c, _)| (c.max_element() - c.min_element()) / c.max_element())
            .collect();
        assert!(
            lit.len() > 50,
            "lit pixels through the prism: {}",
            lit.len()
        );
        lit.iter().sum::<f32>() / lit.len() as f32
    };
    let (with, without) = (chroma(&coloured), chroma(&white));
    assert!(
        with > 0.5,
        "chroma with dispersion {with} (measured 1.04: out of gamut)"
    );
    assert!(without < 0.05, "chroma without dispersion {without}");
}
