//! `refract sweep SWEEP.toml`: the product of a sweep file's axes (scenes × IORs × resolutions ×
//! backends × methods × method parameters, minus `[[exclude]]` combinations) as independent
//! jobs, every `N`-th one with `--shard I/N` (a Slurm array task, a GNU parallel slot), each
//! written atomically to `OUT/jobs/<job>.json` so a re-run skips finished jobs and a failed job
//! is recorded without stopping the others. `docs/sweeps.md` has the format and cluster
//! recipes; `refract report DIR...` merges shards (`sweep_report.rs`).

use refract_eval::FrameFiles;
use std::collections::hash_map::Entry;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::error::Context;
use refract_core::Camera;
use refract_eval::atomic_write::write_text_atomically;
use refract_eval::load_scene;
use refract_eval::metrics::{MetricsRecord, evaluate_method};
use refract_scene::{
    Aov, BackendId, Frame, FrameOutputs, MethodId, MethodParams, Renderer, Scene, TraceSettings,
};
use refract_trace::ReferenceRenderer;
use serde::Deserialize;

use crate::backends::{self, GpuPolicy};
use crate::engines::{EngineRenderers, engine_record};
use crate::jobs::{Job, JobImages, JobResult};
use crate::progress::{Note, Progress};
use crate::timing::time_frames;
use refract_engines::Engine;
use refract_eval::images::{write_color, write_error_map, write_hdr_script, write_mask};
use refract_eval::metrics::ErrorMaps;

/// Arguments of `refract sweep`.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct SweepArgs {
    /// The sweep file (TOML, `docs/sweeps.md`).
    pub file: PathBuf,
    /// Run every N-th job starting at job I (`I/N`, `0 ≤ I < N`), e.g.
    /// `--shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`.
    #[cfg_attr(feature = "clap", arg(long, value_parser = parse_shard))]
    pub shard: Option<Shard>,
    /// Output directory (jobs/, images/); shards of one sweep may share it or not.
    #[cfg_attr(feature = "clap", arg(long, default_value = "sweep-out"))]
    pub out: PathBuf,
    /// A directory where reference frames are kept, keyed by everything they depend on, and
    /// shared between shards and runs (default: each shard renders the references it needs).
    #[cfg_attr(feature = "clap", arg(long))]
    pub cache: Option<PathBuf>,
    /// List the jobs (this shard's) and exit.
    #[cfg_attr(feature = "clap", arg(long))]
    pub list: bool,
}

/// `--shard I/N`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, `0 ≤ index < count`.
    pub index: usize,
    /// Shards in all.
    pub count: usize,
}

/// Parses `I/N` (shard `I` of `N`, `0 ≤ I < N ≤ 100000`), as `--shard` takes it.
pub fn parse_shard(text: &str) -> Result<Shard, String> {
    let err = || format!("`{text}`: expected I/N with 0 ≤ I < N ≤ 100000");
    let (i, n) = text.split_once('/').ok_or_else(err)?;
    let (index, count) = (
        i.trim().parse::<usize>().map_err(|_| err())?,
        n.trim().parse::<usize>().map_err(|_| err())?,
    );
    if count == 0 || count > 100_000 || index >= count {
        return Err(err());
    }
    Ok(Shard { index, count })
}

/// A sweep file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepFile {
    /// Scene names or files (relative to the sweep file).
    scenes: Vec<String>,
    /// Method ids.
    #[serde(default)]
    methods: Vec<String>,
    /// Engines rendered by themselves in headless Chromium (`threejs`, `babylon`), a job each
    /// per scene, IOR and resolution on backend `webgl` (docs/engines.md).
    #[serde(default)]
    engines: Vec<String>,
    #[serde(default = "default_backends")]
    backends: Vec<String>,
    #[serde(default = "default_res")]
    res: Vec<u32>,
    /// Indices of refraction replacing each scene's; absent: the scene's own.
    #[serde(default)]
    ior: Option<Vec<f32>>,
    #[serde(default = "one")]
    spp: u32,
    /// Where the references are traced: `cpu` (the CPU tracer) or `gpu`
    /// (`refract_gpu::reference`).
    #[serde(default = "default_reference_backend")]
    reference_backend: String,
    #[serde(default = "three")]
    frames: u32,
    /// Method parameter axes (`seeds = [3, 7, 15]`), applied to the methods that have them.
    #[serde(default)]
    params: BTreeMap<String, Vec<toml::Value>>,
    /// Combinations to leave out: every key given must match (`method`, `scene`, `backend`,
    /// `res`, `ior` or a parameter name).
    #[serde(default)]
    exclude: Vec<BTreeMap<String, toml::Value>>,
    /// Write each job's images (colour, FLIP and T2 maps) for the report.
    #[serde(default = "yes")]
    images: bool,
}

