//! Error metrics of a method frame against the reference (design.md, "Measuring").

use glam::Vec3;
use refract_core::vector::angle_between;
use serde::Serialize;

use crate::frame::{Aov, Frame};
use crate::tonemap::to_srgb8;

/// One row of `metrics.json`: exactly these fields, `null` where not applicable.
#[derive(Clone, Debug, Serialize)]
pub struct MetricsRecord {
    /// Scene name.
    pub scene: String,
    /// Method id (`reference` for the reference's own timing row).
    pub method: String,
    /// `cpu`, `gpu` or `trace`.
    pub backend: String,
    /// The method's parameters, `name=value` separated by spaces.
    pub params: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Root mean square error of linear RGB over refractor pixels.
    pub rmse: Option<f64>,
    /// `20 log10(1 / rmse)` (peak 1.0 of linear RGB).
    pub psnr_db: Option<f64>,
    /// Mean FLIP (LDR, after the tonemap) over refractor pixels.
    pub flip_mean: Option<f64>,
    /// Mean angle between T2 and the reference T2, degrees.
    pub t2_angle_deg_mean: Option<f64>,
    /// The same over pixels without TIR on the reference path.
    pub t2_angle_deg_mean_non_tir: Option<f64>,
    /// Mean |P~2 − P2| / bounding-sphere diameter.
    pub p2_error_rel_mean: Option<f64>,
    /// The same over non-TIR pixels.
    pub p2_error_rel_mean_non_tir: Option<f64>,
    /// Share of the refractor pixels where the method (or the reference) has TIR.
    pub tir_fraction: Option<f64>,
    /// Median time per frame (all per-frame passes), milliseconds.
    pub ms_per_frame: Option<f64>,
}

/// Per-pixel error maps (NaN where not applicable) for the images.
pub struct ErrorMaps {
    /// FLIP per pixel (over the whole image).
    pub flip: Vec<f32>,
    /// T2 angle error, degrees.
    pub t2_deg: Vec<f32>,
    /// |P~2 − P2| / diameter.
    pub p2_rel: Vec<f32>,
}

fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// FLIP error map of `test` against `reference`, both tonemapped to 8-bit sRGB.
pub fn flip_map(reference: &[Vec3], test: &[Vec3], width: u32, height: u32) -> Vec<f32> {
    let ldr = |img: &[Vec3]| -> Vec<u8> { img.iter().flat_map(|&c| to_srgb8(c)).collect() };
    let r = nv_flip::FlipImageRgb8::with_data(width, height, &ldr(reference));
    let t = nv_flip::FlipImageRgb8::with_data(width, height, &ldr(test));
    nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec()
}

/// The layers a frame lacks read as absent everywhere.
struct Layers<'f> {
    covered: Option<&'f [bool]>,
    t2: Option<&'f [Vec3]>,
    p2: Option<&'f [Vec3]>,
    tir: Option<&'f [bool]>,
}

impl<'f> Layers<'f> {
    fn of(frame: &'f Frame) -> Self {
        Self {
            covered: frame.flag(Aov::Covered),
            t2: frame.vec3(Aov::T2),
            p2: frame.vec3(Aov::P2),
            tir: frame.flag(Aov::Tir),
        }
    }
    fn covered(&self, i: usize) -> bool {
        self.covered.is_some_and(|c| c[i])
    }
    fn t2(&self, i: usize) -> Vec3 {
        self.t2.map_or(Vec3::NAN, |v| v[i])
    }
    fn p2(&self, i: usize) -> Vec3 {
        self.p2.map_or(Vec3::NAN, |v| v[i])
    }
    fn tir(&self, i: usize) -> bool {
        self.tir.is_some_and(|t| t[i])
    }
}

