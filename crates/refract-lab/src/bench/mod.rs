//! `refract bench`: the papers' timing tables on this machine, each beside the paper's
//! figures: Wyman 2005a Table 1 ([`image_space`]), Wyman 2005b Table 1 ([`nearby`]), Umenhoffer
//! et al. 2007 §17.4 ([`distance_map`]), Kakimoto et al. 2007 §5 ([`pvrr`]), the engine methods
//! beside `wyman` ([`engine`]), `depth-peel` at 2, 4 and 8 layers beside `wyman` ([`layers`])
//! and the exact reference on both backends ([`reference`]).
//! `--table all` runs every one and writes them as one file with the machine, the commit and
//! the date ([`all`]); `--update` splices that file into `docs/performance.md`.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::Arc;

use refract_core::Camera;
use refract_eval::atomic_write::write_text_atomically;
use refract_eval::{LoadOptions, load_mesh};
use refract_geometry::{Mesh, builtin};
use refract_scene::{
    Environment, Frame, FrameOutputs, MethodId, MethodParams, PassTime, Refractor, Renderer, Scene,
};
use serde::Serialize;

use crate::error::Context;
use crate::progress::{Note, Progress};
use crate::timing::{FrameTimes, time_frames};

mod all;
mod distance_map;
mod engine;
mod image_space;
mod layers;
pub(crate) mod nearby;
mod pvrr;
mod reference;

/// Arguments of `refract bench`.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct BenchArgs {
    /// Comma-separated models: sphere (built-in), cow, teapot, bunny, horse (from --data).
    #[cfg_attr(
        feature = "clap",
        arg(
            long,
            value_delimiter = ',',
            default_value = "sphere,cow,teapot,bunny,horse"
        )
    )]
    pub scenes: Vec<String>,
    /// Comma-separated methods (Table 1 has wyman = 2-sided and single = 1-sided).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_delimiter = ',', default_value = "wyman,single")
    )]
    pub methods: Vec<MethodId>,
    /// Comma-separated backends: cpu, gpu (gpu is skipped with a notice without an adapter).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_delimiter = ',', default_value = "cpu,gpu")
    )]
    pub backends: Vec<String>,
    /// Square resolution (Table 1: 1024).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=i64::from(refract_scene::MAX_FRAME_SIZE))))]
    pub res: u32,
    /// Timed frames per method (median reported; at least 20 for the table).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=10000)))]
    pub frames: u32,
    /// Where the meshes are (`meshes/cow.obj`, ...).
    #[cfg_attr(feature = "clap", arg(long, default_value = "../shared/data"))]
    pub data: PathBuf,
    /// Output directory for bench.json and bench.md.
    #[cfg_attr(feature = "clap", arg(long, default_value = "out"))]
    pub out: PathBuf,
    /// A small run for smoke tests: 128², 3 frames, sphere and cow only (`--table nearby`:
    /// 64² and 128², the sphere row only).
    #[cfg_attr(feature = "clap", arg(long))]
    pub quick: bool,
    /// Which table: `image-space` (Wyman 2005a Table 1), `nearby` (Wyman 2005b Table 1:
    /// `iterative-seeded` on the paper's four scenes, our models mapped by size, at 1024² and
    /// 512²; `--scenes`, `--methods` and `--res` do not apply), `distance-map` (Umenhoffer et al.
    /// §17.4), `pvrr` (Kakimoto et al. §5), `engine` (the engine methods beside `wyman`),
    /// `layers` (`depth-peel` at 2, 4, 8 layers beside `wyman` on the scenes with several
    /// refractors),
    /// `reference` (the exact reference on the CPU tracer and the GPU at 512² and 1024²,
    /// transmission and full, rays per second; `--scenes` applies) or `all` (every table in
    /// turn, into `bench-all.md` and `bench-all.json` with the CPU, the GPU adapter and driver,
    /// the commit and the date).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = Table::ImageSpace))]
    pub table: Table,
    /// With `--table all`: also rewrite the tables in this Markdown file, between its lines
    /// `<!-- refract bench --table all: begin -->` and `<!-- refract bench --table all: end -->`
    /// (`docs/performance.md` has them); the rest of the file is kept byte for byte.
    #[cfg_attr(feature = "clap", arg(long))]
    pub update: Option<PathBuf>,
}

