//! `refract claims`: every quantitative claim of the seed papers our data can test, measured on
//! named scenes and given a verdict, written as `docs/claims.md` (regenerated, never typed).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::backends::ReferenceBackend;
use crate::error::Context;
use crate::progress::Progress;
use crate::timing::{alternating, spread};
use refract_core::Camera;
use refract_core::exit::ExitNormalSource;
use refract_core::gpu::exit_normal_source_code;
use refract_cpu::CpuRenderer;
use refract_eval::atomic_write::write_text_atomically;
use refract_eval::load_scene;
use refract_eval::metrics::{MetricsRecord, evaluate};
use refract_eval::{LoadOptions, load_mesh};
use refract_scene::{
    Aov, Environment, Frame, FrameOutputs, MethodId, MethodParams, Refractor, Renderer, Scene,
    TraceMode,
};

mod dispersion;
mod distance_map;
mod engine;
mod history;
mod inventory;
mod layers;
mod nearby;
mod pvrr;
mod rough;

use inventory::{Inventory, Ledger, Verdict};

/// Arguments of `refract claims`.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct ClaimsArgs {
    /// Square resolution of the error measurements.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(16..=2048)))]
    pub res: u32,
    /// Where the shared meshes are (`meshes/cow.obj`); scenes whose mesh is missing are skipped
    /// with a note in the file.
    #[cfg_attr(feature = "clap", arg(long, default_value = "../shared/data"))]
    pub data: PathBuf,
    /// The file to write.
    #[cfg_attr(feature = "clap", arg(long, default_value = "docs/claims.md"))]
    pub out: PathBuf,
    /// Alternating rounds of each timing claim (1 to 50; default: the rounds its test states).
    /// Fewer rounds than stated make its verdict inconclusive (a quick run, not a measurement).
    #[cfg_attr(feature = "clap", arg(long, value_parser = clap::value_parser!(u32).range(1..=50)))]
    pub timing_rounds: Option<u32>,
    /// Where the references are traced: cpu (the CPU tracer) or gpu (the WGSL tracer,
    /// docs/reference.md). The timing claims run on the CPU backend either way.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "cpu"))]
    pub reference_backend: ReferenceBackend,
    /// The robustness pass's square resolution: every error verdict is measured again there,
    /// from a second camera (every eye turned 5° about its target; one timing round, no
    /// engines), and a row confirmed in one measurement and not in the other is published as
    /// fragile. 0 skips the pass; otherwise 16 to 2048, and not `--res`. Default: 1.5 × `--res`.
    #[cfg_attr(feature = "clap", arg(long))]
    pub second_res: Option<u32>,
    /// Degrees this pass turns every scene's camera about its target, around its up vector: 0
    /// for the measurement, [`SECOND_ORBIT_DEG`] for the robustness pass (its second camera).
    #[cfg_attr(feature = "clap", arg(skip))]
    pub orbit_deg: f32,
}

/// `scene` with its camera's eye turned `degrees` about the target, around the camera's up
/// vector (unchanged at 0): the distance to the target, the field of view and the planes kept.
pub(crate) fn orbited(mut scene: Scene, degrees: f32) -> Scene {
    if degrees != 0.0 {
        let camera = &mut scene.camera;
        let turn = glam::Quat::from_axis_angle(
            camera.up.normalize_or(glam::Vec3::Y),
            degrees.to_radians(),
        );
        camera.eye = camera.target + turn * (camera.eye - camera.target);
    }
    scene
}

/// The robustness pass's second camera: every scene's eye turned this many degrees about its
/// target, around its up vector.
pub const SECOND_ORBIT_DEG: f32 = 5.0;

impl ClaimsArgs {
    /// `scene` as this pass sees it ([`orbited`] by [`Self::orbit_deg`]).
    pub(crate) fn view(&self, scene: Scene) -> Scene {
        orbited(scene, self.orbit_deg)
    }

    /// The robustness pass's resolution (`None`: no pass), checked: `--second-res` 0 skips it,
    /// else 16 to 2048 and not `--res`; by default 1.5 × `--res`.
    pub(crate) fn second_resolution(&self) -> crate::Result<Option<u32>> {
        match self.second_res {
            Some(0) => Ok(None),
            Some(res) if !(16..=2048).contains(&res) || res == self.res => {
                Err(crate::LabError::invalid(format!(
                    "--second-res {res}: expected 0 (no robustness pass) or 16 to 2048 other than --res {}",
                    self.res
                )))
            }
            Some(res) => Ok(Some(res)),
            None => Ok(Some((self.res + self.res / 2).min(2048)).filter(|&r| r != self.res)),
        }
    }