fn default_backends() -> Vec<String> {
    vec!["cpu".to_owned()]
}
fn default_reference_backend() -> String {
    "cpu".to_owned()
}
fn default_res() -> Vec<u32> {
    vec![256]
}
fn one() -> u32 {
    1
}
fn three() -> u32 {
    3
}
fn yes() -> bool {
    true
}

/// A parsed sweep: its jobs and run settings.
pub struct Sweep {
    /// Every job, in order.
    pub jobs: Vec<Job>,
    spp: u32,
    /// [`BackendId::Trace`] or [`BackendId::Gpu`].
    reference_backend: BackendId,
    frames: u32,
    images: bool,
    base: PathBuf,
}

fn value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// File-name-safe: letters, digits, `.`, `-`; anything else becomes `_`.
fn safe(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

fn scene_label(spec: &str) -> String {
    Path::new(spec)
        .file_stem()
        .map_or_else(|| spec.to_owned(), |s| s.to_string_lossy().into_owned())
}

impl Sweep {
    /// Reads and checks a sweep file: every method, backend, parameter and number is checked
    /// here, with errors naming the file and key.
    pub fn load(path: &Path) -> crate::Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read the sweep file", path.display()))?;
        let file: SweepFile = toml::from_str(&text)
            .with_context(|| format!("{}: invalid sweep file", path.display()))?;
        let origin = path.display().to_string();
        let base = path.parent().map(Path::to_owned).unwrap_or_default();
        crate::ensure!(!file.scenes.is_empty(), "{origin}: `scenes` is empty");
        crate::ensure!(
            !file.methods.is_empty() || !file.engines.is_empty(),
            "{origin}: `methods` and `engines` are empty; list at least one method or engine"
        );
        let engines = crate::engines::parse_engines(&file.engines)
            .with_context(|| format!("{origin}: engines"))?;
        for &res in &file.res {
            crate::ensure!(
                (1..=refract_scene::MAX_FRAME_SIZE).contains(&res),
                "{origin}: res = {res}: expected sizes from 1 to {}",
                refract_scene::MAX_FRAME_SIZE
            );
        }
        if let Some(iors) = &file.ior {
            crate::ensure!(
                !iors.is_empty(),
                "{origin}: `ior` is empty; list at least one IOR, or leave `ior` out for each scene's own"
            );
            for (k, &ior) in iors.iter().enumerate() {
                crate::ensure!(
                    refract_scene::scene::ior_in_range(ior),
                    "{origin}: ior = {ior}: expected {}",
                    refract_scene::scene::IOR_EXPECTED
                );
                // TOML's numbers are read as f32: two that round to one f32 would be one job.
                if let Some(same) = iors[..k].iter().find(|i| i.to_bits() == ior.to_bits()) {
                    crate::bail!(
                        "{origin}: ior lists {same} twice (as 32-bit numbers, which the sweep uses, two of its values are {same}); list each IOR once"
                    );
                }
            }
        }
        crate::ensure!(
            (1..=refract_scene::MAX_SPP).contains(&file.spp),
            "{origin}: spp = {}: expected 1 to {}",
            file.spp,
            refract_scene::MAX_SPP
        );
        crate::ensure!(
            (1..=1000).contains(&file.frames),
            "{origin}: frames = {}: expected 1 to 1000",
            file.frames
        );
        let reference_backend = match file.reference_backend.as_str() {
            "cpu" => BackendId::Trace,
            "gpu" => BackendId::Gpu,
            other => {
                crate::bail!("{origin}: reference_backend = {other:?}: expected \"cpu\" or \"gpu\"")
            }
        };
        backends::parse_backends(&file.backends).with_context(|| format!("{origin}: backends"))?;
        let methods: Vec<MethodId> = file
            .methods
            .iter()
            .map(|m| {
                m.parse()
                    .map_err(|e| crate::LabError::invalid(format_args!("{origin}: methods: {e}")))
            })
            .collect::<crate::Result<_>>()?;
        crate::ensure!(
            !methods.contains(&MethodId::Reference),
            "{origin}: methods: the reference is rendered for every job; list the methods to compare with it"
        );
        for name in file.params.keys() {
            crate::ensure!(
                methods
                    .iter()
                    .any(|m| m.info().params.iter().any(|p| p.name == name)),
                "{origin}: [params] {name}: none of the sweep's methods has this parameter (see `refract methods`)"
            );
        }
        let iors: Vec<Option<f32>> = match &file.ior {
            None => vec![None],
            Some(iors) => iors.iter().copied().map(Some).collect(),
        };
        check_exclusions(&origin, &file.exclude, &methods)?;
        let mut exclusions = Exclusions::new(&file.exclude);
        // The product of the axes, counted before any job is built (exclusions only remove).
        let per_method: u128 = methods
            .iter()
            .map(|method| {
                file.params
                    .iter()
                    .filter(|(name, _)| method.info().params.iter().any(|p| p.name == *name))
                    .fold(1u128, |n, (_, values)| {
                        n.saturating_mul(values.len() as u128)
                    })
            })
            .fold(0u128, u128::saturating_add);
        let count = [file.scenes.len(), iors.len(), file.res.len()].iter().fold(
            per_method
                .saturating_mul(file.backends.len() as u128)
                .saturating_add(engines.len() as u128),
            |n, &axis| n.saturating_mul(axis as u128),
        );
        crate::ensure!(
            count <= MAX_JOBS as u128,
            "{origin}: the axes make {count} jobs (before exclusions); at most {MAX_JOBS} are run from one sweep file: split it, or sweep fewer values"
        );
        let mut jobs = Vec::new();
        for scene in &file.scenes {
            for &ior in &iors {
                for &res in &file.res {
                    for backend in &file.backends {
                        for &method in &methods {
                            // The parameter axes this method has.
                            let axes: Vec<(&String, &Vec<toml::Value>)> = file
                                .params
                                .iter()
                                .filter(|(name, _)| {
                                    method.info().params.iter().any(|p| p.name == *name)
                                })
                                .collect();
                            for combination in product(&axes) {
                                let job = Job {
                                    index: jobs.len(),
                                    id: String::new(),
                                    scene: scene.clone(),
                                    ior,
                                    res,
                                    backend: backend.clone(),
                                    method: method.name().to_owned(),
                                    params: combination.into_iter().collect(),
                                };
                                if exclusions.keep(&job) {
                                    // Checked only for the jobs that run: a combination
                                    // excluded is no error.
                                    MethodParams::defaults(method).set_all(
                                        job.params.iter().map(|(n, v)| (n.as_str(), v.as_str())),
                                        &format!("{origin}: [params]"),
                                    )?;
                                    jobs.push(job);
                                }
                            }
                        }
                    }
                    for engine in &engines {
                        let job = Job {
                            index: jobs.len(),
                            id: String::new(),
                            scene: scene.clone(),
                            ior,
                            res,
                            backend: crate::engines::ENGINE_BACKEND.to_owned(),
                            method: engine.id().to_owned(),
                            params: BTreeMap::new(),
                        };
                        if exclusions.keep(&job) {
                            jobs.push(job);
                        }
                    }
                }
            }
        }
        exclusions.check_all_matched(&origin)?;
        for (index, job) in jobs.iter_mut().enumerate() {
            job.index = index;
            let mut id = format!(
                "{}-{}{}-{}-{}",
                scene_label(&job.scene),
                job.ior.map_or_else(String::new, |i| format!("ior{i}-")),
                job.res,
                job.backend,
                job.method
            );
            for (k, v) in &job.params {
                id.push_str(&format!("-{k}{v}"));
            }
            job.id = safe(&id);
        }
        let mut ids = std::collections::BTreeSet::new();
        if let Some(twice) = jobs.iter().find(|job| !ids.insert(job.id.as_str())) {
            crate::bail!(
                "{origin}: two jobs would have the id {}: an axis lists one value twice",
                twice.id
            );
        }
        Ok(Self {
            jobs,
            spp: file.spp,
            reference_backend,
            frames: file.frames,
            images: file.images,
            base,
        })
    }

    /// The jobs of `shard` (all without one).
    pub fn shard(&self, shard: Option<Shard>) -> Vec<&Job> {
        self.jobs
            .iter()
            .filter(|j| shard.is_none_or(|s| j.index % s.count == s.index))
            .collect()
    }
}