/// The tables `refract bench` reproduces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Table {
    /// Wyman 2005a Table 1.
    ImageSpace,
    /// Wyman 2005b Table 1.
    Nearby,
    /// Umenhoffer et al. 2007 §17.4: the chapter's setting with and without min-max.
    DistanceMap,
    /// Kakimoto et al. 2007 §5: reflection, multiple reflection, the lens (every frame, fixed
    /// to the eye, with chromatic aberration) at 1024².
    Pvrr,
    /// The engine methods beside `wyman` on the sphere and the cow at 1024², both backends.
    Engine,
    /// `depth-peel` at 2, 4 and 8 layers beside `wyman` on the scenes with several refractors
    /// at 1024², both backends.
    Layers,
    /// The exact reference on the CPU tracer and on the GPU: the Table 1 models at 512² and
    /// 1024², transmission and `full`, seconds a frame and rays per second.
    Reference,
    /// Every table above, in that order, as one file with the machine, the commit and the date.
    All,
}

impl Table {
    /// Every table `all` runs, in its order.
    pub const EACH: [Table; 7] = [
        Table::ImageSpace,
        Table::Nearby,
        Table::DistanceMap,
        Table::Pvrr,
        Table::Engine,
        Table::Layers,
        Table::Reference,
    ];

    /// Its name on the command line and in `bench-all.json`.
    pub const fn name(self) -> &'static str {
        match self {
            Table::ImageSpace => "image-space",
            Table::Nearby => "nearby",
            Table::DistanceMap => "distance-map",
            Table::Pvrr => "pvrr",
            Table::Engine => "engine",
            Table::Layers => "layers",
            Table::Reference => "reference",
            Table::All => "all",
        }
    }

    /// The stem of its files in `--out` (`bench.md` and `bench.json` for Table 1).
    const fn file_stem(self) -> &'static str {
        match self {
            Table::ImageSpace => "bench",
            Table::Nearby => "bench-nearby",
            Table::DistanceMap => "bench-distance-map",
            Table::Pvrr => "bench-pvrr",
            Table::Engine => "bench-engine",
            Table::Layers => "bench-layers",
            Table::Reference => "bench-reference",
            Table::All => "bench-all",
        }
    }
}

/// One table measured: its Markdown (a `# ` title, a paragraph saying how it was measured, the
/// table) and its rows as JSON.
struct TableOutput {
    markdown: String,
    rows: serde_json::Value,
}

impl TableOutput {
    fn new(markdown: String, rows: &impl Serialize) -> crate::Result<Self> {
        let rows = serde_json::to_value(rows).context("serialising bench records")?;
        Ok(Self { markdown, rows })
    }

    /// [`TableOutput::new`] for rows of frames, the table followed by [`passes_section`].
    fn of_frames(markdown: String, records: &[BenchRecord]) -> crate::Result<Self> {
        Self::new(markdown + &passes_section(records), &records)
    }
}

/// Where the GPU rows' time goes: the median GPU time of each labelled pass over the timed
/// frames (timestamp queries around each pass), their sum and the frame's span (first pass's
/// start to last pass's end: the sum plus the gaps between passes). Empty without GPU rows or
/// without timestamp queries.
fn passes_section(records: &[BenchRecord]) -> String {
    let timed: Vec<&BenchRecord> = records
        .iter()
        .filter(|r| !r.gpu_passes.is_empty())
        .collect();
    if timed.is_empty() {
        return String::new();
    }
    let mut md = String::from(
        "\nGPU passes: the median GPU time of each pass over the same frames (timestamp queries \
         around each pass), their sum, and the frame (its span from the first pass's start to the \
         last pass's end).\n\n| scene | method | passes (ms) | sum | frame |\n|---|---|---|---|---|\n",
    );
    for r in timed {
        let passes: Vec<String> = r
            .gpu_passes
            .iter()
            .map(|p| {
                let times = if p.count > 1 {
                    format!(" ×{}", p.count)
                } else {
                    String::new()
                };
                format!("{}{times} {:.2}", p.label, p.ms_median)
            })
            .collect();
        let sum: f64 = r.gpu_passes.iter().map(|p| p.ms_median).sum();
        let _ = writeln!(
            md,
            "| {} | `{}` | {} | {sum:.2} | {:.2} |",
            r.scene,
            r.method,
            passes.join(", "),
            r.ms_median
        );
    }
    md
}

/// Runs `args.table`, writes its `.md` and `.json` into `--out` (`bench.md` and `bench.json`
/// for Table 1, `bench-nearby.*` for `--table nearby`, ...; `--table all` writes every table's
/// files and `bench-all.*`) and returns the Markdown; each row goes to `progress` as it is
/// measured.
pub fn run(args: &BenchArgs, progress: &dyn Progress) -> crate::Result<String> {
    crate::ensure!(
        args.update.is_none() || args.table == Table::All,
        "--update: applies to --table all only (the file holds every table)"
    );
    crate::output_dirs::create_dir(&args.out)
        .with_context(|| format!("{}: cannot create the output directory", args.out.display()))?;
    if args.table == Table::All {
        return all::run(args, progress);
    }
    Ok(run_table(args.table, args, progress)?.markdown)
}

