//! `refract`: render, compare and benchmark real-time refraction techniques against an exact
//! reference. See `refract --help`.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod info;

/// Measure how wrong and how fast real-time refraction techniques are, on your meshes.
///
/// Implemented so far: the refraction math (refract-core) and the geometry precompute
/// (refract-geometry: meshes, BVH, d_N, procedural shapes and lenses). Rendering, comparison
/// against the reference tracer and benchmarks arrive with the backends.
#[derive(Debug, Parser)]
#[command(name = "refract", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Load a mesh (.obj, .gltf, .glb or builtin:NAME) and print its facts and d_N statistics.
    Info(info::InfoArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        None => {
            print_overview();
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

/// What `refract` with no arguments prints until the comparison job lands.
fn print_overview() {
    println!(
        "refract {version}: how wrong, and how fast, is each real-time refraction technique?

The default job (compare every method against the reference tracer on the built-in scenes)
needs the CPU/GPU backends and the reference tracer, which are not implemented yet.
What works today:

  refract info builtin:sphere          mesh facts, BVH and d_N precompute of a built-in shape
  refract info path/to/mesh.obj        ... of your own mesh (.obj, .gltf, .glb)
  cargo test --workspace               property tests of the refraction math and geometry

Built-in shapes: {builtins}
Run `refract --help` for every option.",
        version = env!("CARGO_PKG_VERSION"),
        builtins = refract_geometry::builtin::NAMES.join(", "),
    );
}