/// Every combination of one value per axis, as `(name, value)` pairs.
fn product(axes: &[(&String, &Vec<toml::Value>)]) -> Vec<Vec<(String, String)>> {
    let mut combos = vec![Vec::new()];
    for (name, values) in axes {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    c.push(((*name).clone(), value_text(v)));
                    c
                })
            })
            .collect();
    }
    combos
}

/// The keys an `[[exclude]]` rule may have besides the methods' parameter names.
const EXCLUDE_AXES: [&str; 5] = ["scene", "method", "backend", "res", "ior"];

/// Refuses an empty `[[exclude]]` (it would exclude every job) and a key that is neither an
/// axis nor a parameter of one of `methods` (a misspelt key would exclude nothing).
fn check_exclusions(
    origin: &str,
    rules: &[BTreeMap<String, toml::Value>],
    methods: &[MethodId],
) -> crate::Result<()> {
    for (k, rule) in rules.iter().enumerate() {
        crate::ensure!(
            !rule.is_empty(),
            "{origin}: [[exclude]] number {} is empty; it would exclude every job (give the keys it must match)",
            k + 1
        );
        for key in rule.keys() {
            let known = EXCLUDE_AXES.contains(&key.as_str())
                || methods
                    .iter()
                    .any(|m| m.info().params.iter().any(|p| p.name == key));
            crate::ensure!(
                known,
                "{origin}: [[exclude]] number {} has the key `{key}`: expected {} or a parameter of the sweep's methods",
                k + 1,
                EXCLUDE_AXES.join(", ")
            );
        }
    }
    Ok(())
}

