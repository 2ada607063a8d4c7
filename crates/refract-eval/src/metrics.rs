//! Error metrics of a method frame against the reference (design.md, "Measuring"; every
//! definition in `docs/metrics.md`). Image metrics are over the refractor pixels (where the
//! reference's centre ray hits the refractor; the background is the same by construction);
//! geometric metrics compare what the image-space methods approximate: the exit point `P2` and
//! the direction leaving it, `T2`, at the *first* exit, over the pixels without TIR there.

use glam::Vec3;
use refract_core::Camera;
use refract_core::nearby_geometry::{SeedSpacing, guaranteed_feature_px, guard_band_camera};
use refract_core::vector::angle_between;
use serde::{Deserialize, Serialize};

use refract_scene::MethodParams;
use refract_scene::scene::Scene;
use refract_scene::tonemap::to_srgb8;
use refract_scene::{Aov, Frame};

/// The `ε` of the relative MSE, `(a − b)² / (b² + ε)` (pbrt's `imgtool diff --metric MRSE`).
pub const REL_MSE_EPSILON: f64 = 0.01;

/// One row of `metrics.json`: exactly these fields, `null` where not applicable.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
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
    /// Refractor pixels (the reference's centre ray hits the refractor).
    pub refractor_pixels: usize,
    /// Root mean square error of linear RGB over refractor pixels.
    pub rmse: Option<f64>,
    /// Relative MSE of linear RGB over refractor pixels: mean of `(a − b)² / (b² + 0.01)`.
    pub rel_mse: Option<f64>,
    /// PSNR of the tonemapped 8-bit sRGB image over refractor pixels, `10 log10(1 / MSE)` with
    /// values in `[0, 1]`.
    pub psnr_ldr_db: Option<f64>,
    /// Mean FLIP (LDR, after the tonemap) over refractor pixels.
    pub flip_mean: Option<f64>,
    /// Mean angle between T2 and the reference's T2 (leaving the first exit), degrees, over
    /// refractor pixels where both exist.
    pub t2_angle_deg_mean: Option<f64>,
    /// The same over pixels without TIR at the reference's first exit.
    pub t2_angle_deg_mean_non_tir: Option<f64>,
    /// Median (nearest rank) of the non-TIR T2 angle error, degrees.
    pub t2_angle_deg_p50_non_tir: Option<f64>,
    /// 90th percentile (nearest rank) of the non-TIR T2 angle error, degrees.
    pub t2_angle_deg_p90_non_tir: Option<f64>,
    /// 99th percentile (nearest rank) of the non-TIR T2 angle error, degrees.
    pub t2_angle_deg_p99_non_tir: Option<f64>,
    /// Path level: mean angle between T2 and the direction the reference path finally leaves
    /// in (`Tout`), over pixels without TIR anywhere on the reference path.
    pub t_out_angle_deg_mean_no_path_tir: Option<f64>,
    /// Mean `|P~2 − P2|` / bounding-sphere diameter, where both exist.
    pub p2_error_rel_mean: Option<f64>,
    /// The same over pixels without TIR at the first exit.
    pub p2_error_rel_mean_non_tir: Option<f64>,
    /// Median (nearest rank) of the screen-space exit error `|px(P~2) − px(P2)|`, pixels, over
    /// non-TIR pixels where both project.
    pub p2_error_px_p50_non_tir: Option<f64>,
    /// 90th percentile of the screen-space exit error, pixels.
    pub p2_error_px_p90_non_tir: Option<f64>,
    /// 99th percentile of the screen-space exit error, pixels.
    pub p2_error_px_p99_non_tir: Option<f64>,
    /// Share of the refractor pixels where the frame has TIR (the method's own flag; for the
    /// reference, TIR anywhere on the path).
    pub tir_fraction: Option<f64>,
    /// Share of the refractor pixels with TIR at the reference's first exit.
    pub tir_first_exit_fraction: Option<f64>,
    /// Nearby geometry (Wyman 2005b): over pixels where both the reference and the method see
    /// the refractor, `[both hit, method only, reference only, neither]`, where "hit" means the
    /// ray leaving the refractor meets an opaque object (the reference's exact path; the
    /// method's NG lookup).
    pub nearby_confusion: Option<[usize; 4]>,
    /// Share of the reference's hits the method misses ("rays completely miss the dragon").
    pub nearby_miss_rate: Option<f64>,
    /// Share of the reference's misses where the method shows an object.
    pub nearby_false_hit_rate: Option<f64>,
    /// Mean `|P_geom − P_geom,ref|`, world units, over pixels where both hit.
    pub p_geom_error_world_mean: Option<f64>,
    /// Median of the same distance in NG-texture pixels (both projected with the NG camera).
    pub p_geom_error_px_p50: Option<f64>,
    /// 90th percentile of the NG-pixel distance.
    pub p_geom_error_px_p90: Option<f64>,
    /// The lookup alone: median NG-pixel distance between the method's `P_geom` and where the
    /// method's own ray `P~2 + t T~2` exactly meets the objects (BVH), over pixels where both
    /// exist: Wyman 2005b's error without Wyman 2005a's error in `P~2` and `T~2`.
    pub lookup_error_px_p50: Option<f64>,
    /// 90th percentile of the same distance.
    pub lookup_error_px_p90: Option<f64>,
    /// Share of the pixels whose own ray meets an object where the lookup found none.
    pub lookup_miss_rate: Option<f64>,
    /// The hit rule checked: of the lookups that report a hit (a lookup ending on an occupied
    /// texel, converged or not), the share whose `P_geom` lies within one pixel (NG texel:
    /// both axes) of where the method's own ray exactly meets the objects; a reported hit whose
    /// own ray meets nothing counts as outside.
    pub lookup_hits_within_texel: Option<f64>,
    /// The same share over the converged hits only (the texel repeated).
    pub lookup_converged_hits_within_texel: Option<f64>,
    /// Mean distance updates of the iterative lookups over the method's refractor pixels.
    pub iterations_mean: Option<f64>,
    /// Share of those pixels whose iteration reached a fixed point.
    pub converged_share: Option<f64>,
    /// Seeded lookups, Fig. 9: share of refractor pixels whose seeds guarantee every feature at
    /// least 3 NG pixels long ([`refract_core::nearby_geometry::guaranteed_feature_px`] ≤ 3).
    pub feature_guarantee_3px_share: Option<f64>,
    /// The same for features of at least 10 pixels.
    pub feature_guarantee_10px_share: Option<f64>,
    /// Distance maps: mean linear-search samples per pixel that starts a path (Umenhoffer et
    /// al. 2007 §17.2.1), over all its rays and layers.
    pub linear_steps_mean: Option<f64>,
    /// Distance maps: mean secant steps per such pixel.
    pub secant_steps_mean: Option<f64>,
    /// Distance maps: mean secondary rays per such pixel.
    pub bounces_mean: Option<f64>,
    /// Distance maps: share of such pixels where a ray left every layer (environment read).
    pub layer_miss_share: Option<f64>,
    /// `pvrr`: share of reflector pixels not looked up (the zooming region, a lens ray with no
    /// exit, past the last stack level; Kakimoto et al. §4.2).
    pub zoom_share: Option<f64>,
    /// Median time per frame (all per-frame passes), milliseconds.
    pub ms_per_frame: Option<f64>,
    /// What ran the row: the GPU adapter for a `gpu` row, the CPU model for `cpu` and `trace`
    /// rows, the engine's page for an engine's own row.
    pub device: Option<String>,
    /// The refract version that measured it.
    pub version: Option<String>,
    /// The commit of the checkout it ran in (with "(uncommitted changes)" where the tree
    /// differed from it).
    pub commit: Option<String>,
}