    /// The rounds of a timing claim whose test states `stated` (its `repeats` threshold).
    pub(crate) fn rounds(&self, stated: f64) -> u32 {
        self.timing_rounds.unwrap_or(stated as u32)
    }

    /// The verdict of a timing claim from its rounds (`holds`: each round against the bar):
    /// inconclusive with fewer rounds than `stated` or rounds on both sides of the bar.
    pub(crate) fn timing_verdict(&self, stated: f64, holds: &[bool]) -> Verdict {
        if (holds.len() as f64) < stated {
            Verdict::Inconclusive
        } else {
            Verdict::of_repeats(holds.iter().copied())
        }
    }
}

/// One scene's metrics per method, and what the Wyman 2005a claims read from the frames.
struct Measured {
    scene: String,
    metrics: Vec<(MethodId, MetricsRecord)>,
    /// The refractor's index.
    ior: f32,
    /// `wyman` with `back=second` (W6).
    second: MetricsRecord,
    /// The share of `wyman`'s refractor pixels whose N2 is the silhouette fallback (W8).
    fallback_share: Option<f64>,
}

impl Measured {
    fn get(&self, id: MethodId) -> &MetricsRecord {
        &self
            .metrics
            .iter()
            .find(|(m, _)| *m == id)
            .expect("every image-space method measured")
            .1
    }
}

pub(crate) fn value(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "–".to_owned(), |v| format!("{v:.digits$}"))
}

/// A measured value at or above `bar` (a value not measured fails).
pub(crate) fn at_or_above(v: Option<f64>, bar: f64) -> bool {
    v.is_some_and(|v| v >= bar)
}

/// A measured value at or below `bar`.
pub(crate) fn at_or_below(v: Option<f64>, bar: f64) -> bool {
    v.is_some_and(|v| v <= bar)
}

/// A measured value below `bar`.
pub(crate) fn below(v: Option<f64>, bar: f64) -> bool {
    v.is_some_and(|v| v < bar)
}

/// `a < b` where both exist.
fn less(a: Option<f64>, b: Option<f64>) -> bool {
    matches!((a, b), (Some(a), Some(b)) if a < b)
}

/// The scenes of the claims: the paper's sphere (IOR 1.5) and, when the data exists, its cow
/// (IOR 1.2, Wyman 2005a's results).
fn scenes(data: &Path) -> crate::Result<(Vec<Arc<Scene>>, Vec<String>)> {
    let mut scenes = vec![Arc::new(load_scene("sphere")?.scene)];
    let mut notes = Vec::new();
    let cow = data.join("meshes/cow.obj");
    if cow.is_file() {
        let mesh = load_mesh(&cow, &LoadOptions::default())?.mesh;
        scenes.push(Arc::new(Scene::new(
            "cow",
            Refractor::new(mesh, 1.2)?,
            Environment::Procedural,
        )));
    } else {
        notes.push(format!(
            "{} not found: the cow rows are missing.",
            cow.display()
        ));
    }
    Ok((scenes, notes))
}

/// The share of covered pixels of `frame` whose exit normal is the silhouette fallback.
fn fallback_share(frame: &Frame) -> Option<f64> {
    let covered = frame.flag(Aov::Covered)?;
    let source = frame.count(Aov::ExitNormalSource)?;
    let fallback = exit_normal_source_code(ExitNormalSource::SilhouetteFallback);
    let pixels: Vec<usize> = (0..covered.len()).filter(|&i| covered[i]).collect();
    let n = pixels.iter().filter(|&&i| source[i] == fallback).count();
    (!pixels.is_empty()).then(|| n as f64 / pixels.len() as f64)
}

/// W6 and W8 on the horse of Wyman 2005a's Fig. 5 (`meshes/horse.obj`, the default camera):
/// `wyman` with the furthest and the second back surface at IOR 1.5, and its silhouette
/// fallback there and at W8's higher index.
struct Horse {
    furthest: MetricsRecord,
    second: MetricsRecord,
    fallback: Option<f64>,
    high_ior: f32,
    fallback_high: Option<f64>,
}

/// Measures [`Horse`] at `args.res`² on `bench` (`None` without the mesh).
fn measure_horse(
    args: &ClaimsArgs,
    bench: &mut Bench,
    high_ior: f32,
) -> crate::Result<Option<Horse>> {
    let path = args.data.join("meshes/horse.obj");
    if !path.is_file() {
        return Ok(None);
    }
    let mesh = load_mesh(&path, &LoadOptions::default())?.mesh;
    let mut at = |ior: f32| -> crate::Result<(MetricsRecord, MetricsRecord, Option<f64>)> {
        let scene = Scene::new(
            "horse",
            Refractor::new(mesh.clone(), ior)?,
            Environment::Procedural,
        );
        let truth = bench.truth(scene, args.res)?;
        let (frame, furthest) = bench.measure(&truth, &MethodParams::defaults(MethodId::Wyman))?;
        let mut second = MethodParams::defaults(MethodId::Wyman);
        second.set("back", "second", "claims")?;
        let (_, second) = bench.measure(&truth, &second)?;
        Ok((furthest, second, fallback_share(&frame)))
    };
    let (furthest, second, fallback) = at(1.5)?;
    let (_, _, fallback_high) = at(high_ior)?;
    Ok(Some(Horse {
        furthest,
        second,
        fallback,
        high_ior,
        fallback_high,
    }))
}

