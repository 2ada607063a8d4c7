//! `refract`: render, compare and benchmark real-time refraction techniques against an exact
//! reference. See `refract --help`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};
use refract_core::exit::TirPolicy;
use refract_eval::BUILTIN_SCENES;
use refract_scene::registry::ParamKind;
use refract_scene::{MethodId, MethodParams, REGISTRY};

mod backends;
mod bench;
mod claims;
mod cleanup;
mod compare;
mod data_scenes;
mod export;
mod info;
mod memory;
mod render;
mod report;
mod sweep;
mod sweep_report;
mod timing;

/// Measure how wrong and how fast real-time refraction techniques are, on your meshes.
///
/// With no command, compares every method of the registry (`refract methods`) on the CPU backend and the GPU backend (when an adapter exists) against the exact reference ray
/// tracer on the built-in scenes (`refract scenes`: glass, the distance-map rooms, the PVRR mirrors and spectacles) at 512², writes images, error maps,
/// metrics.json, report.md and index.html to out/, and prints a summary table.
#[derive(Debug, Parser)]
#[command(name = "refract", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Compare methods against the reference on one or more scenes.
    Compare(CompareArgs),
    /// Render one scene with one method (or the reference) to .png or .exr.
    Render(render::RenderArgs),
    /// Reproduce Wyman 2005a Table 1: frame rates per model, method and backend, reference times.
    Bench(bench::BenchArgs),
    /// List the built-in scenes.
    Scenes,
    /// List the methods: id, paper and section, parameters (defaults, ranges), AOVs, backends.
    Methods,
    /// Measure the seed papers' claims on named scenes and write docs/claims.md with verdicts.
    Claims(claims::ClaimsArgs),
    /// Run the jobs of a sweep file (the product of its axes), or every N-th with --shard I/N.
    Sweep(sweep::SweepArgs),
    /// Merge sweep (shard) directories into one report: results.json, plots, index.html.
    Report(sweep_report::ReportArgs),
    /// Open a window: fly around a scene and switch methods, IOR, TIR policy and backend live.
    View(refract_view::ViewArgs),
    /// Write a scene as refract renders it (OBJ meshes with normals, scene.json) for other renderers.
    Export(export::ExportArgs),
    /// List GPU adapters; with a mesh (.obj, .gltf, .glb or builtin:NAME), print its facts and d_N.
    Info(info::InfoArgs),
}

/// Second-interface total-internal-reflection policy.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum TirArg {
    /// Clamp to the critical angle: leave tangent to the surface (Wyman 2005a §3.3).
    Clamp,
    /// Reflect once and look the reflected direction up.
    Reflect,
    /// Absorb: black.
    Black,
}

impl From<TirArg> for TirPolicy {
    fn from(t: TirArg) -> Self {
        match t {
            TirArg::Clamp => TirPolicy::ClampToCritical,
            TirArg::Reflect => TirPolicy::ReflectOnce,
            TirArg::Black => TirPolicy::Black,
        }
    }
}

#[derive(Debug, Args)]
struct CompareArgs {
    /// Built-in scene names (see `refract scenes`) or .toml scene files.
    #[arg(required = true)]
    scenes: Vec<String>,
    /// Comma-separated method ids (`refract methods`); default: every method but the reference.
    #[arg(long, value_delimiter = ',')]
    methods: Option<Vec<MethodId>>,
    /// Comma-separated backends: cpu, gpu. With gpu and no adapter, the command fails.
    #[arg(long, value_delimiter = ',', default_value = "cpu,gpu")]
    backends: Vec<String>,
    /// Square resolution in pixels.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=8192))]
    res: u32,
    /// Reference samples per pixel.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1024))]
    spp: u32,
    /// Timed frames per method (median reported, after 2 warm-up frames).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=10000))]
    frames: u32,
    /// Second-interface TIR policy (two-interface methods).
    #[arg(long, value_enum, default_value = "clamp")]
    tir: TirArg,
    /// A method parameter, `NAME=VALUE`, for every selected method that has it (repeatable;
    /// `refract methods` lists them).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    params: Vec<String>,
    /// Output directory.
    #[arg(long, default_value = "out")]
    out: PathBuf,
}

/// Splits `NAME=VALUE`.
pub fn parse_param(assignment: &str) -> anyhow::Result<(&str, &str)> {
    assignment
        .split_once('=')
        .filter(|(name, _)| !name.is_empty())
        .ok_or_else(|| anyhow::anyhow!("--param {assignment}: expected NAME=VALUE"))
}

