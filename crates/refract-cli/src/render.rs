//! `refract render`: one scene, one method (or the reference), to `.png` or `.exr`.

use refract_eval::FrameFiles;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, bail};
use refract_core::CameraDesc;
use refract_eval::load_scene;
use refract_lab::render::{FrameRequest, Renders};
use refract_scene::{BackendId, Frame, FrameOutputs, MethodId, MethodParams, TraceMode};

use crate::TirArg;

/// The reference tracer's mode.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum TraceArg {
    /// Only the refracted path (the reference for image-space methods).
    Transmission,
    /// Fresnel-split reflected and refracted branches.
    Full,
}

/// Arguments of `refract render`.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// A built-in scene (see `refract scenes`), a .toml scene file or a .gltf/.glb file.
    pub scene: std::ffi::OsString,
    /// A method of the registry (`refract methods`), or `reference`.
    #[arg(long, default_value = "wyman")]
    pub method: String,
    /// Backend: `cpu` or `gpu` (wgpu; fails with a clear error when no adapter exists).
    #[arg(long, default_value = "cpu")]
    pub backend: String,
    /// Resolution, `WxH` or `N` for N×N.
    #[arg(long, default_value = "512x512")]
    pub res: String,
    /// Samples per pixel of the reference.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=i64::from(refract_scene::MAX_SPP)))]
    pub spp: u32,
    /// Reference mode: `transmission` (refracted path only, TIR reflects) or `full` (Fresnel
    /// splitting at every interface).
    #[arg(long, value_enum, default_value = "transmission")]
    pub trace: TraceArg,
    /// Reference depth limit (refractor interactions per path).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub depth: u32,
    /// Override the scene's index of refraction.
    #[arg(long, allow_negative_numbers = true)]
    pub ior: Option<f32>,
    /// Second-interface TIR policy (two-interface methods).
    #[arg(long, value_enum, default_value = "clamp")]
    pub tir: TirArg,
    /// A method parameter, `NAME=VALUE` (repeatable; `refract methods` lists them).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    pub params: Vec<String>,
    /// Output file: `.png` (sRGB, tonemapped) or `.exr` (linear, with AOV channels).
    #[arg(long)]
    pub out: PathBuf,
}

fn parse_res(res: &str) -> anyhow::Result<(u32, u32)> {
    let parse = |s: &str| {
        s.trim()
            .parse::<u32>()
            .ok()
            .filter(|&v| (1..=refract_scene::MAX_FRAME_SIZE).contains(&v))
    };
    let parsed = match res.split_once(['x', 'X']) {
        Some((w, h)) => parse(w).zip(parse(h)),
        None => parse(res).map(|n| (n, n)),
    };
    parsed.with_context(|| {
        let max = refract_scene::MAX_FRAME_SIZE;
        format!("--res {res}: expected WxH or N with sizes from 1 to {max}")
    })
}

/// The method of `--method`, with `--tir`, `--spp`, `--trace`, `--depth` and every `--param`
/// applied.
fn method_params(args: &RenderArgs) -> anyhow::Result<MethodParams> {
    let id: MethodId = args
        .method
        .parse()
        .map_err(|e| anyhow::anyhow!("--method: {e}"))?;
    let mut params = MethodParams::defaults(id).with_tir_policy(args.tir.into());
    if let MethodParams::Reference(settings) = &mut params {
        settings.mode = match args.trace {
            TraceArg::Transmission => TraceMode::Transmission,
            TraceArg::Full => TraceMode::Full,
        };
        settings.max_depth = args.depth;
        settings.spp = args.spp;
    }
    let assignments = args
        .params
        .iter()
        .map(|a| crate::parse_param(a))
        .collect::<anyhow::Result<Vec<_>>>()?;
    params.set_all(assignments.iter().copied(), "--param")?;
    Ok(params)
}

/// Runs `refract render`.
pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let extension = args
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(extension.as_deref(), Some("png" | "exr")) {
        bail!("--out {}: expected a .png or .exr file", args.out.display());
    }
    let backend = match args.backend.as_str() {
        "cpu" => BackendId::Cpu,
        "gpu" => BackendId::Gpu,
        other => bail!("--backend {other}: expected cpu or gpu"),
    };
    let (width, height) = parse_res(&args.res)?;
    let method = method_params(args)?;
    let loaded = load_scene(&args.scene)?;
    for warning in &loaded.warnings {
        eprintln!("warning: {warning}");
    }
    let mut scene = loaded.scene;
    if let Some(ior) = args.ior {
        scene.refractor.set_ior(ior).context("--ior")?;
    }
    let camera = CameraDesc {
        width,
        height,
        ..scene.camera
    };
    // A PNG holds the colour only: the AOV layers (most of a frame's memory) are not computed.
    let outputs = match extension.as_deref() {
        Some("exr") => FrameOutputs::ColorAndAovs,
        _ => FrameOutputs::Color,
    };
    let mut renders = Renders::new(Arc::new(scene));
    let start = Instant::now();
    let mut frame = Frame::default();
    renders.render(
        &FrameRequest {
            method: &method,
            backend,
            camera,
            outputs,
        },
        &mut frame,
    )?;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    let backend_id = match (method.id(), backend) {
        (MethodId::Reference, BackendId::Cpu) => BackendId::Trace,
        (_, backend) => backend,
    };
    let description = refract_lab::provenance::frame_description(
        &renders.scene().name,
        &method,
        backend_id.id(),
        renders.adapter(),
        (width, height),
    );
    match extension.as_deref() {
        Some("exr") => frame.write_exr_described(&args.out, &description)?,
        _ => frame.write_png_described(&args.out, &description)?,
    }
    println!(
        "{} {} {width}x{height} in {ms:.1} ms -> {}",
        renders.scene().name,
        args.method,
        args.out.display()
    );
    if let Some(adapter) = renders.adapter() {
        // As compare and bench say it: which GPU the frame came from.
        eprintln!("GPU: {adapter}");
    }
    Ok(())
}