/// What the Wyman 2005a section measures beside the scenes' rows: the cow's timing rounds (W10,
/// W12), the horse (W6, W8) and `wyman-dv` on the sphere at IOR 1.2 (W2).
struct Extra {
    cow_times: Option<Race>,
    horse: Option<Horse>,
    sphere_low_ior: MetricsRecord,
}

/// W2's index-alone row: `wyman-dv` on the built-in sphere at IOR `ior`, at `res`² on `bench`.
fn measure_dv_sphere(bench: &mut Bench, res: u32, ior: f32) -> crate::Result<MetricsRecord> {
    let mut scene = load_scene("sphere")?.scene;
    scene.refractor.set_ior(ior)?;
    let truth = bench.truth(scene, res)?;
    Ok(bench
        .measure(&truth, &MethodParams::defaults(MethodId::WymanDv))?
        .1)
}

/// W2's index row: `a` (the lower index's error) at most `ratio` × `b`; false where either is
/// missing.
fn at_most(a: Option<f64>, ratio: f64, b: Option<f64>) -> bool {
    matches!((a, b), (Some(a), Some(b)) if a <= ratio * b)
}

/// W6: `|a − b| ≤ bar` (barely noticeable: `noticeable == false`) or `> bar` (the choice
/// shows: `noticeable == true`); false where either is missing.
fn back_surfaces_differ(a: Option<f64>, b: Option<f64>, bar: f64, noticeable: bool) -> bool {
    a.zip(b)
        .is_some_and(|(a, b)| ((a - b).abs() > bar) == noticeable)
}

/// Per round, whether its rate `fps` reaches `bar` (W10).
fn at_least(fps: &[f64], bar: f64) -> Vec<bool> {
    fps.iter().map(|&f| f >= bar).collect()
}

/// W8's concave half: `high` is known and larger than every one of `others` (each known).
fn more_often(high: Option<f64>, others: &[Option<f64>]) -> bool {
    high.is_some_and(|h| others.iter().all(|o| o.is_some_and(|o| h > o)))
}

/// Where [`run`] puts the provenance block once the run has ended.
const PROVENANCE_MARK: &str = "<!-- provenance -->\n";

/// Measures every claim, writes `args.out` (docs/claims.md) and returns its text; scenes left
/// out for want of `args.data` go to `progress`.
pub fn run(args: &ClaimsArgs, progress: &dyn Progress) -> crate::Result<String> {
    // A bad `--out` is found before the measurement, not after it (issue 54 #9).
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        crate::output_dirs::create_dir(dir)
            .with_context(|| format!("{}: cannot create the directory", dir.display()))?;
    }
    refract_eval::atomic_write::check_writable(&args.out)?;
    let inventory = Inventory::builtin()?;
    let mut provenance = crate::provenance::Provenance::start();
    if args.reference_backend == ReferenceBackend::Gpu {
        provenance.gpu = refract_gpu::GpuContext::new().ok().map(|c| {
            format!(
                "{} ({:?}, {:?}; the references)",
                c.info.name, c.info.backend, c.info.device_type
            )
        });
    }
    // The robustness pass (issue 51): every section again at a second resolution from a second
    // camera, one timing round, without the engines; its verdicts mark the main pass's rows
    // fragile where they differ.
    let second = args.second_resolution()?;
    let mut ledger = match second {
        Some(res) => {
            let pass = ClaimsArgs {
                res,
                timing_rounds: Some(1),
                orbit_deg: SECOND_ORBIT_DEG,
                ..args.clone()
            };
            let mut second_ledger = Ledger::default();
            measure(&pass, &inventory, &mut second_ledger, progress, false)?;
            Ledger::with_second(
                format!("{res}², camera turned {SECOND_ORBIT_DEG}°"),
                second_ledger,
            )
        }
        None => Ledger::default(),
    };
    let md = measure(args, &inventory, &mut ledger, progress, true)?;
    provenance.finish();
    let md = md.replacen(PROVENANCE_MARK, &provenance.markdown(), 1);
    write_text_atomically(&args.out, &md)?;
    Ok(md)
}