/// A rule as `key = value, ...`, for messages.
fn rule_text(rule: &BTreeMap<String, toml::Value>) -> String {
    rule.iter()
        .map(|(key, value)| format!("{key} = {value}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A sweep file's `[[exclude]]` rules while its jobs are built: which rules matched a job.
struct Exclusions<'a> {
    rules: &'a [BTreeMap<String, toml::Value>],
    matched: Vec<bool>,
}

impl<'a> Exclusions<'a> {
    fn new(rules: &'a [BTreeMap<String, toml::Value>]) -> Self {
        Self {
            rules,
            matched: vec![false; rules.len()],
        }
    }

    /// Whether `job` runs: no rule matches it. Every rule that matches is marked.
    fn keep(&mut self, job: &Job) -> bool {
        let mut keep = true;
        for (rule, matched) in self.rules.iter().zip(&mut self.matched) {
            if excluded(job, rule) {
                *matched = true;
                keep = false;
            }
        }
        keep
    }

    /// An error naming the first rule that matched no job (its values are likely wrong).
    fn check_all_matched(&self, origin: &str) -> crate::Result<()> {
        if let Some(k) = self.matched.iter().position(|matched| !matched) {
            crate::bail!(
                "{origin}: [[exclude]] number {} ({}) matches no job of the sweep; check its values",
                k + 1,
                rule_text(&self.rules[k])
            );
        }
        Ok(())
    }
}

fn excluded(job: &Job, rule: &BTreeMap<String, toml::Value>) -> bool {
    rule.iter().all(|(key, value)| {
        let value = value_text(value);
        match key.as_str() {
            "scene" => job.scene == value,
            "method" => job.method == value,
            "backend" => job.backend == value,
            "res" => job.res.to_string() == value,
            "ior" => job.ior.is_some_and(|i| value.parse::<f32>() == Ok(i)),
            param => job.params.get(param) == Some(&value),
        }
    })
}

/// FNV-1a, 64 bits: a stable key for cached reference frames (not for security).
fn fnv1a(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// A loaded scene and its reference frame for one `(scene, ior, res)`.
struct Prepared {
    scene: Arc<Scene>,
    camera: Camera,
    truth: Frame,
    /// The reference's PNG and HDR script.
    reference_images: (String, String),
}

/// The most jobs one sweep file may make (about 200 bytes each in memory: 200 MB), checked by
/// counting the product of its axes before any job is built.
pub const MAX_JOBS: usize = 1_000_000;

/// The jobs of `args.shard` of the sweep file (what `refract sweep --list` prints).
pub fn shard_jobs(args: &SweepArgs) -> crate::Result<Vec<Job>> {
    let sweep = Sweep::load(&args.file)?;
    Ok(sweep.shard(args.shard).into_iter().cloned().collect())
}

/// What a sweep run did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SweepSummary {
    /// Jobs of the whole sweep.
    pub jobs: usize,
    /// Jobs of this shard.
    pub in_shard: usize,
    /// Jobs run and finished now.
    pub finished: usize,
    /// Jobs run now that failed (recorded, run again next time).
    pub failed: usize,
    /// Jobs skipped as finished before.
    pub skipped: usize,
    /// Where the job results are.
    pub jobs_dir: PathBuf,
}

/// The stage of the jobs (one step per job run).
pub const STAGE_JOBS: &str = "jobs";

/// Runs the jobs of `args.shard` that have no result yet, recording each (`OUT/jobs/<id>.json`);
/// a job that fails or panics is recorded as failed and noted to `progress`.
pub fn run(args: &SweepArgs, progress: &dyn Progress) -> crate::Result<SweepSummary> {
    let sweep = Sweep::load(&args.file)?;
    let mine = sweep.shard(args.shard);
    let jobs_dir = args.out.join("jobs");
    let images_dir = args.out.join("images");
    // The cache first: a cache that cannot be made leaves no output directories behind. The
    // output directories are not removed on a later failure or an interrupt (unlike the other
    // experiments' `output_dirs`): the jobs finished so far are what a rerun resumes from.
    if let Some(cache) = &args.cache {
        std::fs::create_dir_all(cache)
            .with_context(|| format!("{}: cannot create the cache directory", cache.display()))?;
    }
    for dir in [&jobs_dir, &images_dir] {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create the directory", dir.display()))?;
    }
    let todo: Vec<&Job> = mine
        .iter()
        .copied()
        .filter(|job| !finished(&jobs_dir, job))
        .collect();
    progress.note(Note::Info(format!(
        "{}: {} jobs, {} in this shard, {} to run",
        args.file.display(),
        sweep.jobs.len(),
        mine.len(),
        todo.len()
    )));
    progress.start(STAGE_JOBS, todo.len() as u64);
    let mut state = JobState::default();
    let (mut ok, mut failed) = (0usize, 0usize);
    for job in todo {
        if progress.cancelled() {
            return Err(crate::LabError::Cancelled);
        }
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            run_job(&sweep, job, args, &mut state, progress)
        }));
        let result = match outcome {
            Ok(Ok((metrics, images))) => {
                ok += 1;
                JobResult {
                    job: job.clone(),
                    status: "ok".to_owned(),
                    error: None,
                    metrics: Some(metrics),
                    images,
                }
            }
            Ok(Err(err)) => {
                failed += 1;
                record_failure(job, refract_scene::full_message(&err))
            }
            Err(panic) => {
                failed += 1;
                let message = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_owned()))
                    .unwrap_or_else(|| "panic".to_owned());
                record_failure(job, format!("panicked: {message}"))
            }
        };
        if let Some(error) = &result.error {
            progress.note(Note::Warning(format!("job {} failed: {error}", job.id)));
        }
        let json = serde_json::to_string_pretty(&result).context("serialising a job result")?;
        write_text_atomically(&jobs_dir.join(format!("{}.json", job.id)), &json)?;
        progress.advance(STAGE_JOBS, 1);
    }
    progress.finish(STAGE_JOBS);
    Ok(SweepSummary {
        jobs: sweep.jobs.len(),
        in_shard: mine.len(),
        finished: ok,
        failed,
        skipped: mine.len() - ok - failed,
        jobs_dir,
    })
}