impl MetricsRecord {
    /// Records what measured the row: `device`, this build's version and `commit`.
    pub fn made_by(&mut self, device: String, commit: &str) {
        self.device = Some(device);
        self.version = Some(env!("CARGO_PKG_VERSION").to_owned());
        self.commit = Some(commit.to_owned());
    }
}

/// Per-pixel error maps (NaN where not applicable) for the images.
pub struct ErrorMaps {
    /// FLIP per pixel (over the whole image).
    pub flip: Vec<f32>,
    /// T2 angle error against the first-exit T2, degrees.
    pub t2_deg: Vec<f32>,
    /// |P~2 − P2| / diameter.
    pub p2_rel: Vec<f32>,
}

fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// The nearest-rank percentile `p ∈ (0, 100]` of `values` (sorted in place): the smallest value
/// with at least `p` % of the values at or below it, `v[⌈p n / 100⌉ − 1]`.
pub fn percentile(values: &mut [f64], p: f64) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let rank = ((p / 100.0) * values.len() as f64).ceil() as usize;
    Some(values[rank.clamp(1, values.len()) - 1])
}

/// pixelmatch's largest YIQ colour delta (`MAX_COLOR_DISTANCE`), which Render Fidelity divides by.
pub const RENDER_FIDELITY_MAX_DELTA: f64 = 35215.0;

