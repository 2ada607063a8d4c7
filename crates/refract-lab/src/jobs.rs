//! The types compare, sweep and their reports share: a comparison's options, a job, its
//! outcome and its images. They sit below every experiment module, so none imports another in a
//! circle.

use std::collections::BTreeMap;
use std::path::PathBuf;

use refract_eval::metrics::MetricsRecord;
use refract_scene::{BackendId, MethodParams};
use serde::{Deserialize, Serialize};

use crate::backends::GpuPolicy;

/// What to compare.
pub struct CompareOptions {
    /// Backends.
    pub backends: Vec<BackendId>,
    /// What a missing adapter means.
    pub gpu_policy: GpuPolicy,
    /// Scene names or files (any path the OS takes).
    pub scenes: Vec<std::ffi::OsString>,
    /// Methods with their parameters.
    pub methods: Vec<MethodParams>,
    /// Square resolution.
    pub res: u32,
    /// Reference samples per pixel.
    pub spp: u32,
    /// Where the reference is traced: [`BackendId::Trace`] (the CPU tracer, the default) or
    /// [`BackendId::Gpu`] (`refract_gpu::reference`, every mode and sample count).
    pub reference_backend: BackendId,
    /// Untimed frames per method before the timed ones (after the frame with the AOVs, which
    /// has already built what the method keeps between frames).
    pub warm_up: u32,
    /// Timed frames per method (the median is reported).
    pub frames: u32,
    /// The engines whose own renderers run beside the methods (`crate::engines`): their
    /// colour and `P_geom` against the same reference.
    pub engines: Vec<refract_engines::Engine>,
    /// What a missing engine means.
    pub engine_policy: GpuPolicy,
    /// Output directory.
    pub out: PathBuf,
}

/// One job: every input that determines its result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Job {
    /// Its position in the sweep's job list.
    pub index: usize,
    /// A file-name-safe id made of its inputs (`chart-ior1.2-256-cpu-iterative-seeded-seeds7`).
    pub id: String,
    /// The scene as written in the sweep file.
    pub scene: String,
    /// The IOR replacing the scene's, if any.
    pub ior: Option<f32>,
    /// Square resolution.
    pub res: u32,
    /// `cpu` or `gpu`.
    pub backend: String,
    /// Method id.
    pub method: String,
    /// The swept parameters of this job (the rest are the method's defaults).
    pub params: BTreeMap<String, String>,
}

/// A job's recorded outcome (`OUT/jobs/<id>.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JobResult {
    /// The job.
    pub job: Job,
    /// `ok` or `error`.
    pub status: String,
    /// The error of a failed job.
    pub error: Option<String>,
    /// The metrics of a finished job (its `ms_per_frame` is this machine's).
    pub metrics: Option<MetricsRecord>,
    /// The job's images, relative to the output directory (when the sweep writes them).
    pub images: Option<JobImages>,
}

/// A job's images, paths relative to the output directory.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct JobImages {
    /// The method's tonemapped colour (PNG).
    pub color: String,
    /// Its FLIP map.
    pub flip: String,
    /// Its T2-error map.
    pub t2: String,
    /// The reference's tonemapped colour.
    pub reference: String,
    /// The missed-objects mask (nearby-geometry methods).
    pub miss: Option<String>,
    /// The method's linear colour for the exposure control (`images::write_hdr_script`).
    pub color_hdr: Option<String>,
    /// The reference's linear colour.
    pub reference_hdr: Option<String>,
}

impl JobImages {
    /// Every file.
    pub fn files(&self) -> Vec<&str> {
        let mut files = vec![
            self.color.as_str(),
            self.flip.as_str(),
            self.t2.as_str(),
            self.reference.as_str(),
        ];
        files.extend(
            [&self.miss, &self.color_hdr, &self.reference_hdr]
                .into_iter()
                .flatten()
                .map(String::as_str),
        );
        files
    }
}