fn record_failure(job: &Job, error: String) -> JobResult {
    JobResult {
        job: job.clone(),
        status: "error".to_owned(),
        error: Some(error),
        metrics: None,
        images: None,
    }
}

/// The recorded results of the jobs of `args.shard`, in job order (what [`run`] wrote into
/// `OUT/jobs/`, this run's and earlier runs'); a job without a result file is left out.
pub fn shard_results(args: &SweepArgs) -> crate::Result<Vec<JobResult>> {
    let jobs_dir = args.out.join("jobs");
    let mut results = Vec::new();
    for job in shard_jobs(args)? {
        let path = jobs_dir.join(format!("{}.json", job.id));
        let text = match std::fs::read_to_string(&path) {
            Ok(text) => text,
            Err(err) if err.kind() == std::io::ErrorKind::NotFound => continue,
            Err(err) => {
                return Err(err).with_context(|| format!("{}: cannot read", path.display()));
            }
        };
        let result: JobResult = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a job result", path.display()))?;
        results.push(result);
    }
    Ok(results)
}

/// Whether `job` has a recorded successful result (failed jobs run again).
fn finished(jobs_dir: &Path, job: &Job) -> bool {
    std::fs::read_to_string(jobs_dir.join(format!("{}.json", job.id)))
        .ok()
        .and_then(|text| serde_json::from_str::<JobResult>(&text).ok())
        .is_some_and(|r| r.status == "ok" && r.job == *job)
}

fn scene_spec(sweep: &Sweep, spec: &str) -> String {
    let path = Path::new(spec);
    if path.extension().is_some_and(|e| e == "toml") && path.is_relative() {
        sweep.base.join(path).display().to_string()
    } else {
        spec.to_owned()
    }
}

/// The text a reference frame depends on: the scene (its file's text, or the built-in's name),
/// the IOR, the resolution and the tracer settings.
fn reference_key(sweep: &Sweep, job: &Job, settings: &MethodParams) -> crate::Result<String> {
    let spec = scene_spec(sweep, &job.scene);
    let scene_text = if spec.ends_with(".toml") {
        std::fs::read_to_string(&spec).with_context(|| format!("{spec}: cannot read"))?
    } else {
        format!("builtin {spec}")
    };
    // The GPU's references are cached apart from the CPU tracer's (the CPU's key is unchanged).
    let backend = match sweep.reference_backend {
        BackendId::Gpu => "\nreference gpu",
        _ => "",
    };
    Ok(format!(
        "{scene_text}\nior {:?}\nres {}\n{}\nrefract {}{backend}",
        job.ior,
        job.res,
        settings.describe(),
        env!("CARGO_PKG_VERSION")
    ))
}

/// The cached reference at `path` if it is one of `res × res` pixels with every layer the
/// reference renders; otherwise (unreadable, another size, layers missing: a damaged or foreign
/// file) `None` with a warning, and the caller traces the reference again and replaces the
/// entry (issue 54 #6: a wrong size panicked in the job, and the entry was never replaced).
fn usable_cached_reference(path: &Path, res: u32, progress: &dyn Progress) -> Option<Frame> {
    let problem = match Frame::read_exr(path) {
        Ok(frame) if frame.width != res || frame.height != res => format!(
            "{}x{} pixels, expected {res}x{res}",
            frame.width, frame.height
        ),
        Ok(frame) => match MethodId::Reference
            .info()
            .aovs
            .iter()
            .find(|&&aov| !frame.has(aov))
        {
            Some(aov) => format!("no {aov:?} layer"),
            None => return Some(frame),
        },
        Err(err) => err.to_string(),
    };
    progress.note(Note::Warning(format!(
        "{}: the cached reference is unusable ({problem}); traced again and replaced",
        path.display()
    )));
    None
}