/// The glTF Render Fidelity distance between two images, in decibels, as model-viewer's
/// render-fidelity tools compute it (`ImageComparator.analyze`, pixelmatch's `colorDelta`):
/// both images displayed as 8-bit sRGB ([`to_srgb8`], refract's display transform), per pixel
/// the YIQ delta `δ = 0.5053 ΔY² + 0.299 ΔI² + 0.1957 ΔQ²` (0 to 35215 for 8-bit values),
/// `ratio = √(Σ δ² / n) / 35215` over the `n` pixels of `mask`, and `10 log₁₀(ratio)` dB:
/// more negative is closer (model-viewer fails a scenario above −22 dB); `−∞` for identical
/// pixels, `None` for an empty mask.
pub fn render_fidelity_db(a: &[Vec3], b: &[Vec3], mask: &[bool]) -> Option<f64> {
    let yiq = |c: Vec3| {
        let [r, g, b] = to_srgb8(c).map(f64::from);
        (
            r * 0.298_895_31 + g * 0.586_622_47 + b * 0.114_482_23,
            r * 0.595_977_99 - g * 0.274_176_10 - b * 0.321_801_89,
            r * 0.211_470_17 - g * 0.522_617_11 + b * 0.311_146_94,
        )
    };
    let (mut square_sum, mut n) = (0.0, 0usize);
    for ((&x, &y), _) in a.iter().zip(b).zip(mask).filter(|(_, m)| **m) {
        let ((y1, i1, q1), (y2, i2, q2)) = (yiq(x), yiq(y));
        let delta =
            0.5053 * (y1 - y2).powi(2) + 0.299 * (i1 - i2).powi(2) + 0.1957 * (q1 - q2).powi(2);
        square_sum += delta * delta;
        n += 1;
    }
    (n > 0).then(|| 10.0 * ((square_sum / n as f64).sqrt() / RENDER_FIDELITY_MAX_DELTA).log10())
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
    t_out: Option<&'f [Vec3]>,
    p2: Option<&'f [Vec3]>,
    tir: Option<&'f [bool]>,
    tir_first_exit: Option<&'f [bool]>,
}

impl<'f> Layers<'f> {
    fn of(frame: &'f Frame) -> Self {
        Self {
            covered: frame.flag(Aov::Covered),
            t2: frame.vec3(Aov::T2),
            t_out: frame.vec3(Aov::TOut),
            p2: frame.vec3(Aov::P2),
            tir: frame.flag(Aov::Tir),
            tir_first_exit: frame.flag(Aov::TirFirstExit),
        }
    }
    fn flag(layer: Option<&[bool]>, i: usize) -> bool {
        layer.is_some_and(|l| l[i])
    }
    fn vector(layer: Option<&[Vec3]>, i: usize) -> Vec3 {
        layer.map_or(Vec3::NAN, |l| l[i])
    }
}

/// The angle in degrees between a method's direction and a true one, where both exist (a zero
/// method direction, absorbed by `TirPolicy::Black`, has none).
fn angle_deg(ours: Vec3, truth: Vec3) -> Option<f32> {
    (!ours.is_nan() && !truth.is_nan() && ours != Vec3::ZERO)
        .then(|| angle_between(ours, truth).to_degrees())
}