/// Every section measured at `args.res` into `ledger`, the engines themselves with
/// `with_engines` (where they run); the document with the provenance mark.
fn measure(
    args: &ClaimsArgs,
    inventory: &Inventory,
    ledger: &mut Ledger,
    progress: &dyn Progress,
    with_engines: bool,
) -> crate::Result<String> {
    let (scenes, notes) = scenes(&args.data)?;
    let scenes: Vec<Arc<Scene>> = scenes
        .into_iter()
        .map(|s| Arc::new(args.view((*s).clone())))
        .collect();
    let mut measured = Vec::new();
    let mut cpu = CpuRenderer::new();
    let mut reference = args.reference_backend.renderer()?;
    let mut cow_times = None;
    for scene in &scenes {
        let camera = scene.camera(args.res, args.res)?;
        reference.prepare(scene)?;
        cpu.prepare(scene)?;
        let mut truth = Frame::default();
        reference.render(
            &camera,
            &MethodParams::defaults(MethodId::Reference),
            FrameOutputs::ColorAndAovs,
            &mut truth,
        )?;
        let mut measure = |params: &MethodParams| -> crate::Result<(Frame, MetricsRecord)> {
            let mut frame = Frame::default();
            cpu.render(&camera, params, FrameOutputs::ColorAndAovs, &mut frame)?;
            let record = evaluate(&truth, &frame, &camera, scene.refractor.diameter()).0;
            Ok((frame, record))
        };
        let mut metrics = Vec::new();
        let mut fallback = None;
        for id in [
            MethodId::Single,
            MethodId::Wyman,
            MethodId::WymanDv,
            MethodId::WymanDn,
        ] {
            let (frame, record) = measure(&MethodParams::defaults(id))?;
            if id == MethodId::Wyman {
                fallback = fallback_share(&frame);
            }
            metrics.push((id, record));
        }
        let mut second = MethodParams::defaults(MethodId::Wyman);
        second.set("back", "second", "claims")?;
        let (_, second) = measure(&second)?;
        if scene.name == "cow" {
            let camera = scene.camera(1024, 1024)?;
            let configs = [
                MethodParams::defaults(MethodId::Wyman),
                MethodParams::defaults(MethodId::Single),
            ];
            let repeats = args.rounds(inventory.claim("W12")?.threshold("repeats")?);
            cow_times = Some(Race::run(&mut cpu, &camera, &configs, repeats, 3, 20)?);
        }
        measured.push(Measured {
            scene: scene.name.clone(),
            ior: scene.refractor.ior(),
            metrics,
            second,
            fallback_share: fallback,
        });
    }
    let mut bench = Bench::new(args)?;
    let sphere_low_ior = measure_dv_sphere(&mut bench, args.res, 1.2)?;
    let high_ior = inventory.claim("W8")?.threshold("high_ior")? as f32;
    let horse = measure_horse(args, &mut bench, high_ior)?;
    let mut notes = notes;
    if horse.is_none() {
        notes.push(format!(
            "{} not found: the horse rows of W6 and W8 are missing.",
            args.data.join("meshes/horse.obj").display()
        ));
    }
    let extra = Extra {
        cow_times,
        horse,
        sphere_low_ior,
    };
    let mut md = document(args, inventory, ledger, &measured, &notes, &extra)?;
    md.push_str(&nearby::section(args, inventory, ledger, progress)?);
    md.push_str(&distance_map::section(args, inventory, ledger, progress)?);
    md.push_str(&pvrr::section(args, inventory, ledger)?);
    // One browser per engine for both sections that render with the engines themselves.
    let engines = if with_engines {
        crate::engines::EngineRenderers::open(
            &refract_engines::Engine::ALL,
            crate::backends::GpuPolicy::IfAvailable,
            progress,
        )?
    } else {
        None
    };
    md.push_str(&engine::section(
        args,
        inventory,
        ledger,
        progress,
        engines.as_ref(),
    )?);
    md.push_str(&layers::section(args, inventory, ledger)?);
    md.push_str(&rough::section(args, inventory, ledger, engines.as_ref())?);
    md.push_str(&dispersion::section(
        args,
        inventory,
        ledger,
        engines.as_ref(),
    )?);
    let history = history::repository(Path::new("."))
        .and_then(|root| history::History::read(&root, inventory));
    md.push_str(&ledger.coverage(inventory, history.as_ref()));
    Ok(md)
}

/// The CPU backend and the reference, for the sections that measure methods per scene.
pub(crate) struct Bench {
    pub cpu: CpuRenderer,
    reference: Box<dyn Renderer>,
    /// The pass's [`ClaimsArgs::orbit_deg`], applied to every scene it traces.
    orbit_deg: f32,
}

