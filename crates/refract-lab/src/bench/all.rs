//! `refract bench --table all`: every table in turn on every backend present, written as one
//! Markdown file and one JSON file that say where and when they were measured (the CPU, the GPU
//! adapter and its driver, the commit, the date), and, with `--update`, spliced into a document
//! between two marker lines. `docs/performance.md`'s tables are this file.

use std::fmt::Write as _;
use std::path::Path;
use std::time::{Instant, SystemTime};

use refract_scene::BackendId;
use serde::Serialize;

use super::{BenchArgs, Table, TableOutput, run_table, write, write_output};
use crate::backends;
use crate::error::Context;
use crate::progress::{Note, Progress};

/// The line before the tables in a document `--update` rewrites.
pub const BEGIN_MARKER: &str = "<!-- refract bench --table all: begin -->";
/// The line after them.
pub const END_MARKER: &str = "<!-- refract bench --table all: end -->";

/// Where and when the tables were measured, read from the system, never typed.
#[derive(Clone, Debug, Serialize)]
struct Provenance {
    /// UTC, RFC 3339, when the run started.
    date: String,
    /// `git rev-parse --short=12 HEAD` of the checkout the command ran in, with
    /// `(uncommitted changes)` when tracked files differ from it.
    commit: String,
    /// The CPU model and the threads the CPU backend uses.
    cpu: String,
    /// The GPU adapter the GPU rows ran on: name, graphics API, device type; `None` without one
    /// (or without `gpu` in `--backends`).
    gpu: Option<String>,
    /// The adapter's driver and its version.
    gpu_driver: Option<String>,
    /// The command's settings.
    command: String,
    /// Seconds the whole run took.
    seconds: f64,
}

/// The JSON file: the provenance and every table's rows by table name.
#[derive(Serialize)]
struct AllTables<'a> {
    provenance: &'a Provenance,
    tables: serde_json::Map<String, serde_json::Value>,
}

/// Runs every table of [`Table::EACH`], writes their own files, `bench-all.md` and
/// `bench-all.json`, and with `--update` rewrites that file's tables; returns the Markdown.
pub(super) fn run(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<String> {
    // Check the document before measuring for minutes.
    let document = match &args.update {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("--update {}: cannot read it", path.display()))?;
            splice(&text, "", path)?;
            Some((path, text))
        }
        None => None,
    };
    let start = Instant::now();
    let date = humantime::format_rfc3339_seconds(SystemTime::now()).to_string();
    let (gpu, gpu_driver) = gpu_adapter(args, progress)?;
    let mut outputs = Vec::new();
    for table in Table::EACH {
        progress.note(Note::Info(format!("table {}", table.name())));
        outputs.push((table, run_table(table, args, progress)?));
    }
    let provenance = Provenance {
        date,
        commit: crate::provenance::checkout_commit(),
        cpu: crate::timing::cpu_description(),
        gpu,
        gpu_driver,
        command: command_line(args),
        seconds: start.elapsed().as_secs_f64(),
    };
    let body = tables_markdown(&provenance, &outputs);
    let all = TableOutput::new(
        format!("# refract's performance tables\n\n{body}"),
        &AllTables {
            provenance: &provenance,
            tables: outputs
                .iter()
                .map(|(table, output)| (table.name().to_owned(), output.rows.clone()))
                .collect(),
        },
    )?;
    write_output(&args.out, Table::All.file_stem(), &all)?;
    if let Some((path, text)) = document {
        write(path, &splice(&text, &body, path)?)?;
        progress.note(Note::Info(format!("updated {}", path.display())));
    }
    Ok(all.markdown)
}

/// The adapter `--backends gpu` would run on, as (name, API and type; driver), opened once to
/// read it; `(None, None)` without `gpu` in `--backends` or without an adapter.
fn gpu_adapter(
    args: &BenchArgs,
    progress: &dyn Progress,
) -> crate::Result<(Option<String>, Option<String>)> {
    if !backends::parse_backends(&args.backends)?.contains(&BackendId::Gpu) {
        return Ok((None, None));
    }
    match refract_gpu::GpuContext::new() {
        Ok(context) => {
            let info = &context.info;
            Ok((
                Some(format!(
                    "{} ({:?}, {:?})",
                    info.name, info.backend, info.device_type
                )),
                Some(
                    format!("{} {}", info.driver, info.driver_info)
                        .trim()
                        .to_owned(),
                ),
            ))
        }
        Err(err) => {
            progress.note(Note::Skipped(format!("{err}; the tables have no GPU rows")));
            Ok((None, None))
        }
    }
}

/// The settings that shape the numbers, as a command line.
fn command_line(args: &BenchArgs) -> String {
    let backends = args.backends.join(",");
    if args.quick {
        format!("refract bench --table all --backends {backends} --quick")
    } else {
        format!(
            "refract bench --table all --backends {backends} --frames {}",
            args.frames
        )
    }
}

