//! `refract`: render, compare and benchmark real-time refraction techniques against an exact
//! reference. See `refract --help`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};
use refract_core::exit::TirPolicy;
use refract_eval::BUILTIN_SCENES;
use refract_lab::backends::{self, GpuPolicy};
use refract_lab::{bench, claims, compare, sweep, sweep_report};
use refract_scene::registry::ParamKind;
use refract_scene::{BackendId, MethodId, REGISTRY};

mod cleanup;
mod export;
mod info;
mod progress;
mod render;

use progress::Bars;

/// Measure how wrong and how fast real-time refraction techniques are, on your meshes.
///
/// With no command, compares every method of the registry (`refract methods`) on the CPU backend and the GPU backend (when an adapter exists) against the exact reference ray
/// tracer on the built-in scenes (`refract scenes`: glass, the distance-map rooms, the PVRR mirrors and spectacles) at 512², writes images, error maps,
/// metrics.json, report.md and index.html to out/, and prints a summary table.
#[derive(Debug, Parser)]
#[command(name = "refract", version, about, long_about)]
struct Cli {
    /// How the GPU reference finds closest hits: auto (the adapter's hardware ray queries where
    /// it has them, else the WGSL BVH traversal), on (ray queries; an adapter without them is
    /// an error), off (the WGSL traversal). Default: REFRACT_RAY_QUERY, else auto.
    #[arg(long, global = true, value_enum)]
    ray_query: Option<RayQueryArg>,
    #[command(subcommand)]
    command: Option<Command>,
}