/// Runs one table (not `all`) and writes its two files.
fn run_table(
    table: Table,
    args: &BenchArgs,
    progress: &dyn Progress,
) -> crate::Result<TableOutput> {
    let output = match table {
        Table::ImageSpace => image_space::run(args, progress)?,
        Table::Nearby => nearby::run(args, progress)?,
        Table::DistanceMap => distance_map::run(args, progress)?,
        Table::Pvrr => pvrr::run(args, progress)?,
        Table::Engine => engine::run(args, progress)?,
        Table::Layers => layers::run(args, progress)?,
        Table::Reference => reference::run(args, progress)?,
        Table::All => crate::bail!("--table all runs the other tables one by one"),
    };
    write_output(&args.out, table.file_stem(), &output)?;
    Ok(output)
}

/// Writes `stem.md` and `stem.json` into `dir`.
fn write_output(dir: &std::path::Path, stem: &str, output: &TableOutput) -> crate::Result<()> {
    let json = serde_json::to_string_pretty(&output.rows).context("serialising bench records")?;
    write(&dir.join(format!("{stem}.json")), &json)?;
    write(&dir.join(format!("{stem}.md")), &output.markdown)
}

/// One row of `bench.json`.
#[derive(Clone, Debug, Serialize)]
pub struct BenchRecord {
    scene: String,
    triangles: usize,
    method: String,
    backend: String,
    width: u32,
    height: u32,
    ms_median: f64,
    ms_min: f64,
    ms_max: f64,
    frames: u32,
    fps: f64,
    /// The GPU's passes (GPU rows on an adapter with timestamp queries).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    gpu_passes: Vec<PassRecord>,
}

/// The median GPU time of the passes of one label over a row's timed frames.
#[derive(Clone, Debug, Serialize)]
pub struct PassRecord {
    label: &'static str,
    /// Passes with the label in a frame.
    count: u32,
    ms_median: f64,
}

/// Per label (in the last frame's order), the median over `frames` of the label's time, with
/// the last frame's count.
fn pass_medians(frames: &[Vec<PassTime>]) -> Vec<PassRecord> {
    let Some(last) = frames.last() else {
        return Vec::new();
    };
    last.iter()
        .map(|pass| {
            let mut times: Vec<f64> = frames
                .iter()
                .filter_map(|f| f.iter().find(|p| p.label == pass.label).map(|p| p.ms))
                .collect();
            times.sort_by(f64::total_cmp);
            PassRecord {
                label: pass.label,
                count: pass.count,
                ms_median: times[times.len() / 2],
            }
        })
        .collect()
}

/// Model name, file in `meshes/`, IOR (the paper's: 1.5 for the sphere and teapot, 1.2 else).
const MODELS: [(&str, &str, f32); 5] = [
    ("sphere", "builtin:sphere", 1.5),
    ("cow", "cow.obj", 1.2),
    ("teapot", "teapot.obj", 1.5),
    ("bunny", "stanford-bunny.obj", 1.2),
    ("horse", "horse.obj", 1.2),
];

/// The Table 1 scene of model `name` (the model alone in the procedural environment) and its
/// triangle count; `None` (after a note) when its mesh file is missing.
fn model_scene(
    name: &str,
    data: &std::path::Path,
    progress: &dyn Progress,
) -> crate::Result<Option<(Arc<Scene>, usize)>> {
    let Some((mesh, ior)) = load_model(name, data, progress)? else {
        return Ok(None);
    };
    let triangles = mesh.triangles.len();
    let scene = Scene::new(name, Refractor::new(mesh, ior)?, Environment::Procedural);
    Ok(Some((Arc::new(scene), triangles)))
}

fn load_model(
    name: &str,
    data: &std::path::Path,
    progress: &dyn Progress,
) -> crate::Result<Option<(Mesh, f32)>> {
    let Some(&(_, file, ior)) = MODELS.iter().find(|m| m.0 == name) else {
        let names: Vec<&str> = MODELS.iter().map(|m| m.0).collect();
        crate::bail!(
            "--scenes: unknown model `{name}`; expected one of {}",
            names.join(", ")
        );
    };
    if file.starts_with(builtin::PREFIX) {
        return Ok(Some((builtin::mesh(file)?, ior)));
    }
    let path = data.join("meshes").join(file);
    if !path.is_file() {
        progress.note(Note::Skipped(format!(
            "{} not found; skipping {name}",
            path.display()
        )));
        return Ok(None);
    }
    Ok(Some((load_mesh(&path, &LoadOptions::default())?.mesh, ior)))
}