/// The provenance paragraph and every table, each under a `## ` heading (the tables' own `# `
/// titles, one level down).
fn tables_markdown(provenance: &Provenance, outputs: &[(Table, TableOutput)]) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "Measured by `{}` ({:.0} s) at commit {} on {}.\n\n- CPU: {}\n- GPU: {}\n- GPU driver: {}\n- compiler: {}\n- build: {}\n",
        provenance.command,
        provenance.seconds,
        provenance.commit,
        provenance.date,
        provenance.cpu,
        provenance.gpu.as_deref().unwrap_or("none"),
        provenance.gpu_driver.as_deref().unwrap_or("–"),
        crate::provenance::rustc(),
        crate::provenance::build(),
    );
    for (_, output) in outputs {
        let text = output.markdown.trim_end();
        let text = text
            .strip_prefix("# ")
            .map_or_else(|| text.to_owned(), |rest| format!("## {rest}"));
        let _ = writeln!(md, "{text}\n");
    }
    md
}

/// `text` with the lines between [`BEGIN_MARKER`] and [`END_MARKER`] replaced by `body`; the
/// markers and everything outside them are kept byte for byte. An error names `path` when a
/// marker is missing, repeated or out of order.
fn splice(text: &str, body: &str, path: &Path) -> crate::Result<String> {
    let line_at = |marker: &str| {
        let mut found = text
            .match_indices(marker)
            .filter(|(i, _)| *i == 0 || text.as_bytes()[i - 1] == b'\n');
        match (found.next(), found.next()) {
            (Some((i, _)), None) => Ok(i),
            (None, _) => crate::bail!(
                "--update {}: no line `{marker}`; the tables go between that line and `{END_MARKER}`",
                path.display()
            ),
            (Some(_), Some(_)) => crate::bail!(
                "--update {}: `{marker}` appears more than once; expected one",
                path.display()
            ),
        }
    };
    let (begin, end) = (line_at(BEGIN_MARKER)?, line_at(END_MARKER)?);
    crate::ensure!(
        begin < end,
        "--update {}: `{END_MARKER}` comes before `{BEGIN_MARKER}`",
        path.display()
    );
    let after_begin = begin + BEGIN_MARKER.len();
    Ok(format!(
        "{}\n\n{}\n{}",
        &text[..after_begin],
        body.trim_end(),
        &text[end..]
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc(middle: &str) -> String {
        format!("# Title\n\nintro\n\n{BEGIN_MARKER}\n{middle}{END_MARKER}\n\n## After\n\nkept\n")
    }

    /// The region is replaced and everything else kept; a second splice of the same body
    /// changes nothing.
    #[test]
    fn splicing_replaces_only_the_marked_region() {
        let path = Path::new("perf.md");
        let once = splice(&doc("old table\nold row\n"), "## T\n\n| a |\n", path).expect("splice");
        assert_eq!(
            once,
            format!(
                "# Title\n\nintro\n\n{BEGIN_MARKER}\n\n## T\n\n| a |\n{END_MARKER}\n\n## After\n\nkept\n"
            )
        );
        assert_eq!(splice(&once, "## T\n\n| a |\n", path).expect("again"), once);
    }

    /// Missing, repeated or swapped markers are refused with the file's name, before anything is
    /// measured.
    #[test]
    fn a_document_without_its_markers_is_refused() {
        let path = Path::new("docs/perf.md");
        let err = splice("# no markers\n", "x", path).expect_err("missing");
        assert!(
            err.to_string().contains("docs/perf.md") && err.to_string().contains(BEGIN_MARKER),
            "{err}"
        );
        for (text, expected) in [
            (
                format!("{BEGIN_MARKER}\n{BEGIN_MARKER}\n{END_MARKER}\n"),
                "more than once",
            ),
            (format!("{END_MARKER}\n{BEGIN_MARKER}\n"), "comes before"),
        ] {
            let err = splice(&text, "x", path).expect_err(expected).to_string();
            assert!(err.contains(expected), "{err}");
        }
        // A marker quoted inside a line is not a marker line.
        let quoted = format!("see `{BEGIN_MARKER}`\n{END_MARKER}\n");
        assert!(splice(&quoted, "x", path).is_err());
    }

    /// `docs/performance.md` holds the markers, so the documented command can rewrite it.
    #[test]
    fn the_performance_document_can_be_updated() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/performance.md");
        let text = std::fs::read_to_string(&path).expect("docs/performance.md");
        splice(&text, "## T", &path).expect("markers");
        assert!(text.contains("bench --table all --update docs/performance.md"));
    }

    /// The tables are demoted one heading level under the provenance paragraph, which names
    /// what was measured where.
    #[test]
    fn the_tables_follow_the_provenance() {
        let provenance = Provenance {
            date: "2026-12-05T12:00:00Z".into(),
            commit: "abc123".into(),
            cpu: "Some CPU, 2 threads".into(),
            gpu: Some("llvmpipe (Vulkan, Cpu)".into()),
            gpu_driver: Some("llvmpipe Mesa 22.3.6".into()),
            command: "refract bench --table all".into(),
            seconds: 42.0,
        };
        let table = TableOutput {
            markdown: "# Wyman 2005a Table 1\n\n| a |\n".into(),
            rows: serde_json::Value::Null,
        };
        let md = tables_markdown(&provenance, &[(Table::ImageSpace, table)]);
        for part in [
            "at commit abc123 on 2026-12-05T12:00:00Z",
            "- CPU: Some CPU, 2 threads",
            "- GPU: llvmpipe (Vulkan, Cpu)",
            "- GPU driver: llvmpipe Mesa 22.3.6",
            "\n## Wyman 2005a Table 1\n",
        ] {
            assert!(md.contains(part), "{part} in {md}");
        }
        assert!(!md.contains("\n# "), "{md}");
    }
}
