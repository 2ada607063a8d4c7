//! `refract render`: one scene, one method (or the reference), to `.png` or `.exr`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};
use glam::Vec3;
use refract_core::{Camera, CameraDesc, Method};
use refract_cpu::{MethodParams, PreparedRefractor, render_method};
use refract_trace::{Frame, PixelAov, Refractor, TraceMode, TraceSettings, render};

use crate::TirArg;

/// The reference tracer's mode.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum TraceArg {
    /// Only the refracted path (the reference for image-space methods).
    Transmission,
    /// Fresnel-split reflected and refracted branches.
    Full,
}
use crate::scene_file::load_scene;

/// Arguments of `refract render`.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// A built-in scene (see `refract scenes`) or a .toml scene file.
    pub scene: String,
    /// `reference`, `single`, `wyman`, `wyman-dv` or `wyman-dn`.
    #[arg(long, default_value = "wyman")]
    pub method: String,
    /// Backend: `cpu` or `gpu` (wgpu; fails with a clear error when no adapter exists).
    #[arg(long, default_value = "cpu")]
    pub backend: String,
    /// Resolution, `WxH` or `N` for N×N.
    #[arg(long, default_value = "512x512")]
    pub res: String,
    /// Samples per pixel of the reference.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
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
    /// Second-interface TIR policy.
    #[arg(long, value_enum, default_value = "clamp")]
    pub tir: TirArg,
    /// Output file: `.png` (sRGB, tonemapped) or `.exr` (linear, with AOV channels).
    #[arg(long)]
    pub out: PathBuf,
}

fn parse_res(res: &str) -> anyhow::Result<(u32, u32)> {
    let parse = |s: &str| {
        s.trim()
            .parse::<u32>()
            .ok()
            .filter(|&v| (1..=16384).contains(&v))
    };
    let parsed = match res.split_once(['x', 'X']) {
        Some((w, h)) => parse(w).zip(parse(h)),
        None => parse(res).map(|n| (n, n)),
    };
    parsed.with_context(|| format!("--res {res}: expected WxH or N with sizes from 1 to 16384"))
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
    if !matches!(args.backend.as_str(), "cpu" | "gpu") {
        bail!("--backend {}: expected cpu or gpu", args.backend);
    }
    let (width, height) = parse_res(&args.res)?;
    let mut loaded = load_scene(&args.scene)?;
    for warning in &loaded.warnings {
        eprintln!("warning: {warning}");
    }
    if let Some(ior) = args.ior {
        let mesh = loaded.scene.refractor.mesh.clone();
        loaded.scene.refractor = Refractor::new(mesh, ior).context("--ior")?;
    }
    let camera = Camera::new(CameraDesc {
        width,
        height,
        ..loaded.camera
    })?;
    let start = Instant::now();
    let frame = if args.method == "reference" {
        render(
            &loaded.scene,
            &camera,
            &TraceSettings {
                mode: match args.trace {
                    TraceArg::Transmission => TraceMode::Transmission,
                    TraceArg::Full => TraceMode::Full,
                },
                max_depth: args.depth,
                spp: args.spp,
                ..TraceSettings::default()
            },
        )
    } else {
        let method: Method = args
            .method
            .parse()
            .map_err(|e| anyhow::anyhow!("--method: {e} (or reference)"))?;
        let params = MethodParams {
            method,
            ior: loaded.scene.refractor.ior(),
            tir_policy: args.tir.into(),
        };
        let result = if args.backend == "gpu" {
            let context = refract_gpu::GpuContext::new()?;
            let renderer = refract_gpu::GpuRenderer::new(&context)?;
            let mesh = &loaded.scene.refractor.mesh;
            let scene =
                refract_gpu::GpuScene::new(&context, mesh, &loaded.d_n, &loaded.scene.environment);
            refract_gpu::render_method(&context, &renderer, &scene, &camera, &params)?.0
        } else {
            let prepared = PreparedRefractor {
                mesh: &loaded.scene.refractor.mesh,
                d_n: &loaded.d_n,
            };
            render_method(&prepared, &loaded.scene.environment, &camera, &params)?
        };
        let aov = result
            .aov
            .iter()
            .map(|a| PixelAov {
                p2: a.p2,
                n2: a.n2,
                t2: if a.covered { a.t2 } else { Vec3::NAN },
                tir: a.tir,
                ..PixelAov::EMPTY
            })
            .collect();
        Frame {
            width,
            height,
            radiance: result.color,
            aov,
            rays: 0,
        }
    };
    let ms = start.elapsed().as_secs_f64() * 1e3;
    match extension.as_deref() {
        Some("exr") => frame.write_exr(&args.out)?,
        _ => frame.write_png(&args.out)?,
    }
    println!(
        "{} {} {width}x{height} in {ms:.1} ms -> {}",
        loaded.name,
        args.method,
        args.out.display()
    );
    Ok(())
}