/// A scene with its reference frame at one resolution.
pub(crate) struct Truth {
    pub scene: Arc<Scene>,
    pub camera: Camera,
    pub frame: Frame,
}

impl Bench {
    /// The CPU backend and `args`' reference backend.
    pub fn new(args: &ClaimsArgs) -> crate::Result<Self> {
        Ok(Self {
            cpu: CpuRenderer::new(),
            reference: args.reference_backend.renderer()?,
            orbit_deg: args.orbit_deg,
        })
    }

    /// The reference (default settings) of `scene` at `res`², the CPU prepared for it.
    pub fn truth(&mut self, scene: Scene, res: u32) -> crate::Result<Truth> {
        self.truth_with(Arc::new(scene), res, TraceMode::Transmission)
    }

    /// [`Self::truth`] with the reference in `mode`; the scene as the pass sees it
    /// ([`ClaimsArgs::view`]).
    pub fn truth_with(
        &mut self,
        scene: Arc<Scene>,
        res: u32,
        mode: TraceMode,
    ) -> crate::Result<Truth> {
        let settings = refract_scene::TraceSettings {
            mode,
            ..refract_scene::TraceSettings::default()
        };
        self.truth_traced(scene, res, settings)
    }

    /// [`Self::truth`] with the reference's `settings`; the scene as the pass sees it.
    pub fn truth_traced(
        &mut self,
        scene: Arc<Scene>,
        res: u32,
        settings: refract_scene::TraceSettings,
    ) -> crate::Result<Truth> {
        let scene = if self.orbit_deg == 0.0 {
            scene
        } else {
            Arc::new(orbited((*scene).clone(), self.orbit_deg))
        };
        let camera = scene.camera(res, res)?;
        self.reference.prepare(&scene)?;
        let mut frame = Frame::default();
        self.reference.render(
            &camera,
            &MethodParams::Reference(settings),
            FrameOutputs::ColorAndAovs,
            &mut frame,
        )?;
        self.cpu.prepare(&scene)?;
        Ok(Truth {
            scene,
            camera,
            frame,
        })
    }

    /// One CPU frame of `params` with its metrics against `truth`.
    pub fn measure(
        &mut self,
        truth: &Truth,
        params: &MethodParams,
    ) -> crate::Result<(Frame, MetricsRecord)> {
        self.measure_maps(truth, params)
            .map(|(frame, record, _)| (frame, record))
    }

    /// [`Self::measure`] with the per-pixel error maps.
    pub fn measure_maps(
        &mut self,
        truth: &Truth,
        params: &MethodParams,
    ) -> crate::Result<(Frame, MetricsRecord, refract_eval::metrics::ErrorMaps)> {
        let mut frame = Frame::default();
        self.cpu.render(
            &truth.camera,
            params,
            FrameOutputs::ColorAndAovs,
            &mut frame,
        )?;
        let (record, maps) = Self::evaluate(truth, &frame, params);
        Ok((frame, record, maps))
    }

    /// The metrics of `frame`, rendered with `params`, against `truth`.
    pub fn evaluate(
        truth: &Truth,
        frame: &Frame,
        params: &MethodParams,
    ) -> (MetricsRecord, refract_eval::metrics::ErrorMaps) {
        refract_eval::metrics::evaluate_method(
            &truth.frame,
            frame,
            &truth.camera,
            &truth.scene,
            params,
        )
    }
}