/// The parameters of `ids` with `tir` and every `--param` applied to the methods that have it;
/// a parameter no selected method has is an error.
fn method_params(
    ids: &[MethodId],
    tir: TirPolicy,
    assignments: &[String],
) -> anyhow::Result<Vec<MethodParams>> {
    let mut methods: Vec<MethodParams> = ids
        .iter()
        .map(|&id| MethodParams::defaults(id).with_tir_policy(tir))
        .collect();
    for assignment in assignments {
        let (name, value) = parse_param(assignment)?;
        let mut used = false;
        for method in &mut methods {
            if method.get(name).is_some() {
                method.set(name, value, "--param")?;
                used = true;
            }
        }
        anyhow::ensure!(
            used,
            "--param {assignment}: none of the selected methods has a parameter `{name}` (see `refract methods`)"
        );
    }
    Ok(methods)
}

fn compare_options(args: CompareArgs) -> anyhow::Result<compare::CompareOptions> {
    let backends = backends::parse_backends(&args.backends)?;
    // The default list tolerates a missing adapter (with a notice); an explicit list does not.
    let explicit = args.backends != ["cpu", "gpu"];
    let ids = args
        .methods
        .unwrap_or_else(|| MethodId::approximations().collect());
    anyhow::ensure!(
        !ids.contains(&MethodId::Reference),
        "--methods: the reference is always rendered; list the methods to compare with it"
    );
    Ok(compare::CompareOptions {
        backends,
        gpu_policy: if explicit {
            backends::GpuPolicy::Required
        } else {
            backends::GpuPolicy::IfAvailable
        },
        scenes: args.scenes,
        methods: method_params(&ids, args.tir.into(), &args.params)?,
        res: args.res,
        spp: args.spp,
        frames: args.frames,
        out: args.out,
    })
}

fn default_job() -> anyhow::Result<()> {
    let ids: Vec<MethodId> = MethodId::approximations().collect();
    let options = compare::CompareOptions {
        backends: vec![refract_scene::BackendId::Cpu, refract_scene::BackendId::Gpu],
        gpu_policy: backends::GpuPolicy::IfAvailable,
        scenes: BUILTIN_SCENES.iter().map(|s| s.0.to_owned()).collect(),
        methods: method_params(&ids, TirPolicy::ClampToCritical, &[])?,
        res: 512,
        spp: 1,
        frames: 5,
        out: PathBuf::from("out"),
    };
    let records = compare::run(&options)?;
    compare::print_summary(&records, &options.out);
    Ok(())
}

/// `refract methods`: the registry.
fn print_methods() {
    for m in &REGISTRY {
        let backends: Vec<&str> = m.backends.iter().map(|b| b.id()).collect();
        let aovs: Vec<&str> = m.aovs.iter().map(|a| a.name()).collect();
        println!("{:<10} {} {}: {}", m.name, m.paper, m.section, m.summary);
        println!(
            "{:<10} backends: {}; AOVs: {}",
            "",
            backends.join(", "),
            aovs.join(" ")
        );
        for p in m.params {
            let range = match p.kind {
                ParamKind::Choice(values) => values.join(" | "),
                ParamKind::Integer { min, max } => format!("{min}..={max}"),
            };
            println!(
                "{:<10}   --param {}=<{range}> (default {}): {}",
                "", p.name, p.default, p.doc
            );
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    cleanup::install_signal_handler();
    let result = match cli.command {
        None => default_job(),
        Some(Command::Compare(args)) => compare_options(args).and_then(|options| {
            let records = compare::run(&options)?;
            compare::print_summary(&records, &options.out);
            Ok(())
        }),
        Some(Command::Render(args)) => render::run(&args),
        Some(Command::Bench(args)) => bench::run(&args),
        Some(Command::Sweep(args)) => sweep::run(&args),
        Some(Command::Report(args)) => sweep_report::run(&args),
        Some(Command::View(args)) => refract_view::run(args),
        Some(Command::Scenes) => {
            for (name, line, _) in BUILTIN_SCENES {
                println!("{name:<8} {line}");
            }
            println!("\nOr pass a .toml scene file; see docs/scenes.md.");
            Ok(())
        }
        Some(Command::Methods) => {
            print_methods();
            Ok(())
        }
        Some(Command::Info(args)) => info::run(&args),
        Some(Command::Export(args)) => export::run(&args),
        Some(Command::Claims(args)) => claims::run(&args),
    };
    match result {
        Ok(()) => {
            cleanup::keep_created();
            ExitCode::SUCCESS
        }
        Err(err) => {
            // Nothing half-made: directories this run created go with the failure.
            cleanup::remove_created();
            eprintln!("error: {err:#}");
            ExitCode::FAILURE
        }
    }
}