/// The jobs' renderer of `backend` (keyed by its id), opened on first use.
fn renderer_of<'a>(
    renderers: &'a mut HashMap<String, Box<dyn Renderer>>,
    backend: BackendId,
    progress: &dyn Progress,
) -> crate::Result<&'a mut Box<dyn Renderer>> {
    Ok(match renderers.entry(backend.id().to_owned()) {
        Entry::Occupied(entry) => entry.into_mut(),
        Entry::Vacant(slot) => {
            let opened = backends::open(&[backend], GpuPolicy::Required, progress)?;
            let renderer = opened.into_iter().next().ok_or_else(|| {
                crate::LabError::invalid(format_args!("no {backend} renderer opened"))
            })?;
            slot.insert(renderer)
        }
    })
}

/// A method's job: its frame on its backend, timed, and its metrics.
fn method_job(
    sweep: &Sweep,
    job: &Job,
    p: &Prepared,
    key: &SceneKey,
    renderers: &mut HashMap<String, Box<dyn Renderer>>,
    prepared_for: &mut HashMap<String, SceneKey>,
    progress: &dyn Progress,
) -> crate::Result<(MetricsRecord, ErrorMaps, Frame)> {
    let backend = backends::parse_backends(std::slice::from_ref(&job.backend))?[0];
    let renderer = renderer_of(renderers, backend, progress)?;
    if prepared_for.get(&job.backend) != Some(key) {
        renderer.prepare(&p.scene)?;
        prepared_for.insert(job.backend.clone(), key.clone());
    }
    let id: MethodId = job.method.parse()?;
    let mut method = MethodParams::defaults(id);
    for (name, value) in &job.params {
        method.set(name, value, "sweep job")?;
    }
    crate::ensure!(
        renderer.supports(id),
        "the {backend} backend does not support {id}"
    );
    let mut frame = Frame::default();
    renderer.render(&p.camera, &method, FrameOutputs::ColorAndAovs, &mut frame)?;
    let mut scratch = Frame::default();
    let times = time_frames(1, sweep.frames, || {
        Ok(renderer
            .render(&p.camera, &method, FrameOutputs::Color, &mut scratch)?
            .ms)
    })?;
    let (mut record, maps) = evaluate_method(&p.truth, &frame, &p.camera, &p.scene, &method);
    record.method = id.name().to_owned();
    record.backend = backend.id().to_owned();
    record.params = method.describe();
    record.ms_per_frame = Some(times.median);
    Ok((record, maps, frame))
}

/// An engine's job: the engine's own frame (headless Chromium, opened on the first such job)
/// and its metrics; untimed (SwiftShader's times are not a GPU's).
fn engine_job(
    job: &Job,
    p: &Prepared,
    engines: &mut Option<EngineRenderers>,
    progress: &dyn Progress,
) -> crate::Result<(MetricsRecord, ErrorMaps, Frame)> {
    let engine = crate::engines::parse_engines(std::slice::from_ref(&job.method))?
        .into_iter()
        .next()
        .ok_or_else(|| crate::LabError::invalid(format_args!("no engine `{}`", job.method)))?;
    crate::ensure!(
        p.scene.refractor.is_dielectric(),
        "{}: the engines render dielectric glass; this refractor is a conductor",
        job.scene
    );
    if engines.is_none() {
        *engines = EngineRenderers::open(&Engine::ALL, GpuPolicy::Required, progress)?;
    }
    let renderers = engines
        .as_ref()
        .ok_or_else(|| crate::LabError::invalid("the engines could not be opened"))?;
    let rendered = renderers
        .render_engines(&[engine], &p.scene, &p.truth, job.res, job.res)?
        .into_iter()
        .next()
        .ok_or_else(|| {
            crate::LabError::invalid(format_args!("{} returned no frame", engine.id()))
        })?;
    let (mut record, maps) = engine_record(&p.truth, &rendered.frame, &p.scene, &p.camera);
    record.method = rendered.label;
    record.backend = crate::engines::ENGINE_BACKEND.to_owned();
    Ok((record, maps, rendered.frame))
}

/// A scene as the jobs share it: its spec, the IOR's bits where the sweep sets one, the
/// resolution.
type SceneKey = (String, Option<u32>, u32);

/// What the jobs of one run share: each scene prepared with its reference, the renderers of
/// each backend and the scene each is prepared for, the engines once one is needed.
#[derive(Default)]
struct JobState {
    prepared: HashMap<SceneKey, Prepared>,
    renderers: HashMap<String, Box<dyn Renderer>>,
    prepared_for: HashMap<String, SceneKey>,
    engines: Option<EngineRenderers>,
}