fn document(
    args: &ClaimsArgs,
    inventory: &Inventory,
    ledger: &mut Ledger,
    measured: &[Measured],
    notes: &[String],
    extra: &Extra,
) -> crate::Result<String> {
    let (cow, horse, sphere_low_ior) = (
        extra.cow_times.as_ref(),
        extra.horse.as_ref(),
        &extra.sphere_low_ior,
    );
    let t2 = |r: &MetricsRecord| r.t2_angle_deg_mean_non_tir;
    let p2 = |r: &MetricsRecord| r.p2_error_rel_mean_non_tir;
    let mut w1 = inventory.claim("W1")?;
    let mut w3 = inventory.claim("W3")?;
    let mut w4 = inventory.claim("W4")?;
    let mut w6 = inventory.claim("W6")?;
    let mut w8 = inventory.claim("W8")?;
    for m in measured {
        let (single, wyman, dv, dn) = (
            m.get(MethodId::Single),
            m.get(MethodId::Wyman),
            m.get(MethodId::WymanDv),
            m.get(MethodId::WymanDn),
        );
        w1.push((
            m.scene.clone(),
            less(t2(wyman), t2(single)),
            format!("T2 {}° vs {}°", value(t2(wyman), 2), value(t2(single), 2)),
        ));
        for (claim, other) in [(&mut w3, dv), (&mut w4, dn)] {
            claim.push((
                m.scene.clone(),
                less(t2(wyman), t2(other)) && less(p2(wyman), p2(other)),
                format!(
                    "T2 {}° vs {}°, \\|P~2−P2\\|/diam {} vs {}",
                    value(t2(wyman), 2),
                    value(t2(other), 2),
                    value(p2(wyman), 4),
                    value(p2(other), 4)
                ),
            ));
        }
        let bar = w8.threshold("share")?;
        w8.push((
            m.scene.clone(),
            below(m.fallback_share, bar),
            format!(
                "silhouette fallback on {} of `wyman`'s refractor pixels (IOR {})",
                pct(m.fallback_share),
                m.ior
            ),
        ));
    }
    // W6: the cow (nearly convex) and the horse (Fig. 5).
    let w6_bar = w6.threshold("convex_deg")?;
    let pair = |second: &MetricsRecord, furthest: &MetricsRecord| {
        format!(
            "mean T2 error {}° (`back=second`) vs {}° (`furthest`)",
            value(t2(second), 3),
            value(t2(furthest), 3)
        )
    };
    if let Some(cow) = measured.iter().find(|m| m.scene == "cow") {
        let furthest = cow.get(MethodId::Wyman);
        w6.push((
            "cow".into(),
            back_surfaces_differ(t2(&cow.second), t2(furthest), w6_bar, false),
            pair(&cow.second, furthest),
        ));
    }
    let w8_bar = w8.threshold("share")?;
    if let Some(h) = horse {
        w6.push((
            "horse, IOR 1.5".into(),
            back_surfaces_differ(t2(&h.second), t2(&h.furthest), w6_bar, true),
            pair(&h.second, &h.furthest),
        ));
        w8.push((
            "horse, IOR 1.5".into(),
            below(h.fallback, w8_bar),
            format!(
                "silhouette fallback on {} of `wyman`'s refractor pixels",
                pct(h.fallback)
            ),
        ));
        let others: Vec<Option<f64>> = measured
            .iter()
            .map(|m| m.fallback_share)
            .chain([h.fallback])
            .collect();
        w8.push((
            format!("horse, IOR {}", h.high_ior),
            more_often(h.fallback_high, &others),
            format!(
                "silhouette fallback on {} of `wyman`'s refractor pixels, against {} (sphere, cow, horse at 1.5)",
                pct(h.fallback_high),
                others.iter().map(|o| pct(*o)).collect::<Vec<_>>().join(", ")
            ),
        ));
    }
    let mut claims = vec![w1];
    // W2: d_V alone, the index and the shape one at a time.
    let mut w2 = inventory.claim("W2")?;
    let ratio = w2.threshold("ratio")?;
    let dv_low = t2(sphere_low_ior);
    if let Some(sphere) = measured.iter().find(|m| m.scene == "sphere") {
        let dv_high = t2(sphere.get(MethodId::WymanDv));
        w2.push((
            "sphere, IOR 1.2 vs 1.5".into(),
            at_most(dv_low, ratio, dv_high),
            format!(
                "`wyman-dv` T2 {}° at IOR 1.2 vs {}° at 1.5",
                value(dv_low, 2),
                value(dv_high, 2)
            ),
        ));
    }
    if let Some(cow_m) = measured.iter().find(|m| m.scene == "cow") {
        let dv_cow = t2(cow_m.get(MethodId::WymanDv));
        w2.push((
            "IOR 1.2, sphere vs cow".into(),
            less(dv_low, dv_cow),
            format!(
                "`wyman-dv` T2 {}° on the sphere vs {}° on the cow",
                value(dv_low, 2),
                value(dv_cow, 2)
            ),
        ));
    }
    claims.push(w2);
    claims.extend([w3, w4, w6, w8]);
    if let Some(cow) = cow {
        let mut w10 = inventory.claim("W10")?;
        let repeats = w10.threshold("repeats")?;
        for (label, bar, pick) in [
            (
                "`wyman` (2-sided)",
                w10.threshold("two_sided_fps")?,
                (|m: &(f64, f64)| m.0) as fn(&(f64, f64)) -> f64,
            ),
            (
                "`single` (1-sided)",
                w10.threshold("one_sided_fps")?,
                |m: &(f64, f64)| m.1,
            ),
        ] {
            let fps: Vec<f64> = cow.medians.iter().map(|m| 1e3 / pick(m)).collect();
            let (lo, mid, hi) = spread(&fps).unwrap_or_default();
            w10.push((
                format!("cow, 1024², {label}"),
                args.timing_verdict(repeats, &at_least(&fps, bar)),
                format!(
                    "on this machine's CPU backend ({}): median {mid:.1} fps, range {lo:.1}–{hi:.1} over {} rounds of 20 colour-only frames (paper: {bar} fps, GeForce 6800)",
                    crate::timing::cpu_description(),
                    fps.len()
                ),
            ));
        }
        let mut w12 = inventory.claim("W12")?;
        let (low, high) = (w12.threshold("low")?, w12.threshold("high")?);
        let ratios = cow.ratios();
        let (lo, mid, hi) = spread(&ratios).unwrap_or_default();
        w12.push((
            "cow, 1024²".into(),
            args.timing_verdict(
                w12.threshold("repeats")?,
                &ratios
                    .iter()
                    .map(|&r| (low..=high).contains(&r))
                    .collect::<Vec<_>>(),
            ),
            format!(
                "`wyman` / `single` frame time: median {mid:.2}×, range {lo:.2}–{hi:.2}× over {} alternating rounds (CPU)",
                ratios.len()
            ),
        ));
        claims.extend([w10, w12]);
    }
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Paper claims and our measured verdicts\n\n\
         Written by `refract claims` (regenerate with `cargo run --release -- claims`; do not edit by \
         hand). Each claim's test and thresholds are data, the paper's words and section beside \
         them (`crates/refract-lab/claims.toml`); the coverage table at the end has a row for \
         every claim of the four papers, says from git whether its test was stated before its \
         first measurement or with it, and lists the revisions of a test after it was measured. Timing verdicts come from alternating rounds and are \
         **inconclusive** when the rounds fall on both sides of the bar. {robustness} Errors \
         against the exact \
         reference (`transmission`, 1 spp, Mitsuba's interface rule{tracer}) \
         at {res}², CPU backend, over refractor pixels without TIR at the first exit; T2 is the \
         direction leaving the first exit, P2 the first exit point (`docs/metrics.md`). Scenes: the \
         paper's 1,600-triangle sphere at IOR 1.5 and its cow at IOR 1.2, procedural environment, \
         default camera.\n",
        res = args.res,
        tracer = match args.reference_backend {
            ReferenceBackend::Cpu => "",
            ReferenceBackend::Gpu => "; traced on the GPU, `--reference-backend gpu`",
        },
        robustness = match args.second_resolution()? {
            Some(second) => format!(
                "Every section was also measured at {second}² from a second camera, every \
                 scene's eye turned {SECOND_ORBIT_DEG}° about its target around its up vector \
                 (one timing round, without the engines themselves): a row confirmed in one \
                 measurement and not confirmed in the other is **fragile**, with both; rows whose \
                 scene names its resolution, the engines' own rows and timing rows are not \
                 compared."
            ),
            None => "No robustness pass (`--second-res 0`): no row is marked fragile.".to_owned(),
        },
    );
    let _ = writeln!(
        md,
        "## Provenance\n\n\
         Where and how these numbers were measured, read from the checkout, the build and the \
         system by `refract claims` (`refract_lab::provenance`); the engines' frames come from \
         headless Chromium on the same machine (`docs/engines.md`).\n\n{PROVENANCE_MARK}"
    );
    for note in notes {
        let _ = writeln!(md, "Note: {note}\n");
    }
    let heading = "Wyman 2005a, image-space refraction through two interfaces";
    let _ = writeln!(md, "## {heading}\n");
    let _ = writeln!(
        md,
        "| claim | scene | measured | verdict |\n|---|---|---|---|"
    );
    ledger.rows(&mut md, heading, &claims);
    Ok(md)
}

