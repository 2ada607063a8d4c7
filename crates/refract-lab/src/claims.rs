//! `refract claims`: every quantitative claim of the seed papers our data can test, measured on
//! named scenes and given a verdict, written as `docs/claims.md` (regenerated, never typed).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::error::Context;
use refract_core::Camera;
use refract_cpu::CpuRenderer;
use refract_eval::atomic_write::write_text_atomically;
use refract_eval::load_scene;
use refract_eval::metrics::{MetricsRecord, evaluate};
use refract_eval::{LoadOptions, load_mesh};
use refract_scene::{
    Environment, Frame, FrameOutputs, MethodId, MethodParams, Refractor, Renderer, Scene, TraceMode,
};
use refract_trace::ReferenceRenderer;

use crate::progress::Progress;
use crate::timing::time_frames;

mod distance_map;
mod engine;
mod nearby;
mod pvrr;

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
}

/// One scene's metrics per method.
struct Measured {
    scene: String,
    metrics: Vec<(MethodId, MetricsRecord)>,
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

/// Measures every claim, writes `args.out` (docs/claims.md) and returns its text; scenes left
/// out for want of `args.data` go to `progress`.
pub fn run(args: &ClaimsArgs, progress: &dyn Progress) -> crate::Result<String> {
    let (scenes, notes) = scenes(&args.data)?;
    let mut measured = Vec::new();
    let mut cpu = CpuRenderer::new();
    let mut reference = ReferenceRenderer::new();
    let mut cow_fps = None;
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
        let mut metrics = Vec::new();
        for id in [
            MethodId::Single,
            MethodId::Wyman,
            MethodId::WymanDv,
            MethodId::WymanDn,
        ] {
            let mut frame = Frame::default();
            cpu.render(
                &camera,
                &MethodParams::defaults(id),
                FrameOutputs::ColorAndAovs,
                &mut frame,
            )?;
            metrics.push((
                id,
                evaluate(&truth, &frame, &camera, scene.refractor.diameter()).0,
            ));
        }
        if scene.name == "cow" {
            let camera = scene.camera(1024, 1024)?;
            let mut frame = Frame::default();
            let times = time_frames(3, 20, || {
                Ok(cpu
                    .render(
                        &camera,
                        &MethodParams::defaults(MethodId::Wyman),
                        FrameOutputs::Color,
                        &mut frame,
                    )?
                    .ms)
            })?;
            cow_fps = Some(1e3 / times.median);
        }
        measured.push(Measured {
            scene: scene.name.clone(),
            metrics,
        });
    }
    let mut md = document(args, &measured, &notes, cow_fps);
    md.push_str(&nearby::section(args, progress)?);
    md.push_str(&distance_map::section(args, progress)?);
    md.push_str(&pvrr::section(args)?);
    md.push_str(&engine::section(args, progress)?);
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        crate::output_dirs::create_dir(dir)
            .with_context(|| format!("{}: cannot create the directory", dir.display()))?;
    }
    write_text_atomically(&args.out, &md)?;
    Ok(md)
}

/// The CPU backend and the reference, for the sections that measure methods per scene.
pub(crate) struct Bench {
    pub cpu: CpuRenderer,
    reference: ReferenceRenderer,
}

/// A scene with its reference frame at one resolution.
pub(crate) struct Truth {
    pub scene: Arc<Scene>,
    pub camera: Camera,
    pub frame: Frame,
}

impl Bench {
    pub fn new() -> Self {
        Self {
            cpu: CpuRenderer::new(),
            reference: ReferenceRenderer::new(),
        }
    }

    /// The reference (default settings) of `scene` at `res`², the CPU prepared for it.
    pub fn truth(&mut self, scene: Scene, res: u32) -> crate::Result<Truth> {
        self.truth_with(Arc::new(scene), res, TraceMode::Transmission)
    }