/// Computes the metrics of `frame` against `reference` (both from `camera`; the reference
/// needs its AOV layers, the frame at least `covered`, `T2`, `P2`, `tir` where the method has
/// them: a missing layer counts as absent at every pixel) and the per-pixel maps. `diameter`
/// is the refractor's bounding-sphere diameter. Definitions: `docs/metrics.md`.
pub fn evaluate(
    reference: &Frame,
    frame: &Frame,
    camera: &Camera,
    diameter: f32,
) -> (MetricsRecord, ErrorMaps) {
    let n = reference.pixel_count();
    let flip = flip_map(&reference.color, &frame.color, frame.width, frame.height);
    let (truth, ours) = (Layers::of(reference), Layers::of(frame));
    let refractor: Vec<usize> = (0..n).filter(|&i| Layers::flag(truth.covered, i)).collect();
    let non_tir = |i: usize| !Layers::flag(truth.tir_first_exit, i);
    let mut t2_deg = vec![f32::NAN; n];
    let mut p2_rel = vec![f32::NAN; n];
    let mut p2_px = vec![f32::NAN; n];
    let mut t_out_deg = vec![f32::NAN; n];
    let pixel = |p: Vec3| camera.world_to_pixel(p).map(|q| q.truncate());
    for &i in &refractor {
        if !Layers::flag(ours.covered, i) {
            continue;
        }
        let t2 = Layers::vector(ours.t2, i);
        if let Some(a) = angle_deg(t2, Layers::vector(truth.t2, i)) {
            t2_deg[i] = a;
        }
        if let Some(a) = angle_deg(t2, Layers::vector(truth.t_out, i)) {
            t_out_deg[i] = a;
        }
        let (ours_p2, truth_p2) = (Layers::vector(ours.p2, i), Layers::vector(truth.p2, i));
        if !ours_p2.is_nan() && !truth_p2.is_nan() {
            p2_rel[i] = (ours_p2 - truth_p2).length() / diameter;
            if let (Some(a), Some(b)) = (pixel(ours_p2), pixel(truth_p2)) {
                p2_px[i] = (a - b).length();
            }
        }
    }
    let finite = |v: &[f32], i: usize| v[i].is_finite().then_some(f64::from(v[i]));
    let over = |v: &[f32], keep: &dyn Fn(usize) -> bool| -> Vec<f64> {
        refractor
            .iter()
            .filter(|&&i| keep(i))
            .filter_map(|&i| finite(v, i))
            .collect()
    };
    let all = |_: usize| true;
    let mut t2_non_tir = over(&t2_deg, &non_tir);
    let mut p2_px_non_tir = over(&p2_px, &non_tir);
    let no_path_tir = |i: usize| !Layers::flag(truth.tir, i);

    let hdr = |i: usize| (frame.color[i].as_dvec3(), reference.color[i].as_dvec3());
    let mse = mean(refractor.iter().map(|&i| {
        let (a, b) = hdr(i);
        (a - b).length_squared() / 3.0
    }));
    let rel_mse = mean(refractor.iter().map(|&i| {
        let (a, b) = hdr(i);
        let d = (a - b) * (a - b) / (b * b + glam::DVec3::splat(REL_MSE_EPSILON));
        (d.x + d.y + d.z) / 3.0
    }));
    let ldr_mse = mean(refractor.iter().map(|&i| {
        let (a, b) = (to_srgb8(frame.color[i]), to_srgb8(reference.color[i]));
        (0..3)
            .map(|k| ((f64::from(a[k]) - f64::from(b[k])) / 255.0).powi(2))
            .sum::<f64>()
            / 3.0
    }));
    let share = |flags: Option<&[bool]>| {
        mean(
            refractor
                .iter()
                .map(|&i| f64::from(u8::from(Layers::flag(flags, i)))),
        )
    };
    let record = MetricsRecord {
        width: frame.width,
        height: frame.height,
        refractor_pixels: refractor.len(),
        rmse: mse.map(f64::sqrt),
        rel_mse,
        psnr_ldr_db: ldr_mse.map(|m| 10.0 * (1.0 / m.max(1e-20)).log10()),
        flip_mean: mean(refractor.iter().map(|&i| f64::from(flip[i]))),
        t2_angle_deg_mean: mean(over(&t2_deg, &all).into_iter()),
        t2_angle_deg_mean_non_tir: mean(t2_non_tir.iter().copied()),
        t2_angle_deg_p50_non_tir: percentile(&mut t2_non_tir, 50.0),
        t2_angle_deg_p90_non_tir: percentile(&mut t2_non_tir, 90.0),
        t2_angle_deg_p99_non_tir: percentile(&mut t2_non_tir, 99.0),
        t_out_angle_deg_mean_no_path_tir: mean(over(&t_out_deg, &no_path_tir).into_iter()),
        p2_error_rel_mean: mean(over(&p2_rel, &all).into_iter()),
        p2_error_rel_mean_non_tir: mean(over(&p2_rel, &non_tir).into_iter()),
        p2_error_px_p50_non_tir: percentile(&mut p2_px_non_tir, 50.0),
        p2_error_px_p90_non_tir: percentile(&mut p2_px_non_tir, 90.0),
        p2_error_px_p99_non_tir: percentile(&mut p2_px_non_tir, 99.0),
        tir_fraction: share(ours.tir),
        tir_first_exit_fraction: share(truth.tir_first_exit),
        ..MetricsRecord::default()
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

/// The nearby-geometry metrics of `frame` (a Wyman 2005b method's, with its `P_geom`, `T2`,
/// `P2` and, for iterative lookups, `iterations`/`converged` layers) against `reference`, into
/// `record`: the hit/miss confusion, the `P_geom` error in world units and in pixels of the NG
/// texture (`ng_camera`), iteration counts and, with `seeds = Some((K, spacing))`, the Fig. 9
/// feature-size guarantee. Definitions: `docs/metrics.md`.
pub fn evaluate_nearby(
    reference: &Frame,
    frame: &Frame,
    scene: &Scene,
    ng_camera: &Camera,
    seeds: Option<(u32, SeedSpacing)>,
    record: &mut MetricsRecord,
) {
    let n = reference.pixel_count();
    let (truth, ours) = (Layers::of(reference), Layers::of(frame));
    let (truth_geom, ours_geom) = (reference.vec3(Aov::PGeom), frame.vec3(Aov::PGeom));
    let both: Vec<usize> = (0..n)
        .filter(|&i| Layers::flag(truth.covered, i) && Layers::flag(ours.covered, i))
        .collect();
    let mut confusion = [0usize; 4];
    let mut world = Vec::new();
    let mut px = Vec::new();
    let pixel = |p: Vec3| ng_camera.world_to_pixel(p).map(|q| q.truncate());
    for &i in &both {
        let (t, o) = (Layers::vector(truth_geom, i), Layers::vector(ours_geom, i));
        let (t_hit, o_hit) = (!t.is_nan(), !o.is_nan());
        confusion[match (o_hit, t_hit) {
            (true, true) => 0,
            (true, false) => 1,
            (false, true) => 2,
            (false, false) => 3,
        }] += 1;
        if t_hit && o_hit {
            world.push(f64::from((o - t).length()));
            if let (Some(a), Some(b)) = (pixel(o), pixel(t)) {
                px.push(f64::from((a - b).length()));
            }
        }
    }
    let ratio = |a: usize, b: usize| (a + b > 0).then(|| a as f64 / (a + b) as f64);
    record.nearby_confusion = Some(confusion);
    record.nearby_miss_rate = ratio(confusion[2], confusion[0]);
    record.nearby_false_hit_rate = ratio(confusion[1], confusion[3]);
    record.p_geom_error_world_mean = mean(world.iter().copied());
    record.p_geom_error_px_p50 = percentile(&mut px, 50.0);
    record.p_geom_error_px_p90 = percentile(&mut px, 90.0);
    let covered: Vec<usize> = (0..n).filter(|&i| Layers::flag(ours.covered, i)).collect();
    let (mut lookup_px, mut own_hits, mut lookup_misses) = (Vec::new(), 0usize, 0usize);
    let (mut reported, mut within) = (0usize, 0usize);
    let (mut converged_hits, mut converged_within) = (0usize, 0usize);
    let converged = frame.flag(Aov::Converged);
    for &i in &covered {
        let (p2, t2) = (Layers::vector(ours.p2, i), Layers::vector(ours.t2, i));
        if p2.is_nan() || t2.is_nan() || t2 == Vec3::ZERO {
            continue;
        }
        let exact = nearest_object_hit(scene, p2, t2);
        let o = Layers::vector(ours_geom, i);
        if !o.is_nan() {
            reported += 1;
            let near = exact.and_then(|e| Some((pixel(o)?, pixel(e)?)));
            let close = near.is_some_and(|(a, b)| (a - b).abs().max_element() <= 1.0);
            within += usize::from(close);
            if converged.is_some_and(|c| c[i]) {
                converged_hits += 1;
                converged_within += usize::from(close);
            }
        }
        let Some(exact) = exact else {
            continue;
        };
        own_hits += 1;
        if o.is_nan() {
            lookup_misses += 1;
        } else if let (Some(a), Some(b)) = (pixel(o), pixel(exact)) {
            lookup_px.push(f64::from((a - b).length()));
        }
    }
    record.lookup_hits_within_texel = (reported > 0).then(|| within as f64 / reported as f64);
    record.lookup_converged_hits_within_texel =
        (converged_hits > 0).then(|| converged_within as f64 / converged_hits as f64);
    record.lookup_error_px_p50 = percentile(&mut lookup_px, 50.0);
    record.lookup_error_px_p90 = percentile(&mut lookup_px, 90.0);
    record.lookup_miss_rate = (own_hits > 0).then(|| lookup_misses as f64 / own_hits as f64);
    if let Some(iterations) = frame.count(Aov::Iterations) {
        record.iterations_mean = mean(covered.iter().map(|&i| f64::from(iterations[i])));
    }
    if let Some(converged) = frame.flag(Aov::Converged) {
        record.converged_share = mean(covered.iter().map(|&i| f64::from(u8::from(converged[i]))));
    }
    if let Some(seeds) = seeds {
        let sizes: Vec<Option<f32>> = pixel_feature_sizes(reference, frame, ng_camera, seeds)
            .into_iter()
            .enumerate()
            .filter(|&(i, _)| Layers::flag(truth.covered, i))
            .map(|(_, size)| size)
            .collect();
        let share = |limit: f32| {
            mean(
                sizes
                    .iter()
                    .map(|s| f64::from(u8::from(s.is_some_and(|s| s <= limit)))),
            )
        };
        record.feature_guarantee_3px_share = share(3.0);
        record.feature_guarantee_10px_share = share(10.0);
    }
}

/// Per pixel, the largest feature size in NG-texture pixels (`ng_camera`) that the seeds
/// `(K, spacing)` of `frame`'s lookup guarantee to find (Wyman 2005b §4.3, Fig. 9:
/// [`guaranteed_feature_px`] along the method's exit ray `P2 + t T2`); `None` where `reference`
/// does not see the refractor or the method has no exit ray there.
fn pixel_feature_sizes(
    reference: &Frame,
    frame: &Frame,
    ng_camera: &Camera,
    (k, spacing): (u32, SeedSpacing),
) -> Vec<Option<f32>> {
    let (truth, ours) = (Layers::of(reference), Layers::of(frame));
    (0..reference.pixel_count())
        .map(|i| {
            let (p2, t2) = (Layers::vector(ours.p2, i), Layers::vector(ours.t2, i));
            (Layers::flag(truth.covered, i) && !p2.is_nan() && !t2.is_nan() && t2 != Vec3::ZERO)
                .then(|| guaranteed_feature_px(ng_camera, p2, t2, k, spacing))
                .flatten()
        })
        .collect()
}

/// [`pixel_feature_sizes`] of a seeded lookup method (`iterative-seeded`), with the NG camera
/// its `guard` implies and its `seeds` and `spacing`; `None` for a method without seeds.
pub fn feature_sizes_px(
    reference: &Frame,
    frame: &Frame,
    camera: &Camera,
    method: &MethodParams,
) -> Option<Vec<Option<f32>>> {
    let (ng_camera, seeds) = lookup_setup(camera, method)?;
    Some(pixel_feature_sizes(reference, frame, &ng_camera, seeds?))
}

/// A nearby-geometry lookup's NG camera (the eye's camera widened by its `guard` band) and its
/// seeds `(K, spacing)` (`None` without a `seeds` parameter), from its parameters.
fn lookup_setup(
    camera: &Camera,
    method: &MethodParams,
) -> Option<(Camera, Option<(u32, SeedSpacing)>)> {
    let integer = |name| method.get(name).and_then(|v| v.parse::<u32>().ok());
    let (desc, _) = guard_band_camera(camera.desc(), integer("guard").unwrap_or(0));
    // The NG camera differs from a valid camera only by its field of view and size.
    let ng_camera = Camera::new(desc).ok()?;
    let spacing = method
        .get("spacing")
        .and_then(|name| refract_scene::registry::seed_spacing(&name))
        .unwrap_or(SeedSpacing::Screen);
    Some((ng_camera, integer("seeds").map(|k| (k, spacing))))
}

/// Where the ray `origin + t dir` (unit `dir`, `t > 0`) first meets an opaque object of `scene`.
fn nearest_object_hit(scene: &Scene, origin: Vec3, dir: Vec3) -> Option<Vec3> {
    let ray = refract_core::Ray { origin, dir };
    scene
        .objects
        .iter()
        .filter_map(|o| o.bvh().closest_hit(&ray, 1e-4, f32::INFINITY))
        .map(|hit| hit.t)
        .min_by(f32::total_cmp)
        .map(|t| ray.at(t))
}

/// [`evaluate`], and the metrics of the layers the method's registry row writes beside the
/// common ones: with `ng_texel` (Wyman 2005b's lookups) [`evaluate_nearby`] with the NG camera
/// its `guard` parameter implies and its `seeds`/`spacing`; with `linear_steps` the search work
/// of the distance maps; with `zoom` the zooming region's share (Kakimoto et al.). No family is
/// named: a new family's layers and parameters drive its metrics.
pub fn evaluate_method(
    reference: &Frame,
    frame: &Frame,
    camera: &Camera,
    scene: &Scene,
    method: &MethodParams,
) -> (MetricsRecord, ErrorMaps) {
    let (mut record, maps) = evaluate(reference, frame, camera, scene.refractor.diameter());
    let writes = |aov| method.id().info().aovs.contains(&aov);
    if writes(Aov::NgTexel)
        && let Some((ng_camera, seeds)) = lookup_setup(camera, method)
    {
        evaluate_nearby(reference, frame, scene, &ng_camera, seeds, &mut record);
    }
    if let (true, Some(covered)) = (writes(Aov::LinearSteps), frame.flag(Aov::Covered)) {
        let paths: Vec<usize> = (0..frame.pixel_count()).filter(|&i| covered[i]).collect();
        let count_mean = |aov| {
            frame
                .count(aov)
                .and_then(|c| mean(paths.iter().map(|&i| f64::from(c[i]))))
        };
        record.linear_steps_mean = count_mean(Aov::LinearSteps);
        record.secant_steps_mean = count_mean(Aov::SecantSteps);
        record.bounces_mean = count_mean(Aov::Bounces);
        record.layer_miss_share = frame
            .flag(Aov::Miss)
            .and_then(|m| mean(paths.iter().map(|&i| f64::from(u8::from(m[i])))));
    }
    if let (true, Some(covered), Some(zoom)) = (
        writes(Aov::Zoom),
        frame.flag(Aov::Covered),
        frame.flag(Aov::Zoom),
    ) {
        record.zoom_share = mean(
            covered
                .iter()
                .zip(zoom)
                .filter(|(c, _)| **c)
                .map(|(_, z)| f64::from(u8::from(*z))),
        );
    }
    (record, maps)
}

/// Pixels where the reference's path meets an opaque object and the method's lookup found none
/// (Wyman 2005b Fig. 6, 8: "rays completely miss the dragon").
pub fn missed_geometry(truth: &Frame, frame: &Frame) -> Vec<bool> {
    let (Some(t), Some(o)) = (truth.vec3(Aov::PGeom), frame.vec3(Aov::PGeom)) else {
        return vec![false; frame.pixel_count()];
    };
    let covered = frame.flag(Aov::Covered);
    (0..frame.pixel_count())
        .map(|i| covered.is_some_and(|c| c[i]) && !t[i].is_nan() && o[i].is_nan())
        .collect()
}

/// The reference's own row: its refractor pixels, TIR shares and render time.
pub fn reference_record(reference: &Frame, ms: f64) -> MetricsRecord {
    let truth = Layers::of(reference);
    let refractor: Vec<usize> = (0..reference.pixel_count())
        .filter(|&i| Layers::flag(truth.covered, i))
        .collect();
    let share = |flags: Option<&[bool]>| {
        mean(
            refractor
                .iter()
                .map(|&i| f64::from(u8::from(Layers::flag(flags, i)))),
        )
    };
    MetricsRecord {
        method: "reference".to_owned(),
        backend: "trace".to_owned(),
        width: reference.width,
        height: reference.height,
        refractor_pixels: refractor.len(),
        tir_fraction: share(truth.tir),
        tir_first_exit_fraction: share(truth.tir_first_exit),
        ms_per_frame: Some(ms),
        ..MetricsRecord::default()
    }
}

#[cfg(test)]
mod tests {
    use refract_core::CameraDesc;

    use super::*;

    /// Render Fidelity's dB: identical images are −∞; black against white is pixelmatch's
    /// `δ = 0.5053 · 255²` (Y only), `10 log₁₀(32857.4 / 35215) = −0.301` dB; a masked-out
    /// pixel does not count; an empty mask is `None`.
    #[test]
    fn render_fidelity_decibels_follow_pixelmatch() {
        let black = [Vec3::ZERO; 3];
        let white = [Vec3::splat(1e6); 3];
        assert_eq!(
            render_fidelity_db(&black, &black, &[true; 3]),
            Some(f64::NEG_INFINITY)
        );
        let db = render_fidelity_db(&black, &white, &[true, true, false]).expect("pixels");
        let expected = 10.0 * (0.5053 * 255.0f64.powi(2) / RENDER_FIDELITY_MAX_DELTA).log10();
        assert!(
            (db - expected).abs() < 0.01 && (db + 0.301).abs() < 0.005,
            "{db}"
        );
        let mut half = black;
        half[0] = white[0];
        let one_of_two = render_fidelity_db(&black, &half, &[true, true, false]).expect("pixels");
        // One differing pixel of two: the RMS falls by √2, 10 log₁₀(√2) = 1.505 dB lower.
        assert!((db - one_of_two - 1.505).abs() < 0.01, "{one_of_two}");
        assert_eq!(render_fidelity_db(&black, &white, &[false; 3]), None);
    }

    /// A 4 × 1 reference: pixels 0–2 see the refractor (pixel 2 with TIR at the first exit and
    /// a path that leaves and re-enters), pixel 3 is background.
    fn reference() -> (Frame, Camera) {
        let camera = Camera::new(CameraDesc {
            width: 4,
            height: 1,
            ..CameraDesc::default()
        })
        .expect("camera");
        let mut f = Frame::new(4, 1);
        f.color = vec![
            Vec3::splat(0.5),
            Vec3::splat(1.0),
            Vec3::splat(2.0),
            Vec3::ONE,
        ];
        f.flag_mut(Aov::Covered)[..3].fill(true);
        f.flag_mut(Aov::TirFirstExit)[2] = true;
        f.flag_mut(Aov::Tir)[2] = true;
        let t2 = f.vec3_mut(Aov::T2);
        t2[..3].fill(Vec3::NEG_Z);
        let t_out = f.vec3_mut(Aov::TOut);
        t_out[0] = Vec3::NEG_Z;
        t_out[1] = Vec3::X; // left and re-entered: the path leaves along +x
        t_out[2] = Vec3::NEG_Z;
        let p2 = f.vec3_mut(Aov::P2);
        p2[..3].fill(Vec3::new(0.0, 0.0, -1.0));
        (f, camera)
    }

    fn method(color: [Vec3; 4], t2: [Vec3; 3], p2: [Vec3; 3]) -> Frame {
        let mut f = Frame::new(4, 1);
        f.color = color.to_vec();
        f.flag_mut(Aov::Covered)[..3].fill(true);
        f.vec3_mut(Aov::T2)[..3].copy_from_slice(&t2);
        f.vec3_mut(Aov::P2)[..3].copy_from_slice(&p2);
        f.flag_mut(Aov::Tir)[1] = true;
        f
    }

    fn close(a: Option<f64>, b: f64) -> bool {
        a.is_some_and(|a| (a - b).abs() < 1e-6 * b.abs().max(1.0))
    }

    #[test]
    fn a_perfect_frame_has_no_error() {
        let (truth, camera) = reference();
        let p2 = Vec3::new(0.0, 0.0, -1.0);
        let frame = method(
            [
                Vec3::splat(0.5),
                Vec3::splat(1.0),
                Vec3::splat(2.0),
                Vec3::ZERO,
            ],
            [Vec3::NEG_Z; 3],
            [p2; 3],
        );
        let (r, maps) = evaluate(&truth, &frame, &camera, 2.0);
        assert_eq!(r.refractor_pixels, 3);
        assert!(close(r.rmse, 0.0) && close(r.rel_mse, 0.0), "{r:?}");
        assert!(r.psnr_ldr_db.expect("psnr") > 150.0, "identical: huge PSNR");
        assert!(close(r.t2_angle_deg_mean, 0.0) && close(r.p2_error_px_p99_non_tir, 0.0));
        // The background pixel differs (black vs white) but is not counted.
        assert!(maps.t2_deg[3].is_nan() && maps.p2_rel[3].is_nan());
        // Path level: pixel 1's path leaves along +x, 90° from T2.
        assert!(close(r.t_out_angle_deg_mean_no_path_tir, 45.0), "{r:?}");
        assert!(close(r.tir_fraction, 1.0 / 3.0) && close(r.tir_first_exit_fraction, 1.0 / 3.0));
    }

    #[test]
    fn known_errors_give_known_metrics() {
        let (truth, camera) = reference();
        let p2 = Vec3::new(0.0, 0.0, -1.0);
        let tilt = |deg: f32| {
            let r = deg.to_radians();
            Vec3::new(r.sin(), 0.0, -r.cos())
        };
        // Colours off by 0.1, 0.0, 0.5 in every channel; T2 off by 10°, 20°, 30° (the last at a
        // TIR pixel); P~2 off by 0.2, 0.4, 0.6 along x.
        let frame = method(
            [
                Vec3::splat(0.6),
                Vec3::splat(1.0),
                Vec3::splat(2.5),
                Vec3::ONE,
            ],
            [tilt(10.0), tilt(20.0), tilt(30.0)],
            [p2 + Vec3::X * 0.2, p2 + Vec3::X * 0.4, p2 + Vec3::X * 0.6],
        );
        let (r, _) = evaluate(&truth, &frame, &camera, 2.0);
        let mse: f64 = (0.01 + 0.0 + 0.25) / 3.0;
        assert!(close(r.rmse, mse.sqrt()), "{r:?}");
        let rel = (0.01f64 / (0.25 + 0.01) + 0.0 + 0.25 / (4.0 + 0.01)) / 3.0;
        assert!((r.rel_mse.expect("rel") - rel).abs() < 1e-6, "{r:?}");
        // Means: all three pixels, or the two without TIR at the first exit.
        assert!((r.t2_angle_deg_mean.expect("t2") - 20.0).abs() < 1e-3);
        assert!((r.t2_angle_deg_mean_non_tir.expect("t2") - 15.0).abs() < 1e-3);
        // Nearest rank over {10, 20}: p50 = 10, p90 = p99 = 20.
        assert!((r.t2_angle_deg_p50_non_tir.expect("p50") - 10.0).abs() < 1e-3);
        assert!((r.t2_angle_deg_p99_non_tir.expect("p99") - 20.0).abs() < 1e-3);
        assert!((r.p2_error_rel_mean.expect("p2") - 0.2).abs() < 1e-6);
        assert!((r.p2_error_rel_mean_non_tir.expect("p2") - 0.15).abs() < 1e-6);
        // Screen space: the same world offsets seen at distance 4 through the 4-pixel-wide
        // 40° camera (aspect 4): pixels per unit = W / (2 · 4 · tan 20° · 4).
        let per_unit = 4.0 / (2.0 * 4.0 * 20f64.to_radians().tan() * 4.0);
        let p50 = r.p2_error_px_p50_non_tir.expect("px");
        assert!(
            (p50 - 0.2 * per_unit).abs() < 1e-4,
            "{p50} vs {}",
            0.2 * per_unit
        );
        let p90 = r.p2_error_px_p90_non_tir.expect("px");
        assert!((p90 - 0.4 * per_unit).abs() < 1e-4);
    }

    #[test]
    fn percentiles_are_nearest_rank() {
        let mut v: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(percentile(&mut v, 50.0), Some(5.0));
        assert_eq!(percentile(&mut v, 90.0), Some(9.0));
        assert_eq!(percentile(&mut v, 99.0), Some(10.0));
        assert_eq!(percentile(&mut v, 100.0), Some(10.0));
        assert_eq!(percentile(&mut [], 50.0), None);
    }
}