/// Triangles of every mesh of `scene`.
fn triangles(scene: &refract_scene::Scene) -> usize {
    scene.refractor.mesh().triangles.len()
        + scene
            .objects
            .iter()
            .map(|o| o.mesh().triangles.len())
            .sum::<usize>()
}

/// One benchmarked configuration before it is named: method, backend, size and times.
struct Timed {
    method: String,
    backend: String,
    width: u32,
    height: u32,
    frames: u32,
    times: FrameTimes,
    passes: Vec<PassRecord>,
}

impl Timed {
    fn record(self, scene: &str, triangles: usize) -> BenchRecord {
        let FrameTimes { median, min, max } = self.times;
        BenchRecord {
            scene: scene.to_owned(),
            triangles,
            method: self.method,
            backend: self.backend,
            width: self.width,
            height: self.height,
            ms_median: median,
            ms_min: min,
            ms_max: max,
            frames: self.frames,
            fps: 1e3 / median,
            gpu_passes: self.passes,
        }
    }
}

/// `frames` colour-only frames of `method` (as displayed: the AOVs are for comparisons) after 3
/// warm-up frames.
fn timed(
    renderer: &mut dyn Renderer,
    camera: &Camera,
    method: &MethodParams,
    frames: u32,
    frame: &mut Frame,
) -> crate::Result<Timed> {
    const WARM_UP: usize = 3;
    let mut passes: Vec<Vec<PassTime>> = Vec::new();
    let times = time_frames(WARM_UP as u32, frames, || {
        let ms = renderer
            .render(camera, method, FrameOutputs::Color, frame)?
            .ms;
        passes.push(renderer.last_pass_times());
        Ok(ms)
    })?;
    Ok(Timed {
        passes: pass_medians(&passes[WARM_UP.min(passes.len())..]),
        method: method.id().name().to_owned(),
        backend: renderer.backend().id().to_owned(),
        width: camera.width(),
        height: camera.height(),
        frames,
        times,
    })
}

fn write(path: &std::path::Path, text: &str) -> crate::Result<()> {
    Ok(write_text_atomically(path, text)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pass(label: &'static str, ms: f64) -> PassTime {
        PassTime {
            label,
            count: 1,
            ms,
        }
    }

    /// Each label's median over the frames, in the last frame's order; a label missing from a
    /// frame is the median of the frames that have it.
    #[test]
    fn pass_medians_are_per_label() {
        let frames = vec![
            vec![pass("back faces", 1.0), pass("kernel", 5.0)],
            vec![pass("kernel", 4.0)],
            vec![pass("back faces", 3.0), pass("kernel", 6.0)],
            vec![pass("back faces", 2.0), pass("kernel", 9.0)],
        ];
        let medians = pass_medians(&frames);
        let got: Vec<(&str, f64)> = medians.iter().map(|p| (p.label, p.ms_median)).collect();
        assert_eq!(got, [("back faces", 2.0), ("kernel", 6.0)]);
        assert!(pass_medians(&[]).is_empty());
    }

    /// The section lists the GPU rows' passes and is empty without them.
    #[test]
    fn passes_section_lists_timed_rows_only() {
        let record = |backend: &str, passes: Vec<PassRecord>| BenchRecord {
            scene: "sphere".into(),
            triangles: 1600,
            method: "wyman".into(),
            backend: backend.into(),
            width: 64,
            height: 64,
            ms_median: 4.0,
            ms_min: 3.9,
            ms_max: 4.2,
            frames: 3,
            fps: 250.0,
            gpu_passes: passes,
        };
        assert_eq!(passes_section(&[record("cpu", Vec::new())]), "");
        let gpu = record(
            "gpu",
            vec![
                PassRecord {
                    label: "back faces",
                    count: 1,
                    ms_median: 1.5,
                },
                PassRecord {
                    label: "kernel",
                    count: 2,
                    ms_median: 2.0,
                },
            ],
        );
        let md = passes_section(&[record("cpu", Vec::new()), gpu]);
        assert!(
            md.contains("| sphere | `wyman` | back faces 1.50, kernel ×2 2.00 | 3.50 | 4.00 |"),
            "{md}"
        );
        assert_eq!(md.matches("| sphere |").count(), 1, "{md}");
    }
}