/// Computes the metrics of `frame` against `reference` (design.md, "Measuring") and the
/// per-pixel maps. Both frames need their AOV layers (`covered`, `T2`, `P2`, `tir`); a missing
/// layer counts as absent at every pixel. Over the pixels where the reference sees the
/// refractor: RMSE and PSNR of linear RGB, mean FLIP (after the tonemap), mean angle between
/// `T2` and the reference's `T2` (degrees) and mean `|P~2 − P2| / diameter`, each also over the
/// pixels without TIR on the reference path, and the share of pixels with TIR in `frame`.
pub fn evaluate(reference: &Frame, frame: &Frame, diameter: f32) -> (MetricsRecord, ErrorMaps) {
    let n = reference.pixel_count();
    let flip = flip_map(&reference.color, &frame.color, frame.width, frame.height);
    let (truth, ours) = (Layers::of(reference), Layers::of(frame));
    let mut t2_deg = vec![f32::NAN; n];
    let mut p2_rel = vec![f32::NAN; n];
    for i in 0..n {
        if !(truth.covered(i) && ours.covered(i)) {
            continue;
        }
        let (truth_t2, ours_t2) = (truth.t2(i), ours.t2(i));
        if !truth_t2.is_nan() && !ours_t2.is_nan() && ours_t2 != Vec3::ZERO {
            t2_deg[i] = angle_between(ours_t2, truth_t2).to_degrees();
        }
        let (truth_p2, ours_p2) = (truth.p2(i), ours.p2(i));
        if !truth_p2.is_nan() && !ours_p2.is_nan() {
            p2_rel[i] = (ours_p2 - truth_p2).length() / diameter;
        }
    }
    let refractor: Vec<usize> = (0..n).filter(|&i| truth.covered(i)).collect();
    let non_tir = |i: &&usize| !truth.tir(**i);
    let finite = |v: &[f32], i: usize| v[i].is_finite().then_some(f64::from(v[i]));
    let mse = mean(refractor.iter().map(|&i| {
        let d = frame.color[i] - reference.color[i];
        f64::from(d.length_squared()) / 3.0
    }));
    let rmse = mse.map(f64::sqrt);
    let record = MetricsRecord {
        scene: String::new(),
        method: String::new(),
        backend: String::new(),
        params: String::new(),
        width: frame.width,
        height: frame.height,
        rmse,
        psnr_db: rmse.map(|r| 20.0 * (1.0 / r.max(1e-12)).log10()),
        flip_mean: mean(refractor.iter().map(|&i| f64::from(flip[i]))),
        t2_angle_deg_mean: mean(refractor.iter().filter_map(|&i| finite(&t2_deg, i))),
        t2_angle_deg_mean_non_tir: mean(
            refractor
                .iter()
                .filter(non_tir)
                .filter_map(|&i| finite(&t2_deg, i)),
        ),
        p2_error_rel_mean: mean(refractor.iter().filter_map(|&i| finite(&p2_rel, i))),
        p2_error_rel_mean_non_tir: mean(
            refractor
                .iter()
                .filter(non_tir)
                .filter_map(|&i| finite(&p2_rel, i)),
        ),
        tir_fraction: mean(refractor.iter().map(|&i| f64::from(u8::from(ours.tir(i))))),
        ms_per_frame: None,
    };
    (
        record,
        ErrorMaps {
            flip,
            t2_deg,
            p2_rel,
        },
    )
}

/// The reference's own row: its TIR share and render time.
pub fn reference_record(reference: &Frame, ms: f64) -> MetricsRecord {
    let truth = Layers::of(reference);
    let refractor: Vec<usize> = (0..reference.pixel_count())
        .filter(|&i| truth.covered(i))
        .collect();
    MetricsRecord {
        scene: String::new(),
        method: "reference".to_owned(),
        backend: "trace".to_owned(),
        params: String::new(),
        width: reference.width,
        height: reference.height,
        rmse: None,
        psnr_db: None,
        flip_mean: None,
        t2_angle_deg_mean: None,
        t2_angle_deg_mean_non_tir: None,
        p2_error_rel_mean: None,
        p2_error_rel_mean_non_tir: None,
        tir_fraction: mean(refractor.iter().map(|&i| f64::from(u8::from(truth.tir(i))))),
        ms_per_frame: Some(ms),
    }
}