/// Two configurations timed in alternating rounds of colour-only frames on the CPU backend
/// ([`alternating`]): each round's two median frame times.
pub(crate) struct Race {
    pub medians: Vec<(f64, f64)>,
}

impl Race {
    /// `rounds` rounds of `frames` frames (after `warm_up`) of `configs[0]`, then `configs[1]`.
    pub fn run(
        cpu: &mut CpuRenderer,
        camera: &Camera,
        configs: &[MethodParams; 2],
        rounds: u32,
        warm_up: u32,
        frames: u32,
    ) -> crate::Result<Self> {
        let mut frame = Frame::default();
        let times = alternating(rounds, warm_up, frames, |k| {
            Ok(cpu
                .render(camera, &configs[k], FrameOutputs::Color, &mut frame)?
                .ms)
        })?;
        Ok(Self {
            medians: times.iter().map(|(a, b)| (a.median, b.median)).collect(),
        })
    }

    /// Per round, the first configuration's time over the second's.
    pub fn ratios(&self) -> Vec<f64> {
        self.medians.iter().map(|(a, b)| a / b).collect()
    }

    /// The mean over the rounds of each configuration's median, in milliseconds.
    pub fn mean_ms(&self) -> (f64, f64) {
        let n = self.medians.len().max(1) as f64;
        (
            self.medians.iter().map(|m| m.0).sum::<f64>() / n,
            self.medians.iter().map(|m| m.1).sum::<f64>() / n,
        )
    }
}

