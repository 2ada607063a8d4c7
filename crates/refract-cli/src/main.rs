//! `refract`: render, compare and benchmark real-time refraction techniques against an exact
//! reference. See `refract --help`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};
use refract_core::Method;
use refract_core::exit::TirPolicy;

mod bench;
mod compare;
mod images;
mod info;
mod metrics;
mod render;
mod report;
mod scene_file;
mod timing;

/// Measure how wrong and how fast real-time refraction techniques are, on your meshes.
///
/// With no command, compares every implemented method (single, wyman, wyman-dv, wyman-dn) on the
/// CPU backend and the GPU backend (when an adapter exists) against the exact reference ray
/// tracer on the built-in scenes (sphere, torus, lens) at 512², writes images, error maps,
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
    /// Comma-separated methods: single, wyman, wyman-dv, wyman-dn.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "single,wyman,wyman-dv,wyman-dn"
    )]
    methods: Vec<Method>,
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
    /// Second-interface TIR policy.
    #[arg(long, value_enum, default_value = "clamp")]
    tir: TirArg,
    /// Output directory.
    #[arg(long, default_value = "out")]
    out: PathBuf,
}

fn compare_options(args: CompareArgs) -> anyhow::Result<compare::CompareOptions> {
    let backends = compare::Backend::parse_list(&args.backends)?;
    // The default list tolerates a missing adapter (with a notice); an explicit list does not.
    let explicit = args.backends != ["cpu", "gpu"];
    Ok(compare::CompareOptions {
        backends,
        gpu_policy: if explicit {
            compare::GpuPolicy::Required
        } else {
            compare::GpuPolicy::IfAvailable
        },
        scenes: args.scenes,
        methods: args.methods,
        res: args.res,
        spp: args.spp,
        frames: args.frames,
        out: args.out,
        tir_policy: args.tir.into(),
    })
}

fn default_job() -> anyhow::Result<()> {
    let options = compare::CompareOptions {
        backends: vec![compare::Backend::Cpu, compare::Backend::Gpu],
        gpu_policy: compare::GpuPolicy::IfAvailable,
        scenes: scene_file::BUILTIN_SCENES
            .iter()
            .map(|s| s.0.to_owned())
            .collect(),
        methods: Method::ALL.to_vec(),
        res: 512,
        spp: 1,
        frames: 20,
        out: PathBuf::from("out"),
        tir_policy: TirPolicy::ClampToCritical,
    };
    let records = compare::run(&options)?;
    compare::print_summary(&records, &options.out);
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        None => default_job(),
        Some(Command::Compare(args)) => compare_options(args).and_then(|options| {
            let records = compare::run(&options)?;
            compare::print_summary(&records, &options.out);
            Ok(())
        }),
        Some(Command::Render(args)) => render::run(&args),
        Some(Command::Bench(args)) => bench::run(&args),
        Some(Command::Scenes) => {
            for (name, line, _) in scene_file::BUILTIN_SCENES {
                println!("{name:<8} {line}");
            }
            println!("\nOr pass a .toml scene file; see docs/scenes.md.");
            Ok(())
        }
        Some(Command::Info(args)) => info::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            ExitCode::FAILURE
        }
    }
}