/// One job: its scene prepared (the reference traced or read from the cache) unless an
/// earlier job did, the method or the engine rendered, the metrics and the images.
fn run_job(
    sweep: &Sweep,
    job: &Job,
    args: &SweepArgs,
    state: &mut JobState,
    progress: &dyn Progress,
) -> crate::Result<(MetricsRecord, Option<JobImages>)> {
    let JobState {
        prepared,
        renderers,
        prepared_for,
        engines,
    } = state;
    let key = (job.scene.clone(), job.ior.map(f32::to_bits), job.res);
    let trace = TraceSettings {
        spp: sweep.spp,
        ..TraceSettings::default()
    };
    let p = match prepared.entry(key.clone()) {
        Entry::Occupied(entry) => entry.into_mut(),
        Entry::Vacant(slot) => {
            let mut scene = load_scene(scene_spec(sweep, &job.scene))?.scene;
            if let Some(ior) = job.ior {
                scene.refractor.set_ior(ior)?;
            }
            let scene = Arc::new(scene);
            let camera = scene.camera(job.res, job.res)?;
            let settings = MethodParams::Reference(trace.for_scene(&scene));
            let text = reference_key(sweep, job, &settings)?;
            let stem = format!(
                "ref-{}-{:016x}",
                safe(&scene_label(&job.scene)),
                fnv1a(&text)
            );
            let cached = args.cache.as_ref().map(|c| c.join(format!("{stem}.exr")));
            let from_cache = cached
                .as_ref()
                .filter(|p| p.is_file())
                .and_then(|path| usable_cached_reference(path, job.res, progress));
            let truth = match from_cache {
                Some(truth) => truth,
                None => {
                    let mut truth = Frame::default();
                    match sweep.reference_backend {
                        BackendId::Gpu => {
                            // The jobs' GPU renderer traces it, prepared for this job's scene.
                            let renderer = renderer_of(renderers, BackendId::Gpu, progress)?;
                            renderer.prepare(&scene)?;
                            prepared_for.insert(BackendId::Gpu.id().to_owned(), key.clone());
                            renderer.render(
                                &camera,
                                &settings,
                                FrameOutputs::ColorAndAovs,
                                &mut truth,
                            )?;
                        }
                        _ => {
                            let mut reference = ReferenceRenderer::new();
                            reference.prepare(&scene)?;
                            reference.render(
                                &camera,
                                &settings,
                                FrameOutputs::ColorAndAovs,
                                &mut truth,
                            )?;
                        }
                    }
                    if let Some(path) = &cached {
                        truth.write_exr(path)?;
                    }
                    truth
                }
            };
            let reference_images = (
                format!("images/{stem}.png"),
                format!("images/{stem}.hdr.js"),
            );
            if sweep.images {
                write_color(
                    &args.out.join(&reference_images.0),
                    job.res,
                    job.res,
                    &truth.color,
                )?;
                write_hdr_script(
                    &args.out.join(&reference_images.1),
                    &reference_images.1,
                    job.res,
                    job.res,
                    &truth.color,
                )?;
            }
            slot.insert(Prepared {
                scene,
                camera,
                truth,
                reference_images,
            })
        }
    };

    let (mut record, maps, frame) = if job.backend == crate::engines::ENGINE_BACKEND {
        engine_job(job, p, engines, progress)?
    } else {
        method_job(sweep, job, p, &key, renderers, prepared_for, progress)?
    };
    record.scene = scene_label(&job.scene);
    if !sweep.images {
        return Ok((record, None));
    }
    let (w, h) = (job.res, job.res);
    let file = |suffix: &str| format!("images/{}{suffix}", job.id);
    let images = JobImages {
        color: file(".png"),
        flip: file("-flip.png"),
        t2: file("-t2err.png"),
        reference: p.reference_images.0.clone(),
        miss: frame.has(Aov::PGeom).then(|| file("-miss.png")),
        color_hdr: Some(file(".hdr.js")),
        reference_hdr: Some(p.reference_images.1.clone()),
    };
    write_color(&args.out.join(&images.color), w, h, &frame.color)?;
    write_error_map(&args.out.join(&images.flip), w, h, &maps.flip, 1.0)?;
    write_error_map(
        &args.out.join(&images.t2),
        w,
        h,
        &maps.t2_deg,
        refract_eval::images::T2_SCALE_DEG,
    )?;
    if let Some(hdr) = &images.color_hdr {
        write_hdr_script(&args.out.join(hdr), hdr, w, h, &frame.color)?;
    }
    if let Some(miss) = &images.miss {
        write_mask(
            &args.out.join(miss),
            w,
            h,
            &refract_eval::metrics::missed_geometry(&p.truth, &frame),
            &frame.color,
        )?;
    }
    Ok((record, Some(images)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sweep(text: &str) -> crate::Result<Sweep> {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("s.toml");
        std::fs::write(&path, text).expect("write");
        Sweep::load(&path)
    }

    /// A small file whose axes multiply to millions of jobs is refused with the count and the
    /// limit, from the count of the product, before any job is built (issue 34, item 4: 32.8
    /// million jobs took 6 GiB in 18 s).
    #[test]
    fn sweeps_beyond_the_job_limit_are_refused_before_expansion() {
        let values = |n: usize| {
            (1..=n)
                .map(|k| k.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let text = format!(
            "scenes = [\"sphere\", \"chart\"]\nmethods = [\"iterative-seeded\"]\nres = [{}]\n\
             [params]\nseeds = [{}]\niterations = [{}]\nguard = [{}]\n",
            values(64),
            values(16),
            values(16),
            values(100),
        );
        let err = sweep(&text).err().expect("too many jobs").to_string();
        assert!(
            err.contains("3276800 jobs") && err.contains("1000000"),
            "{err}"
        );
    }

    #[test]
    fn jobs_are_the_product_of_the_axes_minus_exclusions() {
        let s = sweep(
            "scenes = [\"sphere\", \"chart\"]\nmethods = [\"wyman\", \"iterative-seeded\"]\n\
             ior = [1.1, 1.5]\nres = [32]\n[params]\nseeds = [3, 7]\n\
             [[exclude]]\nscene = \"sphere\"\nmethod = \"iterative-seeded\"\n",
        )
        .expect("sweep");
        // chart: 2 IORs × (wyman + seeded × 2 seeds) = 6; sphere: 2 IORs × wyman = 2.
        assert_eq!(s.jobs.len(), 8);
        let ids: Vec<&str> = s.jobs.iter().map(|j| j.id.as_str()).collect();
        assert!(
            ids.contains(&"chart-ior1.1-32-cpu-iterative-seeded-seeds7"),
            "{ids:?}"
        );
        assert!(
            ids.iter()
                .all(|id| !id.starts_with("sphere") || id.contains("wyman"))
        );
        let unique: std::collections::BTreeSet<&str> = ids.iter().copied().collect();
        assert_eq!(unique.len(), ids.len(), "ids are unique");
        // Shards partition the jobs.
        let shards: Vec<usize> = (0..3)
            .map(|i| s.shard(Some(Shard { index: i, count: 3 })).len())
            .collect();
        assert_eq!(shards.iter().sum::<usize>(), 8);
    }

    #[test]
    fn sweep_errors_name_the_file_and_key() {
        for (text, expected) in [
            ("scenes = [\"sphere\"]\nmethods = [\"nope\"]\n", "methods"),
            (
                "scenes = [\"sphere\"]\nmethods = [\"wyman\"]\nres = [0]\n",
                "res = 0",
            ),
            (
                "scenes = [\"sphere\"]\nmethods = [\"wyman\"]\nior = [-1.0]\n",
                "ior",
            ),
            (
                "scenes = [\"sphere\"]\nmethods = [\"wyman\"]\n[params]\nseeds = [3]\n",
                "seeds",
            ),
            (
                "scenes = [\"sphere\"]\nmethods = [\"iterative-seeded\"]\n[params]\nseeds = [0]\n",
                "seeds",
            ),
            (
                "scenes = [\"sphere\"]\nmethods = [\"wyman\"]\nbackends = [\"tpu\"]\n",
                "tpu",
            ),
            (
                "scenes = [\"sphere\"]\nmethods = [\"wyman\"]\nframe = 3\n",
                "frame",
            ),
            // Issue 54 #13: mistakes that used to pass without a word.
            (
                "scenes = [\"sphere\"]\nmethods = [\"single\", \"wyman\"]\n[[exclude]]\nmethd = \"single\"\n",
                "[[exclude]] number 1 has the key `methd`: expected scene, method, backend, res, ior",
            ),
            (
                "scenes = [\"sphere\"]\nmethods = [\"wyman\"]\n[[exclude]]\n",
                "[[exclude]] number 1 is empty; it would exclude every job",
            ),
            (
                "scenes = [\"sphere\"]\nmethods = [\"wyman\"]\n[[exclude]]\nmethod = \"single\"\n",
                "[[exclude]] number 1 (method = \"single\") matches no job",
            ),
            (
                "scenes = [\"sphere\"]\nmethods = [\"wyman\"]\nior = [1.2, 1.2000001]\n",
                "ior lists 1.2 twice",
            ),
            (
                "scenes = [\"sphere\"]\nmethods = [\"wyman\"]\nres = [16, 16]\n",
                "two jobs would have the id sphere-16-cpu-wyman",
            ),
            (
                "scenes = [\"sphere\"]\nmethods = [\"wyman\"]\nior = []\n",
                "`ior` is empty",
            ),
        ] {
            let err = refract_scene::full_message(&sweep(text).err().expect(expected));
            assert!(err.contains("s.toml") && err.contains(expected), "{err}");
        }
        assert_eq!(parse_shard("2/3"), Ok(Shard { index: 2, count: 3 }));
        for bad in ["3/3", "1/0", "x/2", "1"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }
}