/// A share as a percentage.
pub(crate) fn pct(v: Option<f64>) -> String {
    v.map_or_else(|| "–".to_owned(), |v| format!("{:.1} %", 100.0 * v))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The second camera turns the eye about the target around the up vector: the distance
    /// and the height along up kept, the horizontal direction turned by the angle.
    #[test]
    fn the_second_camera_orbits_the_target() {
        let scene = load_scene("chart").expect("chart").scene;
        let turned = orbited(scene.clone(), SECOND_ORBIT_DEG);
        let (a, b) = (scene.camera, turned.camera);
        assert_eq!((a.target, a.up, a.fov_y), (b.target, b.up, b.fov_y));
        let up = a.up.normalize();
        let (ra, rb) = (a.eye - a.target, b.eye - b.target);
        assert!((ra.length() - rb.length()).abs() < 1e-5);
        assert!((ra.dot(up) - rb.dot(up)).abs() < 1e-5);
        let flat = |v: glam::Vec3| v - v.dot(up) * up;
        let angle = flat(ra).angle_between(flat(rb)).to_degrees();
        assert!((angle - SECOND_ORBIT_DEG).abs() < 1e-2, "{angle}");
        assert_eq!(orbited(scene.clone(), 0.0).camera, a);
    }

    /// W6 on numbers made for each case: the cow's 0.075° apart is barely noticeable against
    /// 0.1° and would fail the horse's test; the sphere's identical pair fails the horse's test.
    #[test]
    fn w6_verdicts_can_fail() {
        let (cow_second, cow_furthest) = (Some(1.126), Some(1.201));
        assert!(back_surfaces_differ(cow_second, cow_furthest, 0.1, false));
        assert!(!back_surfaces_differ(cow_second, cow_furthest, 0.1, true));
        assert!(!back_surfaces_differ(Some(3.786), Some(3.786), 0.1, true));
        assert!(back_surfaces_differ(Some(2.0), Some(2.4), 0.1, true));
        assert!(!back_surfaces_differ(Some(2.0), Some(2.4), 0.1, false));
        assert!(!back_surfaces_differ(None, Some(2.4), 0.1, false));
    }

    /// W10 at the paper's rates: 151 fps against 122.9 holds, 140 against 295.7 does not; rounds
    /// on both sides are inconclusive.
    #[test]
    fn w10_verdict_can_fail() {
        let args = ClaimsArgs {
            res: 64,
            data: "data".into(),
            out: "claims.md".into(),
            timing_rounds: None,
            reference_backend: ReferenceBackend::Cpu,
            second_res: None,
            orbit_deg: 0.0,
        };
        let verdict = |fps: &[f64], bar| args.timing_verdict(5.0, &at_least(fps, bar));
        assert_eq!(verdict(&[151.0; 5], 122.9), Verdict::Confirmed);
        assert_eq!(verdict(&[140.0; 5], 295.7), Verdict::NotConfirmed);
        assert_eq!(
            verdict(&[130.0, 120.0, 130.0, 130.0, 130.0], 122.9),
            Verdict::Inconclusive
        );
    }

    /// W2's rows on numbers made for them: the index row's ratio, the shape row's order.
    #[test]
    fn w2_verdicts_can_fail() {
        assert!(at_most(Some(1.0), 0.5, Some(2.0)));
        assert!(!at_most(Some(1.1), 0.5, Some(2.0)));
        assert!(!at_most(None, 0.5, Some(2.0)));
        assert!(at_or_above(Some(0.99), 0.99) && !at_or_above(Some(0.98), 0.99));
        assert!(!at_or_above(None, 0.0));
        assert!(at_or_below(Some(2.0), 2.0) && !at_or_below(Some(2.1), 2.0));
        assert!(!at_or_below(None, 2.0));
        assert!(below(Some(0.04), 0.05) && !below(Some(0.05), 0.05) && !below(None, 1.0));
        assert!(less(Some(1.0), Some(1.2)));
        assert!(!less(Some(1.2), Some(1.2)));
        assert!(!less(Some(1.0), None));
    }

    /// W8's concave half: larger than every other share, each known.
    #[test]
    fn w8_concave_verdict_can_fail() {
        let others = [Some(0.0), Some(0.002), Some(0.01)];
        assert!(more_often(Some(0.03), &others));
        assert!(!more_often(Some(0.005), &others));
        assert!(!more_often(Some(0.01), &others));
        assert!(!more_often(None, &others));
        assert!(!more_often(Some(0.03), &[Some(0.0), None]));
    }
}