/// `--ray-query`.
#[derive(Clone, Copy, Debug, ValueEnum)]
enum RayQueryArg {
    /// Ray queries where the adapter has them.
    Auto,
    /// Ray queries, or an error.
    On,
    /// The WGSL BVH traversal.
    Off,
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

/// Where the reference of a comparison is traced.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ReferenceBackendArg {
    /// The CPU tracer.
    Cpu,
    /// The GPU tracer (`refract-gpu/src/reference.wgsl`; docs/reference.md).
    Gpu,
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
    /// Built-in scene names (see `refract scenes`), .toml scene files or .gltf/.glb files.
    #[arg(required = true)]
    scenes: Vec<std::ffi::OsString>,
    /// Comma-separated method ids (`refract methods`); default: every method but the reference.
    #[arg(long, value_delimiter = ',')]
    methods: Option<Vec<MethodId>>,
    /// Comma-separated backends: cpu, gpu. Default: both, the GPU left out with a notice
    /// where no adapter opens; a list given here with gpu and no adapter fails the command.
    #[arg(long, value_delimiter = ',')]
    backends: Option<Vec<String>>,
    /// Square resolution in pixels.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=i64::from(refract_scene::MAX_FRAME_SIZE)))]
    res: u32,
    /// Reference samples per pixel.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1024))]
    spp: u32,
    /// Where the reference is traced: cpu (the CPU tracer) or gpu (the WGSL tracer;
    /// docs/reference.md).
    #[arg(long, value_enum, default_value = "cpu")]
    reference_backend: ReferenceBackendArg,
    /// Timed frames per method (median reported, after 1 warm-up frame).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=10000))]
    frames: u32,
    /// Second-interface TIR policy (two-interface methods).
    #[arg(long, value_enum, default_value = "clamp")]
    tir: TirArg,
    /// A method parameter, `NAME=VALUE`, for every selected method that has it (repeatable;
    /// `refract methods` lists them).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    params: Vec<String>,
    /// Comma-separated engines whose own renderers run beside the methods, in headless
    /// Chromium (docs/engines.md): threejs, babylon, gltf-viewer, or none. A listed engine that cannot run (no
    /// Node, Chromium or `npm ci --prefix engines`) fails the command.
    #[arg(long, value_delimiter = ',', default_value = "none")]
    engines: Vec<String>,
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

fn compare_options(args: CompareArgs) -> anyhow::Result<refract_lab::jobs::CompareOptions> {
    // The default list tolerates a missing adapter (with a notice); a list given does not, even
    // when it is the default's.
    let explicit = args.backends.is_some();
    let backends = backends::parse_backends(
        &args
            .backends
            .unwrap_or_else(|| vec!["cpu".to_owned(), "gpu".to_owned()]),
    )?;
    let ids = args
        .methods
        .unwrap_or_else(|| MethodId::approximations().collect());
    anyhow::ensure!(
        !ids.contains(&MethodId::Reference),
        "--methods: the reference is always rendered; list the methods to compare with it"
    );
    let assignments = args
        .params
        .iter()
        .map(|a| parse_param(a))
        .collect::<anyhow::Result<Vec<_>>>()?;
    Ok(refract_lab::jobs::CompareOptions {
        backends,
        gpu_policy: if explicit {
            GpuPolicy::Required
        } else {
            GpuPolicy::IfAvailable
        },
        scenes: args.scenes,
        methods: compare::method_params(&ids, args.tir.into(), &assignments, "--param")?,
        res: args.res,
        spp: args.spp,
        reference_backend: match args.reference_backend {
            ReferenceBackendArg::Cpu => BackendId::Trace,
            ReferenceBackendArg::Gpu => BackendId::Gpu,
        },
        warm_up: 1,
        frames: args.frames,
        engines: refract_lab::engines::parse_engines(&args.engines)?,
        engine_policy: GpuPolicy::Required,
        out: args.out,
    })
}

/// Runs a comparison with progress bars and prints its summary.
fn run_compare(options: &refract_lab::jobs::CompareOptions) -> anyhow::Result<()> {
    let records = compare::run(options, &Bars::new())?;
    print!("{}", compare::summary(&records, &options.out));
    Ok(())
}

/// `refract sweep`: the shard's job list with `--list`, else its jobs run.
fn run_sweep(args: &sweep::SweepArgs) -> anyhow::Result<()> {
    if args.list {
        for job in sweep::shard_jobs(args)? {
            println!("{:>5} {}", job.index, job.id);
        }
        return Ok(());
    }
    let done = sweep::run(args, &Bars::new())?;
    eprintln!(
        "done: {} finished, {} failed (recorded in {}), {} skipped as finished before",
        done.finished,
        done.failed,
        done.jobs_dir.display(),
        done.skipped
    );
    // A shard with nothing to show for it (every job it ran failed, none finished before)
    // fails, so that `sweep && report` stops; jobs that failed beside finished ones do not.
    anyhow::ensure!(
        done.failed == 0 || done.finished + done.skipped > 0,
        "none of the {} jobs run finished: every one failed (their errors are in {})",
        done.failed,
        done.jobs_dir.display()
    );
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
    // First, before code compiled for the build's instruction set runs (x86-64-v3 by default):
    // an older CPU gets a message instead of an illegal instruction.
    refract_cpu::instruction_set::exit_if_unsupported();
    run()
}

/// The parsed command line. Every command takes negative numbers as values, so that `--res
/// -16` is refused by the option's range ("-16 is not in 1..=16384") rather than read as an
/// unknown option `-1`.
fn parse_command_line() -> Cli {
    use clap::{CommandFactory, FromArgMatches};
    let command = Cli::command()
        .allow_negative_numbers(true)
        .mut_subcommands(|sub| sub.allow_negative_numbers(true));
    let matches = command.get_matches();
    Cli::from_arg_matches(&matches).unwrap_or_else(|err| err.exit())
}

/// The command line's command.
#[inline(never)]
fn run() -> ExitCode {
    let cli = parse_command_line();
    if let Some(policy) = cli.ray_query {
        refract_gpu::RayQueryPolicy::choose(match policy {
            RayQueryArg::Auto => refract_gpu::RayQueryPolicy::Auto,
            RayQueryArg::On => refract_gpu::RayQueryPolicy::On,
            RayQueryArg::Off => refract_gpu::RayQueryPolicy::Off,
        });
    }
    cleanup::install_signal_handler();
    let result = match cli.command {
        None => compare::default_options()
            .map_err(anyhow::Error::from)
            .and_then(|options| run_compare(&options)),
        Some(Command::Compare(args)) => compare_options(args).and_then(|o| run_compare(&o)),
        Some(Command::Render(args)) => render::run(&args),
        Some(Command::Bench(args)) => bench::run(&args, &Bars::new())
            .map(|md| println!("\n{md}"))
            .map_err(Into::into),
        Some(Command::Sweep(args)) => run_sweep(&args),
        Some(Command::Report(args)) => sweep_report::run(&args)
            .map(|r| {
                if !r.missing.is_empty() {
                    let shown: Vec<&str> = r.missing.iter().take(4).map(String::as_str).collect();
                    eprintln!(
                        "warning: {} images the results name are missing ({}{}); the page marks them",
                        r.missing.len(),
                        shown.join(", "),
                        if r.missing.len() > shown.len() { ", ..." } else { "" }
                    );
                }
                println!(
                    "{} jobs ({} failed) -> {}/index.html, report.md, results.json, {} plots",
                    r.jobs,
                    r.failed,
                    r.out.display(),
                    r.plots
                );
            })
            .map_err(Into::into),
        Some(Command::View(args)) => refract_view::run(args),
        Some(Command::Scenes) => {
            for (name, line, _) in BUILTIN_SCENES {
                println!("{name:<8} {line}");
            }
            println!("\nOr pass a .toml scene file or a .gltf/.glb file; see docs/scenes.md.");
            Ok(())
        }
        Some(Command::Methods) => {
            print_methods();
            Ok(())
        }
        Some(Command::Info(args)) => info::run(&args),
        Some(Command::Export(args)) => export::run(&args),
        Some(Command::Claims(args)) => claims::run(&args, &Bars::new())
            .map(|md| println!("{md}"))
            .map_err(Into::into),
    };
    cleanup::yield_to_interrupt();
    match result {
        Ok(()) => {
            refract_lab::output_dirs::keep_created();
            ExitCode::SUCCESS
        }
        Err(err) => {
            // Nothing half-made: directories this run created go with the failure.
            refract_lab::output_dirs::remove_created();
            eprintln!("error: {err:#}");
            ExitCode::FAILURE
        }
    }
}