    /// [`Self::truth`] with the reference in `mode`.
    pub fn truth_with(
        &mut self,
        scene: Arc<Scene>,
        res: u32,
        mode: TraceMode,
    ) -> crate::Result<Truth> {
        let camera = scene.camera(res, res)?;
        self.reference.prepare(&scene)?;
        let mut frame = Frame::default();
        let settings = refract_scene::TraceSettings {
            mode,
            ..refract_scene::TraceSettings::default()
        };
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
        let mut frame = Frame::default();
        self.cpu.render(
            &truth.camera,
            params,
            FrameOutputs::ColorAndAovs,
            &mut frame,
        )?;
        let (record, _) = refract_eval::metrics::evaluate_method(
            &truth.frame,
            &frame,
            &truth.camera,
            &truth.scene,
            params,
        );
        Ok((frame, record))
    }
}

/// A claim: its text, and per scene whether it holds with the numbers that say so.
pub(crate) struct Claim {
    pub text: &'static str,
    pub rows: Vec<(String, bool, String)>,
}

/// The markdown rows of `claims`.
pub(crate) fn claim_rows(md: &mut String, claims: &[Claim]) {
    for claim in claims {
        for (scene, holds, numbers) in &claim.rows {
            let _ = writeln!(
                md,
                "| {} | {scene} | {numbers} | {} |",
                claim.text,
                if *holds {
                    "**confirmed**"
                } else {
                    "**not confirmed**"
                }
            );
        }
    }
}

fn document(
    args: &ClaimsArgs,
    measured: &[Measured],
    notes: &[String],
    cow_fps: Option<f64>,
) -> String {
    let t2 = |r: &MetricsRecord| r.t2_angle_deg_mean_non_tir;
    let p2 = |r: &MetricsRecord| r.p2_error_rel_mean_non_tir;
    let mut claims = vec![
        Claim {
            text: "Two interfaces refract more accurately than one (Wyman 2005a §1, Fig. 1): `wyman` has a smaller T2 error than `single`",
            rows: Vec::new(),
        },
        Claim {
            text: "Interpolating `d~ = (θt/θi) d_V + (1 − θt/θi) d_N` beats `d_V` alone (§3.1): smaller T2 and P2 errors than `wyman-dv`",
            rows: Vec::new(),
        },
        Claim {
            text: "Interpolating `d~` beats `d_N` alone (§3.1): smaller T2 and P2 errors than `wyman-dn`",
            rows: Vec::new(),
        },
    ];
    for m in measured {
        let (single, wyman, dv, dn) = (
            m.get(MethodId::Single),
            m.get(MethodId::Wyman),
            m.get(MethodId::WymanDv),
            m.get(MethodId::WymanDn),
        );
        claims[0].rows.push((
            m.scene.clone(),
            less(t2(wyman), t2(single)),
            format!("T2 {}° vs {}°", value(t2(wyman), 2), value(t2(single), 2)),
        ));
        for (claim, other) in [(1, dv), (2, dn)] {
            claims[claim].rows.push((
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
    }
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Paper claims and our measured verdicts\n\n\
         Written by `refract claims` (regenerate with `cargo run --release -- claims`; do not edit by \
         hand). Errors against the exact reference (`transmission`, 1 spp, Mitsuba's interface rule) \
         at {res}², CPU backend, over refractor pixels without TIR at the first exit; T2 is the \
         direction leaving the first exit, P2 the first exit point (`docs/metrics.md`). Scenes: the \
         paper's 1,600-triangle sphere at IOR 1.5 and its cow at IOR 1.2, procedural environment, \
         default camera.\n",
        res = args.res
    );
    for note in notes {
        let _ = writeln!(md, "Note: {note}\n");
    }
    let _ = writeln!(
        md,
        "## Wyman 2005a, image-space refraction through two interfaces\n"
    );
    let _ = writeln!(
        md,
        "| claim | scene | measured | verdict |\n|---|---|---|---|"
    );
    claim_rows(&mut md, &claims);
    let _ = writeln!(
        md,
        "| Interactive rates: 122.9 fps for the 2-sided cow at 1024² on a GeForce 6800 (Table 1) | cow | {} | {} |",
        cow_fps.map_or_else(|| "–".to_owned(), |fps| format!("`wyman` on this machine's CPU backend: {fps:.1} fps (median of 20 colour-only frames)")),
        match cow_fps {
            Some(fps) if fps >= 30.0 => "**interactive** (≥ 30 fps) on the CPU; not the paper's hardware",
            Some(_) => "**below 30 fps** on this machine",
            None => "not measured (no cow mesh)",
        }
    );
    md
}
