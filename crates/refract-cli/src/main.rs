//! `refract`: render, compare and benchmark real-time refraction techniques against an exact
//! reference. See `refract --help`.

use std::process::ExitCode;

use clap::Parser;

/// Measure how wrong and how fast real-time refraction techniques are, on your meshes.
///
/// Implemented so far: the refraction math (refract-core). Rendering, comparison against the
/// reference tracer and benchmarks arrive with the geometry, the backends and the tracer.
#[derive(Debug, Parser)]
#[command(name = "refract", version, about, long_about)]
struct Cli {}

fn main() -> ExitCode {
    let _cli = Cli::parse();
    println!(
        "refract {}: how wrong, and how fast, is each real-time refraction technique?

The default job (compare every method against the reference tracer on the built-in scenes)
needs the backends and the reference tracer, which are not implemented yet. What works today:

  cargo test --workspace     property tests of the refraction math (refract-core)

Run `refract --help` for the options.",
        env!("CARGO_PKG_VERSION")
    );
    ExitCode::SUCCESS
}
